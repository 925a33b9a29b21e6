"""Batched environments on MuJoCo Warp against raw batched stepping and the CPU, in one run.

Task: manipulation `lift_brick_features` (or `--task`), 20 physics steps per control step.
Throughputs are environment steps (control steps of one world) per second.

Rows, for each num_envs:
  batch: `composer.batch.BatchEnvironment.step` with zero actions (observations, rewards,
    time limits and autoreset included).
  raw warp: the same model on the same device, `mujoco_warp.step` n_sub_steps times per
    control step, nothing else: the ceiling. overhead = raw / batch (goal on a GPU: <= 1.3
    at 4096 worlds).
Baselines, on this machine's cores:
  threaded CPU: `gymnasium.make_vec(..., backend='threads')` with one sub-environment per core.
  mj_step ceiling: one thread per core, each calling raw `mujoco.mj_step(m, d, n_sub_steps)` on
    its own MjData, running free. batch / ceiling is the speed-up over the CPU (goal on a GPU:
    >= 2 at the best num_envs).

Usage: python benchmarks/batch_env.py [--device cpu|cuda:0] [--num-envs 1,64,1024,4096]
  [--seconds 3] [--task lift_brick_features] [--array-type numpy|warp|torch|jax]. On Warp's
  CPU device the default num_envs are 1, 16 and 64 (larger batches take minutes per
  measurement there).
"""

import argparse
import os
import pathlib
import sys
import threading
import time

import mujoco
import numpy as np

_HERE = pathlib.Path(__file__).resolve().parent
_REPOSITORY = _HERE.parent
# This folder holds manipulation.py (a benchmark), which would shadow the package.
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]
os.environ.setdefault("COMPOSER_WARP_KERNEL_CACHE", str(_REPOSITORY / ".cache" / "warp"))

import gymnasium  # noqa: E402
import mujoco_warp as mjw  # noqa: E402
import warp as wp  # noqa: E402

import manipulation  # noqa: E402
from manipulation import batch  # noqa: E402


def _rate(step, count: int, seconds: float) -> float:
    """Environment steps per second of `step()` (each `count` env steps), run for `seconds`."""
    step()  # compiles, captures graphs, warms caches
    start = time.perf_counter()
    calls = 0
    while True:
        step()
        calls += 1
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return calls * count / elapsed


def _batch_rows(
    task: str, num_envs: int, device: str, seconds: float, array_type: str
) -> tuple[float, float]:
    env = batch.load(task, num_envs, device=device, seed=0, array_type=array_type)
    env.reset()
    action = np.zeros((num_envs, *env.action_spec().shape))
    physics = env.physics

    def step():
        env.step(action)
        wp.synchronize_device(physics.device)  # device outputs return before they are ready

    batch_rate = _rate(step, num_envs, seconds)
    n_sub_steps = env.task.task.physics_steps_per_control_step
    model, data = physics.warp_model, physics.warp_data
    if physics.is_cuda:
        with wp.ScopedDevice(physics.device):
            mjw.step(model, data)
            with wp.ScopedCapture() as capture:
                for _ in range(n_sub_steps):
                    mjw.step(model, data)

        def raw():
            wp.capture_launch(capture.graph)
            wp.synchronize_device(physics.device)

    else:

        def raw():
            for _ in range(n_sub_steps):
                mjw.step(model, data)

    return batch_rate, _rate(raw, num_envs, seconds)


def _threaded_cpu(task: str, seconds: float) -> float:
    cores = os.cpu_count() or 1
    env = gymnasium.make_vec(
        f"composer/{task}-v0", num_envs=cores, vectorization_mode="vector_entry_point"
    )
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape)
    try:
        return _rate(lambda: env.step(action), cores, seconds)
    finally:
        env.close()


def _mj_step_ceiling(task: str, seconds: float) -> float:
    cpu_env = manipulation.load(task, seed=0)
    cpu_env.reset()
    model = cpu_env.physics.model.ptr
    n_sub_steps = cpu_env.task.physics_steps_per_control_step
    cores = os.cpu_count() or 1
    counts = [0] * cores
    stop = threading.Event()

    def run(index: int) -> None:
        data = mujoco.MjData(model)
        mujoco.mj_copyData(data, model, cpu_env.physics.data.ptr)
        while not stop.is_set():
            mujoco.mj_step(model, data, n_sub_steps)
            counts[index] += 1

    threads = [threading.Thread(target=run, args=(i,)) for i in range(cores)]
    start = time.perf_counter()
    for thread in threads:
        thread.start()
    time.sleep(seconds)
    stop.set()
    for thread in threads:
        thread.join()
    return sum(counts) / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cpu", help="Warp device: cpu or cuda:0")
    parser.add_argument("--num-envs", default=None, help="comma-separated numbers of worlds")
    parser.add_argument("--seconds", type=float, default=3.0, help="time per measurement")
    parser.add_argument("--task", default="lift_brick_features", choices=batch.BATCHED)
    parser.add_argument(
        "--array-type", default="numpy", help="what the batch hands out: numpy, warp, torch, jax"
    )
    args = parser.parse_args()
    default_sizes = "1,16,64" if args.device == "cpu" else "1,64,1024,4096,8192"
    sizes = [int(n) for n in (args.num_envs or default_sizes).split(",")]

    threaded = _threaded_cpu(args.task, args.seconds)
    ceiling = _mj_step_ceiling(args.task, args.seconds)
    print(
        f"task {args.task}, device {args.device}, array_type {args.array_type}, "
        f"{os.cpu_count()} cores, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    print(f"{'num_envs':>8} {'batch/s':>10} {'raw warp/s':>11} {'overhead':>9} {'vs ceiling':>11}")
    for num_envs in sizes:
        batch_rate, raw_rate = _batch_rows(
            args.task, num_envs, args.device, args.seconds, args.array_type
        )
        print(
            f"{num_envs:>8} {batch_rate:>10.0f} {raw_rate:>11.0f} {raw_rate / batch_rate:>9.2f} "
            f"{batch_rate / ceiling:>11.2f}"
        )
    print(f"threaded CPU vector env ({os.cpu_count()} sub-envs): {threaded:.0f} env-steps/s")
    print(f"mj_step ceiling ({os.cpu_count()} threads, free): {ceiling:.0f} env-steps/s")


if __name__ == "__main__":
    main()
