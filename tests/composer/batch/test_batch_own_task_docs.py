"""docs/batch_own_task.md runs as written, after the task blocks of docs/own_task.md, and
prints what it says; the upstream report's reproduction gives the depths it states. (The
docs tests leave these pages' blocks out: they need the extra [warp].)"""

import contextlib
import io
import pathlib
import re

import pytest

pytestmark = pytest.mark.warp

DOCS = pathlib.Path(__file__).resolve().parents[3] / "docs"
_FENCE = re.compile(r"^```(?P<info>[^\n`]*)\n(?P<code>.*?)^```\s*$", re.M | re.S)


def _blocks(text: str, info: str) -> list[str]:
    return [m["code"] for m in _FENCE.finditer(text) if m["info"].strip() == info]


def _run(blocks: list[str], name: str) -> str:
    namespace = {"__name__": "__docs__"}
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        for number, code in enumerate(blocks):
            exec(compile(code, f"{name}, block {number}", "exec"), namespace)
    return printed.getvalue()


def test_batch_own_task_page_runs_from_the_own_task_pages_task(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    own_task = (DOCS / "own_task.md").read_text(encoding="utf-8").split("## Run it")[0]
    page = (DOCS / "batch_own_task.md").read_text(encoding="utf-8")
    printed = _run(
        _blocks(own_task, "python") + _blocks(page, "{.python .no-run}"), "batch_own_task.md"
    ).splitlines()
    # The goal site's MJCFVariator runs per world: each of the 16 worlds has its own goal.
    assert "(16, 3)" in printed
    assert "16 different goals" in printed
    assert "float64 int8" in printed
    assert "(8, 3) (8,)" in printed
    # The equivalence check: the batch and the float32-rounded CPU leave the bound at the
    # same value, the puck's spin as it lands in the first step.
    reports = [line for line in printed if "of world 1 at step 1" in line]
    assert len(reports) == 2 and all("qvel[6] (joint 'puck/')" in line for line in reports)
    assert reports[1].startswith("the CPU rounded to float32 every step leaves it too")


def test_plane_cylinder_report_reproduces_the_depths_it_states(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    page = (DOCS / "reports" / "mujoco_warp_plane_cylinder.md").read_text(encoding="utf-8")
    printed = _run(_blocks(page, "{.python .no-run}"), "mujoco_warp_plane_cylinder.md")
    assert printed.strip() == (
        "C MuJoCo -4.59734e-05, MuJoCo Warp -3.63598e-05, difference 9.6e-06 m"
    )
