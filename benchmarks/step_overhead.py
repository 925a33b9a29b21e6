"""What composer.Environment adds to the MuJoCo calls it wraps, as ratios measured in one run.

Scene: an arena with a floor, a six-joint arm (a Robot with position actuators) and two
free boxes resting on the floor; 7 enabled observables; 20 physics steps per control
step; `before_step`/`after_step` hooks on the arm and on both boxes. It is measured
twice: with the arm's links as 64-vertex convex meshes, as in real robot models (the
targets apply to this scene), and with capsule links, whose XML compiles about five
times faster, so the reset ratios there show the fixed costs of a reset.

Rows:
  step: `env.step` / 20 raw `mujoco.mj_step` calls on the same model, from the same
    states with the same controls (also against one `mj_step(model, data, 20)` call).
  reset, MJCF unchanged: `env.reset()` / one `mujoco.MjModel.from_xml_string` of the
    scene's XML (the compile a dm_control reset performs every episode).
  reset after an MJCF change: `env.reset()` when `initialize_episode_mjcf` recolours a
    box, so the model must be recompiled / the same one XML compile.

Step times are medians over many identical trials and step ratios medians of the
ratios within each trial; reset and compile times are medians.

Usage: python benchmarks/step_overhead.py [--repeats N]
"""

import argparse
import math
import statistics
import time

import mujoco
import numpy as np

import composer
import mjcf
from composer.observation import observable

_SUB_STEPS = 20
_STEP_TARGET = 1.15
_RESET_UNCHANGED_TARGET = 0.1
_RESET_CHANGED_TARGET = 1.5


class Floor(composer.Arena):
    def _build(self):
        super()._build(name="floor")
        self.mjcf_model.worldbody.add("geom", name="ground", type="plane", size=[2, 2, 0.1])


class ArmObservables(composer.Observables):
    @composer.observable
    def joint_positions(self):
        return observable.MJCFFeature("qpos", self._entity.joints)

    @composer.observable
    def joint_velocities(self):
        return observable.MJCFFeature("qvel", self._entity.joints)

    @composer.observable
    def hand_position(self):
        return observable.MJCFFeature("xpos", self._entity.hand)


def _prism_vertices(sides: int, radius: float, length: float) -> np.ndarray:
    """Vertices of a regular prism along z: a convex mesh like a robot link's."""
    angles = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack([radius * np.cos(angles), radius * np.sin(angles)], axis=1)
    bottom = np.column_stack([ring, np.zeros(sides)])
    top = np.column_stack([ring, np.full(sides, length)])
    return np.concatenate([bottom, top]).ravel()


class Arm(composer.Robot):
    """Six hinge joints alternating between the z and y axes, position-controlled.

    With `mesh_links` each link is a 64-vertex convex mesh, as in real robot models;
    otherwise a capsule.
    """

    def _build(self, mesh_links):
        self._model = mjcf.RootElement(model="arm")
        body = self._model.worldbody.add("body", name="base", pos=[0, 0, 0.1])
        self.joints = []
        for i in range(6):
            axis = [0, 0, 1] if i % 2 == 0 else [0, 1, 0]
            self.joints.append(body.add("joint", name=f"j{i}", axis=axis, damping=1))
            if mesh_links:
                mesh = self._model.asset.add(
                    "mesh", name=f"link{i}", vertex=_prism_vertices(32, 0.03, 0.12)
                )
                body.add("geom", type="mesh", mesh=mesh)
            else:
                body.add("geom", type="capsule", fromto=[0, 0, 0, 0, 0, 0.12], size=[0.03])
            body = body.add("body", name=f"link{i}", pos=[0, 0, 0.12])
        self.hand = body.add("site", name="hand")
        self._actuators = [
            self._model.actuator.add("position", joint=joint, kp=20, ctrlrange=[-1, 1])
            for joint in self.joints
        ]
        self.steps = 0

    def _build_observables(self):
        return ArmObservables(self)

    @property
    def mjcf_model(self):
        return self._model

    @property
    def actuators(self):
        return self._actuators

    def before_step(self, physics, random_state):
        self.steps += 1


class BoxObservables(composer.Observables, composer.FreePropObservableMixin):
    pass


class Box(composer.Entity):
    def _build(self, name):
        self._model = mjcf.RootElement(model=name)
        self.geom = self._model.worldbody.add("geom", type="box", size=[0.04] * 3, mass=0.2)
        self.highest = 0.0

    def _build_observables(self):
        return BoxObservables(self)

    @property
    def mjcf_model(self):
        return self._model

    def initialize_episode(self, physics, random_state):
        self.body = physics.bind(self.root_body)

    def after_step(self, physics, random_state):
        self.highest = max(self.highest, self.body.xpos[2])


class Stack(composer.Task):
    """Reward: minus the distance between the two boxes."""

    def __init__(self, mesh_links, recolour_every_episode=False):
        self.arena = Floor()
        self.arm = Arm(mesh_links)
        self.boxes = [Box("red"), Box("blue")]
        self.arena.attach(self.arm)
        for i, box in enumerate(self.boxes):
            self.arena.add_free_entity(box).pos = [0.3, 0.2 * i - 0.1, 0.04]
            box.observables.position.enabled = True
            box.observables.orientation.enabled = True
        self.arm.observables.enable_all()
        self.recolour_every_episode = recolour_every_episode
        self.set_timesteps(control_timestep=_SUB_STEPS * 0.002, physics_timestep=0.002)

    @property
    def root_entity(self):
        return self.arena

    def initialize_episode_mjcf(self, random_state):
        if self.recolour_every_episode:
            self.boxes[0].geom.rgba = [*random_state.uniform(size=3), 1]

    def initialize_episode(self, physics, random_state):
        for i, box in enumerate(self.boxes):
            box.set_pose(physics, position=[0.3, 0.2 * i - 0.1, 0.04], quaternion=[1, 0, 0, 0])

    def get_reward(self, physics):
        offset = self.boxes[0].body.xpos - self.boxes[1].body.xpos
        return -math.sqrt(offset @ offset)


def _time_block(function, actions) -> float:
    start = time.perf_counter()
    for action in actions:
        function(action)
    return (time.perf_counter() - start) / len(actions)


def _measure_steps(mesh_links, repeats, steps=25):
    """Per-step times of env.step, 20 mj_step calls and one mj_step(20) call, and ratios.

    Every trial runs each for `steps` control steps from the same reset state with the
    same controls, so all trials of all three simulate the same trajectory. Times are
    medians over trials; ratios are medians of the ratios within a trial, whose three
    blocks run back to back and so share the machine's load.
    """
    env = composer.Environment(Stack(mesh_links), random_state=0)
    model = env.physics.model.ptr
    data = mujoco.MjData(model)
    actions = np.random.RandomState(0).uniform(-1, 1, size=(steps, 6))

    def raw_loop(action):
        data.ctrl[:] = action
        for _ in range(_SUB_STEPS):
            mujoco.mj_step(model, data)

    def raw_call(action):
        data.ctrl[:] = action
        mujoco.mj_step(model, data, _SUB_STEPS)

    trials = []
    for _ in range(repeats):
        env.reset()
        start_state = env.physics.data.ptr
        mujoco.mj_copyData(data, model, start_state)
        loop_time = _time_block(raw_loop, actions)
        mujoco.mj_copyData(data, model, start_state)
        call_time = _time_block(raw_call, actions)
        trials.append((_time_block(env.step, actions), loop_time, call_time))
    env_time, loop_time, call_time = (statistics.median(column) for column in zip(*trials))
    loop_ratio = statistics.median(env / loop for env, loop, _ in trials)
    call_ratio = statistics.median(env / call for env, _, call in trials)
    return (env_time, loop_time, loop_ratio), (env_time, call_time, call_ratio)


def _time_calls(function, count) -> list[float]:
    timer = time.perf_counter
    times = []
    for _ in range(count):
        start = timer()
        function()
        times.append(timer() - start)
    return times


def _measure_resets(mesh_links, repeats, count=5):
    """Median times of one XML compile, a reset with nothing changed, and one after a change.

    Each trial times a block of each in turn.
    """
    unchanged = composer.Environment(Stack(mesh_links), random_state=0)
    changed = composer.Environment(Stack(mesh_links, recolour_every_episode=True), random_state=0)
    root = unchanged.task.root_entity.mjcf_model
    xml, assets = root.to_xml_string(), root.get_assets()
    compile_times, unchanged_times, changed_times = [], [], []
    for _ in range(repeats):
        compile_times += _time_calls(lambda: mujoco.MjModel.from_xml_string(xml, assets), count)
        unchanged_times += _time_calls(unchanged.reset, count)
        changed_times += _time_calls(changed.reset, count)
    return tuple(statistics.median(t) for t in (compile_times, unchanged_times, changed_times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=60, help="trials per measurement")
    args = parser.parse_args()

    header = f"{'scene / measurement':<46}{'time (us)':>11}{'baseline (us)':>15}"
    print(f"{header}{'ratio':>8}{'target':>9}")
    for mesh_links, scene in ((True, "mesh links"), (False, "capsule links")):
        step_vs_loop, step_vs_call = _measure_steps(mesh_links, args.repeats)
        compile_time, reset_unchanged, reset_changed = _measure_resets(mesh_links, args.repeats)
        rows = [
            ("env.step / 20 x mj_step", *step_vs_loop, _STEP_TARGET),
            ("env.step / mj_step(nstep=20)", *step_vs_call, None),
            (
                "reset, MJCF unchanged / XML compile",
                reset_unchanged,
                compile_time,
                reset_unchanged / compile_time,
                _RESET_UNCHANGED_TARGET,
            ),
            (
                "reset after MJCF change / XML compile",
                reset_changed,
                compile_time,
                reset_changed / compile_time,
                _RESET_CHANGED_TARGET,
            ),
        ]
        for name, value, baseline, ratio, target in rows:
            target_text = f"<= {target}" if target is not None and mesh_links else ""
            print(
                f"{scene + ': ' + name:<46}{value * 1e6:>11.1f}{baseline * 1e6:>15.1f}"
                f"{ratio:>8.3f}{target_text:>9}"
            )


if __name__ == "__main__":
    main()
