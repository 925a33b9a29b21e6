"""Test-wide set-up: headless rendering through EGL unless the user chose a backend, an empty
cache of patch proofs, a virtual X display for the tests that open windows, recorders of
compiles and resets, and a fresh interpreter for what a process without an optional library
sees."""

import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from collections.abc import Callable

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")

# The virtual screen's size: the viewer's default window (1024x768) fills it.
SCREEN = (1024, 768)


# The MuJoCo Warp tests that compile Warp's kernels shared by every model (minutes on a
# first run): under pytest-xdist they run first, on one worker.
_WARP_WARM_UP = "tests/composer/batch/test_batch_physics.py"


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    if config.pluginmanager.hasplugin("xdist"):
        _order_warp_tests_for_two_workers(items)
    _skip_patches_proven_from_3_17_below_it(items)


def _order_warp_tests_for_two_workers(items):
    """Orders and groups the MuJoCo Warp tests for pytest-xdist's `--dist loadgroup` with
    `--no-loadscope-reorder` (.ci/run), so that no kernel compiles twice at once:

    - the warm-up module's tests first, as one group: one worker compiles the kernels every
      model shares while the other starts on the tests without Warp;
    - every other Warp module last, each module a group (its tests share its tasks'
      kernels and its module fixtures), the largest first: by the time a worker reaches
      them the shared kernels are in the cache, and the modules spread over both workers.

    (pytest 9.2 keeps node ids where xdist 3.8 cannot add the group: pyproject's [test]
    extra holds pytest below it.) Called only where pytest-xdist is loaded."""
    modules: dict[str, list] = {}
    for item in items:
        if "warp" in item.keywords:
            modules.setdefault(item.nodeid.split("::")[0], []).append(item)
    if not modules:
        return
    warm_up = modules.pop(_WARP_WARM_UP if _WARP_WARM_UP in modules else next(iter(modules)))
    last = sorted(modules.values(), key=len, reverse=True)
    for group in [warm_up, *last]:
        for item in group:
            item.add_marker(pytest.mark.xdist_group(group[0].nodeid.split("::")[0]))
    rest = [item for item in items if "warp" not in item.keywords]
    items[:] = warm_up + rest + [item for group in last for item in group]


# The release from which the changes that `patches_from_3_17` tests write in place prove
# equal to a recompile.
_PATCHES_FROM = (3, 17)


def _skip_patches_proven_from_3_17_below_it(items):
    # On older releases (the floor, 3.3.0) the compiler's statistics (stat.center) and the
    # arrays mj_forward leaves unwritten differ from what the patch computes and what these
    # tests compare, so the proofs at first use refuse those changes (the resets recompile,
    # exactly) and what these tests assert patches does not.
    import mujoco

    version = tuple(int(part) for part in mujoco.__version__.split(".")[:2])
    if version >= _PATCHES_FROM:
        return
    skip = pytest.mark.skip(
        reason=f"asserts patches proven from mujoco 3.17 on; on {mujoco.__version__} the "
        "proofs refuse them (statistics and unwritten forward arrays differ) and resets recompile"
    )
    for item in items:
        if "patches_from_3_17" in item.keywords:
            item.add_marker(skip)


def pytest_addoption(parser):
    parser.addoption(
        "--patch-table-elsewhere",
        action="store_true",
        help="pretend that the checked-in patch table (mjcf/patching/patchable_attributes.py) "
        "was proven on another MuJoCo release, so that every patch is proven at first use "
        "(.ci/run runs the patching tests so, beside the default run)",
    )


def pytest_configure(config):
    # An empty cache of patch proofs for the session, as a new user has (each xdist worker
    # its own): nothing a test proves reaches the user's cache, and no test relies on what
    # an earlier run cached.
    config._composer_cache = tempfile.mkdtemp(prefix="composer-test-cache-")
    os.environ["XDG_CACHE_HOME"] = config._composer_cache
    if config.getoption("--patch-table-elsewhere"):
        from mjcf.patching import patchable_attributes

        patchable_attributes.MUJOCO_VERSION = "0.0.0-elsewhere"


def pytest_unconfigure(config):
    shutil.rmtree(getattr(config, "_composer_cache", ""), ignore_errors=True)


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


@pytest.fixture
def compiles(monkeypatch) -> list:
    """The MJCF roots compiled from now on by `mjcf.patching.compiled_model.CompiledModel`
    (and so by `composer.Environment`), in order."""
    from mjcf.patching import compiled_model

    calls = []
    original = compiled_model.compile_mjcf_model

    def recording(root):
        calls.append(root)
        return original(root)

    monkeypatch.setattr(compiled_model, "compile_mjcf_model", recording)
    return calls


@pytest.fixture
def physics_resets(monkeypatch) -> list:
    """The Physics reset afresh from now on (`Physics.reset`, not a copy of kept data)."""
    from mujoco_physics import engine

    calls = []
    original = engine.Physics.reset

    def recording(self, *args, **kwargs):
        calls.append(self)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(engine.Physics, "reset", recording)
    return calls


@pytest.fixture
def fresh_python() -> Callable[[str], subprocess.CompletedProcess]:
    """Runs a snippet of Python (dedented) in a new interpreter whose environment holds only
    `MUJOCO_GL=egl`, an empty PATH and the session's cache directory; returns the finished
    process, its output as text.

    For what importing a package does, or what a missing optional library looks like
    (`sys.modules[name] = None` in the snippet), where this process has already imported it.
    """

    def run(code: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-c", textwrap.dedent(code)],
            capture_output=True,
            text=True,
            check=False,
            env={"MUJOCO_GL": "egl", "PATH": "", "XDG_CACHE_HOME": os.environ["XDG_CACHE_HOME"]},
        )

    return run
