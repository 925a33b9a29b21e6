"""The batch tests: Warp's kernel cache under the repository's .cache/, and tests marked
`warp` skipped, with the reason printed, when MuJoCo Warp is not installed."""

import os
import pathlib

import pytest

from composer.batch import _warp

_REPOSITORY = pathlib.Path(__file__).resolve().parents[3]
os.environ.setdefault(_warp.KERNEL_CACHE_ENV, str(_REPOSITORY / ".cache" / "warp"))

_SKIP = pytest.mark.skip(reason="needs MuJoCo Warp: pip install -e '.[warp]'")


def pytest_collection_modifyitems(config, items):
    if _warp.is_available():
        return
    for item in items:
        if "warp" in item.keywords:
            item.add_marker(_SKIP)
