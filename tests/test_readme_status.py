"""The README's Status table quotes what the harnesses and CI measured, so it cannot drift.

The figures come from the files the harnesses write and the repository commits:
`docs/data/dm_control_conformance.json` (`python -m tools.dm_control_conformance`), the
training curve `docs/data/train_rsl_rl_reach_site_h200.csv` (`examples/train_rsl_rl.py`),
the MuJoCo releases CI runs (`.ci/run`) and the manipulation registry.
"""

import csv
import json
import pathlib
import re

from manipulation.tasks import registry

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DATA = ROOT / "docs" / "data"
_NUMBERS = {2: "two", 3: "three", 4: "four", 5: "five", 6: "six"}
# The reach's goals (docs/concepts/training.md): an evaluation return of at least 200 and a
# mean final distance to the target under 6 cm.
_REACH_RETURN, _REACH_DISTANCE_M = 200.0, 0.06


def _status_row(part: str) -> str:
    """The state column of the Status table's row whose part column starts with `part`."""
    section = README.read_text(encoding="utf-8").split("\n## Status\n", 1)[1]
    for line in section.split("\n## ", 1)[0].splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) == 2 and cells[0].startswith(part):
            return cells[1]
    raise AssertionError(f"the README's Status table has no row for {part!r}")


def _ci_release_lists() -> list[str]:
    """The `--releases` of each `tools.mujoco_versions` run in .ci/run, with the script's
    bash arrays (`name=(a b)`, used as `"${name[@]}"`) written out."""
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    for name, words in re.findall(r"^(\w+)=\(([^)\n]*)\)$", ci, re.M):
        ci = ci.replace(f'"${{{name}[@]}}"', words)
    lists = re.findall(r"python -m tools\.mujoco_versions --releases ([^\n]+?) --strict", ci)
    assert lists, ".ci/run does not run tools.mujoco_versions with --releases"
    return lists


def _ci_releases() -> list[str]:
    """Every release .ci/run gives `tools.mujoco_versions`."""
    return [release for releases in _ci_release_lists() for release in releases.split()]


def _floor() -> str:
    text = (ROOT / "mujoco_physics" / "version.py").read_text(encoding="utf-8")
    return re.search(r'^MINIMUM_VERSION = "([\d.]+)"', text, re.M).group(1)


def test_the_redirect_row_quotes_the_conformance_harness():
    summary = json.loads((DATA / "dm_control_conformance.json").read_text(encoding="utf-8"))
    tests = summary["tests"]
    rate = tests["total"]["passed"] / (tests["total"]["passed"] + tests["total"]["failed"])
    row = _status_row("dm_control import redirect")
    packages = [f"`{package}`" for package in tests if package != "total"]
    named = ", ".join(packages[:-1]) + f" and {packages[-1]}"
    assert f"{rate:.1%} of dm_control {summary['dm_control']}'s own tests of {named}" in row
    environments = summary["environments"]
    assert all(group["ok"] == group["total"] for group in environments.values())
    assert (
        f"all {environments['manipulation']['total']} of its manipulation tasks, "
        f"{environments['suite']['total']} Control Suite tasks and "
        f"{environments['locomotion']['total']} locomotion environments, run through it"
    ) in row


def test_the_mujoco_row_names_the_releases_ci_runs():
    # The version matrix's releases, and the newest, which CI's main run installs.
    releases = _ci_releases()
    if "newest" not in releases:
        # That holds while the project's own mujoco requirement has no upper bound.
        pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
        assert re.search(r'^  "mujoco>=[\d.]+",$', pyproject, re.M)
        releases.append("newest")
    row = _status_row(f"MuJoCo releases {_floor()} to ")
    assert f"CI runs {_NUMBERS[len(releases)]} releases" in row
    phrases = {
        "floor": f"{_floor()} (the floor)",
        "newest": "the newest",
        "below-floor": "the release below the floor",
    }
    for release in releases:
        assert phrases.get(release, release) in row


def test_the_supported_releases_section_quotes_ci_s_releases():
    text = README.read_text(encoding="utf-8")
    for releases in _ci_release_lists():
        assert f"`--releases {releases} --strict" in text


def test_the_batch_row_counts_the_registered_tasks_and_quotes_the_h200_training_run():
    names = registry.names()
    row = _status_row("Batched simulation on `mujoco.batch` (CPU) and MuJoCo Warp")
    vision = sum(name.endswith("_vision") for name in names)
    assert f"all {len(names)} manipulation tasks, the {vision} `*_vision` ones" in row
    with open(DATA / "train_rsl_rl_reach_site_h200.csv", newline="", encoding="utf-8") as file:
        curve = list(csv.DictReader(file))
    reached = next(
        point
        for point in curve
        if float(point["return"]) >= _REACH_RETURN
        and float(point["distance_m"]) < _REACH_DISTANCE_M
    )
    assert f"reached the reach's goals in {float(reached['seconds']):.0f} s on one H200" in row
