"""Test-wide set-up: headless rendering through EGL unless the user chose a backend, and a
virtual X display for the tests that open windows."""

import os
import shutil
import subprocess

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")

# The virtual screen's size: the viewer's default window (1024x768) fills it.
SCREEN = (1024, 768)


def pytest_collection_modifyitems(config, items):
    # The checked-in patch table is proven on one MuJoCo release; on another it does not
    # apply (a proof cached by `python -m mjcf.patch_proof` may), so what it promises is
    # not there to check.
    import mujoco

    from mjcf import patchable_attributes

    if mujoco.__version__ == patchable_attributes.MUJOCO_VERSION:
        return
    skip = pytest.mark.skip(
        reason=f"mjcf/patchable_attributes.py is proven on mujoco "
        f"{patchable_attributes.MUJOCO_VERSION}, not on the installed {mujoco.__version__}"
    )
    for item in items:
        if "patch_table" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def display():
    """Starts Xvfb on a display number it picks itself; yields ':N'. Skips without Xvfb."""
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed (apt-get install xvfb); .ci/run installs it")
    read_end, write_end = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write_end), "-screen", "0", f"{SCREEN[0]}x{SCREEN[1]}x24"]
        + ["-nolisten", "tcp"],
        pass_fds=(write_end,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write_end)
    with os.fdopen(read_end) as numbers:
        number = numbers.readline().strip()
    if not number:
        server.kill()
        pytest.skip(f"Xvfb did not start (exit code {server.wait()})")
    yield f":{number}"
    server.terminate()
    server.wait()
