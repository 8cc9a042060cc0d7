"""No import circle: the modules of ``pkdyn/`` and ``solvers/`` import each other as a tree.

The graph has one node per module (a package is its ``__init__``) and one edge per import
statement naming a module of the two packages: at the top of a file, inside a function (a lazy
import is still a dependency) or under ``if TYPE_CHECKING:`` (a type is a dependency too).
``from package import name`` points at ``package.name`` when that is a module, else at the
package. A circle means that two modules hold pieces of one concept, or that a shared piece
sits in the upper one: move it to the module below (``tests/test_layering.py`` ranks the
parts; this test covers the modules within a part as well).
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("pkdyn", "solvers")


def _modules() -> dict[str, Path]:
    """Every module of the packages by dotted name (a package by its own name)."""
    out = {}
    for top in PACKAGES:
        for path in sorted((ROOT / top).rglob("*.py")):
            if "__pycache__" in path.parts:
                continue
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            out[".".join(parts)] = path
    return out


def _target(dotted: str, modules: dict[str, Path]) -> str | None:
    """The module an import of ``dotted`` runs (its longest prefix that is a module)."""
    parts = dotted.split(".")
    while parts:
        name = ".".join(parts)
        if name in modules:
            return name
        parts.pop()
    return None


def import_graph() -> dict[str, dict[str, int]]:
    """``{module: {imported module: line of the first import}}`` over both packages."""
    modules = _modules()
    graph: dict[str, dict[str, int]] = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        edges: dict[str, int] = {}
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join(up + ([base] if base else []))
                targets = [
                    f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                    for a in node.names
                ]
            for dotted in targets:
                target = _target(dotted, modules)
                if target is not None and target != name:
                    edges[target] = min(edges.get(target, node.lineno), node.lineno)
        graph[name] = edges
    return graph


def cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative).

    Returns:
        Each circle as one shortest cycle through its smallest module name, the first module
        repeated at the end, components sorted by that name.

    """
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    components.append(sorted(component))
    return [_shortest_cycle(graph, set(c)) for c in sorted(components)]


def _shortest_cycle(graph: dict[str, dict[str, int]], component: set[str]) -> list[str]:
    """A shortest cycle through the component's smallest module (breadth-first)."""
    start = min(component)
    parent: dict[str, str] = {}
    frontier = [start]
    while frontier:
        following = []
        for node in frontier:
            for child in sorted(graph[node]):
                if child not in component:
                    continue
                if child == start:
                    path = [node]
                    while path[-1] != start:
                        path.append(parent[path[-1]])
                    return [*reversed(path), start]
                if child not in parent:
                    parent[child] = node
                    following.append(child)
        frontier = following
    raise AssertionError(f"no cycle through {start}")  # (a component always has one)


def _describe(graph: dict[str, dict[str, int]], cycle: list[str]) -> str:
    modules = _modules()
    steps = [
        f"{modules[a].relative_to(ROOT)}:{graph[a][b]} imports {b}"
        for a, b in zip(cycle, cycle[1:], strict=False)
    ]
    return " -> ".join(cycle) + "\n    " + "\n    ".join(steps)


def test_no_import_circle():
    graph = import_graph()
    found = cycles(graph)
    assert not found, "import circles (move the shared piece to the module below):\n" + (
        "\n".join(_describe(graph, c) for c in found)
    )


def test_the_graph_sees_every_kind_of_import():
    """The graph reads lazy, type-only and relative imports, and packages as modules."""
    graph = import_graph()
    # a lazy import inside a function
    assert "pkdyn.model.formats.xacro_files" in graph["pkdyn.cli._common"]
    # ``from package import module`` points at the module
    assert "pkdyn.library" in graph["pkdyn"]
    # a module of solvers imported by pkdyn
    assert "solvers.numerics" in graph["pkdyn.model.robot"]


def test_cycles_are_found_and_named():
    """The detector on a made-up graph: two circles, one of them through three modules."""
    graph = {
        "a": {"b": 1},
        "b": {"c": 2},
        "c": {"a": 3, "d": 4},
        "d": {},
        "e": {"f": 5},
        "f": {"e": 6},
    }
    assert cycles(graph) == [["a", "b", "c", "a"], ["e", "f", "e"]]
    assert cycles({"a": {"b": 1}, "b": {}}) == []
