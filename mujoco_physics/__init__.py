"""The engine layer: dm_control's `dm_control.mujoco` on the official MuJoCo bindings.

`import mujoco_physics` replaces `from dm_control import mujoco`: `Physics` (built from XML,
a binary or a model, with `named` indexing, `reset_context`, `render`, ...),
`action_spec`, the `wrapper` structs and `mjbindings` aliases, `index` and `math`.
It knows nothing of MJCF elements; `mjcf.Physics` builds on it. It cannot be named
`mujoco`, which is the official bindings it wraps. As in dm_control, the `mujoco`
module's own names are available here too (`mujoco_physics.mj_step`).
"""

# Before anything imports mujoco, which reads MUJOCO_GL once: a headless Linux machine
# renders with EGL (see `_gl_backend`).
from mujoco_physics import _gl_backend

_gl_backend.default_to_headless()

from mujoco_physics import version  # noqa: E402

# Before any module that reads the installed MuJoCo's tables: an unsupported release gets
# one clear ImportError.
version.check_version()

from mujoco import *  # noqa: E402, F403  (dm_control.mujoco re-exports the bindings)

from mujoco_physics import (  # noqa: E402
    engine,
    index,
    math,
    wrapper,
)
from mujoco_physics.engine import *  # noqa: E402, F403  (Physics, the cameras, action_spec)

__all__ = [*engine.__all__, "index", "math", "wrapper"]
