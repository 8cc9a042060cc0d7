"""Plug-ins: user code for design studies, loaded only when the user asks for it.

A plug-in is a Python module that adds metrics (:func:`pkdyn.design.metric`, or
:class:`~pkdyn.design.Metric` objects) or parametrisations
(:class:`~pkdyn.design.Parametrisation` objects). A study names them by ``module:attribute``
(``metrics: [mymetrics:arm_ratio]``, ``parametrisation: mymetrics:scaled``), or, for metrics
registered with :func:`~pkdyn.design.metric`, by their plain name.

A study file is data, shared like data: naming a module in it imports nothing. The module must
have been loaded by its user first:

- on the command line, ``pkdyn design --plugin MODULE`` (a module name on the Python path, or a
  ``.py`` file);
- in Python, :func:`load_plugin` (or by passing :class:`~pkdyn.design.Metric` objects directly);
- or installed: a package that declares an entry point in the group :data:`ENTRY_POINT_GROUP`
  (``[project.entry-points."pkdyn.plugins"] mine = "mypackage.metrics"``) is loaded the first
  time a study names something pkdyn does not know (installing a package is the user's choice).

A ``module:attribute`` whose module was not loaded is refused with a message that says how to
load it. A plug-in given as a file is shipped to the workers by value (they need not have it).
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

from pkdyn.exceptions import InvalidInputError

__all__ = ["ENTRY_POINT_GROUP", "load_entry_points", "load_plugin", "loaded_plugins", "resolve"]

ENTRY_POINT_GROUP = "pkdyn.plugins"
"""Entry-point group of installed plug-ins."""

_LOADED: dict[str, ModuleType] = {}
_FILES: dict[str, ModuleType] = {}
_ENTRY_POINTS: list[bool] = []


def loaded_plugins() -> list[str]:
    """Names of the plug-in modules loaded in this process."""
    return sorted(_LOADED)


def load_plugin(name: str) -> ModuleType:
    """Load a plug-in: import a module by name, or a ``.py`` file by path.

    Importing runs the module's code: this is the user's explicit choice (``--plugin``).

    Args:
        name: A module name (``mypackage.metrics``) or a path to a ``.py`` file.

    Returns:
        The module (its metrics registered, its parametrisations resolvable by
        ``module:attribute``).

    Raises:
        InvalidInputError: No such module or file, or the module fails to import (its error
            in one line).

    """
    if not isinstance(name, str) or not name.strip():
        raise InvalidInputError("--plugin", f"expected a module name or a .py file, got {name!r}")
    if name.endswith(".py") or "/" in name or name.startswith("."):
        return _load_file(Path(name))
    try:
        module = importlib.import_module(name)
    except ModuleNotFoundError as err:
        hint = " (a file in this directory: --plugin ./NAME.py)" if err.name == name else ""
        raise InvalidInputError("--plugin", f"no module named '{err.name}'{hint}") from None
    except (Exception, SystemExit) as err:  # the plug-in's own error (or exit), in one line
        raise InvalidInputError("--plugin", f"'{name}' failed to import: {_line(err)}") from None
    _LOADED[name] = module
    return module


def _line(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _load_file(path: Path) -> ModuleType:
    if not path.is_file() or path.suffix != ".py":
        raise InvalidInputError("--plugin", f"'{path}' is not a .py file")
    key = str(path.resolve())
    if key in _FILES:  # once per process
        return _FILES[key]
    name = path.stem
    if not name.isidentifier():
        raise InvalidInputError("--plugin", f"'{path}': the file name must be a Python identifier")
    _check_unshadowed(path, name)
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:  # pragma: no cover - a .py file always has one
        raise InvalidInputError("--plugin", f"'{path}' cannot be imported")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except (Exception, SystemExit) as err:  # the plug-in's own error (or exit), in one line
        sys.modules.pop(name, None)
        raise InvalidInputError("--plugin", f"'{path}' failed to import: {_line(err)}") from None
    try:  # workers (spawned, Dask) cannot import a file by name: ship its code
        import cloudpickle

        cloudpickle.register_pickle_by_value(module)
    except (ImportError, ValueError):  # pragma: no cover
        pass
    _LOADED[name] = module
    _FILES[key] = module
    return module


def _check_unshadowed(path: Path, name: str) -> None:
    """Refuse a plug-in file named like a module Python already has or can import.

    Loading ``json.py`` as module ``json`` would replace the standard library's for the rest of
    the run (every ``import json`` then gets the plug-in); a file that *is* the importable
    module (its directory on the Python path) is not a clash.

    Raises:
        InvalidInputError: The clash, naming the module and where it comes from.

    """
    loaded = sys.modules.get(name)
    origin = getattr(loaded, "__file__", None) if loaded is not None else None
    if name in _LOADED and origin and Path(origin).resolve() != path.resolve():
        raise InvalidInputError(
            "--plugin",
            f"'{path}': a plug-in named '{name}' is already loaded from {origin}; rename one "
            "of the files",
        )
    if loaded is None:
        try:
            spec = importlib.util.find_spec(name)
        except (ImportError, ValueError):
            spec = None
        if spec is None:
            return
        origin = spec.origin
    if origin and Path(origin).resolve() == path.resolve():
        return
    where = f" ({origin})" if origin else " (built in)"
    raise InvalidInputError(
        "--plugin",
        f"'{path}': a plug-in file is loaded as module '{name}', the name of a module Python "
        f"already has{where}; loading it would replace that module: rename the file",
    )


def load_entry_points() -> list[str]:
    """Load the installed plug-ins (entry-point group :data:`ENTRY_POINT_GROUP`) once.

    Returns:
        The names of the modules loaded.

    """
    if _ENTRY_POINTS:
        return []
    _ENTRY_POINTS.append(True)
    from importlib.metadata import entry_points

    names = []
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        module = ep.value.partition(":")[0]
        load_plugin(module)
        names.append(module)
    return names


def resolve(name: str, what: str) -> Any:
    """The object named ``module:attribute`` in a loaded plug-in.

    Args:
        name: ``module:attribute``.
        what: What is looked for (``metric``, ``parametrisation``), for messages.

    Returns:
        The attribute.

    Raises:
        InvalidInputError: The module is not a loaded plug-in (nothing is imported), or it has
            no such attribute.

    """
    module, _, attr = name.partition(":")
    if module not in _LOADED:
        load_entry_points()
    if module not in _LOADED:
        raise InvalidInputError(
            what,
            f"'{name}': module '{module}' is not a loaded plug-in, and a study never imports "
            f"code by itself; load it with --plugin {module} (pkdyn.design.load_plugin"
            f"('{module}') in Python) if you trust it",
        )
    try:
        return getattr(_LOADED[module], attr)
    except AttributeError:
        raise InvalidInputError(what, f"'{name}': plug-in '{module}' has no '{attr}'") from None
