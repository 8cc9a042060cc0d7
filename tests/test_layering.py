"""The packages import each other only downwards (the picture in ``pkdyn/__init__``).

Every ``import`` statement of every module counts, including imports inside functions (lazy
imports are still dependencies).
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

RANK = {
    "exceptions": 0,
    "workers": 1,
    "executors": 2,
    "progress": 1,
    "files": 1,
    "inputs": 1,
    "threads": 1,
    "results": 1,
    "units": 1,
    "tables": 2,
    "identifiability": 2,
    "model": 2,
    "closed_form": 3,
    "library": 4,
    "analysis": 5,
    "dynamics": 6,
    "workspace": 6,
    "tripod": 7,
    "identification": 7,
    "precision": 7,
    "calibration": 8,
    "design": 8,
    "viewer": 9,
    "plotting": 9,
    "cli": 10,
}
"""Rank of each part of pkdyn: a module may import its own part and parts of lower rank."""

ROOT_PACKAGE_FROM = 4
"""``import pkdyn`` (the top-level package, which imports the model and the library) is allowed
from this rank up."""


def _modules(top: str) -> list[Path]:
    return sorted(p for p in (ROOT / top).rglob("*.py") if "__pycache__" not in p.parts)


def _imports(path: Path) -> list[tuple[int, str]]:
    tree = ast.parse(path.read_text())
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "pkdyn":  # from pkdyn import library / load ...
                out += [(node.lineno, f"pkdyn.{a.name}") for a in node.names]
            else:
                out.append((node.lineno, node.module))
    return out


def _part(dotted: str) -> str | None:
    parts = dotted.split(".")
    if parts[0] != "pkdyn":
        return None
    return parts[1] if len(parts) > 1 else ""


def _own_part(path: Path) -> str:
    rel = path.relative_to(ROOT / "pkdyn").with_suffix("")
    return rel.parts[0]


def test_every_part_has_a_rank():
    parts = {_own_part(p) for p in _modules("pkdyn")} - {"__init__", "__main__"}
    assert parts <= set(RANK), f"give these parts a rank: {sorted(parts - set(RANK))}"


def test_solvers_never_import_pkdyn():
    bad = [
        f"{p.relative_to(ROOT)}:{line} imports {name}"
        for p in _modules("solvers")
        for line, name in _imports(p)
        if name.split(".")[0] == "pkdyn"
    ]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize(
    "path", _modules("pkdyn"), ids=lambda p: str(p.relative_to(ROOT / "pkdyn"))
)
def test_imports_point_down(path):
    own = _own_part(path)
    if own in ("__init__", "__main__"):
        return
    rank = RANK[own]
    bad = []
    for line, name in _imports(path):
        part = _part(name)
        if part is None or part == own:
            continue
        if part == "" or part not in RANK:  # the root package, or a name re-exported by it
            if rank < ROOT_PACKAGE_FROM:
                bad.append(f"line {line}: {name} (the top-level package) from rank {rank}")
            continue
        if RANK[part] >= rank:
            bad.append(f"line {line}: {name} (rank {RANK[part]}) from {own} (rank {rank})")
    assert not bad, "\n".join(bad)


def test_core_never_imports_viewer_plotting_or_cli():
    """Stated separately: the core is everything below the viewer, plots and CLI."""
    core = [
        p
        for p in _modules("pkdyn")
        if _own_part(p) != "__main__"  # ``python -m pkdyn``: the command line itself
        and RANK.get(_own_part(p), 0) < RANK["viewer"]
    ]
    bad = [
        f"{p.relative_to(ROOT)}:{line} imports {name}"
        for p in core
        for line, name in _imports(p)
        if _part(name) in ("viewer", "plotting", "cli")
    ]
    assert not bad, "\n".join(bad)
