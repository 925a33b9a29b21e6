"""The README's batched example runs as written (on Warp's CPU device)."""

import contextlib
import io
import pathlib
import re

import pytest

pytestmark = pytest.mark.warp

README = pathlib.Path(__file__).resolve().parents[3] / "README.md"


def test_readme_batched_example_prints_the_batched_shapes():
    text = README.read_text(encoding="utf-8")
    pattern = r"## Batched simulation on MuJoCo Warp\n[^#]*?```python\n(.*?)```"
    match = re.search(pattern, text, re.S)
    assert match, "README has no python block under '## Batched simulation on MuJoCo Warp'"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(match.group(1), str(README), "exec"), {})
    assert printed.getvalue().strip() == "(4,) (4, 1, 3)"
