"""tools/mujoco_versions.py: which releases it tests and how it reads pytest's summary."""

import pytest

from tools import mujoco_versions

_PIP_VERSIONS = ["4.0.0", "3.17.0", "3.4.0", "3.3.7", "3.3.1", "3.3.0", "3.2.7", "2.3.7"]


def test_releases_are_the_newest_patch_of_each_minor_from_the_floor_oldest_first():
    releases = mujoco_versions.supported_releases(_PIP_VERSIONS, "3.3.0")
    assert [r.version for r in releases] == ["3.3.7", "3.4.0", "3.17.0", "4.0.0"]
    assert [r.minor for r in releases] == ["3.3", "3.4", "3.17", "4.0"]


def test_releases_can_be_picked_by_minor_or_by_exact_version():
    releases = mujoco_versions.supported_releases(_PIP_VERSIONS, "3.3.0")
    picked = mujoco_versions.pick(releases, _PIP_VERSIONS, ["3.3", "3.3.1", "4.0"], "3.3.0")
    assert [r.version for r in picked] == ["3.3.7", "3.3.1", "4.0.0"]


def test_floor_and_newest_name_the_exact_floor_and_the_newest_release():
    releases = mujoco_versions.supported_releases(_PIP_VERSIONS, "3.3.0")
    picked = mujoco_versions.pick(releases, _PIP_VERSIONS, ["floor", "newest"], "3.3.0")
    assert [r.version for r in picked] == ["3.3.0", "4.0.0"]


def test_below_floor_is_the_newest_release_older_than_the_floor():
    releases = mujoco_versions.supported_releases(_PIP_VERSIONS, "3.3.0")
    picked = mujoco_versions.pick(releases, _PIP_VERSIONS, ["below-floor"], "3.3.0")
    assert picked == [mujoco_versions.Release("3.2.7", "3.2", below_floor=True)]


def test_picking_a_release_pip_does_not_offer_names_the_choices():
    releases = mujoco_versions.supported_releases(_PIP_VERSIONS, "3.3.0")
    with pytest.raises(SystemExit, match=r"'3\.9'.*3\.3, 3\.4, 3\.17, 4\.0"):
        mujoco_versions.pick(releases, _PIP_VERSIONS, ["3.9"], "3.3.0")


def test_summary_line_counts_errors_as_failures():
    output = (
        "...\nFAILED tests/x.py::t\n2 failed, 1713 passed, 3 skipped, 1 error, 1 warning in 23s\n"
    )
    assert mujoco_versions._summary_counts(output) == {"failed": 3, "passed": 1713, "skipped": 3}


def test_output_without_a_summary_line_has_no_counts():
    assert mujoco_versions._summary_counts("Fatal Python error: Aborted\n") is None


def test_the_floor_is_read_from_the_module_that_enforces_it():
    assert mujoco_versions.minimum_version() == "3.3.0"
