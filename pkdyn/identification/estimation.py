"""Weighted least squares of the base parameters, accumulated sample batch by sample batch.

The rows of each actuator ``j`` are folded into the triangular factor ``R_j`` of
``[Y_j  y_j]`` (QR, never the normal equations), so memory stays ``n_a (p_b + 1)^2`` whatever
the number of samples. Then (Gautier's weighted least squares):

1. ordinary least squares on all rows (unit columns, minimum norm: :func:`solvers.numerics.
   lstsq` with :data:`EXCITATION_RTOL`): ``theta_0``;
2. per actuator the noise variance ``sigma_j^2 = |y_j - Y_j theta_0|^2 / (N - p_b / n_a)``;
3. the rows of actuator ``j`` weighted by ``1 / sigma_j``: the weighted regressor ``W``;
4. **which base parameters the motion excites** (:func:`solvers.numerics.column_basis` on ``W``,
   each column scaled by a plausible magnitude of its parameter, ``reference``: the nominal value
   of the combination, or a typical one of its kind): a parameter is *excited* unless the data
   determine it worse than :data:`EXCITATION_MIN` of that magnitude (the pivoted QR's ``|R_kk|
   >= EXCITATION_MIN``: its standard deviation, the better-determined parameters known, below
   ten times its magnitude: the data see it). The others are not estimated: they are held at
   their nominal values and flagged, never given the small standard deviation a wild estimate
   would have relative to itself;
5. the excited parameters: ``theta_b`` and their covariance ``s^2 (W_e^T W_e)^-1`` (``s^2`` the
   residual variance per degree of freedom), hence the standard deviation of each; the
   unexcited ones get the standard deviation the data would give them, the excited ones known.

``excitation = reference / std`` says per parameter how well the motion excites it: the
standard deviation relative to the parameter's plausible magnitude, not to its estimate (which
would flatter a wild estimate). The condition number of the weighted regressor with unit columns
is reported.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pkdyn.exceptions import InvalidInputError
from solvers import numerics

__all__ = ["EXCITATION_MIN", "EXCITATION_RTOL", "Accumulator", "Estimate"]

EXCITATION_RTOL = 1e-8
"""Relative tolerance of the rank rule on the unit-column weighted regressor: a motion leaves a
base parameter undetermined below it whatever its magnitude."""

EXCITATION_MIN = 0.1
"""Smallest ``reference / std`` of an excited base parameter: a standard deviation beyond ten
times the parameter's plausible magnitude means the data do not see it."""

_FOLD_ROWS = 4096


def _qr_r(A: np.ndarray) -> np.ndarray:
    """The triangular factor of ``A`` (numpy's QR, ``mode="r"``)."""
    return np.asarray(np.linalg.qr(A, mode="r"))


@dataclass(frozen=True, eq=False)  # numpy fields
class Estimate:
    """Weighted least-squares estimate of the base parameters.

    Attributes:
        theta: Base parameters (p_b,) (the unexcited ones: their nominal values, held).
        std: Their standard deviations (p_b,) (the unexcited ones: what the data would give
            them, the excited ones known; ``inf`` where they have no effect on the data).
        covariance: Covariance of the excited ones (p_b, p_b) (zero rows and columns for the
            unexcited ones, whose variance ``std^2`` is on the diagonal).
        sigma: Noise standard deviation per actuator (n_a,) [N m or N] (ordinary residuals).
        rms: Residual RMS per actuator with ``theta`` (n_a,) [N m or N].
        condition: Condition number of the weighted regressor with unit columns.
        samples: Number of samples.
        R: Triangular factor (p_b, p_b) of the weighted regressor (``R^T R = W^T W``):
            ``|R (theta' - theta)|^2`` is the misfit of other base parameters ``theta'`` in
            noise units (what the data say of every direction, the unexcited ones weakly).
        excited: Whether the motion excites each base parameter (p_b,) bool.
        excitation: ``reference / std`` per base parameter (p_b,) (excited from
            :data:`EXCITATION_MIN` on).
        reference: The magnitude each base parameter was judged against (p_b,).

    """

    theta: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    sigma: np.ndarray
    rms: np.ndarray
    condition: float
    samples: int
    R: np.ndarray
    excited: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    excitation: np.ndarray = field(default_factory=lambda: np.zeros(0))
    reference: np.ndarray = field(default_factory=lambda: np.zeros(0))


class Accumulator:
    """Triangular factors of ``[Y_j  y_j]`` per actuator, fed by batches of rows.

    Args:
        n_a: Number of actuators.
        p: Number of base parameters.

    """

    def __init__(self, n_a: int, p: int) -> None:
        self.n_a, self.p = n_a, p
        self.R = [np.zeros((0, p + 1)) for _ in range(n_a)]
        self._pending: list[list[np.ndarray]] = [[] for _ in range(n_a)]
        self._rows = 0
        self.samples = 0

    def add(self, Y: np.ndarray, y: np.ndarray) -> None:
        """Add the rows of ``n`` samples.

        Args:
            Y: Base regressor (n, n_a, p).
            y: Efforts minus the known terms (n, n_a) [N m or N].

        """
        for j in range(self.n_a):
            self._pending[j].append(np.column_stack([Y[:, j], y[:, j]]))
        self._rows += Y.shape[0]
        self.samples += Y.shape[0]
        if self._rows >= _FOLD_ROWS:
            self._fold()

    def merge(self, R: list[np.ndarray], samples: int) -> None:
        """Fold in the factors of another accumulator (the same parameters, other samples).

        Args:
            R: Its triangular factors, one per actuator.
            samples: Its number of samples.

        """
        for j in range(self.n_a):
            self._pending[j].append(R[j])
        self._rows += 1
        self.samples += samples
        self._fold()

    def factors(self) -> list[np.ndarray]:
        """The triangular factors so far, one per actuator (pending rows folded in)."""
        self._fold()
        return list(self.R)

    def _fold(self) -> None:
        for j in range(self.n_a):
            if self._pending[j]:
                A = np.vstack([self.R[j], *self._pending[j]])
                self.R[j] = _qr_r(A)
                self._pending[j] = []
        self._rows = 0

    def estimate(self, names: list[str], reference: np.ndarray, nominal: np.ndarray) -> Estimate:
        """The weighted least-squares estimate (module doc).

        Args:
            names: Base parameter formulas, for messages.
            reference: A plausible magnitude of each base parameter (p_b,) > 0.
            nominal: The nominal value of each base parameter (p_b,): held where the motion does
                not excite it.

        Returns:
            The estimate.

        Raises:
            InvalidInputError: Fewer rows than base parameters, or a motion that excites none.

        """
        self._fold()
        p, N, n_a = self.p, self.samples, self.n_a
        if N * n_a < p or N < 2:
            raise InvalidInputError(
                "data",
                f"{N} samples x {n_a} actuators = {N * n_a} equations for {p} base parameters; "
                f"record at least {int(np.ceil(p / n_a)) + 1} samples (many more in practice)",
            )
        Rs = [self._square(R) for R in self.R]
        # 1-2. ordinary least squares (unit columns, minimum norm), noise per actuator
        S = _qr_r(np.vstack(Rs))
        theta0 = _unit_lstsq(S[:p, :p], S[:p, p], EXCITATION_RTOL)
        dof = max(N - p / n_a, 1.0)
        x = np.append(theta0, -1.0)
        rss = np.array([float(np.sum((R @ x) ** 2)) for R in Rs])
        sigma = np.sqrt(rss / dof)
        top = float(sigma.max())
        # an exact fit (no residual at all) has no noise to weigh the actuators by
        w = 1.0 / np.maximum(sigma, 1e-12 * top) if top > 0.0 else np.ones_like(sigma)
        # 3. the weighted factor [A b]
        Rw = self._square(_qr_r(np.vstack([R * wj for R, wj in zip(Rs, w, strict=True)])))
        A, b = Rw[:p, :p], Rw[:p, p]
        # 4. what the motion excites
        ref = np.asarray(reference, dtype=float)
        basis = numerics.column_basis(A, EXCITATION_RTOL, col_scale=ref, floor=EXCITATION_MIN)
        E = np.sort(basis.independent)
        if E.size == 0:
            raise InvalidInputError(
                "data",
                "the motion does not excite any base parameter (every one is determined worse "
                "than its magnitude); use a richer excitation (pkdyn.identification.excitation)",
            )
        U = np.setdiff1d(np.arange(p), E)
        theta = np.asarray(nominal, dtype=float).copy()
        # 5. the excited parameters, the others held
        AE = A[:, E]
        theta[E] = _unit_lstsq(AE, b - A[:, U] @ theta[U], numerics.machine_rtol(AE))
        xw = np.append(theta, -1.0)
        s2 = float(np.sum((Rw @ xw) ** 2)) / max(N * n_a - E.size, 1)
        RE = _qr_r(AE)[: E.size]
        RE_inv = np.linalg.inv(RE)
        cov = np.zeros((p, p))
        cov[np.ix_(E, E)] = s2 * (RE_inv @ RE_inv.T)
        std = np.zeros(p)
        std[E] = np.sqrt(np.diag(cov)[E])
        if U.size:  # what the data would give them, the excited ones known
            rest = A[:, U] - AE @ (RE_inv @ (RE_inv.T @ (AE.T @ A[:, U])))
            dist = np.linalg.norm(rest, axis=0)
            with np.errstate(divide="ignore"):
                std[U] = np.where(dist > 0.0, np.sqrt(s2) / dist, np.inf)
            cov[U, U] = std[U] ** 2
        rms = np.sqrt(np.array([float(np.sum((R @ xw) ** 2)) for R in Rs]) / N)
        with np.errstate(divide="ignore"):
            excitation = np.where(std > 0.0, ref / std, np.inf)
        excited = np.zeros(p, dtype=bool)
        excited[E] = True
        return Estimate(
            theta, std, cov, sigma, rms, self._condition(A), N, A, excited, excitation, ref
        )

    def _square(self, R: np.ndarray) -> np.ndarray:
        """Pad a factor to (p + 1, p + 1) rows (fewer rows than columns so far)."""
        out = np.zeros((self.p + 1, self.p + 1))
        out[: R.shape[0]] = R[: self.p + 1]
        return out

    @staticmethod
    def _condition(A: np.ndarray) -> float:
        norms = np.linalg.norm(A, axis=0)
        s = np.linalg.svd(A / np.where(norms > 0.0, norms, 1.0), compute_uv=False)
        return float(s[0] / s[-1]) if s[-1] > 0.0 else float("inf")


def _unit_lstsq(A: np.ndarray, b: np.ndarray, rtol: float) -> np.ndarray:
    """Minimum-norm least squares of ``A x = b`` with unit columns (the rank rule, ``rtol``)."""
    norms = np.linalg.norm(A, axis=0)
    safe = np.where(norms > 0.0, norms, 1.0)
    x = numerics.lstsq(A / safe, b, rtol, 1.0)
    return np.where(norms > 0.0, x / safe, 0.0)
