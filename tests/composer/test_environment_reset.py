"""composer.Environment resets: recompiling only when needed, retries, fixed initial states."""

import logging

import numpy as np
import pytest
from composer_scene import ReachTask, assert_same_episodes, play_episodes

import composer


class HeavierEveryStep(ReachTask):
    """Writes into the compiled model during episodes, as a physics variator would.

    Each episode it scales the box's mass and the arm's damping by random factors, so
    a model that is not restored between episodes drifts further every episode.
    """

    def initialize_episode(self, physics, random_state):
        super().initialize_episode(physics, random_state)
        physics.bind(self.box.geom).rgba = random_state.uniform(size=4)

    def after_step(self, physics, random_state):
        physics.bind(self.box.root_body).mass *= random_state.uniform(1.0, 1.5)
        physics.bind(self.arm.joints).damping *= 1.1


class RecompilingTask(HeavierEveryStep):
    """The same task, but a site is added before every episode, so every compile is real.

    Sites do not affect the dynamics, and a model with more sites has a different
    structure, so each episode gets a freshly compiled Physics.
    """

    def initialize_episode_mjcf(self, random_state):
        count = len(self.arena.mjcf_model.worldbody.get_children("site"))
        self.arena.mjcf_model.worldbody.add("site", name=f"marker_{count}")


class ResizingTask(HeavierEveryStep):
    """Changes the box's MJCF size before every episode (a parameter-only change)."""

    def initialize_episode_mjcf(self, random_state):
        self.box.geom.size = [random_state.uniform(0.03, 0.06)] * 3


class ResizingRecompilingTask(RecompilingTask):
    """The resizing task, with the structural change that forces fresh compiles."""

    def initialize_episode_mjcf(self, random_state):
        super().initialize_episode_mjcf(random_state)
        self.box.geom.size = [random_state.uniform(0.03, 0.06)] * 3


class FailsToInitialize(ReachTask):
    """Raises EpisodeInitializationError on the first `failures` initialisations."""

    def __init__(self, failures):
        super().__init__()
        self.failures = failures
        self.attempts = 0

    def initialize_episode(self, physics, random_state):
        self.attempts += 1
        if self.attempts <= self.failures:
            raise composer.EpisodeInitializationError(f"attempt {self.attempts} failed")
        super().initialize_episode(physics, random_state)


def test_reset_without_mjcf_change_matches_a_real_recompile_exactly():
    fast_env = composer.Environment(HeavierEveryStep(), random_state=5)
    recompiling_env = composer.Environment(RecompilingTask(), random_state=5)
    fast = play_episodes(fast_env, 3, 8, seed=99)
    recompiled = play_episodes(recompiling_env, 3, 8, seed=99)
    assert_same_episodes(fast, recompiled)


def test_parameter_only_mjcf_change_matches_a_real_recompile_exactly():
    in_place_env = composer.Environment(ResizingTask(), random_state=5)
    recompiling_env = composer.Environment(ResizingRecompilingTask(), random_state=5)
    in_place = play_episodes(in_place_env, 3, 8, seed=99)
    assert_same_episodes(in_place, play_episodes(recompiling_env, 3, 8, seed=99))


def test_parameter_only_mjcf_change_keeps_the_physics():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    physics = env.physics
    task.box.geom.size = [0.1, 0.1, 0.1]
    env.reset()
    assert env.physics == physics
    np.testing.assert_array_equal(physics.bind(task.box.geom).size, [0.1, 0.1, 0.1])


def test_structural_mjcf_change_gives_a_new_physics():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    physics = env.physics
    task.arena.mjcf_model.worldbody.add("site", name="new_site")
    env.reset()
    assert env.physics.model.nsite == 2
    with pytest.raises(ReferenceError):
        physics.time()


def test_reset_without_mjcf_change_keeps_the_physics_and_its_bindings():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    physics = env.physics
    binding = env.physics.bind(task.box.geom)
    binding.rgba = [1, 0, 0, 1]
    env.reset()
    assert env.physics == physics
    np.testing.assert_array_equal(binding.rgba, [0.5, 0.5, 0.5, 1])


def test_reset_after_mjcf_change_compiles_the_change():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    task.box.geom.size = [0.1, 0.1, 0.1]
    env.reset()
    np.testing.assert_array_equal(env.physics.bind(task.box.geom).size, [0.1, 0.1, 0.1])


def test_initialize_episode_mjcf_changes_are_compiled_before_the_episode():
    class GrowingBox(ReachTask):
        def initialize_episode_mjcf(self, random_state):
            self.box.geom.size = self.box.geom.size * 2

    task = GrowingBox()
    env = composer.Environment(task)
    env.reset()
    np.testing.assert_allclose(env.physics.bind(task.box.geom).size, [0.1, 0.1, 0.1])
    env.reset()
    np.testing.assert_allclose(env.physics.bind(task.box.geom).size, [0.2, 0.2, 0.2])


def test_in_place_mjcf_writes_in_initialize_episode_mjcf_are_compiled():
    # dm_control's Duplo randomises its stud radius this way every episode.
    class WidensBoxInPlace(ReachTask):
        def initialize_episode_mjcf(self, random_state):
            self.box.geom.size[0] += 0.05

    task = WidensBoxInPlace()
    env = composer.Environment(task)
    env.reset()
    np.testing.assert_allclose(env.physics.bind(task.box.geom).size, [0.1, 0.05, 0.05])
    env.reset()
    np.testing.assert_allclose(env.physics.bind(task.box.geom).size, [0.15, 0.05, 0.05])


def test_without_recompiling_every_episode_model_writes_persist_and_mjcf_hooks_run_once():
    class CountsMjcfHooks(ReachTask):
        mjcf_hook_calls = 0

        def initialize_episode_mjcf(self, random_state):
            self.mjcf_hook_calls += 1

    task = CountsMjcfHooks()
    env = composer.Environment(task, recompile_mjcf_every_episode=False)
    env.reset()
    env.physics.bind(task.box.geom).rgba = [1, 0, 0, 1]
    env.reset()
    np.testing.assert_array_equal(env.physics.bind(task.box.geom).rgba, [1, 0, 0, 1])
    assert task.mjcf_hook_calls == 1


def test_without_recompiling_every_episode_a_late_after_compile_hook_runs_at_first_reset():
    calls = []
    env = composer.Environment(ReachTask(), recompile_mjcf_every_episode=False)
    env.add_extra_hook("after_compile", lambda physics, random_state: calls.append(1))
    env.reset()
    assert len(calls) == 1
    for _ in range(3):
        env.reset()
        env.step(np.zeros(env.action_spec().shape))
    assert len(calls) == 1


def test_fixed_initial_state_starts_every_episode_identically():
    env = composer.Environment(HeavierEveryStep(), random_state=1, fixed_initial_state=True)
    first = play_episodes(env, 1, 8, seed=99)
    second = play_episodes(env, 1, 8, seed=99)
    assert_same_episodes(first, second)


def test_without_fixed_initial_state_episodes_start_differently():
    env = composer.Environment(ReachTask(), random_state=1)
    first = env.reset().observation["box/position"]
    second = env.reset().observation["box/position"]
    assert not np.array_equal(first, second)


def test_reset_retries_after_episode_initialization_error_logging_warnings(caplog):
    # Retries were asked for with max_reset_attempts, so a failed attempt is a warning,
    # not an error.
    task = FailsToInitialize(failures=2)
    env = composer.Environment(task, max_reset_attempts=3)
    with caplog.at_level(logging.INFO):
        assert env.reset().first()
    assert task.attempts == 3
    assert [(r.levelno, r.getMessage()) for r in caplog.records] == [
        (
            logging.WARNING,
            "Episode initialization failed (attempt 1 of 3), retrying: "
            "EpisodeInitializationError('attempt 1 failed')",
        ),
        (
            logging.WARNING,
            "Episode initialization failed (attempt 2 of 3), retrying: "
            "EpisodeInitializationError('attempt 2 failed')",
        ),
    ]


def test_reset_raises_once_attempts_are_used_up():
    task = FailsToInitialize(failures=2)
    env = composer.Environment(task, max_reset_attempts=2)
    with pytest.raises(composer.EpisodeInitializationError, match="attempt 2 failed"):
        env.reset()


def test_other_errors_during_reset_are_not_retried():
    class Broken(ReachTask):
        attempts = 0

        def initialize_episode(self, physics, random_state):
            self.attempts += 1
            raise KeyError("broken")

    task = Broken()
    env = composer.Environment(task, max_reset_attempts=5)
    with pytest.raises(KeyError):
        env.reset()
    assert task.attempts == 1


def test_observable_enabled_between_episodes_is_observed_from_the_next_reset():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    task.box.observables.orientation.enabled = True
    observation = env.reset().observation
    assert "box/orientation" in observation
    assert "box/orientation" in env.observation_spec()


def test_control_timestep_changed_between_episodes_applies_from_the_next_reset():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    task.control_timestep = 0.006
    env.reset()
    env.step(np.zeros(2))
    assert env.physics.time() == pytest.approx(0.006)


def test_task_hook_replaced_between_episodes_runs_from_the_next_reset():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()

    def put_box_at_fixed_spot(physics, random_state):
        task.box.set_pose(physics, position=[0.7, 0.1, 0.05])

    task.initialize_episode = put_box_at_fixed_spot
    np.testing.assert_allclose(env.reset().observation["box/position"], [[0.7, 0.1, 0.05]])


def test_entity_hook_replaced_between_episodes_runs_from_the_next_reset():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    calls = []
    task.box.after_step = lambda physics, random_state: calls.append(physics.data.time)
    env.reset()
    env.step(np.zeros(env.action_spec().shape))
    assert calls == [pytest.approx(0.02)]
