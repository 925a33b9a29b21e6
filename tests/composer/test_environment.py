"""composer.Environment: the dm_env loop, specs, time limits and action checking."""

import copy
import gc
import pickle
import warnings
from pathlib import Path

import dm_env
import numpy as np
import pytest
from composer_scene import Arm, ReachTask
from dm_env import specs

import composer
import mjcf
from composer import environment
from composer.observation import observable


class EndsWhenBoxIsHigh(ReachTask):
    """Terminates once the box is above 1 m."""

    def should_terminate_episode(self, physics):
        return physics.bind(self.box.root_body).xpos[2] > 1.0


class CustomSpecs(ReachTask):
    def get_reward_spec(self):
        return specs.Array(shape=(2,), dtype=np.float32, name="reward")

    def get_discount_spec(self):
        return specs.BoundedArray(shape=(), dtype=np.float32, minimum=0, maximum=1)


def test_reset_returns_first_timestep_with_enabled_observations():
    env = composer.Environment(ReachTask(), random_state=0)
    timestep = env.reset()
    assert timestep.step_type == dm_env.StepType.FIRST
    assert timestep.reward is None and timestep.discount is None
    assert list(timestep.observation) == ["arm/joint_positions", "arm/tip_position", "box/position"]


def test_step_returns_mid_with_the_tasks_reward_and_discount():
    task = ReachTask(discount=0.9)
    env = composer.Environment(task, random_state=0)
    env.reset()
    timestep = env.step(np.zeros(2))
    assert timestep.step_type == dm_env.StepType.MID
    assert timestep.reward == task.get_reward(env.physics)
    assert timestep.discount == 0.9


def test_observations_describe_the_physics_after_the_step():
    task = ReachTask()
    env = composer.Environment(task, random_state=0)
    env.reset()
    observation = env.step(np.array([1.0, -1.0])).observation
    np.testing.assert_array_equal(
        observation["arm/tip_position"][0], env.physics.bind(task.arm.tip).xpos
    )
    np.testing.assert_array_equal(
        observation["arm/joint_positions"][0], env.physics.bind(task.arm.joints).qpos
    )


def test_one_step_advances_physics_by_the_control_timestep():
    env = composer.Environment(ReachTask())
    env.reset()
    env.step(np.zeros(2))
    assert env.physics.time() == pytest.approx(0.02)
    assert env.control_timestep() == 0.02


def test_n_sub_steps_overrides_the_tasks_physics_steps_per_control_step():
    env = composer.Environment(ReachTask(), n_sub_steps=3)
    env.reset()
    env.step(np.zeros(2))
    assert env.physics.time() == pytest.approx(0.006)
    assert env.control_timestep() == pytest.approx(0.006)


def test_action_is_written_into_the_actuator_controls():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    env.step([0.5, -0.25])
    np.testing.assert_array_equal(env.physics.bind(task.arm.actuators).ctrl, [0.5, -0.25])


def test_step_before_first_reset_resets():
    env = composer.Environment(ReachTask())
    assert env.step(np.zeros(2)).step_type == dm_env.StepType.FIRST


# 0.09 s is four and a half 0.02 s steps: the fifth step ends the episode.
@pytest.mark.filterwarnings("ignore:time_limit=0.09 s is not a multiple")
def test_time_limit_ends_episode_with_the_tasks_discount():
    env = composer.Environment(ReachTask(discount=0.5), time_limit=0.09)
    env.reset()
    step_types = [env.step(np.zeros(2)) for _ in range(5)]
    assert [t.step_type for t in step_types] == [dm_env.StepType.MID] * 4 + [dm_env.StepType.LAST]
    assert step_types[-1].discount == 0.5
    assert env.physics.time() >= 0.09


def test_task_termination_ends_episode():
    task = EndsWhenBoxIsHigh()
    env = composer.Environment(task)
    env.reset()
    assert env.step(np.zeros(2)).step_type == dm_env.StepType.MID
    task.box.set_pose(env.physics, position=[0, 0, 3])
    assert env.step(np.zeros(2)).last()


@pytest.mark.filterwarnings("ignore:time_limit=0.015 s is not a multiple")
def test_step_after_last_starts_new_episode():
    env = composer.Environment(ReachTask(), time_limit=0.015)
    env.reset()
    assert env.step(np.zeros(2)).last()
    timestep = env.step(np.zeros(2))
    assert timestep.first()
    assert env.physics.time() == 0.0
    assert env.step(np.zeros(2)).last()


def test_action_spec_describes_the_actuators():
    env = composer.Environment(ReachTask())
    spec = env.action_spec()
    assert spec.shape == (2,)
    np.testing.assert_array_equal(spec.minimum, [-1, -1])
    assert spec.name == "arm/shoulder_motor\tarm/elbow_motor"


def test_observation_spec_matches_observations_before_and_after_reset():
    env = composer.Environment(ReachTask())
    spec = env.observation_spec()
    observation = env.reset().observation
    assert list(spec) == list(observation)
    for name, value in observation.items():
        spec[name].validate(value)
    assert spec["arm/tip_position"].shape == (1, 3)


def test_strip_singleton_obs_buffer_dim_removes_the_buffer_axis():
    env = composer.Environment(ReachTask(), strip_singleton_obs_buffer_dim=True)
    assert env.observation_spec()["arm/tip_position"].shape == (3,)
    assert env.reset().observation["arm/tip_position"].shape == (3,)


def test_reward_and_discount_specs_default_to_dm_env_scalars():
    env = composer.Environment(ReachTask())
    assert env.reward_spec() == specs.Array(shape=(), dtype=float, name="reward")
    assert env.discount_spec().maximum == 1.0


def test_reward_and_discount_specs_come_from_the_task_when_it_defines_them():
    env = composer.Environment(CustomSpecs())
    assert env.reward_spec().shape == (2,)
    assert env.discount_spec().dtype == np.float32


def test_deprecated_step_spec_bundles_task_specs_with_a_warning():
    env = composer.Environment(CustomSpecs())
    with pytest.warns(DeprecationWarning) as warned:
        spec = env.step_spec()
    assert [str(w.message) for w in warned] == [
        "Environment.step_spec is deprecated; use reward_spec() and discount_spec()"
    ]
    # The warning points at the caller, not at the library.
    assert warned[0].filename != environment.__file__
    assert spec.reward.shape == (2,)
    assert spec.discount.dtype == np.float32
    assert spec.observation == env.observation_spec()


def test_deprecated_step_spec_without_task_specs_is_not_implemented():
    env = composer.Environment(ReachTask())
    with pytest.warns(DeprecationWarning), pytest.raises(NotImplementedError) as raised:
        env.step_spec()
    assert str(raised.value) == "step_spec: the task ReachTask defines no reward spec"


def test_environment_physics_refuses_elements_of_another_model():
    # An arm built the same way but never attached: its names exist in the compiled model,
    # yet binding it would silently read the attached arm.
    env = composer.Environment(ReachTask())
    env.reset()
    stray = Arm()
    with pytest.raises(ValueError, match="belongs to another model"):
        env.physics.bind(stray.joints)


def test_physics_property_reads_and_writes_through_to_the_physics():
    env = composer.Environment(ReachTask())
    env.reset()
    physics = env.physics
    assert physics is env.physics
    assert isinstance(physics, mjcf.Physics)
    physics.legacy_step = False
    physics.bind(env.task.arm.joints).qpos = [0.3, -0.2]
    assert env.step(np.zeros(2)).mid()
    assert physics.data.time == pytest.approx(0.02)
    assert env.physics.legacy_step is False


class MarkedEveryEpisode(ReachTask):
    """Adds a site before every episode: a structural change, so each reset makes a new
    Physics."""

    def initialize_episode_mjcf(self, random_state):
        count = len(self.arena.mjcf_model.worldbody.get_children("site"))
        self.arena.mjcf_model.worldbody.add("site", name=f"marker_{count}")


def test_physics_of_a_garbage_collected_environment_says_to_keep_the_environment():
    physics = composer.Environment(ReachTask()).physics
    gc.collect()
    with pytest.raises(ReferenceError) as raised:
        physics.data.time  # noqa: B018
    assert str(raised.value) == (
        "env.physics was used after its composer.Environment was garbage-collected, which "
        "freed the Physics: keep a reference to the environment for as long as you use its "
        "physics (env = make_env() and then env.physics, not make_env().physics), or keep a "
        "copy made with env.physics.copy()"
    )


def test_physics_after_close_says_it_was_closed():
    env = composer.Environment(ReachTask())
    physics = env.physics
    env.close()
    with pytest.raises(ReferenceError) as raised:
        physics.bind(env.task.arm.joints)
    assert str(raised.value) == (
        "env.physics was used after env.close() freed the Physics: call env.reset() and "
        "read env.physics again"
    )


def test_physics_replaced_at_a_reset_says_to_read_it_again():
    env = composer.Environment(MarkedEveryEpisode())
    env.reset()
    physics = env.physics
    env.reset()
    with pytest.raises(ReferenceError) as raised:
        physics.legacy_step = False
    assert str(raised.value) == (
        "env.physics was used after the environment replaced its Physics (at a reset that "
        "recompiled a changed model structure, or the first reset after close()): read "
        "env.physics again after each reset instead of keeping it"
    )
    assert env.physics.data.time == 0.0


def test_task_and_random_state_properties():
    task = ReachTask()
    random_state = np.random.RandomState(4)
    env = composer.Environment(task, random_state=random_state)
    assert env.task is task
    assert env.random_state is random_state


def test_integer_seed_makes_episodes_reproducible():
    first = composer.Environment(ReachTask(), random_state=7).reset().observation
    second = composer.Environment(ReachTask(), random_state=7).reset().observation
    np.testing.assert_array_equal(first["box/position"], second["box/position"])


@pytest.mark.parametrize(
    ("action", "got"),
    [
        (np.zeros(3), r"shape \(3,\)"),
        (np.zeros((1, 2)), r"shape \(1, 2\)"),
        ([np.nan, 0.0], "non-finite"),
        ([np.inf, 0.0], "non-finite"),
        (["left", "right"], "cannot be cast"),
    ],
)
def test_bad_action_is_rejected_naming_the_spec_before_stepping(action, got):
    env = composer.Environment(ReachTask())
    env.reset()
    with pytest.raises(ValueError, match=got) as error:
        env.step(action)
    message = str(error.value)
    assert "expected shape (2,)" in message
    assert "arm/shoulder_motor, arm/elbow_motor" in message
    assert "[-1. -1.]" in message
    assert env.physics.time() == 0.0


def test_huge_but_finite_action_is_accepted():
    env = composer.Environment(ReachTask())
    env.reset()
    assert env.step(np.full(2, 1e200)).mid()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_reset_attempts": 0}, "max_reset_attempts: expected an integer >= 1, got 0"),
        ({"n_sub_steps": 2.5}, "n_sub_steps: expected an integer >= 1, got 2.5"),
        ({"time_limit": -1.0}, "time_limit: expected a number of seconds >= 0, got -1.0"),
        ({"time_limit": "10"}, "time_limit: expected a number of seconds >= 0, got '10'"),
        ({"time_limit": float("nan")}, "time_limit: expected a number of seconds >= 0, got nan"),
        (
            {"delayed_observation_padding": 0},
            "delayed_observation_padding: expected ObservationPadding.ZERO or "
            "ObservationPadding.INITIAL_VALUE, got 0",
        ),
    ],
)
def test_bad_constructor_arguments_are_named(kwargs, message):
    with pytest.raises(ValueError) as raised:
        composer.Environment(ReachTask(), **kwargs)
    assert str(raised.value) == message


def test_defaults_are_dm_controls():
    # One reset attempt, legacy stepping, no time limit.
    class FailsOnce(ReachTask):
        failed = False

        def initialize_episode(self, physics, random_state):
            if not self.failed:
                self.failed = True
                raise composer.EpisodeInitializationError("first attempt")
            super().initialize_episode(physics, random_state)

    env = composer.Environment(FailsOnce())
    assert env.physics.legacy_step is True
    with pytest.raises(composer.EpisodeInitializationError):
        env.reset()
    env.reset()
    for _ in range(200):
        assert env.step(np.zeros(2)).mid()


def _every_40ms(time_limit):
    """A ReachTask environment acting every 0.04 s with `time_limit`."""
    task = ReachTask()
    task.set_timesteps(control_timestep=0.04, physics_timestep=0.002)
    return composer.Environment(task, time_limit=time_limit)


def test_a_time_limit_between_two_steps_warns_naming_both_and_ends_at_the_later_step():
    with pytest.warns(UserWarning) as record:
        env = _every_40ms(0.05)
    assert [str(warning.message) for warning in record] == [
        "time_limit=0.05 s is not a multiple of the control timestep 0.04 s: an episode "
        "ends at the first step that reaches it, after 2 steps at t=0.08 s; use a multiple "
        "of the control timestep (0.04 s or 0.08 s) to end episodes at the time limit"
    ]
    env.reset()
    assert [env.step(np.zeros(2)).step_type for _ in range(2)] == [
        dm_env.StepType.MID,
        dm_env.StepType.LAST,
    ]
    assert env.physics.data.time == pytest.approx(0.08)


def test_the_time_limit_warning_points_at_the_line_that_built_the_environment():
    with pytest.warns(UserWarning) as record:
        _every_40ms(0.05)
    assert record[0].filename == __file__


def test_a_time_limit_just_past_one_step_names_one_step_and_its_single_multiple():
    with pytest.warns(UserWarning) as record:
        _every_40ms(0.03)
    assert str(record[0].message) == (
        "time_limit=0.03 s is not a multiple of the control timestep 0.04 s: an episode "
        "ends at the first step that reaches it, after 1 step at t=0.04 s; use a multiple "
        "of the control timestep (0.04 s) to end episodes at the time limit"
    )


def test_under_the_dm_control_redirect_a_time_limit_between_steps_says_nothing(fresh_python):
    # As dm_control, whose locomotion examples end 25 s episodes acting every 0.03 s
    # (cmu_humanoid_heterogeneous_forage): they build without a warning, and an episode
    # still ends at the first step that reaches the limit.
    result = fresh_python(
        f"""
        import sys, warnings
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from composer import dm_control_compat
        dm_control_compat.install()
        warnings.simplefilter("error")
        from dm_control import composer
        from composer_scene import ReachTask
        task = ReachTask()
        task.set_timesteps(control_timestep=0.03, physics_timestep=0.005)
        env = composer.Environment(task, time_limit=25)
        env.reset()
        steps = 1
        while not env.step([0, 0]).last():
            steps += 1
        print(steps, round(env.physics.data.time, 6))
        """
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["834", "25.02"]


def test_the_time_limit_warning_is_given_once_per_environment():
    with pytest.warns(UserWarning):
        env = _every_40ms(0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for _ in range(3):
            env.reset()
            env.step(np.zeros(2))
            env.step(np.zeros(2))


def test_a_time_limit_shorter_than_one_step_suggests_the_one_step_limit():
    with pytest.warns(UserWarning) as record:
        _every_40ms(0.01)
    assert str(record[0].message) == (
        "time_limit=0.01 s is not a multiple of the control timestep 0.04 s: an episode "
        "ends at the first step that reaches it, after 1 step at t=0.04 s; use a multiple "
        "of the control timestep (0.04 s) to end episodes at the time limit"
    )


def test_the_time_limit_is_checked_again_when_the_control_timestep_changes():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = _every_40ms(0.08)
        env.reset()
    env.task.set_timesteps(control_timestep=0.06, physics_timestep=0.002)
    with pytest.warns(UserWarning, match="not a multiple of the control timestep 0.06 s"):
        env.reset()


@pytest.mark.parametrize("time_limit", [0.08, 0.4, 0.0, float("inf")])
def test_a_time_limit_of_whole_steps_or_none_gives_no_warning(time_limit):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = _every_40ms(time_limit)
        env.reset()
    assert env.time_limit == time_limit


def test_a_time_limit_of_zero_ends_the_episode_at_the_first_step():
    env = composer.Environment(ReachTask(), time_limit=0)
    env.reset()
    assert env.step(np.zeros(2)).last()


def test_the_episode_ends_at_the_step_that_reaches_the_time_limit_exactly():
    # The limit is the physics time after three steps, as MuJoCo accumulated it.
    probe = composer.Environment(ReachTask())
    probe.reset()
    for _ in range(3):
        probe.step(np.zeros(2))
    limit = probe.physics.data.time
    env = composer.Environment(ReachTask(), time_limit=limit)
    env.reset()
    assert [env.step(np.zeros(2)).step_type for _ in range(3)] == [
        dm_env.StepType.MID,
        dm_env.StepType.MID,
        dm_env.StepType.LAST,
    ]


class PhysicsDiscount(ReachTask):
    """Discount: the arm tip's height, read from the physics."""

    def get_discount(self, physics):
        return float(physics.bind(self.arm.tip).xpos[2])


def test_discount_is_computed_from_the_physics():
    env = composer.Environment(PhysicsDiscount())
    env.reset()
    timestep = env.step(np.zeros(2))
    assert timestep.discount == pytest.approx(env.physics.bind(env.task.arm.tip).xpos[2])


class RandomObservables(ReachTask):
    """A task observable with a random update interval and a noisy corruptor, both drawing
    from the random state they are given."""

    def __init__(self):
        super().__init__()
        self.states = []
        self.noisy = observable.Generic(
            lambda physics: np.zeros(1),
            update_interval=self._interval,
            corruptor=self._corrupt,
        )
        self.noisy.enabled = True

    def _interval(self, random_state):
        self.states.append(random_state)
        return 1 + random_state.randint(2)

    def _corrupt(self, value, random_state):
        self.states.append(random_state)
        return value + random_state.normal()

    @property
    def task_observables(self):
        return {"noisy": self.noisy}


def test_random_observable_options_draw_from_the_environments_random_state():
    task = RandomObservables()
    env = composer.Environment(task, random_state=3)
    env.reset()
    env.step(np.zeros(2))
    assert task.states and all(state is env.random_state for state in task.states)


def test_close_frees_the_physics():
    env = composer.Environment(ReachTask())
    env.reset()
    proxy = env.physics
    env.close()
    with pytest.raises(ReferenceError):
        proxy.time()


def test_close_twice_is_harmless_and_reset_after_close_builds_a_new_physics():
    env = composer.Environment(ReachTask())
    env.reset()
    env.close()
    assert env.physics is None
    env.close()
    assert env.reset().first()
    assert env.step(np.zeros(2)).mid()


@pytest.mark.parametrize("copier", [copy.copy, copy.deepcopy, pickle.dumps])
def test_copying_an_environment_says_how_to_get_another(copier):
    env = composer.Environment(ReachTask())
    env.reset()
    with pytest.raises(TypeError) as raised:
        copier(env)
    assert str(raised.value) == (
        "a composer.Environment cannot be copied or pickled (its task, entities, observables "
        "and physics refer to each other and to live MuJoCo data); build a new one from the "
        "same task factory and seed instead, or copy just the simulation with "
        "env.physics.copy()"
    )
    assert env.step(np.zeros(env.action_spec().shape)).step_type == dm_env.StepType.MID


def _configured_env(substep_hook):
    task = ReachTask()
    task.arm.observables.joint_positions.configure(buffer_size=4, update_interval=3, delay=2)
    task.box.observables.position.configure(buffer_size=3, aggregator="mean")
    task.arm.observables.tip_position.configure(update_interval=4)
    env = composer.Environment(task, random_state=2)
    if substep_hook:
        env.add_extra_hook("after_substep", lambda physics, random_state: physics.time())
    return env


def test_stepping_in_chunks_observes_exactly_what_substep_by_substep_stepping_does():
    chunked, one_by_one = _configured_env(False), _configured_env(True)
    actions = np.random.RandomState(0).uniform(-1, 1, size=(6, 2))
    for first, second in [(chunked.reset(), one_by_one.reset())] + [
        (chunked.step(action), one_by_one.step(action)) for action in actions
    ]:
        assert first.reward == second.reward
        for name in first.observation:
            np.testing.assert_array_equal(first.observation[name], second.observation[name])


def test_default_observables_step_the_physics_in_one_call_per_control_step(monkeypatch):
    env = composer.Environment(ReachTask())
    env.reset()
    calls = []
    original = mjcf.Physics.step
    monkeypatch.setattr(
        mjcf.Physics, "step", lambda self, nstep=1: calls.append(nstep) or original(self, nstep)
    )
    env.step(np.zeros(2))
    assert calls == [10]


class OneSpecPerMotor(ReachTask):
    """Acts as two agents, each driving one of the arm's motors."""

    def action_spec(self, physics):
        return [specs.BoundedArray((1,), np.float64, -1.0, 1.0) for _ in range(2)]

    def before_step(self, physics, action, random_state):
        physics.bind(self.arm.actuators).ctrl = [action[0][0], action[1][0]]


def test_task_with_a_list_of_action_specs_gets_a_list_of_checked_actions():
    env = composer.Environment(OneSpecPerMotor())
    env.reset()
    env.step([[0.5], [-0.25]])
    np.testing.assert_allclose(env.physics.data.ctrl, [0.5, -0.25])
    with pytest.raises(ValueError, match=r"action\[1\]"):
        env.step([[0.5], [np.nan]])
