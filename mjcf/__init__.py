"""PyMJCF-compatible MJCF object model on the official MuJoCo bindings.

`import mjcf` replaces `from dm_control import mjcf`: build models with `mjcf.RootElement()`,
load them with `mjcf.from_path` / `from_xml_string` / `from_file`, compose them with
`attach`, and simulate them with `mjcf.Physics.from_mjcf_model`.
"""

# First: it picks MuJoCo's OpenGL backend before mujoco is imported.
import mujoco_physics  # noqa: F401
from mjcf import mujoco_compat

# Before any module that reads the installed MuJoCo's tables: an unsupported release gets
# one clear ImportError.
mujoco_compat.check_version()

from mjcf import constants, traversal_utils
from mjcf.asset import Asset
from mjcf.constants import PREFIX_SEPARATOR
from mjcf.element import Element, RootElement
from mjcf.export_with_assets import export_with_assets, export_with_assets_as_zip
from mjcf.parser import from_file, from_path, from_xml_string, from_zip
from mjcf.traversal_utils import (
    commit_defaults,
    get_attachment_frame,
    get_frame_freejoint,
    get_frame_joints,
    get_freejoint,
)

__all__ = [
    "PREFIX_SEPARATOR",
    "Asset",
    "Element",
    "Physics",
    "PhysicsError",
    "RootElement",
    "commit_defaults",
    "constants",
    "export_with_assets",
    "export_with_assets_as_zip",
    "from_file",
    "from_path",
    "from_xml_string",
    "from_zip",
    "get_attachment_frame",
    "get_frame_freejoint",
    "get_frame_joints",
    "get_freejoint",
    "traversal_utils",
]


def __getattr__(name: str):
    # Physics lives in its own module and is imported on first use, so the model layer
    # works on its own.
    if name in ("Physics", "PhysicsError"):
        from mjcf import physics

        return getattr(physics, name)
    raise AttributeError(f"module 'mjcf' has no attribute {name!r}")
