"""How an episode ends, as Gymnasium names it, and when the next one starts: the one rule.

Every adapter of this package that speaks Gymnasium's language (`composer.gym.GymnasiumEnv`
and its vector envs, `composer.batch.BatchEnvironment` and its `BatchVectorEnv`,
`composer.rl.sb3`, `composer.rl.rsl_rl`) applies the rule from here; their docstrings point
here rather than restate it. docs/concepts/gymnasium.md ("The rules every adapter shares")
is its page for users.

**Terminated or truncated** (`episode_ends`). A dm_env episode ends with a LAST step; its
discount says why:

| the LAST step's discount | Gymnasium          | what ended it                              |
|--------------------------|--------------------|--------------------------------------------|
| 0                        | `terminated` True  | the task (`should_terminate_episode`)      |
| anything else            | `truncated` True   | the time limit (the discount is kept)      |

No other step is terminated or truncated, and no step is both. Stable-Baselines3's
`TimeLimit.truncated` and rsl_rl's `time_outs` are `truncated`; their `dones` are
`terminated or truncated`.

**Autoreset** (`Autoreset`, Gymnasium's `AutoresetMode` by our own names), for an episode
that ended (terminated or truncated) at step t:

- NEXT_STEP: step t returns the episode's last observation, reward, terminated and
  truncated; step t + 1 ignores its action, resets, and returns the first observation
  with reward 0, neither terminated nor truncated.
- SAME_STEP: step t resets within the step and returns the next episode's first
  observation, with step t's reward, terminated and truncated; the last observation (and
  info) is kept apart, as Gymnasium's `final_obs` (and `final_info`). Step t + 1 is an
  ordinary step of the new episode.
- DISABLED: step t returns as under NEXT_STEP; stepping again is refused until the caller
  resets it.

Stable-Baselines3 and rsl_rl train on SAME_STEP; `composer`'s own default is NEXT_STEP
(dm_env's order: LAST, then FIRST). A batch of worlds offers NEXT_STEP and SAME_STEP.

The functions here work on Python scalars (one environment) and elementwise on arrays
(NumPy, torch, JAX or any array API namespace's, one row per world) alike: they only use
`&`, `==` and `!=`.
"""

from __future__ import annotations

import enum
from typing import Any, NamedTuple

__all__ = ["Autoreset", "EpisodeEnds", "episode_ends"]


class EpisodeEnds(NamedTuple):
    """How an episode ended, as Gymnasium says it: bools, or bool arrays (one per world).

    Attributes:
      terminated: the task ended the episode (a LAST step with discount 0).
      truncated: the episode ended with a non-zero discount (the time limit).
    """

    terminated: Any
    truncated: Any


def episode_ends(last: Any, discount: Any) -> EpisodeEnds:
    """Gymnasium's `terminated` and `truncated` of a step (see the module docstring).

    Args:
      last: whether the step is LAST (`TimeStep.last()`), or a bool array of them.
      discount: the step's discount, or an array of them of `last`'s shape.

    Returns:
      An `EpisodeEnds` of `last`'s kind: bools for bools, bool arrays for arrays.
    """
    return EpisodeEnds(terminated=last & (discount == 0), truncated=last & (discount != 0))


# Gymnasium's `AutoresetMode` values, which this module reads without importing Gymnasium.
_GYMNASIUM_VALUES = {"next_step": "NextStep", "same_step": "SameStep", "disabled": "Disabled"}


class Autoreset(enum.Enum):
    """An autoreset mode (see the module docstring) and what it does to an ended episode.

    Each method takes a bool or a bool array (one per world) and returns the same kind.
    `Autoreset.of` reads our values ("next_step", ...) and Gymnasium's `AutoresetMode`
    (or its values, "NextStep", ...).
    """

    NEXT_STEP = "next_step"
    SAME_STEP = "same_step"
    DISABLED = "disabled"

    @classmethod
    def of(cls, mode: Any) -> Autoreset:
        """The `Autoreset` named by `mode`: an `Autoreset`, its value, or Gymnasium's
        `AutoresetMode` or its value.

        Raises:
          ValueError: naming `autoreset_mode`, for anything else.
        """
        if isinstance(mode, cls):
            return mode
        value = getattr(mode, "value", mode)
        if isinstance(value, str) and value in _BY_VALUE:
            return _BY_VALUE[value]
        raise ValueError(
            f"autoreset_mode: expected one of {[m.value for m in cls]} or a Gymnasium "
            f"AutoresetMode, got {mode!r}"
        )

    @property
    def gymnasium_value(self) -> str:
        """The value of Gymnasium's `AutoresetMode` of the same name ("NextStep", ...)."""
        return _GYMNASIUM_VALUES[self.value]

    def resets_before_step(self, episode_over: Any) -> Any:
        """Where a step resets instead of stepping: an episode over at the step before,
        under NEXT_STEP."""
        return episode_over & (self is Autoreset.NEXT_STEP)

    def refuses_step(self, episode_over: Any) -> Any:
        """Where a step is refused: an episode over and not reset, under DISABLED."""
        return episode_over & (self is Autoreset.DISABLED)

    def resets_after_step(self, ended: Any) -> Any:
        """Where a step resets once stepped: an episode it ended, under SAME_STEP."""
        return ended & (self is Autoreset.SAME_STEP)

    def over_after_step(self, ended: Any) -> Any:
        """Where an episode is over after a step that `ended` it: all but SAME_STEP's,
        whose next episode has already started."""
        return ended & (self is not Autoreset.SAME_STEP)


# Each mode by our value and by Gymnasium's: `Autoreset.of` runs at every sub-environment step.
_BY_VALUE = {
    **{mode.value: mode for mode in Autoreset},
    **{mode.gymnasium_value: mode for mode in Autoreset},
}
