"""The README's batched example runs as written (on the CPU batch)."""

import contextlib
import io
import pathlib
import re

import pytest

pytestmark = pytest.mark.warp

README = pathlib.Path(__file__).resolve().parents[3] / "README.md"


def test_readme_batched_example_prints_the_batched_shapes():
    text = README.read_text(encoding="utf-8")
    heading = "## Batched simulation: `mujoco.batch` on CPUs, MuJoCo Warp on GPUs"
    match = re.search(re.escape(heading) + r"\n[^#]*?```python\n(.*?)```", text, re.S)
    assert match, f"README has no python block under {heading!r}"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(match.group(1), str(README), "exec"), {})
    assert printed.getvalue().strip() == "(4,) (4, 1, 3)"
