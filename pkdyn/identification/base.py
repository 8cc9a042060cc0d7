"""Base parameters: the combinations of standard parameters the efforts can tell apart.

The regressor's columns are linearly dependent whatever the motion (a body's inertia about a
fixed axis and the rotor inertia of the motor that drives it; parameters of bodies that cannot
move in some direction; parameters that have no effect at all). The dependencies are found
numerically, on the regressor of random joint motions consistent with the closures (so they hold
for every motion): with columns scaled to unit norm, a column is *independent* when its distance
to the span of the independent columns before it exceeds :data:`STRUCTURAL_RTOL` (Gram-Schmidt in
column order, i.e. QR with the pivots taken in the order of the parameter set: a link's own
parameters are kept in preference to the rotor inertia grouped into them). Each dependent column
is a combination of the independent ones, ``Y_d = Y_i beta``, so that

    ``Y theta = Y_i theta_b,   theta_b = theta_i + beta theta_d``.

Dependent parameters whose ``beta`` column is zero have no effect on the efforts: they are
*unidentifiable* and stay at their nominal values; the others are identifiable only in the
combinations ``theta_b`` (each base parameter is reported as its formula).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solvers import numerics

__all__ = ["STRUCTURAL_RTOL", "BaseParameters", "base_parameters"]

STRUCTURAL_RTOL = 1e-7
"""Relative distance below which a (unit) regressor column counts as a combination of others."""

_CLEAN = 1e-9  # |beta| entries below this fraction of the column's largest are rounding noise


@dataclass(frozen=True, eq=False)  # numpy fields
class BaseParameters:
    """Base parameters of a parameter selection.

    Attributes:
        names: Names of the parameters the base is built from (p,).
        independent: Columns (into ``names``) of the base parameters (p_b,).
        dependent: The other columns (p - p_b,).
        beta: Combination coefficients (p_b, p - p_b): ``theta_b = theta_i + beta theta_d``.

    """

    names: tuple[str, ...]
    independent: np.ndarray
    dependent: np.ndarray
    beta: np.ndarray

    @property
    def size(self) -> int:
        """Number of base parameters."""
        return int(self.independent.size)

    @property
    def K(self) -> np.ndarray:
        """The map (p_b, p) from standard to base parameters."""
        K = np.zeros((self.size, len(self.names)))
        K[np.arange(self.size), self.independent] = 1.0
        if self.dependent.size:
            K[:, self.dependent] = self.beta
        return K

    @property
    def unidentifiable(self) -> list[str]:
        """Parameters without any effect on the efforts."""
        if not self.dependent.size:
            return []
        none = ~np.any(self.beta != 0.0, axis=0)
        return [self.names[i] for i in self.dependent[none]]

    @property
    def grouped(self) -> list[str]:
        """Parameters identifiable only in combination with others (their base formulas)."""
        K = self.K
        out = []
        for i, name in enumerate(self.names):
            alone = np.count_nonzero(K[:, i]) == 1 and np.count_nonzero(K[K[:, i] != 0][0]) == 1
            if np.any(K[:, i]) and not alone:
                out.append(name)
        return out

    def formulas(self) -> list[str]:
        """Each base parameter as ``name + c * other + ...``."""
        out = []
        for k, i in enumerate(self.independent):
            terms = [self.names[i]]
            for c, d in zip(self.beta[k], self.dependent, strict=True):
                if c != 0.0:
                    sign = "-" if c < 0 else "+"
                    terms.append(f"{sign} {abs(c):.6g} {self.names[d]}")
            out.append(" ".join(terms))
        return out


def base_parameters(Y: np.ndarray, names: tuple[str, ...] | list[str]) -> BaseParameters:
    """Base parameters from a regressor of random, closure-consistent motions.

    Args:
        Y: Stacked regressor rows (m, p) of random motions (m well above p).
        names: Parameter names (p,).

    Returns:
        The independent columns and the combinations of the others.

    """
    m, p = Y.shape
    norms = np.linalg.norm(Y, axis=0)
    scale = float(norms.max(initial=0.0))
    live = norms > 1e-13 * max(scale, 1e-300)
    Ys = np.zeros_like(Y)
    Ys[:, live] = Y[:, live] / norms[live]
    basis = np.zeros((m, 0))
    independent: list[int] = []
    for k in range(p):
        if not live[k]:
            continue
        c = Ys[:, k]
        r = c - basis @ (basis.T @ c)
        r -= basis @ (basis.T @ r)  # re-orthogonalise
        d = float(np.linalg.norm(r))
        if d > STRUCTURAL_RTOL:
            independent.append(k)
            basis = np.column_stack([basis, r / d])
    ind = np.array(independent, dtype=int)
    dep = np.setdiff1d(np.arange(p), ind)
    beta = np.zeros((ind.size, dep.size))
    if dep.size and ind.size:
        A = Y[:, ind]
        sol = numerics.lstsq(A, Y[:, dep], numerics.machine_rtol(A))
        big = np.abs(sol).max(axis=0, keepdims=True)
        sol[np.abs(sol) < _CLEAN * np.maximum(big, 1e-300)] = 0.0
        sol[:, ~live[dep]] = 0.0
        beta = sol
    return BaseParameters(tuple(names), ind, dep, beta)
