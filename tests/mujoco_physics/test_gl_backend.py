"""Rendering picks EGL on a headless Linux machine, and says which MUJOCO_GL to try where
no OpenGL backend works, instead of aborting the process."""

import os
import subprocess
import sys
import textwrap

import pytest

from mujoco_physics import _gl_backend

pytestmark = pytest.mark.skipif(
    sys.platform != "linux", reason="MUJOCO_GL is chosen for a display-less Linux machine"
)

# What a headless shell has: no display, and none of the variables that pick a backend.
_CHOOSERS = ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")


def _run(code: str, **environ: str) -> subprocess.CompletedProcess:
    env = {name: value for name, value in os.environ.items() if name not in _CHOOSERS}
    env.update(environ)
    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=False,
        env=env,
        timeout=300,
    )


_RENDER_TWICE = textwrap.dedent(
    """
    import gymnasium
    import manipulation

    env = gymnasium.make(
        "composer/reach_site_features-v0", render_mode="rgb_array", width=64, height=48
    )
    env.reset(seed=0)
    for _ in range(2):
        try:
            frame = env.render()
        except RuntimeError as error:
            print("RuntimeError:", error)
        else:
            print(frame.shape, frame.dtype, len(set(frame.reshape(-1).tolist())) > 1)
    """
)


def test_gymnasium_make_renders_twice_without_mujoco_gl_or_a_display():
    result = _run(_RENDER_TWICE + "print(__import__('os').environ['MUJOCO_GL'])\n")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == ["(48, 64, 3) uint8 True"] * 2 + ["egl"]


def test_mujoco_imported_first_gives_a_clear_error_at_every_render_not_an_abort():
    # mujoco chose GLFW before this project could ask for EGL; a second render must not
    # abort the process as MuJoCo's second attempt at a context does.
    result = _run("import mujoco\n" + _RENDER_TWICE)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 2 and lines[0] == lines[1]
    assert lines[0].startswith(
        "RuntimeError: cannot render: MuJoCo renders with GLFW (MUJOCO_GL unset), which "
        "needs a display, and neither DISPLAY nor WAYLAND_DISPLAY is set; `mujoco` was "
        "imported before this project could set MUJOCO_GL=egl."
    )
    assert "MUJOCO_GL=egl" in lines[0] and "MUJOCO_GL=osmesa" in lines[0]


def test_an_egl_context_that_cannot_be_made_gives_an_error_naming_mujoco_gl():
    result = _run(_RENDER_TWICE, MUJOCO_GL="egl", MUJOCO_EGL_DEVICE_ID="99")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 2
    for line in lines:
        assert line.startswith(
            "RuntimeError: cannot render: MuJoCo renders with EGL (MUJOCO_GL='egl'), which "
            "could not make an OpenGL context (The MUJOCO_EGL_DEVICE_ID"
        )
        assert "MUJOCO_GL=osmesa (software rendering" in line


@pytest.mark.parametrize(
    "environ, expected",
    [
        ({}, "egl"),
        ({"MUJOCO_GL": "glfw"}, "glfw"),  # the user's choice stays
        ({"DISPLAY": ":0"}, None),  # a display: mujoco's own default, GLFW
        ({"WAYLAND_DISPLAY": "wayland-0"}, None),
        ({"PYOPENGL_PLATFORM": "osmesa"}, None),  # EGL would refuse to load
    ],
)
def test_importing_the_package_sets_mujoco_gl_only_when_headless_and_unset(environ, expected):
    result = _run("import os, composer; print(os.environ.get('MUJOCO_GL'))", **environ)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == str(expected)


def test_mujoco_gl_stays_unset_when_the_egl_library_does_not_load(monkeypatch):
    for name in _CHOOSERS:
        monkeypatch.delenv(name, raising=False)
    # As before the first `import mujoco`, with libEGL missing.
    monkeypatch.delitem(sys.modules, "mujoco")
    monkeypatch.setattr(_gl_backend, "_loads", lambda names: "libEGL.so.1" not in names)
    monkeypatch.setattr(_gl_backend, "_not_defaulted", None)
    _gl_backend.default_to_headless()
    assert "MUJOCO_GL" not in os.environ
    assert "EGL or OpenGL library" in _gl_backend._not_defaulted
