"""Finds the lifecycle hooks a task and its entities implement, and calls only those."""

import functools
import operator
from collections.abc import Callable

from composer.entity import Entity
from composer.task import Task

HOOK_NAMES = (
    "initialize_episode_mjcf",
    "after_compile",
    "initialize_episode",
    "before_step",
    "before_substep",
    "after_substep",
    "after_step",
)

# The base classes' hooks that do nothing. `Task.before_step` sets the controls, so it counts.
_BASE_NO_OPS = frozenset(
    [getattr(Entity, name) for name in HOOK_NAMES]
    + [getattr(Task, name) for name in HOOK_NAMES if name != "before_step"]
)
_SETS_CONTROLS = Task.before_step
# An object's hooks, looked up as the environment would call them, in `HOOK_NAMES` order.
_LOOK_UP_HOOKS = operator.attrgetter(*HOOK_NAMES)


def _empty():
    pass


def _empty_with_docstring():
    """A docstring."""


_EMPTY_BYTECODES = frozenset((_empty.__code__.co_code, _empty_with_docstring.__code__.co_code))


def _does_nothing(hook) -> bool:
    """Whether calling `hook` can have no effect: a base no-op or an empty Python function."""
    function = getattr(hook, "__func__", hook)
    if function in _BASE_NO_OPS:
        return True
    code = getattr(function, "__code__", None)
    return code is not None and code.co_code in _EMPTY_BYTECODES


class _Chain:
    """The hooks of one name that do something, in call order."""

    __slots__ = ("task", "entities", "extra", "all")

    def __init__(self, task: tuple, entities: tuple, extra: tuple):
        self.task = task
        self.entities = entities
        self.extra = extra
        self.all = task + entities + extra


class EnvironmentHooks:
    """The hooks an environment calls, memoised per episode.

    For each hook name the task's hook runs first, then each entity's (depth first
    through the entity tree), then the extra hooks in the order they were added.
    Hooks that do nothing (the base classes' defaults, or empty functions) are left
    out. `refresh_entity_hooks` brings the chains up to date with the task and the entity
    tree; the environment calls it at every reset and compile, so hooks replaced between
    episodes (on an object or its class) and entities attached or detached are used.
    Task and extra hooks receive the action where entity hooks do not: `before_step`
    and `before_substep` are called as `task_or_extra_hook(physics, action,
    random_state)` and `entity_hook(physics, random_state)`.

    When the task keeps `Task.before_step`, which only writes the action into the
    controls, `task_sets_controls` is True and `before_step` leaves that hook out: the
    caller writes the controls itself, before calling `before_step` (when
    `has_before_step_hooks`).
    """

    __slots__ = (
        "_task",
        "_extra_hooks",
        "_chains",
        "_scanned",
        "has_substep_hooks",
        "has_after_compile_hooks",
        "has_before_step_hooks",
        "has_after_step_hooks",
        "task_sets_controls",
    )

    def __init__(self, task):
        self._task = task
        self._extra_hooks = {name: () for name in HOOK_NAMES}
        self._chains = {}
        self._scanned = None
        self.refresh_entity_hooks()

    def refresh_entity_hooks(self) -> None:
        """Rescans the task and its entity tree for hooks that do something, unless every
        object's hooks are the very ones of the last scan (then the chains are up to date)."""
        entities = (*self._task.root_entity.iter_entities(),)
        # Bound methods compare equal when they bind the same function to the same object.
        scanned = (*map(_LOOK_UP_HOOKS, (self._task, *entities)),)
        if scanned == self._scanned:
            return
        self._scanned = scanned
        task_before_step = self._task.before_step
        self.task_sets_controls = getattr(task_before_step, "__func__", None) is _SETS_CONTROLS
        for name in HOOK_NAMES:
            task_hook = getattr(self._task, name)
            leave_out = name == "before_step" and self.task_sets_controls
            task_hooks = () if leave_out or _does_nothing(task_hook) else (task_hook,)
            hooks = (getattr(entity, name) for entity in entities)
            entity_hooks = tuple(hook for hook in hooks if not _does_nothing(hook))
            self._chains[name] = _Chain(task_hooks, entity_hooks, self._extra_hooks[name])
        self._update_flags()

    def add_extra_hook(self, hook_name: str, hook_callable: Callable) -> None:
        """Adds a callable to run after the task's and entities' `hook_name` hooks.

        Raises:
          ValueError: if `hook_name` is not in `HOOK_NAMES` or `hook_callable` is not callable.
        """
        if hook_name not in HOOK_NAMES:
            raise ValueError(
                f"hook_name: {hook_name!r} is not a hook; valid names are {', '.join(HOOK_NAMES)}"
            )
        if not callable(hook_callable):
            raise ValueError(f"hook_callable: expected a callable, got {hook_callable!r}")
        self._extra_hooks[hook_name] += (hook_callable,)
        chain = self._chains[hook_name]
        self._chains[hook_name] = _Chain(chain.task, chain.entities, self._extra_hooks[hook_name])
        self._update_flags()

    def _update_flags(self) -> None:
        chains = self._chains
        self.has_substep_hooks = bool(chains["before_substep"].all or chains["after_substep"].all)
        self.has_after_compile_hooks = bool(chains["after_compile"].all)
        self.has_before_step_hooks = bool(chains["before_step"].all)
        self.has_after_step_hooks = bool(chains["after_step"].all)

    def _call_with_action(self, name: str, physics, action, random_state) -> None:
        chain = self._chains[name]
        for hook in chain.task:
            hook(physics, action, random_state)
        for hook in chain.entities:
            hook(physics, random_state)
        for hook in chain.extra:
            hook(physics, action, random_state)

    def initialize_episode_mjcf(self, random_state) -> None:
        for hook in self._chains["initialize_episode_mjcf"].all:
            hook(random_state)

    def after_compile(self, physics, random_state) -> None:
        for hook in self._chains["after_compile"].all:
            hook(physics, random_state)

    def initialize_episode(self, physics, random_state) -> None:
        for hook in self._chains["initialize_episode"].all:
            hook(physics, random_state)

    def before_step(self, physics, action, random_state) -> None:
        self._call_with_action("before_step", physics, action, random_state)

    def substep_calls(self, physics, action, random_state) -> tuple[tuple, tuple]:
        """The `before_substep` and `after_substep` hooks with their arguments bound.

        Returns (before, after): zero-argument callables, in call order, so that a control
        step binds the arguments once instead of at every sub-step.
        """
        chain = self._chains["before_substep"]
        before = (
            *(functools.partial(hook, physics, action, random_state) for hook in chain.task),
            *(functools.partial(hook, physics, random_state) for hook in chain.entities),
            *(functools.partial(hook, physics, action, random_state) for hook in chain.extra),
        )
        after = tuple(
            functools.partial(hook, physics, random_state)
            for hook in self._chains["after_substep"].all
        )
        return before, after

    def after_step(self, physics, random_state) -> None:
        for hook in self._chains["after_step"].all:
            hook(physics, random_state)
