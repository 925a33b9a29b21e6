"""Each world of a batch on Warp's CPU device matches a CPU composer.Environment.

From the same seed per world (so the same initial state, drawn by the CPU task's own
initializers) and the same actions, every observation and reward of world i stays within a
float32 tolerance of CPU environment i for 20 control steps, for every batched task, and
worlds whose episodes end at different steps each start their next episode on their own,
as the CPU environments do. Integer-valued observations ('desired_order') match exactly.

The tolerances are `composer.batch.equivalence`'s, derived in its module docstring: a state
quantity (positions, angles, rotations, velocities) may be `state_tolerance(N)` times its
magnitude (at least 1) off after N physics steps. Joint torques
are the velocity servos' output, kv * (ctrl - qvel) plus constraint forces, so their error is
the velocity error times the largest servo gain kv. Rewards change at most as fast as their
sigmoid's steepest slope times the error of the distance or height they are computed from:
two positions, each within the state tolerance, and for a seat (place, stack, reassemble)
also the lower body's z axis times the seat height, so (2 + seat height / 1 m) state
tolerances. The steepest slopes: 1 / LIFT_HEIGHT for lift's linear ramp; for a Gaussian
exp(-ln(10) (x / margin)^2) (reach, place, stack, reassemble, each with its margin),
sqrt(2 ln 10) exp(-1/2) / margin at x = margin / sqrt(2 ln 10). A mean over a tower's pairs
and the factor HELD_FACTOR <= 1 make no slope steeper.

Some tasks are expected to fail the 20-step comparison (strict xfail, so that a change
shows), none because of its batched task:
- reassemble: every episode starts with a tower of bricks settling on its studs, which
  amplifies perturbations some 10^4-fold within the first control step, against the
  derivation's assumption: the CPU reference itself, started from its initial state rounded
  to float32, moves by up to 1.5e-4 m and 4e-3 m/s (seed 202; at 21 physics steps the
  tolerance is 1.7e-5). Once the tower has settled the dynamics are the arm's again: a test
  compares from there, after checking that the reference is reproducible at float32 (a CPU
  twin started from the rounded state stays within the tolerance).
- place_cradle: a finger strikes a cradle post (seed 101, step 20), and the impact
  multiplies the batch's float32 error a hundredfold, past the tolerance (a twin from the
  rounded start, whose error does not grow before the impact, stays within it).
- lift_large_box: once the box tilts under a finger, MuJoCo Warp's box-box contacts with
  the table take the box's face normal where C MuJoCo takes the table's (for the same
  state), so the friction forces that push the box differ.
Random actions never seat a brick, so the seat rewards are also compared in states set up
by hand (a tower seated pair by pair, a seated brick held).
"""

import math

import mujoco
import numpy as np
import pytest

import composer
import mjcf
from composer.batch import BatchEnvironment, BatchTimeStep
from composer.batch.equivalence import bound, state_tolerance
from manipulation import batch as manipulation_batch
from manipulation.props import Duplo2x4
from manipulation.tasks import observation_settings, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.place import Place
from manipulation.tasks.reach import Reach

pytestmark = pytest.mark.warp

NUM_ENVS = 4
SEEDS = (101, 202, 303, 404)
CONTROL_STEPS = 20
# The highest seat of the seated tasks (a brick on a brick; the cradle's is lower), in m.
_SEAT_HEIGHT = Duplo2x4.HEIGHT

_IMPACT = pytest.mark.xfail(
    strict=True,
    reason="a finger striking a cradle post amplifies the float32 error beyond the tolerance",
)
_SETTLING_TOWER = pytest.mark.xfail(
    strict=True,
    reason="the starting tower's settling amplifies float32 rounding beyond the tolerance",
)
_BOX_NORMAL = pytest.mark.xfail(
    strict=True,
    reason="MuJoCo Warp's box-box contact normal differs from C MuJoCo's once the box tilts",
)
_KNOWN_DIFFERENCES = {
    "place_cradle_features": _IMPACT,
    "lift_large_box_features": _BOX_NORMAL,
    "reassemble_3_bricks_fixed_order_features": _SETTLING_TOWER,
    "reassemble_5_bricks_random_order_features": _SETTLING_TOWER,
}


def _gaussian_slope(margin: float) -> float:
    """The steepest slope of exp(-ln(10) (x / margin)^2), at x = margin / sqrt(2 ln 10)."""
    return math.sqrt(2.0 * math.log(10.0)) * math.exp(-0.5) / margin


def _reward_slope(name: str) -> float:
    """The steepest slope (reward per metre) of the task's reward sigmoid."""
    if name.startswith("reach"):
        return _gaussian_slope(tc.REACH_MARGIN)
    if name.startswith("lift"):
        return 1.0 / tc.LIFT_HEIGHT
    if name.startswith(("place", "stack")):
        return _gaussian_slope(tc.PLACE_MARGIN)
    if name.startswith("reassemble"):
        return _gaussian_slope(tc.REASSEMBLE_MARGIN)
    raise ValueError(f"no reward slope for {name!r}")


def _distance_error_factor(name: str) -> float:
    """The error of the rewarded distance, in state tolerances (see the module docstring)."""
    if name.startswith(("place", "stack", "reassemble")):
        return 2.0 + _SEAT_HEIGHT
    return 2.0


def _max_servo_gain(env: composer.Environment) -> float:
    return float(np.max(np.abs(env.physics.model.ptr.actuator_gainprm[:, 0])))


def _assert_world_matches(batch_step, cpu_steps, physics_steps, name, kv):
    reward_factor = _distance_error_factor(name) * _reward_slope(name)
    for world, cpu in enumerate(cpu_steps):
        assert int(batch_step.step_type[world]) == int(cpu.step_type), f"world {world}"
        for key, expected in cpu.observation.items():
            got = batch_step.observation[key][world]
            assert got.shape == expected.shape, key
            if key == "desired_order":
                np.testing.assert_array_equal(got, expected, err_msg=f"world {world}")
                continue
            factor = kv if key.endswith("joints_torque") else 1.0
            tolerance = bound(expected, physics_steps, factor)
            np.testing.assert_array_less(
                np.abs(got - expected), tolerance, err_msg=f"world {world}, {key!r}"
            )
        if cpu.reward is not None:
            reward_tolerance = bound(cpu.reward, physics_steps, reward_factor)
            assert abs(batch_step.reward[world] - cpu.reward) <= reward_tolerance, f"world {world}"


def _actions(env: composer.Environment) -> np.ndarray:
    """CONTROL_STEPS random actions for NUM_ENVS worlds, (CONTROL_STEPS, NUM_ENVS, nu)."""
    spec = env.action_spec()
    return np.random.default_rng(7).uniform(
        spec.minimum, spec.maximum, (CONTROL_STEPS, NUM_ENVS, spec.shape[0])
    )


def _cpu_environments(name: str) -> list[composer.Environment]:
    return [
        composer.Environment(registry.build_task(name), time_limit=tc.TIME_LIMIT, random_state=s)
        for s in SEEDS
    ]


@pytest.mark.parametrize(
    "name",
    [
        pytest.param(n, marks=_KNOWN_DIFFERENCES.get(n, ()))
        for n in manipulation_batch.BATCHED_FEATURES
    ],
)
def test_every_world_matches_its_cpu_environment_for_20_control_steps(name):
    batch_env = manipulation_batch.load(name, NUM_ENVS, random_states=SEEDS, device="warp-cpu")
    cpu_envs = _cpu_environments(name)
    kv = _max_servo_gain(cpu_envs[0])
    n_sub_steps = cpu_envs[0].task.physics_steps_per_control_step
    _assert_world_matches(batch_env.reset(), [e.reset() for e in cpu_envs], 1, name, kv)
    for step, action in enumerate(_actions(cpu_envs[0]), start=1):
        batch_step = batch_env.step(action)
        cpu_steps = [env.step(a) for env, a in zip(cpu_envs, action)]
        _assert_world_matches(batch_step, cpu_steps, step * n_sub_steps + 1, name, kv)
    batch_env.close()


# Control steps with the arm at rest for a starting tower to settle (1 s): the stud
# contacts' transient lasts a few tenths of a second.
SETTLE_STEPS = 25
# The state a batch can be put in, field by field (mjSTATE_INTEGRATION but the controls,
# which every step sets).
_STATE_FIELDS = ("qpos", "qvel", "act", "qacc_warmstart")


def _integration_state(env: composer.Environment) -> np.ndarray:
    model, data = env.physics.model.ptr, env.physics.data.ptr
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    return state


def _stacked(time_steps) -> BatchTimeStep:
    """CPU time steps, one per world, as one batch's."""
    return BatchTimeStep(
        np.array([t.step_type for t in time_steps]),
        np.array([t.reward for t in time_steps]),
        np.array([t.discount for t in time_steps]),
        {
            key: np.stack([t.observation[key] for t in time_steps])
            for key in time_steps[0].observation
        },
    )


@pytest.mark.parametrize(
    "name",
    ["reassemble_3_bricks_fixed_order_features", "reassemble_5_bricks_random_order_features"],
)
def test_reassemble_worlds_match_their_cpu_environments_once_the_tower_has_settled(name):
    cpu_envs, twins = _cpu_environments(name), _cpu_environments(name)
    kv = _max_servo_gain(cpu_envs[0])
    n_sub_steps = cpu_envs[0].task.physics_steps_per_control_step
    rest = np.zeros(cpu_envs[0].action_spec().shape)
    for env in (*cpu_envs, *twins):
        env.reset()
        for _ in range(SETTLE_STEPS):
            env.step(rest)
    # Both the twins and the batch start from the settled state rounded to float32.
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    for twin, env in zip(twins, cpu_envs):
        rounded = _integration_state(env).astype(np.float32).astype(np.float64)
        mujoco.mj_setState(twin.physics.model.ptr, twin.physics.data.ptr, rounded, spec)
        twin.physics.forward()
    # The same seeds as the CPU environments: the same episodes, so the same desired orders.
    batch_env = manipulation_batch.load(name, NUM_ENVS, random_states=SEEDS, device="warp-cpu")
    batch_env.reset()
    for field in _STATE_FIELDS:
        values = np.array([getattr(env.physics.data, field) for env in cpu_envs])
        getattr(batch_env.physics.data, field)[...] = values
    batch_env.physics.forward()
    for step, action in enumerate(_actions(cpu_envs[0]), start=1):
        cpu_steps = [env.step(a) for env, a in zip(cpu_envs, action)]
        twin_steps = [env.step(a) for env, a in zip(twins, action)]
        physics_steps = step * n_sub_steps + 1
        # The reference is reproducible at float32 from here: the derivation holds.
        _assert_world_matches(_stacked(twin_steps), cpu_steps, physics_steps, name, kv)
        _assert_world_matches(batch_env.step(action), cpu_steps, physics_steps, name, kv)
    batch_env.close()


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
        batch_task, NUM_ENVS, random_states=SEEDS, device="warp-cpu", slots_per_world=4
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


def _seat(physics, upper, lower, height: float) -> None:
    """Poses `upper` on its seat `height` above `lower` (same orientation); runs forward."""
    body = physics.bind(lower.root_body)
    position = body.xpos + height * body.xmat.reshape(3, 3)[:, 2]
    upper.set_pose(physics, position=position, quaternion=body.xquat.copy())
    physics.forward()


def _tower(task) -> tuple[list, float]:
    """The entities of the task's rewarded tower, bottom first, and its seat height."""
    if isinstance(task, Place):
        return [task.target, task.prop], task.seat_height
    return [task.bricks[i] for i in task.desired_order], Duplo2x4.HEIGHT


def _seated_states(name: str, seed: int) -> tuple[list, list]:
    """The first episode of `name` from `seed` as reset, then with the first pair of its
    tower seated, then with every pair seated: the qpos and the CPU task's reward of each."""
    env = composer.Environment(registry.build_task(name), random_state=seed)
    env.reset()
    task, physics = env.task, env.physics
    tower, height = _tower(task)
    states, rewards = [physics.data.qpos.copy()], [task.get_reward(physics)]
    for lower, upper in zip(tower[:-1], tower[1:]):
        _seat(physics, upper, lower, height)
        states.append(physics.data.qpos.copy())
        rewards.append(task.get_reward(physics))
    return states, rewards


def _assert_batch_rewards(name, seeds, states, expected):
    """World i of a batch seeded `seeds[i]`, put in `states[i]`, earns `expected[i]` (within
    the reward tolerance of one physics step: the state is set, not simulated)."""
    batch_env = manipulation_batch.load(name, len(states), random_states=seeds, device="warp-cpu")
    batch_env.reset()
    batch_env.physics.data.qpos[...] = np.array(states)
    batch_env.physics.forward()
    got = batch_env.task.get_reward(batch_env.physics)
    tolerance = _distance_error_factor(name) * state_tolerance(1) * _reward_slope(name)
    np.testing.assert_allclose(got, expected, rtol=0.0, atol=tolerance)
    batch_env.close()


@pytest.mark.parametrize(
    "name",
    [
        "place_brick_features",
        "place_cradle_features",
        "stack_3_bricks_random_order_features",
        "stack_2_of_3_bricks_random_order_features",
        "reassemble_3_bricks_fixed_order_features",
        "reassemble_5_bricks_random_order_features",
    ],
)
def test_seat_rewards_match_the_cpu_task_as_the_tower_is_seated_pair_by_pair(name):
    # Random actions never seat a brick: this puts each world's tower together by hand,
    # in the order its own episode asks for.
    seeds, states, expected = [], [], []
    for seed in SEEDS[:2]:
        seed_states, seed_rewards = _seated_states(name, seed)
        seeds += [seed] * len(seed_states)
        states += seed_states
        expected += seed_rewards
    assert expected[len(expected) // 2 - 1] == expected[-1] == 1.0  # both towers seated
    assert min(expected) < 0.5  # and towers that earn less
    _assert_batch_rewards(name, seeds, states, expected)


def test_stack_reward_matches_the_cpu_task_while_the_hand_holds_the_seated_brick():
    name = "stack_2_bricks_moveable_base_features"
    env = composer.Environment(registry.build_task(name), random_state=0)
    env.reset()
    task, physics = env.task, env.physics
    base, brick = task.bricks
    _seat(physics, brick, base, Duplo2x4.HEIGHT)
    states, expected = [physics.data.qpos.copy()], [task.get_reward(physics)]
    # The seated pair moved so that the upper brick is in the fingers, which then close.
    pinch = physics.bind(task.hand.tool_center_point)
    grip_axis = pinch.xmat.reshape(3, 3)[:, 1]
    yaw = np.arctan2(grip_axis[1], grip_axis[0])
    base.set_pose(
        physics,
        position=pinch.xpos - [0.0, 0.0, 1.5 * Duplo2x4.HEIGHT],
        quaternion=[np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)],
    )
    physics.forward()
    _seat(physics, brick, base, Duplo2x4.HEIGHT)
    physics.bind(task.hand.joints).qpos = 0.6
    physics.forward()
    states.append(physics.data.qpos.copy())
    expected.append(task.get_reward(physics))
    assert expected == [1.0, tc.HELD_FACTOR]
    _assert_batch_rewards(name, [0, 0], states, expected)
