"""The one way results come out: ``table()``, ``to_json()`` and, where a picture helps, ``plot()``.

Every result type a public function returns derives from :class:`Result`:

- ``to_json()`` returns a dict of JSON values (numbers finite or ``None``, lists, strings,
  booleans), with SI units stated in the key names or the docs of the result; the CLI prints it
  with ``--json`` (``json.dumps(..., allow_nan=False)``).
- ``table()`` returns the text the CLI prints (units on every figure).
- ``plot(path=None, **options)`` draws the result with matplotlib (:mod:`pkdyn.plotting`) and
  writes it to ``path`` when one is given (atomically); it returns the matplotlib figure.

The core never imports the plotting layer: :mod:`pkdyn.plotting` registers its drawing
functions here (:func:`register_plot`) when it is imported, and :meth:`Result.plot` imports it
on first use (as an optional viewer would be), so the direction of imports stays downwards.
"""

from __future__ import annotations

import functools
import importlib
import math
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, TypeVar

from pkdyn.exceptions import InvalidInputError

__all__ = [
    "Result",
    "deprecated",
    "deprecated_alias",
    "jsonable",
    "plotter_for",
    "register_plot",
    "renamed_keyword",
]

F = TypeVar("F", bound=Callable[..., Any])

_PLOTTERS: dict[type, Callable[..., Any]] = {}


def register_plot(result_type: type) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Decorator of :mod:`pkdyn.plotting`: the drawing function of ``result_type``.

    The function is called as ``fn(result, path=None, **options)`` and returns the figure.

    Args:
        result_type: A :class:`Result` subclass.

    Returns:
        The decorator: the function, its first argument checked (an instance of
        ``result_type``, or what its annotation names besides: a sequence, a mapping); any other
        value is refused by :class:`~pkdyn.exceptions.InvalidInputError` naming the argument.

    """

    def deco(fn: Callable[..., Any]) -> Callable[..., Any]:
        import functools
        import inspect

        first, param = next(iter(inspect.signature(fn).parameters.items()))
        hint = str(param.annotation)
        also: tuple[type, ...] = ()
        if "Sequence" in hint:
            also += (list, tuple)
        if "Mapping" in hint:
            also += (Mapping,)

        @functools.wraps(fn)
        def checked(*args: Any, **kwargs: Any) -> Any:
            value = args[0] if args else kwargs.get(first)
            if not isinstance(value, (result_type, *also)):
                from pkdyn.exceptions import InvalidInputError

                raise InvalidInputError(
                    first,
                    f"expected a {result_type.__name__}, got {type(value).__name__} {value!r:.40}",
                )
            return fn(*args, **kwargs)

        _PLOTTERS[result_type] = checked
        return checked

    return deco


def plotter_for(result_type: type) -> Callable[..., Any] | None:
    """The drawing function registered for ``result_type`` or a base class, or ``None``.

    Imports :mod:`pkdyn.plotting` (which registers the drawing functions) on first use.
    """
    if not _PLOTTERS:
        importlib.import_module("pkdyn.plotting")
    for cls in result_type.__mro__:
        fn = _PLOTTERS.get(cls)
        if fn is not None:
            return fn
    return None


def jsonable(value: Any) -> Any:
    """``value`` with numpy arrays and scalars as lists and floats, non-finite floats as ``None``.

    Args:
        value: Numbers, arrays, sequences, mappings (string keys), strings, booleans, ``None``.

    Returns:
        A value ``json.dumps(..., allow_nan=False)`` accepts.

    """
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, Path):
        return str(value)
    tolist = getattr(value, "tolist", None)
    if tolist is not None:  # numpy arrays and scalars
        return jsonable(tolist())
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return value + 0.0 if math.isfinite(value) else None  # (+ 0.0: no negative zero)
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    raise TypeError(f"{type(value).__name__} is not a JSON value")


class Result:
    """Base of every result type: ``table()``, ``to_json()``, ``plot()`` (module docstring)."""

    def to_json(self) -> dict[str, Any]:
        """The result as JSON values (finite numbers or ``None``), SI units."""
        raise NotImplementedError(f"{type(self).__name__}.to_json")

    def table(self) -> str:
        """The result as the text the command line prints, units on every figure."""
        raise NotImplementedError(f"{type(self).__name__}.table")

    def plot(self, path: str | Path | None = None, **options: Any) -> Any:
        """Draw the result (matplotlib); write it to ``path`` when given.

        Args:
            path: Figure file (``.png``, ``.pdf``, ``.svg``...), written to a temporary name
                and renamed when complete; ``None``: only return the figure.
            **options: Options of this result's drawing function.

        Returns:
            The matplotlib figure.

        Raises:
            NotImplementedError: This result type has no picture.

        """
        fn = plotter_for(type(self))
        if fn is None:
            raise NotImplementedError(f"{type(self).__name__} has no plot")
        return fn(self, path=path, **options)


def deprecated(old: str, new: str) -> None:
    """Warn (``DeprecationWarning``) that ``old`` is kept for one release and ``new`` replaces it.

    Args:
        old: The old spelling (``CalibrationResult.as_dict``).
        new: What to use instead (``to_json()``).

    """
    warnings.warn(
        f"{old} is deprecated and will be removed in the next release: use {new}",
        DeprecationWarning,
        stacklevel=3,
    )


def deprecated_alias(old: str, new: str) -> Any:
    """A method ``old`` that warns (``DeprecationWarning``) and calls ``new``, for one release.

    ``as_json = deprecated_alias("as_json", "to_json")`` in a class body keeps the old
    spelling working while every caller moves to the one of the result protocol.
    """

    def alias(self: Any, *args: Any, **kwargs: Any) -> Any:
        warnings.warn(
            f"{type(self).__name__}.{old}() is deprecated and will be removed in the next "
            f"release; use {new}()",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(self, new)(*args, **kwargs)

    alias.__name__ = old
    alias.__doc__ = f"Deprecated alias of :meth:`{new}` (kept for one release)."
    return alias


def renamed_keyword(old: str, new: str) -> Callable[[F], F]:
    """A function's keyword ``old`` still accepted for one release, as ``new`` (the one spelling).

    ``@renamed_keyword("progress_bar", "progress")`` on a function whose parameter is now
    ``progress``: a call with ``progress_bar=`` warns (``DeprecationWarning``, naming the
    function and the new spelling) and passes the value as ``progress``; positional calls are
    unchanged (the parameter keeps its place).

    Args:
        old: The former keyword.
        new: The parameter's name now.

    Returns:
        The decorator.

    Raises:
        InvalidInputError: (from the decorated function) both spellings given.

    """

    def deco(fn: F) -> F:
        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if old in kwargs:
                if new in kwargs:
                    raise InvalidInputError(old, f"give {new} only ({old} is its former name)")
                warnings.warn(
                    f"{fn.__qualname__}({old}=...) is deprecated and will be removed in the next "
                    f"release: use {new}=",
                    DeprecationWarning,
                    stacklevel=2,
                )
                kwargs[new] = kwargs.pop(old)
            return fn(*args, **kwargs)

        renamed = {**getattr(fn, "renamed_keywords", {}), old: new}
        wrapper.renamed_keywords = renamed  # type: ignore[attr-defined]
        return wrapper  # type: ignore[return-value]

    return deco
