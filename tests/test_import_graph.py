"""The packages import downwards only, and in no circle but the documented `mjcf.element` ring.

Layers, lowest first: `mujoco_physics` (the engine), `mjcf` (models), `composer`
(environments), `manipulation` (the task suite), `suite_batch` (dm_control's Control Suite
batched). The graph is read from the source (every
`import`, at module level or inside a function, except those under `if TYPE_CHECKING:`,
which never run), so a lazy import up counts as much as a top-level one.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

_ROOT = Path(__file__).resolve().parent.parent
_LAYERS = ("mujoco_physics", "mjcf", "composer", "manipulation", "suite_batch")

# The ring `mjcf/element.py` documents at its end: the modules its element classes delegate
# to, imported after the classes, each importing `mjcf.element` back.
_ELEMENT_RING = frozenset(
    {
        "mjcf.element",
        "mjcf.attachment",
        "mjcf.copier",
        "mjcf.model_files",
        "mjcf.parser",
        "mjcf.xml_writer",
    }
)


def _module_files(root: Path, packages) -> dict[str, Path]:
    """Dotted module name -> its source file, for every module of `packages` under `root`."""
    found = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join(parts)] = path
    return found


def _is_type_checking(test: ast.expr) -> bool:
    name = test.attr if isinstance(test, ast.Attribute) else getattr(test, "id", None)
    return name == "TYPE_CHECKING"


def _imported_names(module: str, path: Path, modules) -> set[str]:
    """The dotted names `module` imports anywhere in its source, `from a import b` as `a.b`
    where that is a module of `modules` and as `a` otherwise."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names = set()
    pending = list(ast.parse(path.read_text(encoding="utf-8")).body)
    while pending:
        node = pending.pop()
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            pending.extend(node.orelse)
            continue
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            for alias in node.names:
                full = f"{base}.{alias.name}"
                names.add(full if full in modules else base)
        pending.extend(ast.iter_child_nodes(node))
    return names


def import_graph(root: Path, packages) -> dict[str, set[str]]:
    """Module -> the modules of `packages` it imports (not itself)."""
    modules = _module_files(root, packages)
    graph = {}
    for module, path in modules.items():
        targets = set()
        for name in _imported_names(module, path, modules):
            while name and name not in modules:
                name = name.rpartition(".")[0]
            if name and name != module:
                targets.add(name)
        graph[module] = targets
    return graph


def cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(graph[node]):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = set()
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.add(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(frozenset(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


@pytest.fixture(scope="module")
def graph():
    return import_graph(_ROOT, _LAYERS)


def _layer(module: str) -> int:
    return _LAYERS.index(module.split(".")[0])


def test_no_module_imports_a_package_above_its_own(graph):
    upward = sorted(
        f"{module} -> {target}"
        for module, targets in graph.items()
        for target in targets
        if _layer(target) > _layer(module)
    )
    assert upward == []


def test_the_only_import_cycles_are_the_element_ring(graph):
    assert cycles(graph) == [_ELEMENT_RING]


def test_every_cycle_of_the_element_ring_goes_through_the_element_module(graph):
    ring = {module: graph[module] & _ELEMENT_RING for module in _ELEMENT_RING}
    without_element = {
        module: targets - {"mjcf.element"}
        for module, targets in ring.items()
        if module != "mjcf.element"
    }
    assert cycles(without_element) == []


def test_the_graph_sees_imports_in_functions_and_not_those_for_type_checking(tmp_path):
    package = tmp_path / "low"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "eager.py").write_text("from high import task\n")
    (package / "lazy.py").write_text("def build():\n    from high.task import Task\n")
    (package / "typed.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import high.task\n"
    )
    (package / "relative.py").write_text("from . import eager\n")
    (tmp_path / "high").mkdir()
    (tmp_path / "high" / "__init__.py").write_text("")
    (tmp_path / "high" / "task.py").write_text("import low.lazy\n")
    graph = import_graph(tmp_path, ("low", "high"))
    assert graph["low.eager"] == {"high.task"}
    assert graph["low.lazy"] == {"high.task"}
    assert graph["low.typed"] == set()
    assert graph["low.relative"] == {"low.eager"}
    assert cycles(graph) == [frozenset({"low.lazy", "high.task"})]
