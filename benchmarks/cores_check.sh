#!/usr/bin/env bash
# The vector envs on every core of a machine, in one call of at most 9.5 minutes: the anchors'
# table (a loop, Gymnasium's AsyncVectorEnv and SyncVectorEnv, the threaded env and the
# lock-step ceiling) for reach_site_features at N = 1 to 64 and reach_site_vision at N = 1
# to 16 (its frames render with EGL), then the threaded env's profile (hand-offs, waits,
# renders in flight; the speed at N = 32 with 2 to 16 threads, and vision's at N = 16 with
# 1 to 16 renders allowed at once), and what stepping the physics of all sub-environments
# in one mujoco.batch call would give, and the CPU batch (device="cpu") with raw
# mujoco.batch at N = 64 to 4,096 on 1 to 16 C threads. Prints the tables and, when $OUT is
# set, writes each under $OUT too.
#
# Usage: bash benchmarks/cores_check.sh
# Set-up, the first that applies:
#   .whl/*.whl   wheels for the machine's python3 (mujoco, gymnasium, dm-env and what
#                they need that the machine lacks), installed offline into a scratch
#                folder; the project runs from this tree. Fetch them on any machine with
#                `pip download --only-binary=:all: --python-version X.Y --platform ...
#                -d .whl mujoco gymnasium dm-env`.
#   .venv        a virtual environment with the project and its [gym] extra.
#   neither      makes .venv and installs the project with [gym] from the package index.
# EGL: where the machine lacks libEGL, carry Debian packages of it in .gl/ (libegl1,
# libglvnd0, libopengl0, libgl1, libglx0, libgles2); they are unpacked into / first.
set -uo pipefail
cd "$(dirname "$0")/.."

if compgen -G ".gl/*.deb" >/dev/null; then
  for deb in .gl/*.deb; do dpkg -x "$deb" /; done
  ldconfig
fi
nvidia_egl=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
[ -f "$nvidia_egl" ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$nvidia_egl

if compgen -G ".whl/*.whl" >/dev/null; then
  site=$(mktemp -d)
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir \
    --target "$site" .whl/*.whl || exit 1
  export PYTHONPATH="$site:$PWD"
  python=python3
else
  if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
    .venv/bin/python -m pip install -q -e ".[gym]"
  fi
  python=.venv/bin/python
fi
export MUJOCO_GL=egl PYTHONUNBUFFERED=1

out=${OUT:-$(mktemp -d)}
echo "cores: $(nproc), load: $(cut -d' ' -f1 /proc/loadavg)"
$python -c "import mujoco, numpy, gymnasium
print('mujoco', mujoco.__version__, 'numpy', numpy.__version__, 'gymnasium', gymnasium.__version__)"

# Each part has its own time limit (580 s in all).
echo "== vector envs on $(nproc) cores: features"
timeout 150 $python benchmarks/vector_env.py --tasks reach_site_features \
  --sizes 1,4,8,16,32,64 --repeats 3 --steps 20 --no-ray 2>&1 | tee "$out/features.txt"
echo "== vector envs on $(nproc) cores: vision"
timeout 100 $python benchmarks/vector_env.py --tasks reach_site_vision --no-overhead \
  --sizes 1,4,8,16 --repeats 2 --steps 10 --no-ray 2>&1 | tee "$out/vision.txt"
echo "== where the threaded env's time goes"
timeout 120 $python benchmarks/vector_env_profile.py --sizes 4,16,32 --steps 20 2>&1 \
  | tee "$out/profile.txt"
echo "== the threaded vision env: renders in flight, and capped, on $(nproc) threads"
timeout 60 $python benchmarks/vector_env_profile.py --task reach_site_vision --sizes 16 \
  --steps 10 --no-switch-intervals --no-thread-counts 2>&1 | tee "$out/profile_vision.txt"
echo "== a shard's physics in one call (mujoco.batch): parts measured, whole modelled"
timeout 40 $python benchmarks/batch_physics_route.py --sizes 1,4,8,16,32,64 2>&1 \
  | tee "$out/batch_physics_route.txt"
echo "== the CPU batch (mujoco.batch) on 1 to 16 C threads"
timeout 110 $python benchmarks/cpu_batch.py --tasks reach_site_features,lift_brick_features \
  --sizes 64,256,1024,4096 --threads 1,2,4,8,16 --scaling-only --repeats 1 \
  --scaling-steps 5 --state-workers 8 2>&1 | tee "$out/cpu_batch_threads.txt"
