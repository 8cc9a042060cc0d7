"""Every public name has a docstring (the API reference of ``make docs`` is built from them).

A public name is one listed in the ``__all__`` of a public module or package of ``pkdyn`` or
``solvers`` (modules whose name starts with ``_`` are private); a module that defines public
top-level names must list them in ``__all__``. Functions and classes need a docstring,
constants an attribute docstring (a string literal right after the assignment, which Sphinx's
autodoc reads). A name re-exported from another module is checked where it is defined. The check
reads the sources (``ast``): a dataclass's generated ``__doc__`` does not count.
"""

from __future__ import annotations

import ast
import importlib
import pkgutil
from functools import cache
from pathlib import Path

import pytest

import pkdyn
import solvers

PACKAGES = (pkdyn, solvers)


def _modules() -> list[str]:
    names = []
    for package in PACKAGES:
        names.append(package.__name__)
        prefix = package.__name__ + "."
        names += [m.name for m in pkgutil.walk_packages(package.__path__, prefix)]
    return sorted(n for n in names if not any(p.startswith("_") for p in n.split(".")))


MODULES = _modules()


@cache
def _definitions(module: str) -> dict[str, tuple[str, object]]:
    """Top-level names of a module's source: ``(kind, detail)``.

    ``kind`` is ``doc`` (a def, class or assignment; ``detail``: has a docstring) or ``import``
    (``detail``: ``(source module, name there)``).
    """
    mod = importlib.import_module(module)
    path = Path(mod.__file__ or "")
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out: dict[str, tuple[str, object]] = {}
    body = tree.body
    for k, node in enumerate(body):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out[node.name] = ("doc", bool(ast.get_docstring(node)))
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            nxt = body[k + 1] if k + 1 < len(body) else None
            documented = (
                isinstance(nxt, ast.Expr)
                and isinstance(nxt.value, ast.Constant)
                and isinstance(nxt.value.value, str)
                and bool(nxt.value.value.strip())
            )
            for t in targets:
                for leaf in t.elts if isinstance(t, ast.Tuple) else [t]:
                    if isinstance(leaf, ast.Name):
                        out[leaf.id] = ("doc", documented)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = module.split(".")
                # a package's own __init__ counts as level 0 of itself
                keep = len(parts) - node.level + (1 if path.name == "__init__.py" else 0)
                base = ".".join(parts[:keep] + ([base] if base else []))
            for alias in node.names:
                out[alias.asname or alias.name] = ("import", (base, alias.name))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                out[alias.asname or alias.name.split(".")[0]] = ("import", (alias.name, None))
    return out


def _documented(module: str, name: str, seen: tuple[str, ...] = ()) -> bool | None:
    """Whether ``module.name`` has a docstring where it is defined (None: not ours)."""
    if not module.startswith(tuple(p.__name__ for p in PACKAGES)) or module in seen:
        return None
    entry = _definitions(module).get(name)
    if entry is None:
        # a submodule listed in a package's __all__ (checked as a module of its own)
        if f"{module}.{name}" in MODULES:
            return True
        # a name provided at run time (a lazy export): checked where its object is defined
        obj = getattr(importlib.import_module(module), name, None)
        home = getattr(obj, "__module__", None)
        if isinstance(home, str) and home != module:
            return _documented(home, getattr(obj, "__name__", name), (*seen, module))
        return None
    kind, detail = entry
    if kind == "doc":
        return bool(detail)
    source, original = detail  # type: ignore[misc]
    if original is None:  # `import x.y as name`: a module
        return True
    if f"{source}.{original}" in MODULES:  # `from package import submodule`
        return True
    return _documented(source, original, (*seen, module))


@pytest.mark.parametrize("module", MODULES)
def test_public_names_have_docstrings(module):
    mod = importlib.import_module(module)
    assert (mod.__doc__ or "").strip(), f"{module} has no module docstring"
    if not hasattr(mod, "__all__"):
        defined = [n for n, (kind, _) in _definitions(module).items() if kind == "doc"]
        public = [n for n in defined if not n.startswith("_")]
        assert not public, f"{module} has no __all__ but defines public names: {public}"
        return
    missing, unknown = [], []
    for name in mod.__all__:
        assert hasattr(mod, name), f"{module}.__all__ lists {name!r}, which does not exist"
        ok = _documented(module, name)
        if ok is None:
            unknown.append(name)
        elif not ok:
            missing.append(name)
    assert not missing, f"{module}: public names without a docstring: {', '.join(missing)}"
    assert not unknown, f"{module}: public names defined outside pkdyn/solvers: {unknown}"


def test_the_check_catches_an_undocumented_constant(tmp_path, monkeypatch):
    pkg = tmp_path / "pkdyn_probe"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        '"""Probe."""\n__all__ = ["A", "B", "f"]\nA = 1\n"""Documented."""\nB = 2\n'
        "def f():\n    pass\n",
        encoding="utf-8",
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(
        "test_docstrings.PACKAGES", (*PACKAGES, importlib.import_module("pkdyn_probe"))
    )
    assert _documented("pkdyn_probe", "A") is True
    assert _documented("pkdyn_probe", "B") is False
    assert _documented("pkdyn_probe", "f") is False
