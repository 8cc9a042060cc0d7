"""Typed fields of study files and design options, checked where they enter.

A study file is data: every field is checked for its type and range before any design is
built, and a wrong one is an :class:`~pkdyn.exceptions.InvalidInputError` naming the field, what
was expected and what was found (YAML gives ``n: abc`` as a string, ``family: [delta]`` as a
list, ``payload: yes`` as a boolean: none reaches arithmetic). Counts are whole numbers (``2.0``
is accepted, ``2.5`` and ``true`` are not); numbers are finite unless a field says otherwise.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import Any

from pkdyn.exceptions import InvalidInputError

__all__ = ["integer", "mapping", "names", "number", "text"]


def _found(value: Any) -> str:
    text = repr(value)
    text = text if len(text) <= 60 else text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def integer(name: str, value: Any, low: int | None = None, high: int | None = None) -> int:
    """A whole number in ``[low, high]``.

    Raises:
        InvalidInputError: Not a whole number (booleans and fractions refused), or out of range.

    """
    ok = isinstance(value, numbers.Integral) or (
        isinstance(value, numbers.Real)
        and math.isfinite(float(value))
        and float(value).is_integer()
    )
    if isinstance(value, bool) or not ok:
        raise InvalidInputError(name, f"expected a whole number, got {_found(value)}")
    n = int(value)
    if (low is not None and n < low) or (high is not None and n > high):
        span = f">= {low}" if high is None else f"<= {high}" if low is None else f"in {low}..{high}"
        raise InvalidInputError(name, f"must be {span}, got {n}")
    return n


def number(
    name: str,
    value: Any,
    low: float | None = None,
    high: float | None = None,
    open_low: bool = False,
    unit: str = "",
) -> float:
    """A finite real number in ``[low, high]`` (``(low, high]`` with ``open_low``).

    Raises:
        InvalidInputError: Not a real number (booleans and text refused), not finite, or out of
            range.

    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidInputError(name, f"expected a number, got {_found(value)}")
    x = float(value)
    u = f" {unit}" if unit else ""
    if not math.isfinite(x):
        raise InvalidInputError(name, f"must be finite, got {x}")
    if low is not None and (x <= low if open_low else x < low):
        raise InvalidInputError(name, f"must be {'>' if open_low else '>='} {low:g}{u}, got {x:g}")
    if high is not None and x > high:
        raise InvalidInputError(name, f"must be <= {high:g}{u}, got {x:g}")
    return x


def text(name: str, value: Any, choices: Sequence[str] | None = None) -> str:
    """A string (one of ``choices`` when given).

    Raises:
        InvalidInputError: Not a string, or not one of the choices.

    """
    if not isinstance(value, str):
        raise InvalidInputError(name, f"expected a name, got {_found(value)}")
    if choices is not None and value not in choices:
        raise InvalidInputError(name, f"unknown '{value}' (use {', '.join(choices)})")
    return value


def mapping(name: str, value: Any) -> dict[str, Any]:
    """A mapping with string keys (``None``: empty).

    Raises:
        InvalidInputError: Not a mapping, or a key that is not a string.

    """
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise InvalidInputError(name, f"expected a mapping (NAME: VALUE), got {_found(value)}")
    bad = [k for k in value if not isinstance(k, str)]
    if bad:
        raise InvalidInputError(name, f"keys are names, got {_found(bad[0])}")
    return dict(value)


def names(
    name: str, value: Any, allowed: tuple[type, ...] = (), expected: str = "names"
) -> tuple[Any, ...]:
    """A list of strings (or objects of the ``allowed`` types); one string is a list of one.

    Raises:
        InvalidInputError: Not a list, or an item that is neither a string nor allowed.

    """
    if value is None:
        return ()
    if isinstance(value, str) or (allowed and isinstance(value, allowed)):
        return (value,)
    if not isinstance(value, Sequence):
        raise InvalidInputError(name, f"expected a list of {expected}, got {_found(value)}")
    for item in value:
        if not isinstance(item, str) and not (allowed and isinstance(item, allowed)):
            raise InvalidInputError(name, f"expected {expected}, got {_found(item)}")
    return tuple(value)
