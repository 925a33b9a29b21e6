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


@pytest.mark.parametrize("heading", ["The environment", "Device arrays: `array_type`"])
def test_batch_page_example_runs(heading, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with contextlib.redirect_stdout(io.StringIO()):
        exec(compile(_block_under(heading), f"{PAGE.name}: {heading}", "exec"), {})
