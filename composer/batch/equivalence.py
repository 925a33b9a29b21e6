"""Does a batch match the CPU environment? World by world, step by step: bit for bit on the
CPU batch (`device="cpu"`), to float32 on MuJoCo Warp.

`compare(task_factory)` runs `num_envs` CPU `composer.Environment`s and one
`BatchEnvironment` of the same task, world i of the batch seeded like CPU environment i (so
both start from the state the CPU task's initializers draw), with the same actions, and
returns an `EquivalenceReport` naming the first quantity, step and world that leaves the
float32 bound below. From a shell, for a function `make_task()` returning the CPU task:

    python -m composer.batch.equivalence my_package.tasks:make_task --steps 50

prints the report and exits with status 1 when a world leaves the bound (`--device cpu`:
when any value of any world differs from its CPU environment's).

The bound, derived rather than fitted (the project's own equivalence tests use it): Warp
computes in float32 (machine epsilon `EPS`), C MuJoCo in float64, so each physics step adds
a rounding error of order EPS relative to the state; uncorrelated, these errors grow like
sqrt(N) over N physics steps. lift_brick's qpos was measured 1.2e-6 off after 21 physics
steps, that is 22 * sqrt(21) * EPS, the constant that the conditioning of the arm's
dynamics puts in front; rounded up to `STATE_FACTOR` = 32, a state quantity (positions,
angles, rotations, velocities) may be `state_tolerance(N)` = STATE_FACTOR * sqrt(N) * EPS
times its magnitude (at least 1) away. A quantity computed from the state with a gain gets
that gain as its factor: a velocity servo's torque kv * (ctrl - qvel) the servo's kv, a
reward the steepest slope of its sigmoid (reward per metre) times the number of state
errors its distance adds up (2 for the distance between two points).

The bound holds between discrete events (a contact starting, a joint leaving its limit),
not always across them: an impact amplifies the float32 error, and an event can fall in
another physics step in float32 than in float64. So `compare` also runs CPU environments
whose state is rounded to float32 after every control step: where they leave the bound as
well (`EquivalenceReport.rounded_cpu_first`), the task itself amplifies rounding there, and
the batch's difference says nothing against it (docs: "Batch your own task").
"""

import argparse
import importlib
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple

import dm_env
import mujoco
import numpy as np

import composer
from composer.batch import devices
from composer.batch.environment import BatchEnvironment
from composer.batch.task import BatchTask
from composer.utils import argument_checks

__all__ = [
    "EPS",
    "STATE_FACTOR",
    "Divergence",
    "EquivalenceReport",
    "bound",
    "compare",
    "state_tolerance",
]

#: float32's machine epsilon: the relative rounding error of one float32 operation.
EPS = float(np.finfo(np.float32).eps)
#: The state error per sqrt(physics step), in EPS times the state's magnitude (see above).
STATE_FACTOR = 32.0


def state_tolerance(physics_steps: int) -> float:
    """The relative float32 error a state quantity may have after `physics_steps` steps."""
    return STATE_FACTOR * math.sqrt(max(physics_steps, 1)) * EPS


def bound(expected, physics_steps: int, factor: float = 1.0) -> np.ndarray:
    """How far a batch's value may be from `expected` (the CPU's float64 value), elementwise:
    `factor * state_tolerance(physics_steps) * max(1, |expected|)`."""
    scale = np.maximum(1.0, np.abs(np.asarray(expected, dtype=np.float64)))
    return factor * state_tolerance(physics_steps) * scale


class Divergence(NamedTuple):
    """The first value of a batch that left the bound.

    Attributes:
      quantity: 'qpos', 'qvel', 'reward', 'discount', 'step_type' or
        "observation 'key'".
      step: the control step: 0 for the reset, k for the k-th step.
      world: the world (and CPU environment) index.
      index: the element's index within the world's value (() for a scalar).
      element: the joint a qpos or qvel entry belongs to ('' otherwise).
      got: the batch's value (or the rounded CPU environment's).
      expected: the CPU environment's value.
      bound: the largest difference allowed there (0 for values compared exactly).
    """

    quantity: str
    step: int
    world: int
    index: tuple[int, ...]
    element: str
    got: float
    expected: float
    bound: float

    def __str__(self) -> str:
        where = f"{self.quantity}{list(self.index) if self.index else ''}"
        if self.element:
            where += f" (joint {self.element!r})"
        return (
            f"{where} of world {self.world} at step {self.step}: got {self.got:.9g}, "
            f"CPU float64 {self.expected:.9g}, difference {abs(self.got - self.expected):.3g} "
            f"> bound {self.bound:.3g}"
        )


class EquivalenceReport(NamedTuple):
    """What `compare` found.

    Attributes:
      num_envs: the worlds compared.
      control_steps: the steps compared after the reset.
      seeds: world i's seed (its CPU environment's `random_state`).
      first: the first value that left the bound (earliest step, then world, then in the
        order qpos, qvel, observations, reward, discount, step type), or None.
      worst: by quantity, the largest difference over its bound seen over all steps (a
        value above 1 left the bound); how much room the batch has.
      rounded_cpu_first: the same for CPU environments whose state (positions,
        velocities, activations) is rounded to float32 after the reset and every control
        step, or None (always on the CPU batch, compared exactly): C MuJoCo's own
        sensitivity to float32. Where these leave the bound
        too, the task amplifies rounding there (an impact, a body landing flat) and a
        batch cannot be expected to stay within it either.
    """

    num_envs: int
    control_steps: int
    seeds: tuple[int, ...]
    first: Divergence | None
    worst: dict[str, float]
    rounded_cpu_first: Divergence | None

    @property
    def passed(self) -> bool:
        """Whether every world stayed within the bound at every step."""
        return self.first is None

    def __str__(self) -> str:
        head = (
            f"{self.num_envs} worlds, {self.control_steps} control steps, seeds "
            f"{list(self.seeds)}: "
        )
        head += "within the float32 bound" if self.passed else f"left the bound: {self.first}"
        if self.rounded_cpu_first is None:
            twin = "the CPU rounded to float32 every step stays within the bound"
        else:
            twin = f"the CPU rounded to float32 every step leaves it too: {self.rounded_cpu_first}"
        rows = [f"  {name}: {r:.3g} of its bound at worst" for name, r in self.worst.items()]
        return "\n".join([head, twin, *rows])


def _joint_of(model: mujoco.MjModel, address: int, addresses: np.ndarray) -> str:
    """The name of the joint whose entries (starting at `addresses`) hold `address`."""
    if model.njnt == 0:
        return ""
    joint = int(np.flatnonzero(addresses <= address)[-1])
    return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, joint) or f"joint {joint}"


class _Comparison:
    """Keeps the first divergence and the worst ratio of each quantity."""

    def __init__(self, model: mujoco.MjModel):
        self._model = model
        self.first: Divergence | None = None
        self.worst: dict[str, float] = {}

    def check(self, quantity, step, got, expected, allowed, element_addresses=None) -> None:
        """Compares (num_envs, ...) arrays; `allowed` is the bound (num_envs, ...) or None
        for an exact comparison."""
        got = np.asarray(got, dtype=np.float64)
        expected = np.asarray(expected, dtype=np.float64)
        if got.shape != expected.shape:
            raise ValueError(
                f"{quantity}: the batch's shape {got.shape} is not the CPU's {expected.shape}"
            )
        difference = np.abs(got - expected)
        difference[np.isnan(got) != np.isnan(expected)] = np.inf
        difference[np.isnan(got) & np.isnan(expected)] = 0.0
        if allowed is None:
            outside = difference > 0
            ratio = float(np.any(outside)) * np.inf if difference.size else 0.0
            allowed = np.zeros_like(difference)
        else:
            outside = difference > allowed
            ratio = float(np.max(difference / allowed)) if difference.size else 0.0
        self.worst[quantity] = max(self.worst.get(quantity, 0.0), ratio)
        if self.first is not None or not np.any(outside):
            return
        where = tuple(int(i) for i in np.argwhere(outside)[0])
        world, index = where[0], where[1:]
        element = ""
        if element_addresses is not None:
            element = _joint_of(self._model, index[0], element_addresses)
        self.first = Divergence(
            quantity,
            step,
            world,
            index,
            element,
            float(got[where]),
            float(expected[where]),
            float(allowed[where]),
        )


def _random_actions(spec, control_steps: int, num_envs: int, seed: int) -> np.ndarray:
    """Uniform in a bounded spec, standard normal where a bound is infinite."""
    rng = np.random.default_rng(seed)
    shape = (control_steps, num_envs, *spec.shape)
    minimum = np.broadcast_to(getattr(spec, "minimum", -np.inf), spec.shape)
    maximum = np.broadcast_to(getattr(spec, "maximum", np.inf), spec.shape)
    bounded = np.isfinite(minimum) & np.isfinite(maximum)
    uniform = rng.uniform(np.where(bounded, minimum, 0.0), np.where(bounded, maximum, 1.0), shape)
    return np.where(bounded, uniform, rng.standard_normal(shape))


def compare(
    task_factory: Callable[[], composer.Task],
    *,
    num_envs: int = 4,
    control_steps: int = 50,
    seed: int = 0,
    actions: np.ndarray | None = None,
    time_limit: float = float("inf"),
    factors: Mapping[str, float] | None = None,
    batch_task: Callable[[composer.Task], BatchTask] | None = None,
    device: str = "warp-cpu",
    autoreset_mode: str = "next_step",
) -> EquivalenceReport:
    """Steps `num_envs` CPU environments and a batch of the same task side by side.

    World i of the batch and CPU environment i are seeded `seed + i` and get the same
    actions. After the reset and after each step, every world's qpos, qvel, observations,
    reward and discount are compared with the CPU environment's within
    `bound(cpu_value, N, factor)`, N the physics steps since the reset (a float32 bound;
    see the module docstring), and its step type exactly, as are observations whose CPU
    dtype is an integer or bool.

    Args:
      task_factory: returns a new CPU task; called twice per world (the CPU environment
        and its float32-rounded twin) and once for the batch.
      num_envs: the worlds (and CPU environments) to compare.
      control_steps: the steps after the reset.
      seed: world i's seed is `seed + i`; the default actions are drawn from it too.
      actions: (control_steps, num_envs, *action shape), or None for random actions in the
        action spec (uniform; standard normal along unbounded dimensions).
      time_limit: both environments' time limit, in seconds.
      factors: a gain per quantity, by name ('qpos', 'qvel', 'reward', 'discount', or an
        observation's key), multiplying its bound (1 by default): a reward's steepest
        slope times the state errors it adds up, a servo torque's kv.
      batch_task: makes the `BatchTask` from the CPU task; None looks the task's class up
        in the registry (`composer.batch.register`).
      device: the batch's device (`composer.batch.devices`). On the CPU batch ("cpu") every
        value is compared exactly: a world must equal its CPU environment bit for bit
        (the report's bounds are 0, and no rounded CPU twins run).
      autoreset_mode: the batch's; under "same_step" a CPU environment whose episode
        ended is reset at once, its LAST step carrying the new episode's first
        observation, as the batch's does.

    Returns:
      An `EquivalenceReport`; `report.first` names the first value outside its bound.

    Raises:
      ValueError: for `actions` of the wrong shape, `num_envs` below 1 or `control_steps`
        below 0, named.
    """
    argument_checks.integer(num_envs=num_envs)
    argument_checks.integer(0, control_steps=control_steps)
    factors = dict(factors or {})
    seeds = tuple(seed + i for i in range(num_envs))

    def cpu_environments():
        return [
            composer.Environment(task_factory(), time_limit=time_limit, random_state=s)
            for s in seeds
        ]

    exact = not devices.resolve(device).on_warp
    cpu_envs, twins = cpu_environments(), ([] if exact else cpu_environments())
    task = task_factory()
    batch_env = BatchEnvironment(
        task if batch_task is None else batch_task(task),
        num_envs,
        device=device,
        time_limit=time_limit,
        random_states=seeds,
        autoreset_mode=autoreset_mode,
    )
    same_step = autoreset_mode == "same_step"
    try:
        spec = cpu_envs[0].action_spec()
        if actions is None:
            actions = _random_actions(spec, control_steps, num_envs, seed)
        actions = np.asarray(actions, dtype=np.float64)
        expected_shape = (control_steps, num_envs, *spec.shape)
        if actions.shape != expected_shape:
            raise ValueError(f"actions: expected shape {expected_shape}, got {actions.shape}")
        model = cpu_envs[0].physics.model.ptr
        batch_comparison, twin_comparison = _Comparison(model), _Comparison(model)
        n_sub_steps = cpu_envs[0].task.physics_steps_per_control_step
        physics = batch_env.physics
        batch_step = batch_env.reset()
        cpu_steps, twin_steps = [e.reset() for e in cpu_envs], [e.reset() for e in twins]
        for step in range(control_steps + 1):
            if step:
                batch_step = batch_env.step(actions[step - 1])
                cpu_steps = [
                    _cpu_step(env, a, same_step) for env, a in zip(cpu_envs, actions[step - 1])
                ]
                twin_steps = [
                    _cpu_step(env, a, same_step) for env, a in zip(twins, actions[step - 1])
                ]
            physics_steps = step * n_sub_steps + 1
            batch_states = {f: physics.arrays.to_host(getattr(physics.data, f)) for f in _STATE}
            compared = [(batch_comparison, batch_states, batch_step)]
            if twins:
                compared.append((twin_comparison, _cpu_states(twins), _stacked(twin_steps)))
            for comparison, states, outputs in compared:
                _compare_states(comparison, step, physics_steps, factors, states, cpu_envs, exact)
                _compare_outputs(
                    comparison, step, physics_steps, factors, outputs, cpu_steps, exact
                )
            for twin in twins:
                _round_state(twin.physics)
    finally:
        batch_env.close()
    return EquivalenceReport(
        num_envs,
        control_steps,
        seeds,
        batch_comparison.first,
        batch_comparison.worst,
        twin_comparison.first,
    )


# The state compared, field by field; and the state a rounded twin has rounded.
_STATE = ("qpos", "qvel")
_PHYSICS_STATE = mujoco.mjtState.mjSTATE_PHYSICS


def _cpu_step(env: composer.Environment, action, same_step: bool) -> dm_env.TimeStep:
    """A CPU environment's step; under "same_step" autoreset, a LAST step carries the next
    episode's first observation (the environment is reset at once), as a batch's does."""
    time_step = env.step(action)
    if same_step and time_step.last():
        time_step = time_step._replace(observation=env.reset().observation)
    return time_step


def _cpu_states(envs) -> dict[str, np.ndarray]:
    return {f: np.array([getattr(env.physics.data, f) for env in envs]) for f in _STATE}


def _round_state(physics) -> None:
    """Rounds the positions, velocities and activations of `physics` to float32."""
    model, data = physics.model.ptr, physics.data.ptr
    state = np.empty(mujoco.mj_stateSize(model, _PHYSICS_STATE))
    mujoco.mj_getState(model, data, state, _PHYSICS_STATE)
    rounded = state.astype(np.float32).astype(np.float64)
    mujoco.mj_setState(model, data, rounded, _PHYSICS_STATE)


class _Outputs(NamedTuple):
    """CPU time steps, one per world, stacked as a batch's."""

    step_type: np.ndarray
    reward: np.ndarray
    discount: np.ndarray
    observation: dict[str, np.ndarray]


def _stacked(time_steps) -> _Outputs:
    def value(v, first):
        return first if v is None else v

    return _Outputs(
        np.array([int(t.step_type) for t in time_steps]),
        np.array([value(t.reward, 0.0) for t in time_steps]),
        np.array([value(t.discount, 1.0) for t in time_steps]),
        {k: np.stack([t.observation[k] for t in time_steps]) for k in time_steps[0].observation},
    )


def _compare_states(comparison, step, physics_steps, factors, states, cpu_envs, exact):
    """Compares every world's qpos and qvel with the CPU environments' (bit for bit where
    `exact`)."""
    model = cpu_envs[0].physics.model.ptr
    expected_states = _cpu_states(cpu_envs)
    for field, addresses in (("qpos", model.jnt_qposadr), ("qvel", model.jnt_dofadr)):
        expected = expected_states[field]
        allowed = None if exact else bound(expected, physics_steps, factors.get(field, 1.0))
        comparison.check(field, step, states[field], expected, allowed, addresses)


def _compare_outputs(comparison, step, physics_steps, factors, batch, cpus, exact):
    """Compares every world's observations, reward, discount and step type (bit for bit
    where `exact`)."""
    for key in cpus[0].observation:
        expected = np.array([t.observation[key] for t in cpus])
        got = np.asarray(batch.observation[key])
        whole = exact or expected.dtype.kind in "biu"
        allowed = None if whole else bound(expected, physics_steps, factors.get(key, 1.0))
        comparison.check(f"observation {key!r}", step, got, expected, allowed)
    expected_outputs = _stacked(cpus)
    for name in ("reward", "discount"):
        expected = getattr(expected_outputs, name).astype(np.float64)
        allowed = None if exact else bound(expected, physics_steps, factors.get(name, 1.0))
        comparison.check(name, step, np.asarray(getattr(batch, name)), expected, allowed)
    got_types = np.asarray(batch.step_type)
    comparison.check("step_type", step, got_types, expected_outputs.step_type, None)


def _load_factory(spec: str) -> Callable[[], composer.Task]:
    module_name, _, name = spec.partition(":")
    if not name:
        raise ValueError(f"task: expected 'module:function', got {spec!r}")
    return getattr(importlib.import_module(module_name), name)


def _parse_factors(pairs: Sequence[str]) -> dict[str, float]:
    factors = {}
    for pair in pairs:
        name, sep, value = pair.rpartition("=")
        if not sep:
            raise ValueError(f"--factor: expected NAME=NUMBER, got {pair!r}")
        factors[name] = float(value)
    return factors


def main(argv: Sequence[str] | None = None) -> int:
    """The command line: prints the report; returns 1 when a world left the bound."""
    parser = argparse.ArgumentParser(
        prog="python -m composer.batch.equivalence", description=__doc__.split("\n")[0]
    )
    parser.add_argument("task", help="module:function returning a new CPU composer.Task")
    parser.add_argument("--num-envs", type=int, default=4)
    parser.add_argument("--steps", type=int, default=50, help="control steps after the reset")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--time-limit", type=float, default=float("inf"))
    parser.add_argument(
        "--device", default="warp-cpu", help="the batch's device; 'cpu' compares exactly"
    )
    parser.add_argument(
        "--factor", action="append", default=[], help="NAME=GAIN for a quantity's bound"
    )
    args = parser.parse_args(argv)
    report = compare(
        _load_factory(args.task),
        num_envs=args.num_envs,
        control_steps=args.steps,
        seed=args.seed,
        time_limit=args.time_limit,
        factors=_parse_factors(args.factor),
        device=args.device,
    )
    print(report)
    return 0 if report.passed else 1


if __name__ == "__main__":
    sys.exit(main())
