"""The ahead-of-time kernel cache: its command reads CUDA architectures as NVIDIA writes
them, refuses others by name, and records what a batch launches with CUDA's block sizes."""

import argparse

import pytest

from manipulation.batch.kernel_cache import parse_arch


@pytest.mark.parametrize("text", ["sm_90", "sm90", "90"])
def test_architecture_reads_with_or_without_sm(text):
    assert parse_arch(text) == 90


def test_architecture_that_is_not_one_is_refused_by_name():
    with pytest.raises(argparse.ArgumentTypeError, match=r"sm_90, got 'hopper'"):
        parse_arch("hopper")


@pytest.mark.warp
def test_recorded_launches_use_cudas_block_size():
    from composer.batch import _warp
    from composer.batch.kernel_cache import recorded_launches

    wp = _warp.load().warp

    @wp.kernel(module="unique")
    def add_one(values: wp.array(dtype=wp.float32)):
        values[wp.tid()] += 1.0

    values = wp.zeros(4, dtype=wp.float32, device="cpu")
    with recorded_launches() as launched:
        wp.launch(add_one, dim=4, inputs=[values], device="cpu")
        wp.launch(add_one, dim=4, inputs=[values], device="cpu", block_dim=64)
    # On the CPU device both run one thread per block; CUDA would use 256 and 64.
    assert sorted(block for _, block in launched.values()) == [64, 256]
    assert values.numpy().tolist() == [2.0] * 4


@pytest.mark.warp
def test_an_architecture_nvrtc_lacks_is_refused_with_the_list():
    from composer.batch.kernel_cache import build_cuda_cache

    with pytest.raises(ValueError, match=r"arch: expected one of NVRTC's architectures \[.*got 12"):
        build_cuda_cache(lambda: None, arch=12)
