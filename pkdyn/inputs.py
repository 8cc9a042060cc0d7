"""Numbers checked at the public boundary, before any arithmetic touches them.

Every public function that takes a scalar from a user (a time step, a duration, a count, a
distance) validates it here first: a real number (not a string, a complex, a bool or ``None``),
finite, in its range, and whole where it counts something. A failure raises
:class:`~pkdyn.exceptions.InvalidInputError` naming the input, its unit and what was given, so
the CLI prints one line; nothing reaches a division, a ``range`` or an ``int()`` that would
raise ``ZeroDivisionError``, ``OverflowError`` or run without end.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from typing import Any

from pkdyn.exceptions import InvalidInputError

__all__ = [
    "MAX_MAGNITUDE",
    "callable_input",
    "count",
    "non_negative",
    "positive",
    "real",
]

MAX_MAGNITUDE = 1e9
"""Largest magnitude of an input in SI units: beyond it a length, time or mass is a typing or
unit error, and products of a few such numbers would overflow."""


def _unit(unit: str) -> str:
    return f" {unit}" if unit else ""


def real(name: str, value: Any, unit: str = "", *, bound: float = MAX_MAGNITUDE) -> float:
    """A finite real number of magnitude at most ``bound``.

    Args:
        name: The input's name, for the message (``dt``, ``--step``).
        value: What was given.
        unit: Its unit, for the message (``s``, ``m``).
        bound: Largest magnitude accepted.

    Returns:
        ``value`` as a float.

    Raises:
        InvalidInputError: Not a real number (a string, complex, bool, ``None``), NaN,
            infinite or beyond ``bound``.

    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        what = f"a real number [{unit}]" if unit else "a real number"
        raise InvalidInputError(name, f"expected {what}, got {value!r} ({type(value).__name__})")
    x = float(value)
    if not math.isfinite(x):
        what = f"a finite number [{unit}]" if unit else "a finite number"
        raise InvalidInputError(name, f"must be {what}, got {x}")
    if abs(x) > bound:
        raise InvalidInputError(
            name, f"{x:g}{_unit(unit)} is beyond any plausible value (at most {bound:g})"
        )
    return x


def positive(name: str, value: Any, unit: str = "", *, bound: float = MAX_MAGNITUDE) -> float:
    """A finite real number > 0 (see :func:`real`).

    Raises:
        InvalidInputError: Not a finite real number, or not > 0.

    """
    x = real(name, value, unit, bound=bound)
    if not x > 0.0:
        raise InvalidInputError(name, f"must be > 0{_unit(unit)}, got {x:g}")
    return x


def non_negative(name: str, value: Any, unit: str = "", *, bound: float = MAX_MAGNITUDE) -> float:
    """A finite real number >= 0 (see :func:`real`).

    Raises:
        InvalidInputError: Not a finite real number, or negative.

    """
    x = real(name, value, unit, bound=bound)
    if x < 0.0:
        raise InvalidInputError(name, f"must be >= 0{_unit(unit)}, got {x:g}")
    return x


def count(name: str, value: Any, minimum: int = 1, maximum: int | None = None) -> int:
    """A whole number in ``[minimum, maximum]``.

    An integral float (``2.0``) is accepted; ``2.5``, a bool, NaN or a string are not.

    Args:
        name: The input's name, for the message.
        value: What was given.
        minimum: Smallest value accepted.
        maximum: Largest value accepted (``None``: no bound beyond :data:`MAX_MAGNITUDE`).

    Returns:
        ``value`` as an int.

    Raises:
        InvalidInputError: Not a whole number, or out of range.

    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidInputError(
            name, f"expected a whole number, got {value!r} ({type(value).__name__})"
        )
    if isinstance(value, numbers.Integral):
        n = int(value)
    else:
        x = float(value)
        if not (math.isfinite(x) and x.is_integer()):
            raise InvalidInputError(name, f"must be a whole number, got {value!r}")
        n = int(x)
    if n < minimum:
        raise InvalidInputError(name, f"must be a whole number >= {minimum}, got {n}")
    top = int(MAX_MAGNITUDE) if maximum is None else maximum
    if n > top:
        raise InvalidInputError(name, f"must be a whole number <= {top}, got {n}")
    return n


def callable_input(name: str, value: Any) -> Callable[..., Any]:
    """A function given by the user (a torque law, a metric).

    Raises:
        InvalidInputError: ``value`` cannot be called.

    """
    if not callable(value):
        raise InvalidInputError(
            name, f"expected a function, got {value!r} ({type(value).__name__})"
        )
    return value
