"""Soak: many short episodes of a task whose MJCF changes every episode; memory and speed drift.

Scene: a floor, a two-link arm with motors and a free box. Every episode the box is resized
and recoloured (so the model is recompiled), and on every other episode a marker site is
added to or removed from the arm (so the model's structure changes too). Each episode is
a reset and `--steps` random control steps.

Prints the resident memory (RSS) after the first 100 episodes and at the end, its growth,
and the median time per episode over the first 100 and the last 100 episodes (medians,
so that other processes sharing the machine disturb them less), with their ratio, and the
fastest episode of each window, which the load of a shared machine hardly moves.
Targets: RSS growth < 5 MB over 10,000 episodes; last-100 time within 5% of the first-100.

Usage: python benchmarks/soak.py [--episodes 10000] [--steps 10] [--seed 0]
"""

import argparse
import gc
import os
import resource
import time

import numpy as np

import composer
import mjcf
from composer.observation import observable

_WINDOW = 100
_RSS_TARGET_MB = 5.0
_TIME_DRIFT_TARGET = 0.05


def _rss_mb() -> float:
    """Current resident set size in MB (peak RSS where /proc is unavailable)."""
    try:
        with open(f"/proc/{os.getpid()}/statm") as handle:
            pages = int(handle.read().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


class _Floor(composer.Arena):
    def _build(self, name="floor"):
        super()._build(name=name)
        self.mjcf_model.worldbody.add("geom", name="ground", type="plane", size=[2, 2, 0.1])


class _Arm(composer.Robot):
    def _build(self, name="arm"):
        self._model = mjcf.RootElement(model=name)
        upper = self._model.worldbody.add("body", name="upper", pos=[0, 0, 0.5])
        shoulder = upper.add("joint", name="shoulder", axis=[0, 1, 0], damping=0.1)
        upper.add("geom", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.03])
        self.lower = upper.add("body", name="lower", pos=[0.3, 0, 0])
        elbow = self.lower.add("joint", name="elbow", axis=[0, 1, 0], damping=0.1)
        self.lower.add("geom", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.025])
        self.joints = [shoulder, elbow]
        self._actuators = [
            self._model.actuator.add("motor", joint=joint, ctrlrange=[-1, 1], gear=[5])
            for joint in self.joints
        ]

    @property
    def mjcf_model(self):
        return self._model

    @property
    def actuators(self):
        return self._actuators


class _Box(composer.Entity):
    def _build(self):
        self._model = mjcf.RootElement(model="box")
        self.geom = self._model.worldbody.add("geom", type="box", size=[0.05] * 3, mass=0.2)

    @property
    def mjcf_model(self):
        return self._model


class ChangingTask(composer.Task):
    """Reach for the box; its size and colour, and the arm's marker site, change per episode."""

    def __init__(self):
        self.arena = _Floor()
        self.arm = _Arm()
        self.box = _Box()
        self.arena.attach(self.arm)
        self.arena.add_free_entity(self.box)
        self.marker = None
        self.episodes = 0
        self.set_timesteps(control_timestep=0.02, physics_timestep=0.004)
        self.box_position = observable.MJCFFeature("xpos", self.box.geom)
        self.box_position.enabled = True

    @property
    def root_entity(self):
        return self.arena

    @property
    def task_observables(self):
        return {"box_position": self.box_position}

    def initialize_episode_mjcf(self, random_state):
        self.episodes += 1
        self.box.geom.size = random_state.uniform(0.02, 0.08, size=3)
        self.box.geom.rgba = random_state.uniform(0, 1, size=4)
        if self.episodes % 2 == 0:
            if self.marker is None:
                self.marker = self.arm.lower.add("site", name="marker", pos=[0.3, 0, 0])
            else:
                self.marker.remove()
                self.marker = None

    def initialize_episode(self, physics, random_state):
        self.box.set_pose(physics, position=[random_state.uniform(0.2, 0.5), 0.0, 0.1])

    def get_reward(self, physics):
        return -float(np.linalg.norm(physics.bind(self.box.geom).xpos))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=10, help="control steps per episode")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if args.episodes < 2 * _WINDOW:
        parser.error(f"--episodes must be at least {2 * _WINDOW}")

    env = composer.Environment(ChangingTask(), random_state=args.seed)
    spec = env.action_spec()
    actions = np.random.RandomState(args.seed)
    durations = []
    rss_after_window = None
    start_all = time.perf_counter()
    for episode in range(args.episodes):
        start = time.perf_counter()
        env.reset()
        for _ in range(args.steps):
            env.step(actions.uniform(spec.minimum, spec.maximum))
        durations.append(time.perf_counter() - start)
        if episode + 1 == _WINDOW:
            gc.collect()
            rss_after_window = _rss_mb()
    gc.collect()
    rss_end = _rss_mb()
    total = time.perf_counter() - start_all

    first = 1e3 * float(np.median(durations[:_WINDOW]))
    last = 1e3 * float(np.median(durations[-_WINDOW:]))
    fastest_first = 1e3 * min(durations[:_WINDOW])
    fastest_last = 1e3 * min(durations[-_WINDOW:])
    growth = rss_end - rss_after_window
    rows = [
        ("episodes", f"{args.episodes} x {args.steps} steps, {total:.0f} s in all", ""),
        (f"RSS after {_WINDOW} episodes", f"{rss_after_window:.1f} MB", ""),
        ("RSS at the end", f"{rss_end:.1f} MB", ""),
        ("RSS growth", f"{growth:+.2f} MB", f"target < {_RSS_TARGET_MB:g} MB"),
        (f"time per episode, first {_WINDOW}", f"{first:.2f} ms", ""),
        (f"time per episode, last {_WINDOW}", f"{last:.2f} ms", ""),
        ("last / first", f"{last / first:.3f}", f"target within {_TIME_DRIFT_TARGET:.0%}"),
        (f"fastest episode, first {_WINDOW}", f"{fastest_first:.2f} ms", ""),
        (f"fastest episode, last {_WINDOW}", f"{fastest_last:.2f} ms", ""),
        ("last / first (fastest)", f"{fastest_last / fastest_first:.3f}", "load-independent"),
    ]
    width = max(len(r[0]) for r in rows)
    value_width = max(len(r[1]) for r in rows)
    for name, value, target in rows:
        print(f"{name:<{width}}  {value:>{value_width}}  {target}")


if __name__ == "__main__":
    main()
