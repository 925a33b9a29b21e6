"""tools/dm_control_conformance.py: the figures a run saves for the README's Status table."""

import json

from tools import dm_control_conformance as conformance

FileResult = conformance.FileResult


def test_test_figures_count_each_package_and_the_total():
    figures = conformance._test_figures(
        [
            FileResult("mjcf/element_test.py", 100, 2, 0),
            FileResult("mjcf/physics_test.py", 18, 1, 0),
            FileResult("suite/cartpole_test.py", 20, 0, 3),
        ]
    )
    assert figures["mjcf"] == {"passed": 118, "failed": 3, "skipped": 0}
    assert figures["suite"] == {"passed": 20, "failed": 0, "skipped": 3}
    assert figures["composer"] == {"passed": 0, "failed": 0, "skipped": 0}
    assert figures["total"] == {"passed": 138, "failed": 3, "skipped": 3}
    assert list(figures) == [*conformance.TESTED_PACKAGES, "total"]


def test_environment_figures_count_what_ran_per_group():
    figures = conformance._environment_figures(
        {
            "lift_brick_features": {"group": "manipulation", "ok": True, "seconds": 1.0},
            "reach_site_vision": {"group": "manipulation", "ok": False, "error": "E"},
            "cartpole-swingup": {"group": "suite", "ok": True, "seconds": 0.5},
        }
    )
    assert figures == {"manipulation": {"ok": 1, "total": 2}, "suite": {"ok": 1, "total": 1}}


def test_saving_one_section_keeps_the_others(monkeypatch, tmp_path):
    summary = tmp_path / "summary.json"
    monkeypatch.setattr(conformance, "SUMMARY", summary)
    conformance.save_summary("environments", {"suite": {"ok": 1, "total": 1}})
    conformance.save_summary("tests", {"total": {"passed": 1, "failed": 0, "skipped": 0}})
    conformance.save_summary("tests", {"total": {"passed": 2, "failed": 0, "skipped": 0}})
    assert json.loads(summary.read_text()) == {
        "dm_control": "1.0.50",
        "environments": {"suite": {"ok": 1, "total": 1}},
        "tests": {"total": {"passed": 2, "failed": 0, "skipped": 0}},
    }
