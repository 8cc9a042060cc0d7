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
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = [
    "MAX_MAGNITUDE",
    "callable_input",
    "count",
    "flag",
    "instance",
    "is_complex",
    "matrix",
    "names",
    "non_negative",
    "number_array",
    "positive",
    "real",
    "seed",
    "vector",
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


def seed(name: str, value: Any) -> int:
    """A random seed: a whole number in ``[0, 2**32)`` (numpy refuses negative seeds).

    Raises:
        InvalidInputError: Not a whole number, or out of range.

    """
    return count(name, value, 0, 2**32 - 1)


def flag(name: str, value: Any) -> bool:
    """A yes/no option: ``True`` or ``False`` (a numpy bool too), nothing else.

    Raises:
        InvalidInputError: Any other value (a string ``"no"`` would otherwise count as true).

    """
    if isinstance(value, bool | np.bool_):
        return bool(value)
    raise InvalidInputError(name, f"expected True or False, got {value!r} ({type(value).__name__})")


def instance(name: str, value: Any, kind: Any, what: str) -> Any:
    """``value`` if it is an instance of ``kind``.

    Args:
        name: The input's name, for the message.
        value: What was given.
        kind: Accepted type(s).
        what: What is expected, in words (``a Robot (pkdyn.load)``).

    Raises:
        InvalidInputError: Another type.

    """
    if not isinstance(value, kind):
        raise InvalidInputError(name, f"expected {what}, got {type(value).__name__} {value!r:.60}")
    return value


def number_array(name: str, value: Any, what: str = "numbers") -> np.ndarray:
    """A number or a sequence of numbers as a flat float array (not checked further).

    Args:
        name: The input's name, for the message.
        value: A number or a (nested) sequence of numbers.
        what: What the input holds, for the message (``numbers [N, N m]``).

    Returns:
        A float array copy (n,), NaN and infinite values included.

    Raises:
        InvalidInputError: Strings, mappings, complex numbers or nested ragged lists.

    """
    try:
        if isinstance(value, str | bytes | dict) or is_complex(value):
            raise TypeError
        return np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):  # (a ragged list: np.array raises ValueError)
        raise InvalidInputError(name, f"expected {what}, got {value!r:.60}") from None


def _nonfinite(x: float) -> str:
    """``nan (NaN: not a number)``, ``inf`` or ``-inf``, for messages."""
    return "nan (NaN: not a number)" if math.isnan(x) else f"{x}"


def is_complex(value: Any) -> bool:
    """``value`` holds complex numbers.

    ``False`` for what numpy cannot make an array of, such as rows of unequal length
    (``np.iscomplexobj`` raises ``ValueError`` on those: the caller refuses them as such).
    """
    try:
        return bool(np.iscomplexobj(value))
    except (TypeError, ValueError):  # ragged: refused as such by the caller
        return False


def vector(
    name: str,
    value: Any,
    size: int | tuple[int, ...] | None = None,
    unit: str = "",
    *,
    bound: float = MAX_MAGNITUDE,
    infinite: bool = False,
) -> np.ndarray:
    """A flat array of finite real numbers, each of magnitude at most ``bound``.

    Args:
        name: The input's name, for the message.
        value: A number or a sequence of numbers.
        size: Accepted length(s), or ``None`` for any.
        unit: Unit, for the message.
        bound: Largest magnitude accepted.
        infinite: ``+inf`` is accepted (a rigid stiffness).

    Returns:
        A float array copy (n,).

    Raises:
        InvalidInputError: Strings, complex numbers or nested ragged lists; the wrong count; NaN,
            infinite or absurd values.

    """
    if isinstance(value, bool):
        raise InvalidInputError(name, f"expected numbers, got {value!r:.60}")
    arr = number_array(name, value)
    sizes = (size,) if isinstance(size, int) else size
    if sizes is not None and arr.size not in sizes:
        want = " or ".join(str(s) for s in sizes)
        raise InvalidInputError(name, f"expected {want} values, got {arr.size}")
    ok = np.isfinite(arr) | (infinite & (arr == np.inf))
    if not ok.all():
        k = int(np.flatnonzero(~ok)[0])
        raise InvalidInputError(
            name, f"value #{k + 1} is {_nonfinite(arr[k])}; give finite numbers"
        )
    big = np.isfinite(arr) & (np.abs(arr) > bound)
    if big.any():
        k = int(np.flatnonzero(big)[0])
        raise InvalidInputError(
            name,
            f"value #{k + 1} = {arr[k]:g}{_unit(unit)} is beyond any plausible value "
            f"(at most {bound:g})",
        )
    return arr


def matrix(
    name: str,
    value: Any,
    rows: int | None = None,
    cols: int | None = None,
    unit: str = "",
    *,
    bound: float = MAX_MAGNITUDE,
) -> np.ndarray:
    """A 2-D array of finite real numbers (rows of values), each of magnitude at most ``bound``.

    Args:
        name: The input's name, for the message.
        value: Rows of numbers (a sequence of sequences, or an array).
        rows: Required number of rows, or ``None`` for any (at least one).
        cols: Required number of columns, or ``None`` for any (at least one).
        unit: Unit, for the message.
        bound: Largest magnitude accepted.

    Returns:
        A float array copy (rows, cols).

    Raises:
        InvalidInputError: Not rows of numbers (strings, complex numbers, rows of unequal
            length, more or fewer than 2 dimensions), the wrong shape, no value, NaN, infinite
            or absurd values.

    """
    if isinstance(value, str | bytes | dict) or is_complex(value):
        raise InvalidInputError(name, f"expected rows of numbers, got {value!r:.60}")
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(
            name, f"expected rows of numbers (each as long), got {value!r:.60}"
        ) from None
    if arr.ndim != 2 or arr.size == 0:
        raise InvalidInputError(name, f"expected rows of numbers (2-D), got shape {arr.shape}")
    for axis, want, what in ((0, rows, "rows"), (1, cols, "columns")):
        if want is not None and arr.shape[axis] != want:
            raise InvalidInputError(
                name, f"expected {want} {what}, got {arr.shape[axis]} (shape {arr.shape})"
            )
    bad = ~np.isfinite(arr)
    if bad.any():
        i, j = (int(k) for k in np.argwhere(bad)[0])
        raise InvalidInputError(
            name, f"row {i + 1}, value #{j + 1} is {_nonfinite(arr[i, j])}; give finite numbers"
        )
    big = np.abs(arr) > bound
    if big.any():
        i, j = (int(k) for k in np.argwhere(big)[0])
        raise InvalidInputError(
            name,
            f"row {i + 1}, value #{j + 1} = {arr[i, j]:g}{_unit(unit)} is beyond any plausible "
            f"value (at most {bound:g})",
        )
    return arr


def names(
    name: str,
    value: Any,
    known: Sequence[str] | None = None,
    what: str = "name",
    *,
    empty: bool = False,
) -> tuple[str, ...]:
    """A list of names (joints, actuators, frames, metrics...), each a string, none twice.

    A single string is one name (not a sequence of one-letter names).

    Args:
        name: The input's name, for the message.
        value: A string or a sequence of strings.
        known: The names accepted, or ``None`` for any.
        what: What a name is, for the message (``joint``).
        empty: An empty list is accepted.

    Returns:
        The names, in order.

    Raises:
        InvalidInputError: Not strings (numbers, nested lists, a mapping, ``None``), no name
            when one is needed, a name given twice, or one not in ``known`` (the message lists
            the closest).

    """
    if isinstance(value, str):
        value = (value,)
    if isinstance(value, Mapping) or not isinstance(value, Iterable):
        raise InvalidInputError(
            name, f"expected a list of {what} names, got {type(value).__name__} {value!r:.60}"
        )
    out = tuple(value)
    for v in out:
        if not isinstance(v, str):
            raise InvalidInputError(
                name, f"expected {what} names (strings), got {type(v).__name__} {v!r:.60}"
            )
        if not v.strip():
            raise InvalidInputError(name, f"an empty {what} name")
    if not out and not empty:
        raise InvalidInputError(name, f"name at least one {what}")
    seen: set[str] = set()
    for v in out:
        if v in seen:
            raise InvalidInputError(name, f"{what} '{v}' is named twice")
        seen.add(v)
        if known is not None and v not in known:
            from pkdyn.exceptions import close_match

            listed = ", ".join(known[:12]) + (" ..." if len(known) > 12 else "")
            raise InvalidInputError(
                name, f"'{v}' is not a {what} ({listed}){close_match(v, list(known))}"
            )
    return out
