"""What stepping a vector env's physics in one call would give: parts measured, whole modelled.

The threaded vector env steps each sub-environment's physics with dm_control's split step
(`mj_step2`, `mj_step(n - 1)`, `mj_step1`) on the sub-environment's own thread: three
releases of the GIL per sub-environment step, each a hand-off when other threads wait for
the lock. MuJoCo 4's `mujoco.batch.Batch` steps many simulations in one call on threads of
its own (the GIL released once); persistent, with `stage=mjSTAGE_VEL`, a step continues
from the position and velocity stages of the last one, which is the split step. This
benchmark measures, on the task's model (`--task`, default reach_site_features), for each
N of `--sizes`:

  identical: whether the batch's trajectory (qpos, qvel, xpos, site_xpos, sensordata)
    equals the split step's, bit for bit, for the same controls (the premise of the
    route; a batch stepped without `stage=VEL` reads NO: its positions lag a substep);
  split us: the split step on one thread, us per simulation step (the baseline);
  batch us: `Batch(persistent=True).step(nstep, stage=VEL)` of N simulations on
    min(N, cores) threads, us per simulation step, and split / batch (what the physics
    alone gains, like the lock-step ceiling);
  copies us: per simulation step, its state into the batch (`mj_getState` into the
    batch's row) and its whole MjData back out (`Batch.get_data`), which a sub-environment
    whose Python reads its own MjData needs;
  modelled: a vector step that runs every sub-environment's Python (P us, the task's
    environment step less its split physics, both measured here) and copies on the
    calling thread, then the physics in one batch call: N (P + copies) + batch, as a
    speed-up over a loop of N environment steps; and the GIL bound, loop / (N (P +
    copies)): what any design reaches at best while one interpreter runs all the Python
    (with the Python of some sub-environments overlapping the physics of others; none
    at N = 1, where a step's Python and physics follow each other).

Not a vector env: the composer step would have to be split around its physics for this.
Needs mujoco >= 4 (`mujoco.batch`); says so and stops otherwise.

Usage: python benchmarks/batch_physics_route.py [--task T] [--sizes 1,4,8,16,32] [--steps N]
"""

import argparse
import os
import pathlib
import statistics
import sys
import time

# `import manipulation` finds the package rather than benchmarks/manipulation.py.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

import manipulation  # noqa: E402

_VEL = int(mujoco.mjtStage.mjSTAGE_VEL)
_STATE = mujoco.mjtState.mjSTATE_INTEGRATION


def _split_step(model: mujoco.MjModel, data: mujoco.MjData, sub_steps: int) -> None:
    mujoco.mj_step2(model, data)
    if sub_steps > 1:
        mujoco.mj_step(model, data, sub_steps - 1)
    mujoco.mj_step1(model, data)


def _median_us(function, calls: int, per: int, repeats: int = 5) -> float:
    """us per item: the median over `repeats` passes of `calls` calls doing `per` items."""
    passes = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            function()
        passes.append(time.perf_counter() - start)
    return statistics.median(passes) / calls / per * 1e6


class _Route:
    """The task's model, N datas from a reset episode, and a persistent batch of them."""

    def __init__(self, task: str, num_envs: int, cores: int):
        from mujoco import batch as mujoco_batch

        self.env = manipulation.load(task)
        self.env.reset()
        physics = self.env.physics
        self.model, start = physics.model.ptr, physics.data.ptr
        self.sub_steps = round(self.env.control_timestep() / physics.timestep())
        self.datas = [mujoco.MjData(self.model) for _ in range(num_envs)]
        for data in self.datas:
            mujoco.mj_copyData(data, self.model, start)
        self.batch = mujoco_batch.Batch(
            self.model, nsim=num_envs, nthread=min(num_envs, cores), persistent=True
        )
        self._load_states()
        rng = np.random.default_rng(0)
        low, high = self.model.actuator_ctrlrange.T
        self.controls = rng.uniform(low, high, (50, num_envs, self.model.nu))

    def _load_states(self) -> None:
        for i, data in enumerate(self.datas):
            mujoco.mj_getState(self.model, data, self.batch.state[i], _STATE)
        self.batch.forward(stage=_VEL)

    def identical(self) -> bool:
        """The batch's trajectory against the split step's, from the same states."""
        references = [mujoco.MjData(self.model) for _ in self.datas]
        for reference, data in zip(references, self.datas):
            mujoco.mj_copyData(reference, self.model, data)
        out = mujoco.MjData(self.model)
        ctrl = self.batch.bind("ctrl")
        for controls in self.controls:
            ctrl[:] = controls
            self.batch.step(nstep=self.sub_steps, stage=_VEL)
            for i, reference in enumerate(references):
                reference.ctrl[:] = controls[i]
                _split_step(self.model, reference, self.sub_steps)
                self.batch.get_data(i, out)
                for field in ("qpos", "qvel", "xpos", "site_xpos", "sensordata"):
                    if not np.array_equal(getattr(out, field), getattr(reference, field)):
                        return False
        self._load_states()
        return True

    def split_us(self, steps: int) -> float:
        def one_pass():
            for data in self.datas:
                _split_step(self.model, data, self.sub_steps)

        return _median_us(one_pass, steps, len(self.datas))

    def batch_us(self, steps: int) -> float:
        return _median_us(
            lambda: self.batch.step(nstep=self.sub_steps, stage=_VEL), steps, len(self.datas)
        )

    def copies_us(self, steps: int) -> float:
        batch, model, state = self.batch, self.model, self.batch.state

        def one_pass():
            for i, data in enumerate(self.datas):
                mujoco.mj_getState(model, data, state[i], _STATE)
                batch.get_data(i, data)

        return _median_us(one_pass, steps, len(self.datas))

    def env_step_us(self, steps: int) -> float:
        """The task's composer step, us: its physics and its Python."""
        env, spec = self.env, self.env.action_spec()
        action = np.zeros(spec.shape, spec.dtype)

        def one_step():
            if env.step(action).last():
                env.reset()

        return _median_us(one_step, steps, 1)

    def close(self) -> None:
        self.env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="reach_site_features")
    parser.add_argument("--sizes", default="1,4,8,16,32")
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()
    try:
        from mujoco import batch  # noqa: F401
    except ImportError:
        print(f"mujoco {mujoco.__version__} has no mujoco.batch (MuJoCo 4 and later): skipped")
        return
    cores = os.cpu_count() or 1
    print(
        f"task {args.task}, {cores} cores, 1-minute load average {os.getloadavg()[0]:.2f}; "
        f"{args.steps} steps a pass, medians of 5 passes"
    )
    print(
        "\n| N | identical | split us | batch us | split/batch | copies us | P us "
        "| modelled: serial | GIL bound |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for size in (int(size) for size in args.sizes.split(",")):
        route = _Route(args.task, size, cores)
        try:
            identical = route.identical()
            split, batched = route.split_us(args.steps), route.batch_us(args.steps)
            copies = route.copies_us(args.steps)
            env_step = route.env_step_us(args.steps)
        finally:
            route.close()
        python = max(env_step - split, 0.0)
        serial_python = size * (python + copies)
        batch_call = size * batched
        loop = size * env_step
        print(
            f"| {size} | {'yes' if identical else 'NO'} | {split:.0f} | {batched:.0f} | "
            f"{split / batched:.2f}x | {copies:.1f} | {python:.0f} | "
            f"{loop / (serial_python + batch_call):.2f}x | "
            + ("- |" if size == 1 else f"{loop / serial_python:.2f}x |")
        )
    print(f"\n1-minute load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
