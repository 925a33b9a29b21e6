#!/usr/bin/env bash
# The GPU check, in one call on a machine with an NVIDIA GPU, in about 6 minutes: the warp
# tests on cuda:0 and the batch benchmark at 1,024 to 8,192 worlds beside raw MuJoCo Warp and
# the CPU ceiling (raw mj_step on all cores). Prints the tables; each part has its own time
# limit (in all 320 s at most). The vector envs' tables on all of the machine's cores are
# benchmarks/cores_check.sh, a call of their own.
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

echo "kernel cache: $(cuda_binaries) CUDA binaries after the run (more: some compiled here)"
