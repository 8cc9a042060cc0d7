"""Figures with their units, the same way everywhere (tables, one-line reports, plots' labels).

``quantity(5.328e-5, "m")`` -> ``"53.28 um"``; ``quantity(0.0005201, "m")`` -> ``"520.1 um"``;
``quantity(2.0e4, "N m/rad")`` -> ``"20 kN m/rad"``; ``quantity(float("nan"), "m")`` -> ``"n/a"``.
SI prefixes from pico to tera on the first unit symbol (``um`` is written with a plain ``u`` so that
terminals and CSV files need no Unicode); units that take no prefix (``rad``, ``deg``, ``%``, ``s``
above one second, dimensionless ``""``, and a first symbol with a power: ``m^2``, ``m^3``, whose
prefix would scale by that power) keep their value in plain notation, without an exponent below
1e15 (``130``, not ``1.3e+02``).

:func:`vector` writes a short vector with one unit and shared precision (``[0.1, -0.2, 0] m``),
never a negative zero.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = ["columns", "matrix", "quantity", "value_range", "vector"]

_PREFIXES = [
    (1e12, "T"),
    (1e9, "G"),
    (1e6, "M"),
    (1e3, "k"),
    (1.0, ""),
    (1e-3, "m"),
    (1e-6, "u"),
    (1e-9, "n"),
    (1e-12, "p"),
]

_NO_PREFIX = {"", "rad", "deg", "%", "rad/s", "rad/s^2", "Hz"}
"""Units written without an SI prefix (angles read better in plain radians, frequencies in Hz)."""


def _plain(value: float, digits: int) -> str:
    text = f"{value:.{digits}g}"
    if "e+" in text and abs(value) < 1e15:  # 130 with 2 digits: "130", not "1.3e+02"
        mag = math.floor(math.log10(abs(value)))
        text = f"{round(value, digits - 1 - mag):.0f}"
    if text in ("-0", "-0.0"):
        text = "0"
    return text


def quantity(value: float, unit: str = "", digits: int = 4) -> str:
    """``value`` with ``digits`` significant digits, an SI prefix on ``unit`` where it helps.

    Args:
        value: The figure in SI units (``unit``).
        unit: Its SI unit (``m``, ``N``, ``N m``, ``N/m``, ``s``, ``kg m^2``, ``rad``...).
        digits: Significant digits (1 to 17).

    Returns:
        The text, e.g. ``"53.28 um"``; ``"n/a"`` for NaN, ``"inf m"`` for infinity.

    """
    v = float(value)
    if math.isnan(v):
        return "n/a"
    if math.isinf(v):
        return f"{'-' if v < 0 else ''}inf{(' ' + unit) if unit else ''}"
    first = unit.split(" ")[0].split("/")[0]
    powered = "^" in first or " or " in unit  # m^2: scaled by its power; "rad or m": which?
    if first.startswith("kg"):  # the kilogram has its prefix: grams
        return _kilograms(v, unit, digits)
    if unit in _NO_PREFIX or powered or v == 0.0 or (unit == "s" and abs(v) >= 1.0):
        return f"{_plain(v, digits)}{(' ' + unit) if unit else ''}"
    mag = abs(v)
    round_up = 1.0 - 0.5 * 10.0 ** (1 - digits)  # 999.99999 m shown as 1 km, not 1000 m
    scale, prefix = next(((s, p) for s, p in _PREFIXES if mag >= s * round_up), _PREFIXES[-1])
    return f"{_plain(v / scale, digits)} {prefix}{unit}"


def _kilograms(v: float, unit: str, digits: int) -> str:
    """A mass unit (``kg``, ``kg m^2``): prefixed on the gram, ``g`` below 1 kg, plain above."""
    rest = unit[2:]
    if v == 0.0 or abs(v) >= 1.0 or rest.startswith("^"):
        return f"{_plain(v, digits)} {unit}"
    return quantity(v * 1e3, "g" + rest, digits)


def vector(values: Iterable[float], unit: str = "", digits: int = 4, roundoff: float = 0.0) -> str:
    """A short vector with one unit: ``[0.1, -0.2, 0] m`` (no negative zero, no exponent noise).

    Args:
        values: The components in SI units.
        unit: Their common unit.
        digits: Significant digits of each component.
        roundoff: Components at most ``roundoff`` times the largest one are shown as ``0``
            (``1e-12`` for computed vectors, whose round-off would print as ``3e-15``).

    Returns:
        The text.

    """
    xs = [float(x) for x in values]
    finite = [abs(x) for x in xs if math.isfinite(x)]
    tiny = roundoff * max(finite, default=0.0)  # round-off of the vector's own scale: 0
    parts = ", ".join(_plain(0.0 if abs(x) <= tiny else x, digits) for x in xs)
    return f"[{parts}]{(' ' + unit) if unit else ''}"


def value_range(name: str, values: Iterable[float] | np.ndarray, unit: str = "") -> str:
    """``name min .. max unit`` over the finite values, or ``name: none`` when none is finite.

    Args:
        name: What the values are (``LCI``, ``cond(J)``).
        values: The values in SI units, any shape (NaN and infinite ones are passed over).
        unit: Their unit.

    Returns:
        The text, each bound written by :func:`quantity`.

    """
    x = np.asarray(values, dtype=float)
    finite = x[np.isfinite(x)]
    if finite.size == 0:
        return f"{name}: none"
    return f"{name} {quantity(float(finite.min()), unit)} .. {quantity(float(finite.max()), unit)}"


def columns(rows: Iterable[Iterable[str]], indent: str = "") -> str:
    """Rows of cells as aligned text: the first column left-aligned, the others right-aligned.

    Args:
        rows: The rows (the first is usually a header), each a sequence of cells.
        indent: Text put before every line.

    Returns:
        The lines, joined by newlines.

    """
    cells = [[str(c) for c in r] for r in rows]
    if not cells:
        return ""
    n = max(len(r) for r in cells)
    cells = [r + [""] * (n - len(r)) for r in cells]
    widths = [max(len(r[k]) for r in cells) for k in range(n)]
    return "\n".join(
        indent
        + "  ".join(
            c.ljust(widths[k]) if k == 0 else c.rjust(widths[k]) for k, c in enumerate(r)
        ).rstrip()
        for r in cells
    )


def matrix(
    values: Any,
    row_names: Iterable[str],
    column_names: Iterable[str],
    digits: int = 4,
    indent: str = "  ",
) -> str:
    """A labelled matrix: a header of column names, one line per row (no negative zero).

    Entries below ``1e-12`` of the largest one are round-off and shown as ``0``.

    Args:
        values: The (r, c) matrix.
        row_names: The r row labels (with their units, ``x [m]``).
        column_names: The c column labels.
        digits: Significant digits.
        indent: Text put before every line.

    Returns:
        The lines, joined by newlines.

    """
    import numpy as np

    M = np.atleast_2d(np.asarray(values, dtype=float))
    finite = M[np.isfinite(M)]
    tiny = 1e-12 * float(np.max(np.abs(finite))) if finite.size else 0.0
    M = np.where(np.abs(M) <= tiny, 0.0, M)  # round-off of the matrix's own scale: 0
    rows = [["", *column_names]]
    rows += [
        [name, *(_plain(float(v), digits) for v in row)]
        for name, row in zip(row_names, M, strict=True)
    ]
    return columns(rows, indent)
