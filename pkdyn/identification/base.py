"""Base parameters: the combinations of standard parameters the efforts can tell apart.

The regressor's columns are linearly dependent whatever the motion (a body's inertia about a
fixed axis and the rotor inertia of the motor that drives it; parameters of bodies that cannot
move in some direction; parameters that have no effect at all). The dependencies are found
numerically, on the regressor of random joint motions consistent with the closures (so they hold
for every motion), by the project's one identifiability analysis
(:func:`pkdyn.identifiability.identifiability`, :func:`solvers.numerics.column_basis`): columns
scaled to unit norm, QR in the order of the parameter set (a link's own parameters are kept in
preference to the rotor inertia grouped into them), a column *identifiable* when its distance to
the span of the identifiable columns before it exceeds :data:`STRUCTURAL_RTOL`. Each
unidentifiable column is a combination of the identifiable ones, ``Y_u = Y_i C``, so that

    ``Y theta = Y_i theta_b,   theta_b = theta_i + C theta_u = K theta``.

Unidentifiable parameters whose combination is zero have no effect on the efforts
(:attr:`~pkdyn.identifiability.Identifiability.no_effect`) and stay at their nominal values; the
others are identifiable only in the combinations ``theta_b`` (each base parameter is reported as
its formula).
"""

from __future__ import annotations

import numpy as np

from pkdyn.identifiability import Identifiability, identifiability

__all__ = ["STRUCTURAL_RTOL", "BaseParameters", "base_parameters"]

STRUCTURAL_RTOL = 1e-4
"""Relative distance below which a (unit) regressor column counts as a combination of others.

Exact dependencies fall to ~1e-12 and the library's robots have no column between 1e-10 and
1e-3 of the span of the others; a described robot whose symmetry is broken by small geometric
errors (a calibrated description: millimetres on a robot of a metre) has columns 1e-8 to 1e-4
from it, which only those errors tell apart: a recording would need efforts measured to better
than that fraction of their size to see them, and counted as independent they make
ill-conditioned base parameters (coefficients of hundreds) that no physically consistent fit
reproduces. They are combined instead."""

BaseParameters = Identifiability
"""The base parameters are an :class:`~pkdyn.identifiability.Identifiability` (one type for
calibration and identification; ``independent``, ``dependent`` and ``beta`` are the deprecated
spellings of ``identifiable``, ``unidentifiable`` and ``coefficients``)."""


def base_parameters(
    Y: np.ndarray, names: tuple[str, ...] | list[str], units: tuple[str, ...] | list[str] = ()
) -> Identifiability:
    """Base parameters from a regressor of random, closure-consistent motions.

    Args:
        Y: Stacked regressor rows (m, p) of random motions (m well above p).
        names: Parameter names (p,).
        units: Their units (p,), for the tables.

    Returns:
        The identifiable columns (the base) and the combinations of the others.

    """
    return identifiability(Y, names, Y.shape[0], STRUCTURAL_RTOL, pivot=False, units=units)
