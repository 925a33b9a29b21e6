"""What a batch cannot run, refused by name before anything is compiled.

A batch steps its sub-steps on the device without Python between them, and runs the CPU
task's episode hooks only on the producers of its initial states: CPU hooks that need
Python between sub-steps, or a producer where there is none, are refused with the owner and
hook named. (MJCF variations are checked attribute by attribute in
`composer.batch.variations`.)
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


def refuse_mjcf_variations(batch_task: BatchTask) -> None:
    """Raises NotImplementedError if the task or an entity changes its MJCF per episode while
    `batch_task` sets initial states with array code, where no CPU hook runs."""
    task = batch_task.task
    owners = _hook_owners(task, ("initialize_episode_mjcf",))
    if owners:
        raise NotImplementedError(
            f"{', '.join(owners)} varies the MJCF model per episode, but "
            f"{type(batch_task).__name__} sets initial states with array code, where no CPU "
            "hook runs: a per-world variation runs on the producers of the CPU task's initial "
            "states (leave BatchTask.initialize_episode as it is)"
        )
