"""Figures for tables: round-off below a result's own scale shown as zero.

A stiffness matrix's off-diagonal ``1e-10 N/m`` beside ``5e5 N/m``, a rotation of ``1e-18 rad``
of a nacelle that cannot turn: the last bits of a computation in double precision, not figures.
:func:`chop` sets every value below ``rtol`` times a scale to zero before it is printed (the
numbers in ``to_json()`` are left as computed).
"""

from __future__ import annotations

import numpy as np

__all__ = ["ROUND_OFF", "chop"]

ROUND_OFF = 1e-12
"""Values below this fraction of their scale are printed as zero."""


def chop(values: np.ndarray, scale: float, rtol: float = ROUND_OFF) -> np.ndarray:
    """``values`` with the entries below ``rtol * scale`` set to zero (for printing).

    Args:
        values: Numbers (any shape).
        scale: The magnitude they are judged against (e.g. the largest of them, or the
            translation divided by the robot's size for rotations).
        rtol: Relative threshold.

    Returns:
        A copy.

    """
    x = np.array(values, dtype=float)
    with np.errstate(invalid="ignore"):
        x[np.abs(x) < rtol * scale] = 0.0
    return x
