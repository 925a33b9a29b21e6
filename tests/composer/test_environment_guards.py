"""Environment behaviours around bad actions, bad observables, divergence and options, each
checked where a plausible slip would otherwise go unnoticed."""

import dm_env
import numpy as np
import pytest
from composer_scene import Diverges
from dm_env import specs

import composer
import mjcf
from composer.observation import observable

_CLOCK_OFFSET = 10.0


class ClockTask(Diverges):
    """Diverges with a task observable `clock` (physics time + 10, never zero), optionally
    delayed; counts `after_step` calls; makes the box's mass NaN before control step
    `diverge_at` of an episode."""

    def __init__(self, delay=None, diverge_at=None, shape=(1,)):
        super().__init__(diverge_at)
        self.shape = shape
        self.clock = observable.Generic(self._read_clock, delay=delay)
        self.clock.enabled = True
        self.after_steps = 0
        self.reads = []

    def _read_clock(self, physics):
        self.reads.append(physics.data.time + _CLOCK_OFFSET)
        return np.full(self.shape, self.reads[-1])

    @property
    def task_observables(self):
        return {"clock": self.clock}

    def after_step(self, physics, random_state):
        self.after_steps += 1


@pytest.mark.parametrize(
    ("padding", "expected"),
    [
        (composer.ObservationPadding.ZERO, 0.0),
        (composer.ObservationPadding.INITIAL_VALUE, _CLOCK_OFFSET),
    ],
)
def test_delayed_observation_is_padded_as_asked_before_its_first_sample(padding, expected):
    env = composer.Environment(ClockTask(delay=10), delayed_observation_padding=padding)
    assert env.reset().observation["clock"][0] == expected


@pytest.mark.parametrize("legacy_step", [True, False])
def test_environment_physics_steps_in_the_mode_asked(legacy_step):
    env = composer.Environment(ClockTask(), legacy_step=legacy_step)
    env.reset()
    assert env.physics.legacy_step is legacy_step
    env.step(np.zeros(2))
    arm_tip = env.physics.bind(env.task.arm.tip)
    stale = arm_tip.xpos.copy()
    env.physics.forward()
    # A legacy step leaves positions computed for the new qpos; a plain one, for the old.
    assert np.array_equal(arm_tip.xpos, stale) is legacy_step


def test_legacy_step_choice_survives_recompiling_every_episode():
    env = composer.Environment(ClockTask(), legacy_step=False, recompile_mjcf_every_episode=True)
    env.reset()
    env.task.arm.mjcf_model.worldbody.add("site", name="marker")
    env.reset()
    assert env.physics.legacy_step is False


@pytest.mark.parametrize("n_sub_steps", [1, 3])
def test_diverging_step_still_runs_after_step_and_updates_the_observation(n_sub_steps):
    # Default observables are sampled once, at the end of each control step; a diverging
    # step must still take that sample, whatever the number of sub-steps.
    task = ClockTask(diverge_at=2)
    env = composer.Environment(
        task, raise_exception_on_physics_error=False, n_sub_steps=n_sub_steps
    )
    env.reset()
    steps, timestep = 0, None
    while steps < 5 and (timestep is None or not timestep.last()):
        reads = len(task.reads)
        timestep = env.step(np.zeros(2))
        steps += 1
    assert timestep.last() and timestep.reward == 0.0 and task.after_steps == steps
    # The observation was read again after the failed step, and that reading is returned.
    assert len(task.reads) == reads + 1
    assert timestep.observation["clock"].ravel()[0] == task.reads[-1]


@pytest.mark.parametrize("raise_exception", [True, False])
def test_environment_is_usable_after_reset_following_divergence(raise_exception):
    task = ClockTask(diverge_at=1)
    env = composer.Environment(task, raise_exception_on_physics_error=raise_exception)
    env.reset()
    if raise_exception:
        with pytest.raises(mjcf.PhysicsError):
            env.step(np.zeros(2))
    else:
        assert env.step(np.zeros(2)).last()
    task.diverge_at = None
    first = env.reset()
    assert first.first() and first.observation["clock"][0] == _CLOCK_OFFSET
    for _ in range(3):
        timestep = env.step(np.full(2, 0.5))
        assert timestep.mid()
        assert np.isfinite(env.physics.data.qpos).all()


@pytest.mark.parametrize(
    "action",
    [[np.nan, 0.0], [0.0, np.inf], [0.0, -np.inf], [0.0, 0.0, 0.0], [[0.0, 0.0]], "go"],
    ids=["nan", "inf", "-inf", "too long", "wrong rank", "string"],
)
def test_bad_action_is_rejected_without_stepping_and_the_episode_goes_on(action):
    env = composer.Environment(ClockTask())
    env.reset()
    with pytest.raises(ValueError, match="action"):
        env.step(action)
    assert env.physics.data.time == 0.0
    timestep = env.step(np.zeros(2))
    assert timestep.step_type == dm_env.StepType.MID
    assert env.physics.data.time == pytest.approx(0.02)


def test_observable_changing_shape_raises_and_reset_recovers():
    task = ClockTask()
    env = composer.Environment(task)
    shape = env.reset().observation["clock"].shape
    task.shape = (3,)
    with pytest.raises(ValueError):
        env.step(np.zeros(2))
    task.shape = (1,)
    assert env.reset().observation["clock"].shape == shape
    assert env.step(np.zeros(2)).mid()


class SubstepRecorder(ClockTask):
    """Records what each sub-step hook receives."""

    def __init__(self):
        super().__init__()
        self.before = []
        self.after = []

    def before_substep(self, physics, action, random_state):
        self.before.append((np.array(action), random_state, physics.data.time))

    def after_substep(self, physics, random_state):
        self.after.append((random_state, physics.data.time))


def test_substep_hooks_get_the_action_and_the_environments_random_state_every_substep():
    task = SubstepRecorder()
    env = composer.Environment(task, random_state=5)
    env.reset()
    env.step(np.array([0.5, -0.25]))
    assert len(task.before) == len(task.after) == 10
    for action, random_state, _ in task.before:
        np.testing.assert_array_equal(action, [0.5, -0.25])
        assert random_state is env.random_state
    assert all(random_state is env.random_state for random_state, _ in task.after)
    # before_substep sees the time before each physics step, after_substep the time after.
    np.testing.assert_allclose([t for *_, t in task.before], np.arange(10) * 0.002)
    np.testing.assert_allclose([t for _, t in task.after], np.arange(1, 11) * 0.002)


class ShiftsTimeAfterStep(ClockTask):
    """Moves the clock on by 100 s in `after_step`; `substep_hooks` adds a sub-step hook."""

    def __init__(self, substep_hooks):
        super().__init__()
        self.substeps = 0
        if substep_hooks:
            # A hook that does something: one that does nothing is left out of the loop.
            self.before_substep = self._count_substep

    def _count_substep(self, physics, action, random_state):
        self.substeps += 1

    def after_step(self, physics, random_state):
        super().after_step(physics, random_state)
        physics.data.time += 100.0


@pytest.mark.parametrize("substep_hooks", [False, True])
def test_final_observation_is_taken_after_the_after_step_hooks(substep_hooks):
    task = ShiftsTimeAfterStep(substep_hooks)
    env = composer.Environment(task)
    env.reset()
    clock = env.step(np.zeros(2)).observation["clock"].ravel()[0]
    assert clock == pytest.approx(0.02 + 100.0 + _CLOCK_OFFSET)
    assert task.substeps == (10 if substep_hooks else 0)


class RewardSpecOnly(ClockTask):
    def get_reward_spec(self):
        return specs.Array((), np.float64, name="reward")


def test_step_spec_needs_both_the_reward_and_the_discount_spec():
    env = composer.Environment(RewardSpecOnly())
    with pytest.warns(DeprecationWarning), pytest.raises(NotImplementedError) as raised:
        env.step_spec()
    assert str(raised.value) == "step_spec: the task RewardSpecOnly defines no discount spec"
