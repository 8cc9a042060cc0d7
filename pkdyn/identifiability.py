"""Which parameters data can tell apart: one result type for calibration and identification.

Geometric calibration (the identification Jacobian of measured poses) and dynamic identification
(the regressor of the actuator efforts) both estimate parameters whose effects on the data may be
linearly dependent. :func:`identifiability` analyses such a matrix ``A`` (m, p) with
:func:`solvers.numerics.column_basis` (the project's one rank rule, on the diagonal of a QR
factorisation of the scaled columns) and returns an :class:`Identifiability`, in one
vocabulary:

- **identifiable** parameters: the independent columns, a basis of the column space;
- **unidentifiable** parameters: the others; each one's effect equals a **combination** of the
  identifiable ones' (``A_j = sum_i c_ij A_i``), so that only the *base parameters*
  ``theta_b = K theta`` (each identifiable parameter plus the combinations loading on it) are
  determined. An unidentifiable parameter whose combination is zero has **no effect** at all;
  one that is *weak* is structurally identifiable but the data determine it worse than the
  magnitude its caller gave it (the prior of calibration, the plausible magnitude of
  identification).

Calibration holds the unidentifiable parameters at their nominal values (their errors are
absorbed by the identifiable ones, ``c_ij e_j``); identification estimates the base parameters
and writes a physically consistent full set.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkdyn.results import Result, deprecated
from solvers import numerics

__all__ = ["Identifiability", "identifiability"]


@dataclass(eq=False)  # numpy fields: no boolean ==
class Identifiability(Result):
    """Identifiable and unidentifiable parameters, and how the latter combine (module docstring).

    Attributes:
        names: Parameter names (p,).
        identifiable: Indices of the identifiable parameters (r,), in the factorisation's order
            (pivoted: the best determined first; else the given order).
        unidentifiable: Indices of the others (p - r,).
        coefficients: Combinations (r, p - r): column ``k`` holds the coefficients, over
            ``identifiable``, of the combination ``unidentifiable[k]``'s effect equals (zero:
            no effect).
        r_diag: ``|R_kk|`` of the scaled columns in factorisation order (p,) (relative to the
            first for unit columns; in units of the given magnitudes otherwise).
        weak: The unidentifiable parameters that are only weakly so (structurally independent,
            determined worse than their magnitude).
        units: Unit of each parameter (p,) (``m``, ``rad``, ``-``, ``kg``...), or empty.
        singular_values: Singular values of the scaled identifiable columns (r,) (calibration:
            the observability indices' input).
        indices: Observability indices ``O1`` ... ``O5`` (calibration), or empty.
        poses: Number of poses or samples the matrix stacks.

    """

    names: tuple[str, ...]
    identifiable: np.ndarray
    unidentifiable: np.ndarray
    coefficients: np.ndarray
    r_diag: np.ndarray = field(default_factory=lambda: np.zeros(0))
    weak: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    units: tuple[str, ...] = ()
    singular_values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    indices: dict[str, float] = field(default_factory=dict)
    poses: int = 0

    # -- the vocabulary ------------------------------------------------------------------

    @property
    def rank(self) -> int:
        """Number of identifiable parameters (base parameters)."""
        return int(self.identifiable.size)

    @property
    def size(self) -> int:
        """Number of base parameters (:attr:`rank`)."""
        return self.rank

    @property
    def combinations(self) -> dict[int, np.ndarray]:
        """``{unidentifiable index: coefficients (r,) over identifiable}``."""
        return {int(j): self.coefficients[:, k] for k, j in enumerate(self.unidentifiable)}

    @property
    def K(self) -> np.ndarray:
        """The base map (r, p): base parameters ``theta_b = K theta``."""
        K = np.zeros((self.rank, len(self.names)))
        K[np.arange(self.rank), self.identifiable] = 1.0
        if self.unidentifiable.size:
            K[:, self.unidentifiable] = self.coefficients
        return K

    @property
    def no_effect(self) -> list[str]:
        """Names of the unidentifiable parameters without any effect (zero combination)."""
        if not self.unidentifiable.size:
            return []
        none = ~np.any(self.coefficients != 0.0, axis=0)
        return [self.names[int(i)] for i in self.unidentifiable[none]]

    @property
    def grouped(self) -> list[str]:
        """Names of the parameters determined only in a combination with others."""
        K = self.K
        out = []
        for i, name in enumerate(self.names):
            col = K[:, i]
            if not np.any(col):
                continue
            rows = np.flatnonzero(col)
            alone = rows.size == 1 and np.count_nonzero(K[rows[0]]) == 1
            if not alone:
                out.append(name)
        return out

    @property
    def noise_amplification(self) -> float:
        """Noise amplification index ``O4 = s_L^2 / s_1`` (calibration; 0 without indices)."""
        return float(self.indices.get("O4", 0.0))

    def formulas(self) -> list[str]:
        """Each base parameter as ``name + c * other + ...`` (coefficients to 6 digits)."""
        out = []
        for k, i in enumerate(self.identifiable):
            terms = [self.names[int(i)]]
            for c, d in zip(self.coefficients[k], self.unidentifiable, strict=True):
                if c != 0.0:
                    terms.append(f"{'-' if c < 0 else '+'} {abs(c):.6g} {self.names[int(d)]}")
            out.append(" ".join(terms))
        return out

    def combination(self, j: int, tol: float = 1e-6, top: int = 6) -> list[tuple[str, float]]:
        """The identifiable parameters an unidentifiable one ``j`` is absorbed by.

        Args:
            j: Index of an unidentifiable parameter.
            tol: Smallest coefficient listed (relative to the largest).
            top: Largest number of terms listed.

        Returns:
            ``[(name, coefficient), ...]``, largest first: an error ``e`` of parameter ``j``
            moves the data as errors ``coefficient * e`` of those parameters do. Empty when the
            parameter has no effect (or is identifiable).

        """
        from pkdyn.inputs import count, positive

        j = count("j", j, 0, len(self.names) - 1)
        tol = positive("tol", tol)
        top = count("top", top, 1)
        c = self.combinations.get(j)
        if c is None or c.size == 0 or not np.any(c):
            return []
        order = np.argsort(-np.abs(c))
        big = float(np.max(np.abs(c)))
        return [
            (self.names[int(self.identifiable[i])], float(c[i]))
            for i in order[:top]
            if abs(c[i]) > tol * big
        ]

    # -- the result protocol -------------------------------------------------------------

    def to_json(self) -> dict[str, Any]:
        """Identifiable names, unidentifiable ones with what absorbs them, indices (JSON)."""
        weak = {int(i) for i in self.weak}
        return {
            "identifiable": [self.names[int(i)] for i in self.identifiable],
            "unidentifiable": [
                {
                    "name": self.names[int(j)],
                    "reason": "weak" if int(j) in weak else "structural",
                    "absorbed_by": [{"name": n, "coefficient": c} for n, c in self.combination(j)],
                }
                for j in self.unidentifiable
            ],
            "no_effect": self.no_effect,
            "observability": dict(self.indices),
            "noise_amplification": self.noise_amplification,
            "poses": self.poses,
        }

    def table(self) -> str:
        """Identifiable parameters, then each unidentifiable one and its combination."""
        p = len(self.names)
        lines = [f"{self.rank} of {p} parameters identifiable from {self.poses} poses or samples"]
        if self.rank:
            lines.append(
                "identifiable: " + ", ".join(self.names[int(i)] for i in self.identifiable)
            )
        weak = {int(i) for i in self.weak}
        for j in self.unidentifiable:
            terms = self.combination(int(j))
            name = self.names[int(j)]
            if not terms:
                lines.append(f"unidentifiable: {name} (no effect)")
                continue
            combo = " ".join(
                f"{'-' if c < 0 else '+'} {self._coefficient(abs(c), int(j), n)} {n}"
                for n, c in terms
            )
            why = "weakly seen, " if int(j) in weak else ""
            lines.append(f"unidentifiable: {name} ({why}acts as {combo.lstrip('+ ')})")
        if self.indices:
            lines.append(self.indices_line())
        return "\n".join(lines)

    def indices_line(self) -> str:
        """The observability indices on one line (calibration; ``""`` without them)."""
        if not self.indices:
            return ""
        return (
            "observability: "
            + ", ".join(f"{k} = {v:.3g}" for k, v in self.indices.items())
            + " (O4: noise amplification index)"
        )

    def _coefficient(self, c: float, j: int, name: str) -> str:
        """A coefficient with its unit (unit of ``j`` per unit of ``name``) when they differ."""
        if not self.units:
            return f"{c:.4g}"
        uj, ui = self.units[j], self.units[self.names.index(name)]
        if uj == ui:
            return f"{c:.4g}"
        unit = ui if uj == "-" else (f"1/{uj}" if ui == "-" else f"{ui}/{uj}")
        return f"{c:.4g} {unit}"

    # -- the old spellings (one release) -------------------------------------------------

    @property
    def independent(self) -> np.ndarray:
        """Deprecated: :attr:`identifiable`."""
        deprecated("Identifiability.independent (BaseParameters)", "identifiable")
        return self.identifiable

    @property
    def dependent(self) -> np.ndarray:
        """Deprecated: :attr:`unidentifiable`."""
        deprecated("Identifiability.dependent (BaseParameters)", "unidentifiable")
        return self.unidentifiable

    @property
    def beta(self) -> np.ndarray:
        """Deprecated: :attr:`coefficients`."""
        deprecated("Identifiability.beta (BaseParameters)", "coefficients")
        return self.coefficients

    def as_dict(self) -> dict[str, Any]:
        """Deprecated: :meth:`to_json`."""
        deprecated("Identifiability.as_dict", "to_json()")
        return self.to_json()


def identifiability(
    A: np.ndarray,
    names: tuple[str, ...] | list[str],
    poses: int = 0,
    rtol: float = numerics.IDENTIFIABILITY_RTOL,
    magnitude: np.ndarray | None = None,
    pivot: bool = True,
    units: tuple[str, ...] | list[str] = (),
) -> Identifiability:
    """Identifiable parameters of the columns of ``A`` and the combinations of the others.

    Args:
        A: The effect of each parameter on the data (m, p): an identification Jacobian or a
            regressor, each row divided by its measurement's standard deviation when
            ``magnitude`` is given.
        names: Parameter names (p,).
        poses: Number of poses or samples ``A`` stacks (reported).
        rtol: Relative tolerance of the rank rule (:data:`solvers.numerics.
            IDENTIFIABILITY_RTOL`) on unit columns, or on the columns times ``magnitude``.
        magnitude: A magnitude per parameter (p,) > 0 (a prior standard deviation, a plausible
            size): the columns are scaled by it instead of to unit norm and a parameter the data
            determine worse than it (``|R_kk| < 1``) is *weak*: unidentifiable.
        pivot: Pivoted (the best determined first) or in the order of ``names`` (earlier
            parameters kept in preference: a link's own inertia before the rotor inertia that
            combines with it).
        units: Unit of each parameter (for the table).

    Returns:
        The analysis.

    """
    A = np.asarray(A, dtype=float)
    basis = numerics.column_basis(
        A, rtol, magnitude, floor=1.0 if magnitude is not None else 0.0, pivot=pivot
    )
    return Identifiability(
        tuple(names),
        basis.independent,
        basis.dependent,
        basis.beta,
        basis.r_diag,
        basis.weak,
        tuple(units),
        poses=int(poses),
    )
