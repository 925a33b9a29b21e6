#!/usr/bin/env bash
# The GPU check, in one call on a machine with an NVIDIA GPU, in about 8 minutes: the warp
# tests on cuda:0, the batch benchmark at 1,024 to 8,192 worlds beside raw MuJoCo Warp and
# the CPU ceiling (raw mj_step on all cores), then the vector envs' tables on all cores
# (features N up to 64, vision up to 16) and the threaded env's profile (features, and
# vision's renders in flight). Prints the tables; each part has its own time limit (in
# all 490 s at most).
#
# Usage: bash benchmarks/gpu_check.sh
# Set-up: uses .venv when it exists (carry it to the machine), else makes one and installs
# the project with the extras [warp,test] and torch (CUDA task code runs on torch), from
# whatever package index the machine reaches.
# Kernel cache: a cold compile of MuJoCo Warp's CUDA kernels takes minutes per model. Build
# them beforehand on any machine (no GPU needed), with the same Warp and MuJoCo Warp, and
# carry .cache/warp along:
#   python -m manipulation.batch.kernel_cache --task reach_site_features \
#     --task lift_brick_features --arch sm_90 --out .cache/warp
set -uo pipefail
cd "$(dirname "$0")/.."

if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
  .venv/bin/python -m pip install -q -e ".[warp,test]" torch
fi
. .venv/bin/activate
export COMPOSER_WARP_KERNEL_CACHE=.cache/warp MUJOCO_GL=egl
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader || true
echo "cores: $(nproc), load: $(cut -d' ' -f1 /proc/loadavg)"
cuda_binaries() { find .cache/warp \( -name '*.cubin' -o -name '*.ptx' \) 2>/dev/null | wc -l; }
echo "kernel cache: $(cuda_binaries) CUDA binaries in .cache/warp before the run"

# The tests that build their batches on the default device, which is cuda:0 here; the
# others pin Warp's CPU device.
echo "== warp tests on cuda:0"
timeout 120 python -m pytest -q -p no:cacheprovider -m warp tests/composer/batch/test_batch_device.py \
  tests/composer/batch/test_batch_equivalence.py tests/composer/batch/test_batch_gym.py | tail -15

echo "== batch benchmark on cuda:0"
timeout 200 python benchmarks/batch_env.py --device cuda:0 --num-envs 1024,4096,8192 \
  --steps 50 --baselines --producer-states 256

# The anchors in one run: loop, Gymnasium's Async and Sync vector envs, the threaded env
# and the lock-step ceiling; features first, then vision (its frames render on the GPU).
echo "== vector envs on $(nproc) cores: features"
timeout 60 python benchmarks/vector_env.py --tasks reach_site_features \
  --sizes 1,4,8,16,32,64 --repeats 3 --steps 20 --no-ray
echo "== vector envs on $(nproc) cores: vision"
timeout 40 python benchmarks/vector_env.py --tasks reach_site_vision --no-overhead \
  --sizes 1,4,8,16 --repeats 2 --steps 10 --no-ray
echo "== where the threaded env's time goes"
timeout 30 python benchmarks/vector_env_profile.py --sizes 4,16,32 --steps 20
echo "== the threaded vision env: renders in flight at once on $(nproc) threads"
timeout 40 python benchmarks/vector_env_profile.py --task reach_site_vision --sizes 16 --steps 10 \
  --no-switch-intervals

echo "kernel cache: $(cuda_binaries) CUDA binaries after the run (more: some compiled here)"
