"""What a batch cannot run, refused by name before anything is compiled.

A batch steps its sub-steps on the device without Python between them, and compiles its
model once: CPU hooks that need either are refused with the owner and hook named.
"""

import composer
from composer.batch.task import BatchTask
from composer.hooks import EnvironmentHooks

__all__ = ["refuse_mjcf_variations", "refuse_unbatched_hooks"]


def _hook_owners(task: composer.Task, names: tuple[str, ...]) -> list[str]:
    """'Owner.hook' for each of `names` that the task or an entity overrides."""
    found = []
    for owner in (task, *task.root_entity.iter_entities()):
        base = composer.Task if isinstance(owner, composer.Task) else composer.Entity
        for name in names:
            if getattr(type(owner), name) is not getattr(base, name):
                found.append(f"{type(owner).__name__}.{name}")
    return found


def refuse_unbatched_hooks(hooks: EnvironmentHooks, batch_task: BatchTask) -> None:
    """Raises NotImplementedError for CPU hooks that a batch would otherwise skip."""
    task = batch_task.task
    if hooks.has_substep_hooks or hooks.has_after_step_hooks:
        owners = _hook_owners(task, ("before_substep", "after_substep", "after_step"))
        raise NotImplementedError(
            f"{', '.join(owners)}: a batch steps its sub-steps on the device, without Python "
            "hooks between them (before_substep, after_substep and after_step are not run)"
        )
    if hooks.has_before_step_hooks and type(batch_task).before_step is BatchTask.before_step:
        owners = _hook_owners(task, ("before_step",))
        raise NotImplementedError(
            f"{', '.join(owners)} does more than set the controls; "
            f"{type(batch_task).__name__} must override before_step to do it for every world"
        )


def refuse_mjcf_variations(task: composer.Task) -> None:
    """Raises NotImplementedError if the task or an entity changes its MJCF per episode."""
    owners = [task, *task.root_entity.iter_entities()]
    base_hooks = (composer.Task.initialize_episode_mjcf, composer.Entity.initialize_episode_mjcf)
    for owner in owners:
        hook = getattr(type(owner), "initialize_episode_mjcf", None)
        if hook is not None and hook not in base_hooks:
            raise NotImplementedError(
                f"{type(owner).__name__}.initialize_episode_mjcf changes the MJCF model per "
                "episode, which needs a recompile; a batch compiles once (put per-world "
                "physics variation in batched_model_fields instead)"
            )
