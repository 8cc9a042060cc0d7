"""Tables of time series for the trajectory results: what each column does, in units.

A trajectory's ``table()`` is its duration and samples, then per quantity and per actuator (or
pose component) the range it covers and its peak magnitude: what a reader checks first (does it
move, how far, how fast, how hard).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pkdyn.units import columns, quantity

__all__ = ["series_table"]


def series_table(
    title: str,
    t: np.ndarray,
    quantities: Sequence[tuple[str, np.ndarray, Sequence[str], Sequence[str]]],
) -> str:
    """The duration, then one row per column of each quantity: start, end, min, max, peak.

    Args:
        title: What the series is (a trajectory's name).
        t: Sample times (N,) [s].
        quantities: ``(label, values (N, k), column names (k,), units (k,))`` each.

    Returns:
        The text.

    """
    t = np.asarray(t, dtype=float)
    head = (
        f"{title}: {quantity(float(t[-1] - t[0]), 's')}, {t.size} samples"
        if t.size
        else f"{title}: no sample"
    )
    rows = [["", "start", "end", "min", "max", "peak |x|"]]
    for label, values, names, units in quantities:
        X = np.asarray(values, dtype=float).reshape(t.size, -1) if t.size else np.zeros((0, 0))
        for k in range(X.shape[1]):
            x, u = X[:, k], units[k] if k < len(units) else ""
            x = np.where(np.abs(x) <= 1e-12 * np.max(np.abs(x)), 0.0, x)  # round-off: 0
            rows.append(
                [
                    f"  {label} {names[k]}",
                    quantity(float(x[0]), u),
                    quantity(float(x[-1]), u),
                    quantity(float(np.min(x)), u),
                    quantity(float(np.max(x)), u),
                    quantity(float(np.max(np.abs(x))), u),
                ]
            )
    return head if len(rows) == 1 else head + "\n" + columns(rows)
