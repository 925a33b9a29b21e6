"""What composer.Environment adds on a user's own task, as ratios measured in one run.

Task (written as a user would): a four-legged creature (a free torso, two hinges per leg,
eight motors) on a floor with a button, a static box carrying a touch sensor. The task's
`after_substep` hook reads the touch sensor through `physics.bind` and sets the button's
`rgba` (pressed or released) every sub-step. Observables: the touch reading with
`buffer_size=20` and a mean aggregator plus an additive-noise corruptor, and the leg joint
angles with a multiplicative-noise corruptor. An `MJCFVariator` recolours the torso every
episode (a change that `mjcf.patching.model_patch` writes into the compiled model instead of
recompiling it) and a `PhysicsVariator` scales the floor's friction every episode. 20
physics steps per control step.

Rows:
  env.step / raw: `env.step` / 20 raw `mujoco.mj_step` calls on the same model, from the
    same state with the same controls.
  env.step without the hook / raw: the same task with its `after_substep` hook removed, so
    the hook's own cost is the difference between the two rows.
  first reset / XML compile: the environment's first `env.reset()` (one measurement; on a
    release no proof covers yet, it proves the colour change: at most one compile more than
    a recompile) / one `mujoco.MjModel.from_xml_string` of the task's XML.
  reset from the second on / XML compile: `env.reset()` (the torso colour having changed:
    patched in place, and the reset's data copied from the last reset's, which a colour
    does not change) / one XML compile.
  reset without patching / XML compile: the same with `patch_compiled_model=False`, which
    recompiles (the previous implementation).

Each step trial times a block of 25 steps and its baseline back to back (so both share the
machine's load); each reset trial is one compile then one reset. Ratios are medians over
trials of the ratio within a trial, and times are medians over trials. The machine may be
shared: use enough trials.

Usage: python benchmarks/custom_task.py [--trials N] [--table-elsewhere]
"""

import argparse
import statistics
import time

import mujoco
import numpy as np

import composer
import mjcf
from composer import variation
from composer.observation import observable
from composer.variation import colors, distributions, noises
from mjcf.patching import patchable_attributes

_SUB_STEPS = 20
_STEP_TARGET = 1.5
_RESET_TARGET = 0.5
_PRESSED = np.array([1.0, 0.2, 0.2, 1.0])
_RELEASED = np.array([0.2, 0.2, 1.0, 1.0])


class Floor(composer.Arena):
    """A floor with a button: a flat static box whose touch sensor feels what presses it."""

    def _build(self):
        super()._build(name="floor")
        worldbody = self.mjcf_model.worldbody
        self.ground = worldbody.add("geom", name="ground", type="plane", size=[3, 3, 0.1])
        button = worldbody.add("body", name="button", pos=[0, 0, 0.01])
        self.button = button.add("geom", type="box", size=[0.3, 0.3, 0.01], rgba=_RELEASED)
        pad = button.add("site", name="pad", type="box", size=[0.31, 0.31, 0.03])
        self.touch = self.mjcf_model.sensor.add("touch", name="button_touch", site=pad)


class CreatureObservables(composer.Observables):
    @composer.observable
    def leg_angles(self):
        return observable.MJCFFeature("qpos", self._entity.joints)


class Creature(composer.Entity):
    """A spherical torso with four two-segment legs, a motor on every joint."""

    def _build(self):
        self._model = mjcf.RootElement(model="creature")
        torso = self._model.worldbody.add("body", name="torso")
        self.torso_geom = torso.add("geom", type="sphere", size=[0.1], rgba=[0.8, 0.6, 0.4, 1])
        self.joints = []
        for i, angle in enumerate(np.arange(4) * np.pi / 2 + np.pi / 4):
            direction = np.array([np.cos(angle), np.sin(angle), 0.0])
            thigh = torso.add("body", name=f"thigh{i}", pos=0.1 * direction)
            self.joints.append(thigh.add("joint", name=f"hip{i}", axis=[0, 0, 1], range=[-40, 40]))
            thigh.add("geom", type="capsule", fromto=[0, 0, 0, *(0.2 * direction)], size=[0.03])
            shin = thigh.add("body", name=f"shin{i}", pos=0.2 * direction)
            knee_axis = np.cross([0, 0, 1], direction)
            self.joints.append(shin.add("joint", name=f"knee{i}", axis=knee_axis, range=[0, 70]))
            foot = 0.3 * direction - [0, 0, 0.3]
            shin.add("geom", type="capsule", fromto=[0, 0, 0, *foot], size=[0.03])
        for joint in self.joints:
            self._model.actuator.add("motor", joint=joint, gear=[10], ctrlrange=[-1, 1])

    def _build_observables(self):
        return CreatureObservables(self)

    @property
    def mjcf_model(self):
        return self._model


class PressTheButton(composer.Task):
    """Reward: the button's touch reading, capped at 1."""

    def __init__(self):
        self.arena = Floor()
        self.creature = Creature()
        self.arena.add_free_entity(self.creature)
        self.mjcf_variator = variation.MJCFVariator()
        self.mjcf_variator.bind_attributes(
            self.creature.torso_geom,
            rgba=colors.RgbVariation(*(distributions.Uniform(0, 1) for _ in range(3))),
        )
        self.physics_variator = variation.PhysicsVariator()
        self.physics_variator.bind_attributes(
            self.arena.ground, friction=noises.Multiplicative(distributions.Uniform(0.8, 1.2))
        )
        self._touch_observable = observable.MJCFFeature(
            "sensordata",
            self.arena.touch,
            buffer_size=20,
            aggregator="mean",
            corruptor=noises.Additive(distributions.Normal(scale=0.01)),
        )
        self._touch_observable.enabled = True
        legs = self.creature.observables.leg_angles
        legs.enabled = True
        legs.corruptor = noises.Multiplicative(distributions.LogNormal(sigma=0.01))
        self.set_timesteps(control_timestep=_SUB_STEPS * 0.002, physics_timestep=0.002)

    @property
    def root_entity(self):
        return self.arena

    @property
    def task_observables(self):
        return {"button_touch": self._touch_observable}

    def initialize_episode_mjcf(self, random_state):
        self.mjcf_variator.apply_variations(random_state)

    def initialize_episode(self, physics, random_state):
        self.physics_variator.apply_variations(physics, random_state)
        self.creature.set_pose(
            physics,
            position=[*random_state.uniform(-0.2, 0.2, size=2), 0.5],
            quaternion=[1, 0, 0, 0],
        )

    def after_substep(self, physics, random_state):
        pressed = physics.bind(self.arena.touch).sensordata[0] > 0
        physics.bind(self.arena.button).rgba = _PRESSED if pressed else _RELEASED

    def get_reward(self, physics):
        return min(1.0, float(physics.bind(self.arena.touch).sensordata[0]))


class PressTheButtonWithoutHook(PressTheButton):
    """The same task with no `after_substep` hook at all."""

    after_substep = composer.Task.after_substep


def _time_block(function, actions) -> float:
    start = time.perf_counter()
    for action in actions:
        function(action)
    return (time.perf_counter() - start) / len(actions)


def _measure_steps(task, trials: int, steps: int = 25) -> tuple[float, float, float]:
    """(env.step time, raw time, median ratio) over `trials` trials of `steps` steps."""
    env = composer.Environment(task, random_state=0)
    model = env.physics.model.ptr
    data = mujoco.MjData(model)
    actions = np.random.RandomState(0).uniform(-1, 1, size=(steps, model.nu))

    def raw_loop(action):
        data.ctrl[:] = action
        for _ in range(_SUB_STEPS):
            mujoco.mj_step(model, data)

    results = []
    for _ in range(trials):
        env.reset()
        model = env.physics.model.ptr
        mujoco.mj_copyData(data, model, env.physics.data.ptr)
        raw = _time_block(raw_loop, actions)
        results.append((_time_block(env.step, actions), raw))
    env_time, raw_time = (statistics.median(column) for column in zip(*results))
    return env_time, raw_time, statistics.median(env / raw for env, raw in results)


def _measure_resets(trials: int, *, patch: bool) -> tuple[tuple, tuple]:
    """The first reset's (time, compile time, ratio), and (reset time, compile time, median
    ratio) over the `trials` resets after it.

    Each pair compiles the task's current XML (the reset compiles the same XML with another
    torso colour), then resets, so that both run in the same conditions: right after Python
    work, not in a tight loop of compiles that keeps MuJoCo's compiler in the CPU caches.
    The first reset is apart: on a MuJoCo release no proof covers yet, it proves the colour
    change on this model (`mjcf.patching.first_use_proof`).
    """
    env = composer.Environment(PressTheButton(), random_state=0, patch_compiled_model=patch)
    root = env.task.root_entity.mjcf_model
    results = []
    for _ in range(trials + 1):
        xml, assets = root.to_xml_string(), root.get_assets()
        start = time.perf_counter()
        mujoco.MjModel.from_xml_string(xml, assets)
        compile_time = time.perf_counter() - start
        start = time.perf_counter()
        env.reset()
        results.append((time.perf_counter() - start, compile_time))
    (first_reset, first_compile), later = results[0], results[1:]
    reset_time, compile_time = (statistics.median(column) for column in zip(*later))
    return (
        (first_reset, first_compile, first_reset / first_compile),
        (reset_time, compile_time, statistics.median(r / c for r, c in later)),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=40, help="trials per measurement")
    parser.add_argument(
        "--table-elsewhere",
        action="store_true",
        help="pretend the checked-in patch table was proven on another MuJoCo release, as on "
        "a release newer than the table (with an empty cache: XDG_CACHE_HOME=$(mktemp -d))",
    )
    args = parser.parse_args()
    if args.table_elsewhere:
        patchable_attributes.MUJOCO_VERSION = "0.0.0-elsewhere"
    first_reset, resets = _measure_resets(10 * args.trials, patch=True)
    rows = [
        ("env.step / 20 x mj_step", *_measure_steps(PressTheButton(), args.trials), _STEP_TARGET),
        (
            "env.step without the hook / 20 x mj_step",
            *_measure_steps(PressTheButtonWithoutHook(), args.trials),
            None,
        ),
        ("first reset / XML compile", *first_reset, None),
        ("reset from the second on / XML compile", *resets, _RESET_TARGET),
        (
            "reset without patching / XML compile",
            *_measure_resets(10 * args.trials, patch=False)[1],
            None,
        ),
    ]
    print(f"{'measurement':<44}{'time (us)':>11}{'baseline (us)':>15}{'ratio':>8}{'target':>9}")
    for name, value, baseline, ratio, target in rows:
        target_text = "" if target is None else f"<= {target}"
        print(f"{name:<44}{value * 1e6:>11.1f}{baseline * 1e6:>15.1f}{ratio:>8.3f}{target_text:>9}")


if __name__ == "__main__":
    main()
