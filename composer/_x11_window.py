"""Retitles and resizes this process's MuJoCo viewer window through its own X11 connection.

MuJoCo's passive viewer creates its GLFW window in a thread it keeps to itself, with a title
("MuJoCo : <model name>") and a size (2/3 of the screen) the Python API cannot set, and GLFW
calls are only safe on the thread that owns the window. So the window is found and changed
from outside GLFW: a separate Xlib connection (used by the calling thread alone) looks for
the top-level window whose `_NET_WM_PID` is this process and whose name is the viewer's,
then sets its title and size. GLFW sees the new size as an ordinary resize event. On
anything but X11 (Wayland without XWayland, macOS) `retitle_and_resize` says so instead.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import time

# The viewer names its window "MuJoCo : <model name>" once the model is loaded.
_VIEWER_TITLE_PREFIX = b"MuJoCo : "
# How long to wait for the viewer to have named its window.
_FIND_TIMEOUT = 2.0

_XA_CARDINAL = 6
_PROP_MODE_REPLACE = 0
_ANY_PROPERTY_TYPE = 0

_ERROR_HANDLER = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p)
_xlib = None
_previous_error_handler = None
_our_display = ctypes.c_void_p()


@_ERROR_HANDLER
def _ignore_our_errors(display, event):
    # A window that disappears while it is being looked at (BadWindow) must not end the
    # process, which is what Xlib's default handler does; errors on other connections
    # (GLFW's) go to the handler that was there before.
    if display == _our_display.value or _previous_error_handler is None:
        return 0
    return _previous_error_handler(display, event)


def _load_xlib():
    global _xlib, _previous_error_handler
    if _xlib is not None:
        return _xlib
    path = ctypes.util.find_library("X11")
    if path is None:
        raise OSError("libX11 was not found")
    xlib = ctypes.CDLL(path)
    ptr, ulong = ctypes.c_void_p, ctypes.c_ulong
    xlib.XOpenDisplay.restype = ptr
    xlib.XOpenDisplay.argtypes = [ctypes.c_char_p]
    xlib.XCloseDisplay.argtypes = [ptr]
    xlib.XDefaultRootWindow.restype = ulong
    xlib.XDefaultRootWindow.argtypes = [ptr]
    xlib.XInternAtom.restype = ulong
    xlib.XInternAtom.argtypes = [ptr, ctypes.c_char_p, ctypes.c_int]
    xlib.XQueryTree.argtypes = (
        [ptr, ulong]
        + [ctypes.POINTER(ulong)] * 2
        + [
            ctypes.POINTER(ctypes.POINTER(ulong)),
            ctypes.POINTER(ctypes.c_uint),
        ]
    )
    xlib.XGetWindowProperty.argtypes = [
        ptr,
        ulong,
        ulong,
        ctypes.c_long,
        ctypes.c_long,
        ctypes.c_int,
        ulong,
        ctypes.POINTER(ulong),
        ctypes.POINTER(ctypes.c_int),
        ctypes.POINTER(ulong),
        ctypes.POINTER(ulong),
        ctypes.POINTER(ctypes.c_void_p),
    ]
    xlib.XFetchName.argtypes = [ptr, ulong, ctypes.POINTER(ctypes.c_char_p)]
    xlib.XFree.argtypes = [ptr]
    xlib.XChangeProperty.argtypes = [
        ptr,
        ulong,
        ulong,
        ulong,
        ctypes.c_int,
        ctypes.c_int,
        ctypes.c_char_p,
        ctypes.c_int,
    ]
    xlib.XStoreName.argtypes = [ptr, ulong, ctypes.c_char_p]
    xlib.XResizeWindow.argtypes = [ptr, ulong, ctypes.c_uint, ctypes.c_uint]
    xlib.XSync.argtypes = [ptr, ctypes.c_int]
    xlib.XSetErrorHandler.restype = ctypes.c_void_p
    xlib.XSetErrorHandler.argtypes = [_ERROR_HANDLER]
    previous = xlib.XSetErrorHandler(_ignore_our_errors)
    _previous_error_handler = _ERROR_HANDLER(previous) if previous else None
    _xlib = xlib
    return xlib


def _children(xlib, display, window) -> list[int]:
    root, parent = ctypes.c_ulong(), ctypes.c_ulong()
    children = ctypes.POINTER(ctypes.c_ulong)()
    count = ctypes.c_uint()
    if not xlib.XQueryTree(
        display, window, ctypes.byref(root), ctypes.byref(parent), children, count
    ):
        return []
    found = [children[i] for i in range(count.value)]
    if children:
        xlib.XFree(children)
    return found


def _pid(xlib, display, window, pid_atom) -> int | None:
    actual_type, actual_format = ctypes.c_ulong(), ctypes.c_int()
    items, after, value = ctypes.c_ulong(), ctypes.c_ulong(), ctypes.c_void_p()
    status = xlib.XGetWindowProperty(
        display,
        window,
        pid_atom,
        0,
        1,
        0,
        _XA_CARDINAL,
        actual_type,
        actual_format,
        items,
        after,
        value,
    )
    if status != 0 or not value.value:
        return None
    try:
        # Format-32 properties come back as an array of C longs.
        return ctypes.cast(value, ctypes.POINTER(ctypes.c_long))[0] if items.value else None
    finally:
        xlib.XFree(value)


def _name(xlib, display, window) -> bytes:
    name = ctypes.c_char_p()
    if not xlib.XFetchName(display, window, ctypes.byref(name)) or name.value is None:
        return b""
    value = name.value
    xlib.XFree(ctypes.cast(name, ctypes.c_void_p))
    return value


def _viewer_windows(xlib, display) -> list[int]:
    """This process's top-level windows named by the viewer (under a window manager too)."""
    pid_atom = xlib.XInternAtom(display, b"_NET_WM_PID", 0)
    root = xlib.XDefaultRootWindow(display)
    found = []
    for top in _children(xlib, display, root):
        # A reparenting window manager puts the client window one level down.
        for window in [top, *_children(xlib, display, top)]:
            if _pid(xlib, display, window, pid_atom) == os.getpid() and _name(
                xlib, display, window
            ).startswith(_VIEWER_TITLE_PREFIX):
                found.append(window)
    return found


def retitle_and_resize(title: str, width: int, height: int) -> None:
    """Gives the viewer window of this process `title` and a `width` x `height` size.

    Raises:
      OSError: not on X11 (no `DISPLAY`, no libX11), or no viewer window was found.
    """
    if not os.environ.get("DISPLAY"):
        raise OSError("DISPLAY is not set (not an X11 session)")
    xlib = _load_xlib()
    display = xlib.XOpenDisplay(None)
    if not display:
        raise OSError(f"cannot open X display {os.environ['DISPLAY']!r}")
    _our_display.value = display
    try:
        deadline = time.monotonic() + _FIND_TIMEOUT
        windows = _viewer_windows(xlib, display)
        while not windows and time.monotonic() < deadline:
            time.sleep(0.02)
            windows = _viewer_windows(xlib, display)
        if not windows:
            raise OSError("no window of this process is named 'MuJoCo : ...'")
        encoded = title.encode("utf-8")
        utf8 = xlib.XInternAtom(display, b"UTF8_STRING", 0)
        net_wm_name = xlib.XInternAtom(display, b"_NET_WM_NAME", 0)
        for window in windows:
            xlib.XStoreName(display, window, title.encode("latin-1", "replace"))
            xlib.XChangeProperty(
                display, window, net_wm_name, utf8, 8, _PROP_MODE_REPLACE, encoded, len(encoded)
            )
            xlib.XResizeWindow(display, window, width, height)
        xlib.XSync(display, 0)
    finally:
        xlib.XCloseDisplay(display)
        _our_display.value = None
