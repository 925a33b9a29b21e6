"""Test-wide set-up: headless rendering through EGL unless the user chose a backend."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
