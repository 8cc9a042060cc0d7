"""Which parameters a set of measurements identifies: QR with column pivoting, observability.

The identification Jacobian ``W`` stacks, over the measured poses, the derivatives of the
weighted residuals (measurement minus model, divided by the measurement's standard deviation)
with respect to the parameters; for a closed-loop robot each block is
:func:`pkdyn.precision.sensitivity.pose_sensitivity`'s ``K`` (the loops eliminated).

**Identifiable subset.** Columns are scaled to unit norm (identifiability does not depend on
units) and factorised by QR with column pivoting, ``W P = Q R``: the pivoted columns whose
``|R_kk|`` exceed ``rtol |R_00|`` form the identifiable subset (a basis of the column space,
the best-determined first); each of the others is a combination of them, ``W_j = sum_i c_ij
W_i`` (``c = R11^-1 R12`` rescaled): its error cannot be told apart from errors ``c_ij p_j`` of
the identifiable parameters, which absorb it. Those *unidentifiable* parameters are reported
with their combination and held at their nominal values, never estimated.

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

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg

from pkdyn.exceptions import InvalidInputError

__all__ = [
    "INDICES",
    "RTOL",
    "Identifiability",
    "identifiability",
    "observability",
    "pivoted_qr",
]

RTOL = 1e-7
"""Default relative threshold on ``|R_kk| / |R_00|`` (unit columns): structural losses of rank
fall to ~1e-12 (the sensitivities are exact to ~1e-10), a parameter with ``|R_kk|`` below this
would amplify a 1e-5 measurement noise to metres."""

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


@dataclass
class Identifiability:
    """The identifiable subset of a parameter model on a set of measurements.

    Attributes:
        names: Parameter names (n_par,).
        identifiable: Indices of the identifiable parameters, best determined first (r,).
        unidentifiable: Indices of the others.
        combinations: For each unidentifiable index, the coefficients ``c`` (r,) over
            ``identifiable`` of the combination its column equals (its error is absorbed by
            ``c * p_j`` on those parameters).
        r_diag: ``|R_kk| / |R_00|`` in pivot order (n_par,).
        singular_values: Singular values of the scaled identifiable columns (r,).
        indices: Observability indices ``O1`` ... ``O5``.
        poses: Number of poses.
        weak: The unidentifiable parameters that are so only because the measurements tell
            less about them than the prior (:func:`identifiability`'s ``prior``): identifiable
            in principle, with other poses or less noise.

    """

    names: tuple[str, ...]
    identifiable: np.ndarray
    unidentifiable: np.ndarray
    combinations: dict[int, np.ndarray] = field(default_factory=dict)
    r_diag: np.ndarray = field(default_factory=lambda: np.zeros(0))
    singular_values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    indices: dict[str, float] = field(default_factory=dict)
    poses: int = 0
    weak: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))

    @property
    def rank(self) -> int:
        """Number of identifiable parameters."""
        return int(self.identifiable.size)

    @property
    def noise_amplification(self) -> float:
        """Noise amplification index ``O4 = s_L^2 / s_1``."""
        return self.indices.get("O4", 0.0)

    def combination(self, j: int, tol: float = 1e-6, top: int = 6) -> list[tuple[str, float]]:
        """The identifiable parameters an unidentifiable one ``j`` is absorbed by.

        Args:
            j: Index of an unidentifiable parameter.
            tol: Smallest coefficient listed (relative to the largest).
            top: Largest number of terms listed.

        Returns:
            ``[(name, coefficient), ...]``, largest coefficients first: an error ``e`` of
            parameter ``j`` moves the poses as errors ``coefficient * e`` of those parameters
            do. Empty when the parameter moves nothing measured.

        """
        from pkdyn.inputs import count, positive

        j = count("j", j, 0, len(self.names) - 1)
        tol = positive("tol", tol)
        top = count("top", top, 1)
        c = self.combinations.get(j)
        if c is None or c.size == 0 or np.max(np.abs(c)) == 0.0:
            return []
        order = np.argsort(-np.abs(c))
        big = float(np.max(np.abs(c)))
        return [
            (self.names[int(self.identifiable[i])], float(c[i]))
            for i in order[:top]
            if abs(c[i]) > tol * big
        ]

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "identifiable": [self.names[i] for i in self.identifiable],
            "unidentifiable": [
                {
                    "name": self.names[j],
                    "reason": "weak" if j in set(self.weak.tolist()) else "structural",
                    "absorbed_by": [{"name": n, "coefficient": c} for n, c in self.combination(j)],
                }
                for j in self.unidentifiable
            ],
            "observability": dict(self.indices),
            "noise_amplification": self.noise_amplification,
            "poses": self.poses,
        }


def pivoted_qr(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """QR with column pivoting (Businger-Golub): ``A[:, piv] = Q R``, ``|R_kk|`` non-increasing.

    Householder reflections with the largest remaining column norm as pivot, in elementwise
    numpy (no multithreaded BLAS call: LAPACK's ``geqp3`` and ``geqrf`` can be 100 times
    slower than this on a loaded two-core machine, their threads waiting on each other).

    Args:
        A: Matrix (m, n).

    Returns:
        ``R`` (min(m, n), n), upper trapezoidal, and the permutation ``piv`` (n,).

    """
    R = np.array(A, dtype=float)
    m, n = R.shape
    piv = np.arange(n)
    for k in range(min(m, n)):
        norms = np.einsum("ij,ij->j", R[k:, k:], R[k:, k:])
        j = k + int(np.argmax(norms))
        if j != k:
            R[:, [k, j]] = R[:, [j, k]]
            piv[[k, j]] = piv[[j, k]]
        x = R[k:, k]
        nx = float(np.sqrt(np.einsum("i,i->", x, x)))
        if nx == 0.0:
            break
        v = x.copy()
        v[0] += nx if x[0] >= 0.0 else -nx
        vv = float(np.einsum("i,i->", v, v))
        block = R[k:, k:]
        block -= np.multiply.outer(v, np.einsum("i,ij->j", v, block) * (2.0 / vv))
        R[k + 1 :, k] = 0.0
    return np.triu(R[: min(m, n)]), piv


def identifiability(
    W: np.ndarray,
    names: tuple[str, ...] | list[str],
    poses: int,
    scale: np.ndarray | None = None,
    rtol: float = RTOL,
    prior: np.ndarray | None = None,
) -> Identifiability:
    """Identifiable subset, unidentifiable combinations and observability indices of ``W``.

    With ``prior`` (a prior standard deviation per parameter, ``W`` weighted by the measurement
    standard deviations), the columns are scaled by it instead of to unit norm: ``|R_kk|`` is
    then the ratio of the prior to the standard deviation the measurements give that parameter
    (the others of the subset known), and a parameter with ``|R_kk| < 1`` (the measurements
    tell less about it than the prior) is *weakly* identifiable: not estimated either.

    Args:
        W: Weighted identification Jacobian (rows, n_par) (module docstring).
        names: Parameter names (n_par,).
        poses: Number of measured poses.
        scale: Parameter scales (n_par,) for the observability indices (e.g. 1 for lengths in
            m, the robot's size for angles); default 1.
        rtol: Relative threshold of the pivoted QR (:data:`RTOL`).
        prior: Prior standard deviations (n_par,) (see above), or ``None``.

    Returns:
        The identifiability analysis.

    """
    from pkdyn.inputs import count, matrix, positive, vector
    from pkdyn.inputs import names as names_

    W = matrix("W", W, bound=np.inf)
    n = W.shape[1]
    names = names_("names", names, what="parameter")
    if len(names) != n:
        raise InvalidInputError("names", f"{len(names)} names for {n} columns of W")
    poses = count("poses", poses, 1)
    rtol = positive("rtol", rtol)
    if scale is not None:
        scale = vector("scale", scale, n)
    if prior is not None:
        prior = vector("prior", prior, n, bound=np.inf)
    norms = np.linalg.norm(W, axis=0)
    big = float(np.max(norms, initial=0.0))
    live = np.flatnonzero(norms > 1e-12 * max(big, 1e-300))
    dead = np.setdiff1d(np.arange(n), live)
    if live.size == 0:
        return Identifiability(tuple(names), np.zeros(0, int), np.arange(n), poses=poses)
    with np.errstate(divide="ignore"):
        col = 1.0 / norms if prior is None else np.asarray(prior, dtype=float)
    R, piv = pivoted_qr(W[:, live] * col[live])
    d = np.abs(np.diag(R))
    d_full = np.zeros(live.size)
    d_full[: d.size] = d
    r_struct = int(np.sum(d > rtol * d[0]))
    r = r_struct if prior is None else int(np.sum(d[:r_struct] >= 1.0))
    ident = live[piv[:r]]
    rest = live[piv[r:]]
    weak = live[piv[r:r_struct]]
    combos: dict[int, np.ndarray] = {}
    if rest.size:
        R11 = R[:r, :r]
        R12 = R[:r, r:] if R.shape[0] >= r else np.zeros((r, rest.size))
        beta = scipy.linalg.solve_triangular(R11, R12)
        for k, j in enumerate(rest):
            combos[int(j)] = beta[:, k] * col[ident] / col[j]
    for j in dead:
        combos[int(j)] = np.zeros(r)
    sc = np.ones(n) if scale is None else np.asarray(scale, dtype=float)
    Ws = W[:, ident] * sc[ident]
    if r and Ws.shape[0] > r:
        Ws = pivoted_qr(Ws)[0]  # same singular values, a small matrix
    s = np.linalg.svd(Ws, compute_uv=False) if r else np.zeros(0)
    return Identifiability(
        tuple(names),
        ident,
        np.concatenate([rest, dead]).astype(int),
        combos,
        d_full / d[0],
        s,
        observability(s, poses),
        poses,
        weak.astype(int),
    )
