"""Batched cameras on MuJoCo Warp: frames per second of the batch renderer, and environment
steps per second of a batched vision task, beside the threaded CPU vision env of this host.

The task is manipulation `lift_brick_vision` (`--task`): its 'front_close' camera, 84x84
RGB, 20 physics steps per control step, zero actions. Throughputs count one world's frame
or one world's control step.

Table 1, the renderer, for each num_envs:
  batch frames/s: `BatchCameras.render` (refit the worlds' bounding volumes, ray trace,
    unpack to uint8) of every world, the worlds in their initial state.
  cpu frames/s: MuJoCo's OpenGL renderer drawing the same camera of one host physics,
    one thread (`Physics.render`, as the CPU camera observable does): the baseline.
Table 2, the environment (unless `--render-only`): `BatchEnvironment.step` of the vision
  task, observations (the images) included, beside the threaded CPU vector env of the same
  task with one sub-environment per core (`gymnasium.make_vec`, `MUJOCO_GL` rendering in
  every thread); batch / threaded is the speed-up (goal on a GPU: >= 10x).

Usage: python benchmarks/batch_cameras.py [--device cpu|cuda:0] [--num-envs 16,64]
  [--steps 10] [--seconds 5] [--render-only] [--no-threaded]
"""

import argparse
import importlib.util
import os
import pathlib
import sys
import time

import numpy as np

_HERE = pathlib.Path(__file__).resolve().parent
_REPOSITORY = _HERE.parent
# This folder holds manipulation.py (a benchmark), which would shadow the package.
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]
os.environ.setdefault("COMPOSER_WARP_KERNEL_CACHE", str(_REPOSITORY / ".cache" / "warp"))
os.environ.setdefault("MUJOCO_GL", "egl")


import manipulation  # noqa: E402
from composer.batch import BatchEnvironment, _warp, arrays  # noqa: E402
from composer.batch.cameras import BatchCameras  # noqa: E402
from composer.batch.physics import BatchPhysics  # noqa: E402
from manipulation import batch as manipulation_batch  # noqa: E402

CAMERA = "front_close"


def _median_rate(work, count: int, repeats: int = 3) -> float:
    """count / the median seconds of `work()` over `repeats` timed calls (after one more)."""
    work()
    times = []
    for _ in range(repeats):
        begin = time.perf_counter()
        work()
        times.append(time.perf_counter() - begin)
    return count / float(np.median(times))


def _renderer_rates(task: str, num_envs: int, device: str, frames: int) -> tuple[float, float]:
    """(batch frames/s, CPU OpenGL frames/s) of the task's camera."""
    cpu_env = manipulation.load(task, seed=0)
    cpu_env.reset()
    host = cpu_env.physics
    camera = cpu_env.task.observables[CAMERA]
    wp = _warp.load().warp
    bridge = arrays.ArrayBridge(wp, wp.get_device(device), "numpy")
    physics = BatchPhysics(host, num_envs, arrays=bridge)
    cameras = BatchCameras({CAMERA: camera}, physics)

    def batch_frames():
        for _ in range(frames):
            cameras.render()
        wp.synchronize_device(physics.device)

    camera_id = host.bind(camera.mjcf_element).element_id

    def cpu_frames():
        for _ in range(frames):
            host.render(camera.height, camera.width, camera_id=camera_id)

    return (
        _median_rate(batch_frames, frames * num_envs),
        _median_rate(cpu_frames, frames),
    )


def _batch_steps(task: str, num_envs: int, device: str, steps: int) -> float:
    env = manipulation_batch.load(task, num_envs, seed=0, device=device)
    assert isinstance(env, BatchEnvironment)
    env.reset()
    action = np.zeros((num_envs, *env.action_spec().shape), np.float32)
    action = env.physics.arrays.asarray(action)

    def run():
        for _ in range(steps):
            env.step(action)
        _warp.load().warp.synchronize_device(env.physics.device)

    try:
        return _median_rate(run, steps * num_envs)
    finally:
        env.close()


def _batch_env():
    """benchmarks/batch_env.py as a module (this folder is not on sys.path, see above)."""
    spec = importlib.util.spec_from_file_location("batch_env", _HERE / "batch_env.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cpu", help="Warp device: cpu or cuda:0")
    parser.add_argument("--num-envs", default=None, help="comma-separated numbers of worlds")
    parser.add_argument("--task", default="lift_brick_vision")
    parser.add_argument("--steps", type=int, default=10, help="frames or steps per timing")
    parser.add_argument("--seconds", type=float, default=5.0, help="threaded timing")
    parser.add_argument("--render-only", action="store_true", help="table 1 only")
    parser.add_argument("--no-threaded", action="store_true", help="leave out the CPU env")
    args = parser.parse_args()
    default = "16,64" if args.device == "cpu" else "1024,4096"
    sizes = [int(n) for n in (args.num_envs or default).split(",")]
    load = os.getloadavg()[0]
    print(
        f"task {args.task}, camera {CAMERA}, device {args.device}, {os.cpu_count()} cores, "
        f"load average {load:.2f}; medians of 3 timings"
    )
    print(f"{'num_envs':>8} {'batch frames/s':>15} {'cpu frames/s':>13} {'ratio':>7}")
    for n in sizes:
        batch_rate, cpu_rate = _renderer_rates(args.task, n, args.device, args.steps)
        print(f"{n:8d} {batch_rate:15.0f} {cpu_rate:13.0f} {batch_rate / cpu_rate:6.1f}x")
    if args.render_only:
        return
    threaded = None
    if not args.no_threaded:
        cores, threaded = (
            os.cpu_count() or 1,
            _batch_env().threaded_cpu_steps(args.task, args.seconds),
        )
        print(f"threaded CPU vision env, {cores} sub-environments: {threaded:.0f} steps/s")
    print(f"{'num_envs':>8} {'batch steps/s':>14} {'batch/threaded':>15}")
    for n in sizes:
        rate = _batch_steps(args.task, n, args.device, args.steps)
        ratio = f"{rate / threaded:14.1f}x" if threaded else f"{'-':>15}"
        print(f"{n:8d} {rate:14.0f} {ratio}")
    print(f"1-minute load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
