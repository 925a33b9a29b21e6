"""The oldest MuJoCo release this project supports, and the import-time check against it."""

import re

import mujoco

#: The oldest MuJoCo release the whole test suite passes on (also `mujoco>=` in pyproject).
MINIMUM_VERSION = "3.3.0"


def version_tuple(version: str) -> tuple[int, ...]:
    """`"3.3.0"` -> `(3, 3, 0)`."""
    return tuple(int(part) for part in re.findall(r"\d+", version)[:3])


def check_version(installed: str | None = None) -> None:
    """Raises ImportError when `installed` (default: the imported mujoco's) is below the floor."""
    installed = mujoco.__version__ if installed is None else installed
    if version_tuple(installed) < version_tuple(MINIMUM_VERSION):
        raise ImportError(
            f"this project needs mujoco>={MINIMUM_VERSION}, but mujoco {installed} is "
            f"installed; upgrade it with: pip install 'mujoco>={MINIMUM_VERSION}'"
        )
