"""A `dm_env.Environment` (a `composer.Environment` above all) as a `gymnasium.Env`.

Contract of the adapter (`GymnasiumEnv`):

- `observation_space` and `action_space` come from the wrapped environment's specs
  (see `composer.gym.spec_spaces`): observations are the wrapped environment's own dict
  of arrays, unchanged, or with `flatten_observations` as `spec_spaces.FlatObservations`
  packs them (one `Box` of every feature, images kept apart).
- `observation_space` follows the wrapped environment's observation spec at every
  `reset`: observables enabled, disabled or reconfigured after wrapping (which a
  `composer.Environment` applies at its next reset) change it there, never mid-episode.
- `reset(seed=s)` reseeds the wrapped environment's `random_state` in place, so the same
  `s` gives the same episode; `reset()` without a seed continues the random sequence.
- `step` returns `(observation, reward, terminated, truncated, info)`, terminated and
  truncated as `composer.episode_end` says (discount 0: terminated; the time limit:
  truncated); `info['discount']` is the discount.
  At an episode's end (terminated or truncated), a wrapped environment whose task defines
  success (`composer.Task.get_success` returns a bool, not None) adds `info['is_success']`,
  a bool (Stable-Baselines3's key); no other step carries it.
  The reward is checked against the wrapped environment's `reward_spec()`, which must
  describe one number.
- `write_observations_to(out)` makes `reset` and `step` copy their observations into
  `out` (arrays laid out as `observation_space`, such as views of one row of a vector
  env's batch) and return `out` itself, which the next `reset` or `step` overwrites.
- `render()` draws the `camera` with `mujoco`'s off-screen renderer: (height, width, 3)
  uint8 for 'rgb_array', (height, width) float32 metres for 'depth_array'. With 'human',
  `reset` and `step` draw the scene in a window themselves (`composer.viewer`'s, on
  MuJoCo's `launch_passive`) and `render()` returns None.
"""

import math
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import dm_env
import gymnasium
import numpy as np

from composer.episode_end import episode_ends
from composer.gym import spec_spaces
from composer.gym.rows import row_writer
from composer.utils import argument_checks

__all__ = ["GymnasiumEnv"]

_RENDER_MODES = ("human", "rgb_array", "depth_array")


def _spec_signature(spec) -> Any:
    """What two observation specs must share to give the same space: names, kinds, specs."""
    if isinstance(spec, Mapping):
        return tuple((name, type(value), _spec_signature(value)) for name, value in spec.items())
    return spec


def _reward_converter(env: dm_env.Environment) -> Callable[[Any], float]:
    """Returns the check that turns the rewards of `env` into floats, from its reward spec.

    Raises:
      ValueError: if the reward spec is not that of one number.
    """
    spec = env.reward_spec()
    if not isinstance(spec, dm_env.specs.Array) or spec.shape != ():
        raise ValueError(
            f"{type(env).__name__}.reward_spec(): expected the spec of one number (Gymnasium's "
            f"step returns one float reward), got {spec!r}"
        )
    bounded = isinstance(spec, dm_env.specs.BoundedArray)
    low = float(spec.minimum) if bounded else -math.inf
    high = float(spec.maximum) if bounded else math.inf
    expected = "one number" if not bounded else f"one number in [{low:g}, {high:g}]"
    said = f"as {type(env).__name__}.reward_spec() says ({spec!r})"

    def to_float(reward) -> float:
        if not isinstance(reward, float):
            array = np.asarray(reward)
            if array.shape != ():
                raise ValueError(
                    f"reward: expected {expected}, {said}, got {reward!r} of shape "
                    f"{array.shape}; make the task's get_reward return a float"
                )
            try:
                reward = float(array)
            except (TypeError, ValueError):
                raise ValueError(f"reward: expected {expected}, {said}, got {reward!r}") from None
        if bounded and not low <= reward <= high:
            raise ValueError(f"reward: expected {expected}, {said}, got {reward!r}")
        return float(reward)

    return to_float


def _check_out(space: gymnasium.Space, out: Any, where: str = "out") -> None:
    """Checks that `out` holds one array per leaf of `space`, of its shape and dtype.

    Raises:
      ValueError: naming the part of `out` (`where`) that does not match.
    """
    if isinstance(space, gymnasium.spaces.Dict):
        if not isinstance(out, Mapping) or list(out) != list(space.spaces):
            keys = list(out) if isinstance(out, Mapping) else type(out).__name__
            raise ValueError(
                f"{where}: expected a dict with the keys {list(space.spaces)}, got {keys}"
            )
        for key, part in space.spaces.items():
            _check_out(part, out[key], f"{where}[{key!r}]")
        return
    problem = argument_checks.writeable_array_problem(out, space.shape, space.dtype)
    if problem is not None:
        raise ValueError(f"{where}: {problem}")


def _same_layout(observation_spec: Any, space: gymnasium.Space) -> bool:
    """Whether `space` (a Dict of Boxes) has `observation_spec`'s keys, shapes and dtypes."""
    if not isinstance(observation_spec, Mapping) or not isinstance(space, gymnasium.spaces.Dict):
        return False
    return set(observation_spec) == set(space.spaces) and all(
        space[name].shape == spec.shape and space[name].dtype == np.dtype(spec.dtype)
        for name, spec in observation_spec.items()
    )


def _window_title(env: dm_env.Environment) -> str:
    task = getattr(env, "task", None)
    return type(env).__name__ if task is None else f"{type(task).__name__} ({type(env).__name__})"


class GymnasiumEnv(gymnasium.Env):
    """Runs a `dm_env.Environment` through Gymnasium's `Env` API.

    Args:
      env: the environment to wrap; seeding needs its `random_state` (an
        `np.random.RandomState`, as `composer.Environment` has), rendering its `physics`.
      render_mode: None, 'human', 'rgb_array' or 'depth_array'. 'human' opens a window
        (`composer.viewer.PassiveWindow`; it needs a display, and GLFW, which comes with
        `mujoco`) at the first `reset` and redraws it after every `reset` and `step`, as
        fast as they come (no pacing to real time; `composer.viewer.launch` plays an
        environment in real time, with keys); `close()` closes it.
      camera: the camera `render()` draws, by name or index; -1 is the free camera (the
        'human' window always starts on the free camera).
      width, height: the size of rendered images in pixels (at most the model's
        off-screen buffer, `<visual><global offwidth offheight>`), or of the 'human'
        window in screen pixels.
      flatten_observations: concatenate every feature observation, in the observation
        spec's order and each flattened in C order, into one `Box`. Camera images (uint8
        with at least 3 axes) stay separate: with any, observations are a dict of the
        features (key 'features') and the images. For a `composer.Environment` the spec's
        order is the task's observables first, then each entity's in the order of
        `task.root_entity.iter_entities()` (the root first, then depth first), each
        entity's in the order of its `observables.as_dict()` (declared ones by name).

    Observable changes: `observation_space` is rebuilt at `reset` whenever the wrapped
    environment's observation spec changed (an observable enabled, disabled or given
    another buffer size since the last reset), so it always describes the observations
    `reset` and `step` return. Gymnasium wrappers that read `env.observation_space` follow
    it; vector environments (`ThreadedVectorEnv`, `RayVectorEnv`) fix their spaces when
    built, so change observables before building one.

    Raises:
      ValueError: for an unknown `render_mode`, a render mode for an environment
        without `physics`, or a reward spec that is not that of one number.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": list(_RENDER_MODES)}

    def __init__(
        self,
        env: dm_env.Environment,
        *,
        render_mode: str | None = None,
        camera: int | str = -1,
        width: int = 640,
        height: int = 480,
        flatten_observations: bool = False,
    ):
        if render_mode is not None and render_mode not in _RENDER_MODES:
            raise ValueError(
                f"render_mode: expected None or one of {_RENDER_MODES}, got {render_mode!r}"
            )
        if render_mode is not None and not hasattr(env, "physics"):
            raise ValueError(
                f"render_mode={render_mode!r}: the wrapped {type(env).__name__} has no "
                "`physics` to render"
            )
        self._env = env
        self.render_mode = render_mode
        self._window = None
        if render_mode == "human":
            from composer import viewer  # imports glfw: only for a window

            self._window = viewer.PassiveWindow(
                title=_window_title(env), width=width, height=height
            )
        self._camera = camera
        self._width = width
        self._height = height
        self.metadata = dict(self.metadata)
        if hasattr(env, "control_timestep"):
            self.metadata["render_fps"] = 1.0 / env.control_timestep()
        self._flatten = flatten_observations
        self._out = None
        self._write_out = None
        self._observation_signature = None
        self._follow_observation_spec()
        self.action_space = spec_spaces.box_from_spec(env.action_spec())
        self._reward = _reward_converter(env)
        self._episode_over = True

    @property
    def dm_env(self) -> dm_env.Environment:
        """The wrapped `dm_env.Environment`."""
        return self._env

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Starts a new episode and returns `(observation, info)`.

        Args:
          seed: reseeds the wrapped environment's random state (an int in [0, 2**32));
            None continues from where the previous episode left it.
          options: accepted for the Gymnasium API; no option is read.

        Raises:
          ValueError: for a seed given to an environment without a `random_state`, or a
            seed outside [0, 2**32).
        """
        super().reset(seed=seed)
        if seed is not None:
            random_state = getattr(self._env, "random_state", None)
            if not isinstance(random_state, np.random.RandomState):
                raise ValueError(
                    f"reset(seed={seed!r}): the wrapped {type(self._env).__name__} has no "
                    "`random_state` (np.random.RandomState) to seed"
                )
            random_state.seed(seed)
        timestep = self._env.reset()
        self._follow_observation_spec()
        self._episode_over = False
        self._show_in_window()
        return self._observation(timestep.observation), {}

    def step(self, action) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Applies `action` for one control step.

        Returns:
          observation, reward (a float), terminated and truncated (bools, as
          `composer.episode_end.episode_ends` says), and an info dict
          holding 'discount' and, when the episode ended and the task defines success,
          'is_success' (a bool: `task.get_success(physics)`).

        Raises:
          RuntimeError: if the episode is over (or never started) and `reset` was not
            called.
          ValueError: naming the reward, if it does not match the wrapped environment's
            `reward_spec()` (one number, within its bounds if it has any); naming
            `get_success`, if the task's returns something other than a bool or None.
        """
        if self._episode_over:
            raise RuntimeError(
                "step() called on an episode that is over or not started: call reset() first"
            )
        timestep = self._env.step(action)
        discount = timestep.discount
        info = {"discount": discount}
        terminated = truncated = False
        if timestep.last():
            self._episode_over = True
            terminated, truncated = (bool(end) for end in episode_ends(timestep.last(), discount))
            success = self._success()
            if success is not None:
                info["is_success"] = success
        self._show_in_window()
        return (
            self._observation(timestep.observation),
            self._reward(timestep.reward),
            terminated,
            truncated,
            info,
        )

    def write_observations_to(self, out: Any) -> None:
        """Makes `reset` and `step` copy their observations into `out` and return it.

        A vector env gives each sub-environment views of its row of the batched arrays,
        so that an observation is copied once, straight to where it is returned from.
        The arrays returned are then `out`'s, overwritten by the next `reset` or `step`.

        Args:
          out: arrays laid out as `observation_space` (a dict of them for a `Dict`, one
            for a `Box`), each writeable and of its leaf's shape and dtype; None to
            return new arrays again.

        Raises:
          ValueError: naming the part of `out` that does not match `observation_space`;
            also raised by the `reset` that changes `observation_space` (an observable
            was changed) so that `out` no longer matches.
        """
        if out is not None:
            _check_out(self.observation_space, out)
        self._out = out
        self._write_out = None if out is None or self._flat is not None else row_writer(out)
        # A composer.Environment writes its observations into `out` itself, which saves
        # copying them twice; its spec may still differ from the space in a dtype.
        wrapped_writes = getattr(self._env, "write_observations_to", None)
        if wrapped_writes is not None:
            forwarded = self._write_out is not None and _same_layout(
                self._env.observation_spec(), self.observation_space
            )
            wrapped_writes(out if forwarded else None)

    def render(self) -> np.ndarray | None:
        """Returns the camera's view in the render mode chosen at construction; None for
        no render mode, and for 'human' (which redraws the window now)."""
        if self.render_mode is None:
            return None
        if self._window is not None:
            self._window.handle_for(self._env.physics).sync()
            return None
        return self._env.physics.render(
            height=self._height,
            width=self._width,
            camera_id=self._camera,
            depth=self.render_mode == "depth_array",
        )

    def close(self) -> None:
        """Closes the 'human' window, if any, and the wrapped environment."""
        if self._window is not None:
            self._window.close()
        self._env.close()

    def _success(self) -> bool | None:
        """The task's `get_success(physics)`, or None for an environment without one."""
        task = getattr(self._env, "task", None)
        get_success = getattr(task, "get_success", None)
        if get_success is None:
            return None
        success = get_success(self._env.physics)
        if success is None:
            return None
        if isinstance(success, bool | np.bool_):
            return bool(success)
        raise ValueError(
            f"{type(task).__name__}.get_success: expected True, False or None, got {success!r}"
        )

    def _show_in_window(self) -> None:
        if self._window is not None:
            self.render()

    def _follow_observation_spec(self) -> None:
        """Rebuilds `observation_space` if the wrapped environment's observation spec changed."""
        observation_spec = self._env.observation_spec()
        signature = _spec_signature(observation_spec)
        if signature == self._observation_signature:
            return
        self._observation_signature = signature
        if self._flatten:
            self._flat = spec_spaces.FlatObservations(observation_spec)
            self.observation_space = self._flat.space
        else:
            self._flat = None
            self.observation_space = spec_spaces.space_from_spec(observation_spec)
        if self._out is not None:
            self.write_observations_to(self._out)

    def _observation(self, observation):
        if self._flat is not None:
            return self._flat(observation, out=self._out)
        if self._out is None or observation is self._out:  # already written there
            return observation
        self._write_out(observation)
        return self._out
