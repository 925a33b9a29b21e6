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


def test_skip_installed_leaves_out_only_the_running_release(capsys):
    releases = mujoco_versions.supported_releases(_PIP_VERSIONS, "3.3.0")
    picked = mujoco_versions.pick(releases, _PIP_VERSIONS, ["floor", "3.17", "newest"], "3.3.0")
    kept = mujoco_versions.without_installed(picked, "4.0.0")
    assert [r.version for r in kept] == ["3.3.0", "3.17.0"]
    assert "mujoco 4.0.0: left out" in capsys.readouterr().out
    assert mujoco_versions.without_installed(picked, "4.1.0") == picked


def test_summary_line_counts_errors_as_failures():
    output = (
        "...\nFAILED tests/x.py::t\n2 failed, 1713 passed, 3 skipped, 1 error, 1 warning in 23s\n"
    )
    assert mujoco_versions._summary_counts(output) == {"failed": 3, "passed": 1713, "skipped": 3}


def test_output_without_a_summary_line_has_no_counts():
    assert mujoco_versions._summary_counts("Fatal Python error: Aborted\n") is None


def test_the_floor_is_read_from_the_module_that_enforces_it():
    assert mujoco_versions.minimum_version() == "3.3.0"


def _fake_venv(tmp_path, script: str):
    python = tmp_path / "venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text("#!/bin/sh\n" + script)
    python.chmod(0o755)
    return python.parent.parent


def test_the_patch_proof_runs_in_the_release_venv_and_its_count_is_read(tmp_path):
    venv = _fake_venv(
        tmp_path,
        'echo "patch  geom  rgba  write"\n'
        'echo "72 pairs patch, 221 recompile (30 s)"\n'
        'echo "ran $* with cache $XDG_CACHE_HOME"\n',
    )
    log = tmp_path / "log.txt"
    env = {"XDG_CACHE_HOME": str(tmp_path / "xdg"), "PATH": "/usr/bin:/bin"}
    assert mujoco_versions._prove_patch_table(venv, env, log) == (72, "")
    assert f"ran -m manipulation.patch_proof with cache {tmp_path / 'xdg'}" in log.read_text()


def test_a_failing_patch_proof_is_a_problem_of_the_release(tmp_path):
    stale = 'echo "mjcf/patching/patchable_attributes.py is stale" >&2\nexit 1\n'
    venv = _fake_venv(tmp_path, stale)
    log = tmp_path / "log.txt"
    patched, problem = mujoco_versions._prove_patch_table(venv, {"PATH": "/usr/bin:/bin"}, log)
    assert patched is None
    assert problem == f"patch proof failed (exit 1), see {log}"
    assert "is stale" in log.read_text()


def test_the_table_shows_how_many_pairs_each_release_proved(capsys):
    outcomes = [
        mujoco_versions.Outcome("3.2.7", 1, 0, 0, 2.0, "", (), None),
        mujoco_versions.Outcome("3.3.0", 1700, 0, 30, 90.0, "", (), 72),
    ]
    mujoco_versions.print_table(outcomes, {"3.2.7"})
    rows = capsys.readouterr().out.splitlines()
    header = ["mujoco", "passed", "failed", "skipped", "patched", "seconds", "result"]
    assert rows[0].split() == header
    assert rows[1].split()[:6] == ["3.2.7", "1", "0", "0", "-", "2"]
    assert rows[2].split() == ["3.3.0", "1700", "0", "30", "72", "90", "ok"]
