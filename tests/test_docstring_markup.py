"""Docstrings of the packages use Markdown, the markup mkdocstrings renders, not RST."""

import ast
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("mujoco_physics", "mjcf", "composer", "manipulation")

# What RST writes differently: ``literal`` (Markdown: `literal`), :role:`target`,
# `.. directive::`, a literal block introduced by a line ending in '::', and the rule lines
# of a simple table ('=====  =====').
_RST = {
    "double-backtick literal": re.compile(r"(?<!`)``(?!`)"),
    "role": re.compile(r":[a-z]+:`"),
    "directive": re.compile(r"^\s*\.\. \w+::", re.M),
    "literal block": re.compile(r"[^:\s]::\s*$", re.M),
    "simple table": re.compile(r"^\s*={3,}\s+={3,}", re.M),
}


def _modules() -> list[pathlib.Path]:
    return sorted(path for package in PACKAGES for path in (ROOT / package).rglob("*.py"))


def _docstrings(path: pathlib.Path) -> list[tuple[int, str]]:
    """(line, text) of the docstring of the module and of each class and function in it."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            text = ast.get_docstring(node, clean=False)
            if text is not None:
                found.append((node.body[0].lineno, text))
    return found


def rst_markup(text: str) -> list[str]:
    """The kinds of RST markup in `text`."""
    return [kind for kind, pattern in _RST.items() if pattern.search(text)]


def test_rst_markup_is_recognised_and_markdown_is_not():
    assert rst_markup("Returns ``x``.") == ["double-backtick literal"]
    assert rst_markup("See :class:`Physics`.") == ["role"]
    assert rst_markup("Note:\n\n.. note:: careful") == ["directive"]
    assert rst_markup("Run it::\n\n    python x.py") == ["literal block"]
    assert rst_markup("=====  =====\nkey    action\n=====  =====") == ["simple table"]
    markdown = "Returns `x`.\n\n```python\nx = 1\n```\n\n| key | action |\n|---|---|\n"
    assert rst_markup(markdown + "A mapping name -> value: {'a': 1}.") == []


@pytest.mark.parametrize(
    "path",
    _modules(),
    ids=lambda p: p.relative_to(ROOT).as_posix(),
)
def test_docstrings_use_markdown(path):
    found = [
        f"line {line}: {kind}" for line, text in _docstrings(path) for kind in rst_markup(text)
    ]
    assert found == []
