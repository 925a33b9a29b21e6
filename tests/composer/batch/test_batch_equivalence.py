"""Each world of a batch on Warp's CPU device matches a CPU composer.Environment.

From the same seed per world (so the same initial state, drawn by the CPU task's own
initializers) and the same actions, every observation and reward of world i stays within a
float32 tolerance of CPU environment i for 20 control steps, and worlds whose episodes end
at different steps each start their next episode on their own, as the CPU environments do.

The tolerances, derived rather than fitted to this test: Warp computes in float32 (machine
epsilon EPS), C MuJoCo in float64, so each physics step adds a rounding error of order EPS
relative to the state; uncorrelated, these errors grow like sqrt(N) over N physics steps.
The issue measured 1.2e-6 on lift_brick's qpos after 21 physics steps, that is
22 * sqrt(21) * EPS, the constant that the conditioning of the arm's dynamics puts in front;
rounded up to STATE_FACTOR = 32, a state quantity (positions, angles, rotations, velocities)
is allowed `STATE_FACTOR * sqrt(N) * EPS` times its magnitude (at least 1). Joint torques
are the velocity servos' output, kv * (ctrl - qvel) plus constraint forces, so their error is
the velocity error times the largest servo gain kv. Rewards change at most as fast as their
sigmoid's steepest slope times the error of the distance or height they are computed from
(two positions, each within the state tolerance).
"""

import math

import numpy as np
import pytest

import composer
import mjcf
from composer.batch import BatchEnvironment
from manipulation import batch as manipulation_batch
from manipulation.tasks import observation_settings, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.reach import Reach

pytestmark = pytest.mark.warp

NUM_ENVS = 4
SEEDS = (101, 202, 303, 404)
CONTROL_STEPS = 20
EPS = float(np.finfo(np.float32).eps)
STATE_FACTOR = 32.0


def _state_tolerance(physics_steps: int) -> float:
    return STATE_FACTOR * math.sqrt(max(physics_steps, 1)) * EPS


def _reward_slope(name: str) -> float:
    """The steepest slope (reward per metre) of the task's reward sigmoid."""
    if name.startswith("reach"):
        # exp(-ln(10) (x / margin)^2) is steepest at x = margin / sqrt(2 ln 10).
        scale = math.sqrt(math.log(10.0)) / tc.REACH_MARGIN
        return scale * math.sqrt(2.0) * math.exp(-0.5)
    return 1.0 / tc.LIFT_HEIGHT


def _max_servo_gain(env: composer.Environment) -> float:
    return float(np.max(np.abs(env.physics.model.ptr.actuator_gainprm[:, 0])))


def _assert_world_matches(batch_step, cpu_steps, physics_steps, name, kv):
    state_tolerance = _state_tolerance(physics_steps)
    for world, cpu in enumerate(cpu_steps):
        assert int(batch_step.step_type[world]) == int(cpu.step_type), f"world {world}"
        for key, expected in cpu.observation.items():
            got = batch_step.observation[key][world]
            assert got.shape == expected.shape, key
            scale = np.maximum(1.0, np.abs(expected))
            tolerance = state_tolerance * scale * (kv if key.endswith("joints_torque") else 1.0)
            np.testing.assert_array_less(
                np.abs(got - expected), tolerance, err_msg=f"world {world}, {key!r}"
            )
        if cpu.reward is not None:
            reward_tolerance = 2.0 * state_tolerance * _reward_slope(name)
            assert abs(batch_step.reward[world] - cpu.reward) <= reward_tolerance, f"world {world}"


@pytest.mark.parametrize("name", ["reach_site_features", "lift_brick_features"])
def test_every_world_matches_its_cpu_environment_for_20_control_steps(name):
    batch_env = manipulation_batch.load(name, NUM_ENVS, random_states=SEEDS)
    cpu_envs = [
        composer.Environment(registry.build_task(name), time_limit=tc.TIME_LIMIT, random_state=s)
        for s in SEEDS
    ]
    kv = _max_servo_gain(cpu_envs[0])
    n_sub_steps = cpu_envs[0].task.physics_steps_per_control_step
    spec = cpu_envs[0].action_spec()
    actions = np.random.default_rng(7).uniform(
        spec.minimum, spec.maximum, (CONTROL_STEPS, NUM_ENVS, spec.shape[0])
    )
    _assert_world_matches(batch_env.reset(), [e.reset() for e in cpu_envs], 1, name, kv)
    for step, action in enumerate(actions, start=1):
        batch_step = batch_env.step(action)
        cpu_steps = [env.step(a) for env, a in zip(cpu_envs, action)]
        _assert_world_matches(batch_step, cpu_steps, step * n_sub_steps + 1, name, kv)


class _EndsAfter(Reach):
    """reach_site whose episodes end after `limit` control steps (the CPU side), read from
    the simulated time (half a physics step below the limit's time, as float32 reaches it)."""

    def __init__(self, limit: int):
        super().__init__(observation_settings.FEATURES)
        self.limit = limit

    def should_terminate_episode(self, physics) -> bool:
        return physics.data.time >= self.limit * self.control_timestep - 0.5 * self.physics_timestep


class _BatchEndsAfter(manipulation_batch.BatchReach):
    """The batched twin: world i's episodes end after limits[i] control steps, read from
    each world's simulated time (which the initial state sets back to 0)."""

    def __init__(self, task, limits):
        super().__init__(task)
        self._end_times = np.asarray(limits) * task.control_timestep - 0.5 * task.physics_timestep

    def should_terminate_episode(self, physics):
        return physics.data.time >= self._end_times


def test_each_world_ends_and_restarts_its_episode_on_its_own():
    limits = (2, 3, 5, 100)
    batch_task = _BatchEndsAfter(_EndsAfter(limit=0), limits)
    # World 0 starts 3 episodes in the 8 steps before the first refill: 4 slots hold them.
    batch_env = BatchEnvironment(
        batch_task, NUM_ENVS, random_states=SEEDS, device="cpu", slots_per_world=4
    )
    cpu_envs = [
        composer.Environment(_EndsAfter(limit), random_state=s) for limit, s in zip(limits, SEEDS)
    ]
    kv = _max_servo_gain(cpu_envs[0])
    spec = cpu_envs[0].action_spec()
    rng = np.random.default_rng(3)
    _assert_world_matches(batch_env.reset(), [e.reset() for e in cpu_envs], 1, "reach", kv)
    step_types = []
    for step in range(1, 9):
        action = rng.uniform(spec.minimum, spec.maximum, (NUM_ENVS, spec.shape[0]))
        batch_step = batch_env.step(action)
        # Physics steps since each world's episode began bound its error; 8 steps at most.
        _assert_world_matches(
            batch_step, [e.step(a) for e, a in zip(cpu_envs, action)], step * 20 + 1, "reach", kv
        )
        step_types.append(batch_step.step_type.tolist())
    first, mid, last = 0, 1, 2
    assert [row[0] for row in step_types] == [mid, last, first, mid, last, first, mid, last]
    assert [row[1] for row in step_types] == [mid, mid, last, first, mid, mid, last, first]
    assert [row[3] for row in step_types] == [mid] * 8
    assert batch_env.initial_state_stats().reused == 0


def test_lift_reward_matches_the_cpu_task_when_the_hand_holds_the_brick_up():
    cpu = composer.Environment(registry.build_task("lift_brick_features"), random_state=0)
    cpu.reset()
    task, physics = cpu.task, cpu.physics
    joint = mjcf.get_frame_freejoint(task.prop.mjcf_model)
    pinch = physics.bind(task.hand.tool_center_point).xpos.copy()
    rest = physics.bind(joint).qpos.copy()
    states, expected = [], []
    # In the fingers above the table, high above the table out of reach, on the table.
    for position in (pinch + [0.0, 0.0, 0.03], pinch + [0.3, 0.0, 0.0], rest[:3]):
        physics.bind(joint).qpos[:3] = position
        physics.forward()
        states.append(physics.data.qpos.copy())
        expected.append(task.get_reward(physics))
    assert expected == [1.0, 0.0, 0.0]
    batch_env = manipulation_batch.load("lift_brick_features", len(states), seed=0)
    batch_env.reset()
    batch_env.physics.data.qpos[...] = np.array(states)
    batch_env.physics.forward()
    np.testing.assert_array_equal(batch_env.task.get_reward(batch_env.physics), expected)
