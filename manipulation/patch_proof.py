"""The patch proof of `mjcf.patching.patch_proof` on the manipulation suite's models.

Usage: `python -m manipulation.patch_proof [--write] [--extra-models DIR]` (about half a
minute): proves which MJCF attributes a reset may patch in place on the 25 tasks' models
(each distinct model once) and the proof's own scenes; on the release of the checked-in
table `mjcf/patching/patchable_attributes.py` it checks the table, on any other it caches
its proof. `mjcf.patching.patch_proof` says what is proven and how.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator

import mjcf
from manipulation.tasks import registry
from mjcf.patching import patch_proof


def task_models() -> Iterator[tuple[str, mjcf.RootElement]]:
    """Yields (task name, RootElement) for each task whose model no earlier task has."""
    seen = set()
    for name in registry.names():
        root = registry.build_task(name).root_entity.mjcf_model
        xml = root.to_xml_string()
        if xml not in seen:
            seen.add(xml)
            yield name, root


def main(argv: list[str] | None = None) -> int:
    """Runs the proof on the tasks' models with `argv`; returns its exit status."""
    return patch_proof.main(task_models(), argv)


if __name__ == "__main__":
    sys.exit(main())
