"""Which parameters a set of measurements identifies, and how well: observability indices.

The identification Jacobian ``W`` stacks, over the measured poses, the derivatives of the
weighted residuals (measurement minus model, divided by the measurement's standard deviation)
with respect to the parameters; for a closed-loop robot each block is
:func:`pkdyn.precision.sensitivity.pose_sensitivity`'s ``K`` (the loops eliminated).

**Identifiable subset** (:func:`identifiability`): the project's one analysis,
:func:`pkdyn.identifiability.identifiability` (:func:`solvers.numerics.column_basis`: QR with
column pivoting of the scaled columns, the rank rule on its diagonal). The columns are scaled to
unit norm (identifiability does not depend on units), or by the prior standard deviation of each
parameter (then a parameter the measurements determine worse than the prior is *weak*: not
estimated either). Each unidentifiable parameter is a combination of the identifiable ones,
``W_j = sum_i c_ij W_i``: its error cannot be told apart from errors ``c_ij e_j`` of the
identifiable parameters, which absorb it; it is reported with its combination and held at its
nominal value, never estimated.

**Observability indices** (Sun and Hollerbach, 2008) of the identifiable columns, from the
singular values ``s_1 >= ... >= s_L`` of the scaled Jacobian (``L`` identifiable parameters,
``M`` poses; lengths in m, angles times the robot's size):

- ``O1 = (s_1 s_2 ... s_L)^(1/L) / sqrt(M)`` (Borm and Menq; D-optimality);
- ``O2 = s_L / s_1`` (the inverse condition number; Driels and Pathre);
- ``O3 = s_L`` (the minimum singular value; Nahvi et al.);
- ``O4 = s_L^2 / s_1``, the **noise amplification index** (Nahvi and Hollerbach, 1996);
- ``O5 = 1 / (1/s_1 + ... + 1/s_L)`` (Sun and Hollerbach; A-optimality).

Larger is better for all five.
"""

from __future__ import annotations

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.identifiability import Identifiability
from pkdyn.identifiability import identifiability as _identifiability
from pkdyn.results import deprecated
from solvers import numerics

__all__ = [
    "INDICES",
    "RTOL",
    "Identifiability",
    "identifiability",
    "observability",
    "pivoted_qr",
]

RTOL = numerics.IDENTIFIABILITY_RTOL
"""Default relative threshold of the rank rule on unit columns (:data:`solvers.numerics.
IDENTIFIABILITY_RTOL`)."""

INDICES = ("O1", "O2", "O3", "O4", "O5")
"""Observability indices (module docstring)."""


def observability(s: np.ndarray, poses: int) -> dict[str, float]:
    """The five observability indices of singular values ``s`` (descending) and ``poses``.

    Args:
        s: Singular values (L,) of the scaled identification Jacobian.
        poses: Number of measured poses ``M``.

    Returns:
        ``{"O1": ..., "O5": ...}`` (zeros when ``s`` is empty or has a zero).

    """
    from pkdyn.inputs import count, vector

    s = np.sort(vector("s", s, unit="", bound=np.inf))[::-1]
    poses = count("poses", poses, 1)
    if np.any(s < 0.0):
        raise InvalidInputError("s", "singular values are >= 0")
    if s.size == 0 or s[-1] <= 0.0:
        return dict.fromkeys(INDICES, 0.0)
    return {
        "O1": float(np.exp(np.mean(np.log(s))) / np.sqrt(max(poses, 1))),
        "O2": float(s[-1] / s[0]),
        "O3": float(s[-1]),
        "O4": float(s[-1] ** 2 / s[0]),
        "O5": float(1.0 / np.sum(1.0 / s)),
    }


def pivoted_qr(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Deprecated: :func:`solvers.numerics.column_qr` (``R`` and the permutation)."""
    deprecated("pkdyn.calibration.identifiability.pivoted_qr", "solvers.numerics.column_qr")
    qr = numerics.column_qr(A, rtol=0.0)
    return qr.R, qr.perm


def identifiability(
    W: np.ndarray,
    names: tuple[str, ...] | list[str],
    poses: int,
    scale: np.ndarray | None = None,
    rtol: float = RTOL,
    prior: np.ndarray | None = None,
    units: tuple[str, ...] | list[str] = (),
) -> Identifiability:
    """Identifiable subset, unidentifiable combinations and observability indices of ``W``.

    Args:
        W: Weighted identification Jacobian (rows, n_par) (module docstring).
        names: Parameter names (n_par,).
        poses: Number of measured poses.
        scale: Parameter scales (n_par,) for the observability indices (e.g. 1 for lengths in
            m, the robot's size for angles); default 1.
        rtol: Relative threshold of the rank rule (:data:`RTOL`).
        prior: Prior standard deviations (n_par,) (module docstring), or ``None``.
        units: Unit of each parameter, for the table.

    Returns:
        The analysis, with the singular values and observability indices of the identifiable
        columns.

    """
    from pkdyn.inputs import count, matrix, positive, vector
    from pkdyn.inputs import names as names_

    W = matrix("W", W, bound=np.inf)
    names = names_("names", names, what="parameter")
    if len(names) != W.shape[1]:
        raise InvalidInputError("names", f"{len(names)} names for {W.shape[1]} columns of W")
    poses = count("poses", poses, 1)
    rtol = positive("rtol", rtol)
    if scale is not None:
        scale = vector("scale", scale, W.shape[1])
    if prior is not None:
        prior = vector("prior", prior, W.shape[1], bound=np.inf)
    out = _identifiability(W, names, poses, rtol, prior, pivot=True, units=units)
    ident = out.identifiable
    sc = np.ones(W.shape[1]) if scale is None else np.asarray(scale, dtype=float)
    Ws = W[:, ident] * sc[ident]
    if ident.size and Ws.shape[0] > ident.size:
        Ws = numerics.column_qr(Ws, rtol=0.0).R  # the same singular values, a small matrix
    s = np.linalg.svd(Ws, compute_uv=False) if ident.size else np.zeros(0)
    out.singular_values = s
    out.indices = observability(s, poses)
    return out
