"""Lifecycle hooks: order, arguments, memoisation and extra hooks."""

import numpy as np
import pytest
from composer_scene import Box, ReachTask

import composer
from composer.hooks import EnvironmentHooks


class LoggingBox(Box):
    """A box that logs every hook call into `self.log` as (name, hook, argument count)."""

    def _build(self, log, name="box"):
        super()._build(name=name)
        self.log = log

    def initialize_episode_mjcf(self, random_state):
        self.log.append((self.mjcf_model.model, "initialize_episode_mjcf"))

    def after_compile(self, physics, random_state):
        self.log.append((self.mjcf_model.model, "after_compile"))

    def initialize_episode(self, physics, random_state):
        self.log.append((self.mjcf_model.model, "initialize_episode"))

    def before_step(self, physics, random_state):
        self.log.append((self.mjcf_model.model, "before_step"))

    def before_substep(self, physics, random_state):
        self.log.append((self.mjcf_model.model, "before_substep"))

    def after_substep(self, physics, random_state):
        self.log.append((self.mjcf_model.model, "after_substep"))

    def after_step(self, physics, random_state):
        self.log.append((self.mjcf_model.model, "after_step"))


class LoggingTask(ReachTask):
    """The reach task plus two logging boxes (one nested in the other) and 2 sub-steps."""

    def __init__(self):
        super().__init__()
        self.log = []
        self.outer = LoggingBox(self.log, name="outer")
        self.inner = LoggingBox(self.log, name="inner")
        self.arena.add_free_entity(self.outer)
        self.outer.attach(self.inner)
        self.set_timesteps(control_timestep=0.004, physics_timestep=0.002)

    def initialize_episode_mjcf(self, random_state):
        self.log.append(("task", "initialize_episode_mjcf"))

    def after_compile(self, physics, random_state):
        self.log.append(("task", "after_compile"))

    def initialize_episode(self, physics, random_state):
        self.log.append(("task", "initialize_episode"))

    def before_step(self, physics, action, random_state):
        super().before_step(physics, action, random_state)
        self.log.append(("task", "before_step"))

    def before_substep(self, physics, action, random_state):
        self.log.append(("task", "before_substep"))

    def after_substep(self, physics, random_state):
        self.log.append(("task", "after_substep"))

    def after_step(self, physics, random_state):
        self.log.append(("task", "after_step"))


def _sources(log, hook):
    return [source for source, name in log if name == hook]


def test_hook_names_list_every_lifecycle_hook_in_call_order():
    assert composer.HOOK_NAMES == (
        "initialize_episode_mjcf",
        "after_compile",
        "initialize_episode",
        "before_step",
        "before_substep",
        "after_substep",
        "after_step",
    )


def test_each_hook_runs_task_then_entities_depth_first_then_extra_hooks():
    task = LoggingTask()
    env = composer.Environment(task)
    for name in composer.HOOK_NAMES:
        env.add_extra_hook(name, lambda *args, name=name: task.log.append(("extra", name)))
    env.reset()
    task.log.clear()
    env.reset()
    env.step(np.zeros(2))
    for name in composer.HOOK_NAMES:
        per_call = 2 if name in ("before_substep", "after_substep") else 1
        assert _sources(task.log, name) == ["task", "outer", "inner", "extra"] * per_call, name


def test_reset_calls_mjcf_then_compile_then_episode_hooks():
    task = LoggingTask()
    env = composer.Environment(task)
    task.log.clear()
    env.reset()
    names = [name for source, name in task.log if source == "task"]
    assert names == ["initialize_episode_mjcf", "after_compile", "initialize_episode"]


def test_step_calls_substep_hooks_around_every_physics_step():
    task = LoggingTask()
    env = composer.Environment(task)
    env.reset()
    times = []
    env.add_extra_hook("before_substep", lambda physics, action, rs: times.append(physics.time()))
    env.add_extra_hook("after_substep", lambda physics, rs: times.append(physics.time()))
    env.step(np.zeros(2))
    np.testing.assert_allclose(times, [0.0, 0.002, 0.002, 0.004])


def test_task_and_extra_hooks_receive_the_action_and_entity_hooks_do_not():
    received = []

    class Recorder(Box):
        def before_step(self, physics, random_state):
            received.append(("entity", random_state))

    task = ReachTask()
    task.arena.add_free_entity(Recorder(name="recorder"))
    env = composer.Environment(task, random_state=3)
    env.add_extra_hook(
        "before_step", lambda physics, action, rs: received.append(("extra", action))
    )
    env.reset()
    env.step([0.5, -0.5])
    assert received[0] == ("entity", env.random_state)
    assert received[1][0] == "extra"
    np.testing.assert_array_equal(received[1][1], [0.5, -0.5])


def test_entity_before_step_hooks_see_the_action_in_the_controls():
    seen = []

    class Recorder(Box):
        def before_step(self, physics, random_state):
            seen.append(physics.data.ctrl.copy())

    task = ReachTask()
    task.arena.add_free_entity(Recorder(name="recorder"))
    env = composer.Environment(task)
    env.reset()
    env.step([0.5, -0.25])
    np.testing.assert_array_equal(seen, [[0.5, -0.25]])


def test_task_before_step_override_sets_the_controls_instead_of_the_action():
    class Halving(ReachTask):
        def before_step(self, physics, action, random_state):
            physics.set_control(0.5 * np.asarray(action))

    env = composer.Environment(Halving())
    env.reset()
    env.step([0.5, -0.25])
    np.testing.assert_array_equal(env.physics.data.ctrl, [0.25, -0.125])


def test_entities_without_overrides_contribute_no_hooks():
    task = ReachTask()
    hooks = EnvironmentHooks(task)
    assert not hooks.has_substep_hooks
    task.arena.add_free_entity(LoggingBox([], name="logger"))
    hooks.refresh_entity_hooks()
    assert hooks.has_substep_hooks


def test_empty_overrides_count_as_no_hook():
    class Quiet(Box):
        def before_substep(self, physics, random_state):
            pass

        def after_substep(self, physics, random_state):
            """Does nothing."""

    task = ReachTask()
    task.arena.add_free_entity(Quiet(name="quiet"))
    assert not EnvironmentHooks(task).has_substep_hooks


def test_extra_substep_hook_switches_on_substep_hooks():
    hooks = EnvironmentHooks(ReachTask())
    hooks.add_extra_hook("after_substep", lambda physics, random_state: print("stepped"))
    assert hooks.has_substep_hooks


def test_entity_tree_is_scanned_once_per_compile():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    calls = []
    task.box.after_step = lambda physics, random_state: calls.append("after_step")
    env.step(np.zeros(2))
    assert calls == []
    task.box.geom.rgba = [1, 0, 0, 1]
    env.reset()
    env.step(np.zeros(2))
    assert calls == ["after_step"]


def test_add_extra_hook_with_unknown_name_lists_valid_names():
    env = composer.Environment(ReachTask())
    with pytest.raises(ValueError, match="'after_reset'.*initialize_episode_mjcf.*after_step"):
        env.add_extra_hook("after_reset", lambda *args: None)


def test_add_extra_hook_rejects_non_callable():
    env = composer.Environment(ReachTask())
    with pytest.raises(ValueError, match="callable"):
        env.add_extra_hook("after_step", 3)
