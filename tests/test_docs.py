"""Every Python code block in docs/ runs as written.

A page's ```python blocks run in order in one namespace, in a temporary working directory,
so a later block may use what an earlier one defined. Two other fences are recognised:
``` {.python .subprocess} runs the block alone in a fresh interpreter (for code that changes
the import system), and ``` {.python .no-run} is shown but not run; a page must say next to
such a block why it cannot run here (it needs a display, a network or a long time).
"""

import contextlib
import dataclasses
import io
import pathlib
import re
import subprocess
import sys

import pytest

DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs"
_FENCE = re.compile(r"^```(?P<info>[^\n`]*)\n(?P<code>.*?)^```\s*$", re.M | re.S)
_RUN_MODES = {"python": "run", "{.python .subprocess}": "subprocess", "{.python .no-run}": "skip"}


@dataclasses.dataclass(frozen=True)
class Block:
    """A fenced Python block: its code, how it is run, and the line it starts on."""

    code: str
    mode: str
    line: int


def _pages() -> list[pathlib.Path]:
    return sorted(
        path for path in DOCS.rglob("*.md") if "generated" not in path.relative_to(DOCS).parts
    )


def python_blocks(text: str) -> list[Block]:
    """The page's Python blocks; raises ValueError for a python fence with an unknown form."""
    blocks = []
    for match in _FENCE.finditer(text):
        info = match["info"].strip()
        if "python" not in info and info not in ("py", "pycon"):
            continue
        if info not in _RUN_MODES:
            raise ValueError(f"unknown python fence {info!r}; expected one of {list(_RUN_MODES)}")
        line = text.count("\n", 0, match.start()) + 1
        blocks.append(Block(match["code"], _RUN_MODES[info], line))
    return blocks


def test_python_blocks_are_found_with_their_modes():
    text = "x\n```python\na = 1\n```\n\n```bash\nls\n```\n```{.python .no-run}\nb\n```\n"
    assert python_blocks(text) == [Block("a = 1\n", "run", 2), Block("b\n", "skip", 9)]


def test_an_unknown_python_fence_is_an_error():
    with pytest.raises(ValueError, match="unknown python fence"):
        python_blocks("```{.python .maybe}\na = 1\n```\n")


def test_docs_have_pages_with_python_blocks():
    pages_with_code = [page for page in _pages() if python_blocks(page.read_text(encoding="utf-8"))]
    assert len(pages_with_code) >= 10


@pytest.mark.parametrize("page", _pages(), ids=lambda page: str(page.relative_to(DOCS)))
def test_page_code_runs(page, tmp_path, monkeypatch):
    blocks = python_blocks(page.read_text(encoding="utf-8"))
    if not any(block.mode != "skip" for block in blocks):
        pytest.skip("no runnable python blocks")
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__docs__"}
    for block in blocks:
        where = f"{page.relative_to(DOCS)}:{block.line}"
        if block.mode == "subprocess":
            result = subprocess.run(
                [sys.executable, "-c", block.code], capture_output=True, text=True, timeout=300
            )
            assert result.returncode == 0, f"{where}\n{result.stderr}"
        elif block.mode == "run":
            # Pages print what they show; the output is not checked here, only that it runs.
            with contextlib.redirect_stdout(io.StringIO()):
                exec(compile(block.code, where, "exec"), namespace)


_WIDEST_CODE_LINE = 80


@pytest.mark.parametrize("page", _pages(), ids=lambda page: str(page.relative_to(DOCS)))
def test_code_lines_fit_the_page_without_scrolling(page):
    # At a 1280-pixel window the theme shows about 82 characters of a code block.
    text = page.read_text(encoding="utf-8")
    too_wide = [
        f"line {text.count(chr(10), 0, match.start('code')) + 1 + i}: {line}"
        for match in _FENCE.finditer(text)
        if match["info"].strip() != "bash"
        for i, line in enumerate(match["code"].splitlines())
        if len(line) > _WIDEST_CODE_LINE
    ]
    assert not too_wide, "\n".join(too_wide)
