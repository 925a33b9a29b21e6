"""Developer tools, not library code; run each from the repository root as `python -m tools.NAME`.

The reliability harnesses are the modules of this package (`dm_control_conformance`,
`mujoco_versions`, `fuzz` with its engine `mjcf_differential`, and `mutation.sh`); the docs
builders are `tools.docs`.
"""

from pathlib import Path

#: The repository's root folder: every tool finds files relative to it.
ROOT = Path(__file__).resolve().parent.parent
