"""MuJoCo's OpenGL backend: chosen so that a headless Linux machine renders, or says why not.

`mujoco` reads the `MUJOCO_GL` environment variable once, when it is imported, and takes
its `GLContext` from it: 'egl' or 'osmesa' render without a display, 'glfw' (also what an
unset variable gives) opens a hidden window and needs one. dm_control's renderer, when
`MUJOCO_GL` is unset, tries GLFW, EGL and OSMesa in turn and keeps the first that loads;
GLFW does not load without a display, so a headless machine gets EGL. The same choice is
made here, in two places:

- `default_to_headless()` runs first thing in `mujoco_physics/__init__.py` (`mjcf` and
  `composer` import `mujoco_physics` before anything else for this): on Linux, when
  neither `MUJOCO_GL` nor a display (`DISPLAY`, `WAYLAND_DISPLAY`) is set, it sets
  `MUJOCO_GL=egl`, if the EGL and OpenGL libraries load (without them `import mujoco`
  itself would fail with MUJOCO_GL=egl) and `PYOPENGL_PLATFORM` is unset or 'egl' (EGL
  refuses any other). Once `mujoco` is imported the variable no longer matters, so then
  it does nothing.
- `new_renderer()` makes this package's `mujoco.Renderer`s. Where no OpenGL context can be
  made (GLFW without a display, EGL without a device, a backend's library missing) it
  raises a `RuntimeError` naming `MUJOCO_GL` and the values to try. MuJoCo itself raises a
  `FatalError` there, and aborts the process when a renderer is made again after one.

This module imports `mujoco` only inside `new_renderer`: it is imported before `mujoco`.
"""

from __future__ import annotations

import ctypes
import os
import sys
import warnings
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import mujoco

#: The values of `MUJOCO_GL` to suggest, each with what it needs.
_VALUES_TO_TRY = (
    "MUJOCO_GL=egl (a GPU's or Mesa's EGL, no display needed), MUJOCO_GL=osmesa "
    "(software rendering, needs libOSMesa) or MUJOCO_GL=glfw (needs a display)"
)

_BACKEND_NAMES = {"glfw": "GLFW", "egl": "EGL", "osmesa": "OSMesa", "cgl": "CGL", "wgl": "WGL"}

# The libraries `mujoco`'s EGL backend loads (through PyOpenGL): EGL, and OpenGL or GL.
_EGL_LIBRARIES = (("libEGL.so.1", "libEGL.so"), ("libOpenGL.so.0", "libGL.so.1", "libGL.so"))

# Why `default_to_headless` left MUJOCO_GL unset on a machine without a display.
_not_defaulted: str | None = None
# Set once GLFW started: it stays started for the life of the process.
_glfw_started = False
# Set once MuJoCo raised FatalError making a context: a second try aborts the process.
_fatal_error: str | None = None


def has_display() -> bool:
    """Whether an X11 or Wayland display is named in the environment."""
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def default_to_headless() -> None:
    """Sets `MUJOCO_GL=egl` where rendering needs it and `mujoco` would not choose it.

    Only on Linux, only when `MUJOCO_GL` is unset (or empty) and no display is named, only
    before `mujoco` is imported (which reads the variable once), and only if EGL can work.
    """
    global _not_defaulted
    if sys.platform != "linux" or os.environ.get("MUJOCO_GL", "").strip() or has_display():
        return
    platform = os.environ.get("PYOPENGL_PLATFORM", "").strip()
    if "mujoco" in sys.modules:
        _not_defaulted = "`mujoco` was imported before this project could set MUJOCO_GL=egl"
    elif platform and platform.lower() != "egl":
        _not_defaulted = f"PYOPENGL_PLATFORM={platform!r} rules out MUJOCO_GL=egl"
    elif not all(_loads(names) for names in _EGL_LIBRARIES):
        _not_defaulted = "the EGL or OpenGL library, which MUJOCO_GL=egl needs, does not load"
    else:
        os.environ["MUJOCO_GL"] = "egl"


def _loads(names: tuple[str, ...]) -> bool:
    """Whether one of the shared libraries `names` loads."""
    for name in names:
        try:
            ctypes.CDLL(name, mode=ctypes.RTLD_GLOBAL)
        except OSError:
            continue
        return True
    return False


def new_renderer(model: mujoco.MjModel, height: int, width: int, **kwargs) -> mujoco.Renderer:
    """`mujoco.Renderer(model, height=height, width=width, **kwargs)`, with a clear error
    where MuJoCo's OpenGL backend cannot render.

    Raises:
      RuntimeError: if no OpenGL context can be made with the backend `mujoco` chose; the
        message names `MUJOCO_GL`, why it failed and the values to try.
      ValueError: as `mujoco.Renderer`, for an image larger than the off-screen buffer.
    """
    global _fatal_error
    import mujoco  # imported by now; not at the top (see the module docstring)

    if _fatal_error is not None:
        raise RuntimeError(_fatal_error)
    backend = _backend(mujoco)
    reason = _why_unusable(backend)
    if reason is not None:
        raise RuntimeError(_message(backend, reason))
    try:
        return mujoco.Renderer(model, height=height, width=width, **kwargs)
    except mujoco.FatalError as error:
        _fatal_error = _message(backend, f"could not make an OpenGL context ({error})")
        raise RuntimeError(_fatal_error) from error
    except (ImportError, RuntimeError) as error:
        message = _message(backend, f"could not make an OpenGL context ({error})")
        raise RuntimeError(message) from error


def _backend(mujoco) -> str | None:
    """The backend `mujoco` chose when imported ('glfw', 'egl', ...), None when disabled."""
    context = getattr(mujoco, "GLContext", None)
    if context is None:
        return None
    # mujoco.glfw.GLContext, mujoco.egl.GLContext, ...; a placeholder class of mujoco's
    # gl_context module when the backend's library failed to load.
    module = context.__module__.rsplit(".", 1)[-1]
    return os.environ.get("MUJOCO_GL", "").strip().lower() if module == "gl_context" else module


def _why_unusable(backend: str | None) -> str | None:
    """Why no context can be made with `backend`, where that is known beforehand."""
    global _glfw_started
    if backend is None:
        return "turns rendering off"
    if backend != "glfw" or _glfw_started or sys.platform != "linux":
        return None
    if not has_display():
        reason = "needs a display, and neither DISPLAY nor WAYLAND_DISPLAY is set"
        if _not_defaulted is not None and not os.environ.get("MUJOCO_GL", "").strip():
            reason += f"; {_not_defaulted}"
        return reason
    import glfw  # comes with mujoco; imported only for this backend

    # GLFW reports why it cannot start as warnings; they go into the message instead.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        started = glfw.init()
    if not started:
        reasons = "; ".join(str(warning.message) for warning in caught) or "no reason given"
        display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
        return f"could not open the display {display!r} ({reasons})"
    _glfw_started = True
    return None


def _message(backend: str | None, reason: str) -> str:
    value = os.environ.get("MUJOCO_GL", "").strip()
    setting = f"MUJOCO_GL={value!r}" if value else "MUJOCO_GL unset"
    if backend is None:
        chosen = f"{setting} turns MuJoCo's rendering off"
    else:
        name = _BACKEND_NAMES.get(backend, backend)
        chosen = f"MuJoCo renders with {name} ({setting}), which {reason}"
    return (
        f"cannot render: {chosen}. Set MUJOCO_GL before Python imports mujoco (in the "
        f"shell: `MUJOCO_GL=egl python ...`): {_VALUES_TO_TRY}"
    )
