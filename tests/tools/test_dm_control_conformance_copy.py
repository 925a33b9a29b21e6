"""tools/dm_control_conformance.py: which of dm_control's test files a run copies."""

import os
import sys

from tools import dm_control_conformance as conformance


def test_single_tested_files_are_copied_without_the_rest_of_their_package(monkeypatch, tmp_path):
    # A stand-in dm_control: a tested package and `utils`, of which only the IK test is run.
    installed = tmp_path / "site"
    for relative in (
        "__init__.py",
        "mjcf/__init__.py",
        "mjcf/element_test.py",
        "utils/__init__.py",
        "utils/inverse_kinematics_test.py",
        "utils/rewards_test.py",
    ):
        path = installed / "dm_control" / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("")
    monkeypatch.setenv("PYTHONPATH", str(installed) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    monkeypatch.setattr(conformance, "CACHE", tmp_path / "cache")

    tests = conformance.copy_tests(sys.executable, ("mjcf",))

    copied = sorted(p.relative_to(tests).as_posix() for p in tests.rglob("*_test.py"))
    assert copied == [
        "dm_control_mjcf/element_test.py",
        "dm_control_utils/inverse_kinematics_test.py",
    ]
