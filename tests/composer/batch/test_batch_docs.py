"""The batch docs page's CPU examples run as written (the docs tests leave them out: they
need the extra [warp])."""

import contextlib
import io
import pathlib
import re

import pytest

pytestmark = pytest.mark.warp

PAGE = pathlib.Path(__file__).resolve().parents[3] / "docs" / "concepts" / "batch.md"


def _block_under(heading: str) -> str:
    text = PAGE.read_text(encoding="utf-8")
    match = re.search(
        rf"## {re.escape(heading)}\n.*?```\{{\.python \.no-run\}}\n(.*?)```", text, re.S
    )
    assert match, f"{PAGE.name} has no python block under '## {heading}'"
    return match.group(1)


@pytest.mark.parametrize("heading", ["The environment", "Device arrays: `array_type`", "Cameras"])
def test_batch_page_example_runs(heading, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with contextlib.redirect_stdout(io.StringIO()):
        exec(compile(_block_under(heading), f"{PAGE.name}: {heading}", "exec"), {})


def test_array_code_example_rewards_the_worlds_dropped_from_above_the_bar():
    printed = io.StringIO()
    heading = "Writing a BatchTask"
    with contextlib.redirect_stdout(printed):
        exec(compile(_block_under(heading), f"{PAGE.name}: {heading}", "exec"), {})
    # Dropped from 0.6, 0.9 and 1.2 m, 60 physics steps of 5 ms: semi-implicit Euler falls
    # g dt^2 n (n + 1) / 2 = 0.449 m, which leaves 0.15, 0.45 and 0.75 m; the bar is 0.5 m.
    assert printed.getvalue().split("\n")[:2] == ["[0. 0. 1.]", "InitialStateSource.ARRAY_CODE"]


def test_per_world_variation_example_prints_a_friction_per_world_and_the_derived_fields():
    printed = io.StringIO()
    heading = "Per-world variation"
    with contextlib.redirect_stdout(printed):
        exec(compile(_block_under(heading), f"{PAGE.name}: {heading}", "exec"), {})
    frictions, fields = printed.getvalue().splitlines()
    assert len(set(frictions.strip("[]").split())) == 3
    assert fields == "['body_inertia', 'body_mass', 'geom_friction', 'geom_rgba']"


def test_observables_example_reads_one_speed_per_world_with_its_registered_twin():
    printed = io.StringIO()
    heading = "Observables"
    with contextlib.redirect_stdout(printed):
        exec(compile(_block_under(heading), f"{PAGE.name}: {heading}", "exec"), {})
    assert printed.getvalue().split("\n")[0] == "(4, 1)"
