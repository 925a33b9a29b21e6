"""The manipulation suite: a Jaco-style arm and hand, props and 26 tasks on a table (the 25
of dm_control's suite and `lift_brick_randomised_features`, whose brick varies per episode).

`load(name, seed)` builds the environment called `name` (one of `ALL`) as a
`composer.Environment`: control steps of 0.04 s (20 physics steps of 0.002 s), 10 s
episodes, a 9-D action (six arm joint velocities, then three finger velocities).
"""

import composer
from manipulation import _gymnasium_hook
from manipulation.tasks import registry
from manipulation.tasks import task_constants as _task_constants

ALL = registry.names()
TAGS = registry.tags()


def get_environments_by_tag(tag: str) -> tuple[str, ...]:
    """Returns the names of the environments tagged `tag` (one of `TAGS`).

    Raises:
      ValueError: if `tag` is not one of `TAGS`.
    """
    return registry.names_with_tag(tag)


def load(
    environment_name: str, seed=None, *, strip_singleton_obs_buffer_dim: bool = False
) -> composer.Environment:
    """Returns the environment `environment_name`, seeded with `seed`.

    Args:
      environment_name: one of `ALL`, e.g. 'reach_site_features'.
      seed: an int, a `np.random.RandomState`, or None for a random seed; it drives every
        random choice of the episodes (initial arm pose, prop placement, targets).
      strip_singleton_obs_buffer_dim: as in `composer.Environment`: True drops the leading
        buffer axis of the observations, (1, 3) -> (3,); False (dm_control's) keeps it.
        The Gymnasium ids (`composer/<name>-v0`) drop it.

    Raises:
      ValueError: if the name is not one of `ALL`; the message suggests close names.
    """
    task = registry.build_task(environment_name)
    return composer.Environment(
        task,
        time_limit=_task_constants.TIME_LIMIT,
        random_state=seed,
        strip_singleton_obs_buffer_dim=strip_singleton_obs_buffer_dim,
    )


_gymnasium_hook.register_when_gymnasium_is_imported()
