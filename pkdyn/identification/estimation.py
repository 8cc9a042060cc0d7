"""Weighted least squares of the base parameters, accumulated sample batch by sample batch.

The rows of each actuator ``j`` are folded into the triangular factor ``R_j`` of
``[Y_j  y_j]`` (QR, never the normal equations), so memory stays ``n_a (p_b + 1)^2`` whatever
the number of samples. Then (Gautier's weighted least squares):

1. ordinary least squares on all rows: ``theta_0``;
2. per actuator the noise variance ``sigma_j^2 = |y_j - Y_j theta_0|^2 / (N - p_b / n_a)``;
3. the rows of actuator ``j`` weighted by ``1 / sigma_j``: ``theta_b`` and its covariance
   ``s^2 (W^T W)^-1`` (``W``: the weighted regressor, ``s^2`` its residual variance per degree
   of freedom), hence the standard deviation of each base parameter.

The motion must excite every base parameter: the condition number of the weighted regressor
with unit columns is reported, and a numerically rank-deficient one (an unexciting motion) is
refused, naming the base parameters it leaves undetermined.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = ["EXCITATION_RTOL", "Accumulator", "Estimate"]

EXCITATION_RTOL = 1e-8
"""Smallest singular value, relative to the largest, of the unit-column weighted regressor
below which a motion leaves a base parameter undetermined."""

_FOLD_ROWS = 4096


def _qr_r(A: np.ndarray) -> np.ndarray:
    """The triangular factor of ``A`` (numpy's QR, ``mode="r"``)."""
    return np.asarray(np.linalg.qr(A, mode="r"))


@dataclass(frozen=True, eq=False)  # numpy fields
class Estimate:
    """Weighted least-squares estimate of the base parameters.

    Attributes:
        theta: Base parameters (p_b,).
        std: Their standard deviations (p_b,).
        covariance: Their covariance (p_b, p_b).
        sigma: Noise standard deviation per actuator (n_a,) [N m or N] (ordinary residuals).
        rms: Residual RMS per actuator with ``theta`` (n_a,) [N m or N].
        condition: Condition number of the weighted regressor with unit columns.
        samples: Number of samples.
        R: Triangular factor (p_b, p_b) of the weighted regressor (``R^T R = W^T W``).

    """

    theta: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    sigma: np.ndarray
    rms: np.ndarray
    condition: float
    samples: int
    R: np.ndarray


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

    def estimate(self, names: list[str]) -> Estimate:
        """The weighted least-squares estimate (module doc).

        Args:
            names: Base parameter formulas, for the message of an unexciting motion.

        Returns:
            The estimate.

        Raises:
            InvalidInputError: Fewer rows than base parameters, or a motion that does not
                excite every base parameter.

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
        theta0 = self._solve(np.vstack(Rs), names, weighted=False)
        dof = max(N - p / n_a, 1.0)
        x = np.append(theta0, -1.0)
        rss = np.array([float(np.sum((R @ x) ** 2)) for R in Rs])
        sigma = np.sqrt(rss / dof)
        top = float(sigma.max())
        # an exact fit (no residual at all) has no noise to weigh the actuators by
        w = 1.0 / np.maximum(sigma, 1e-12 * top) if top > 0.0 else np.ones_like(sigma)
        Rw = _qr_r(np.vstack([R * wj for R, wj in zip(Rs, w, strict=True)]))
        Rw = self._square(Rw)
        theta = self._solve(Rw, names, weighted=True)
        A = Rw[:p, :p]
        xw = np.append(theta, -1.0)
        s2 = float(np.sum((Rw @ xw) ** 2)) / max(N * n_a - p, 1)
        Ainv = np.linalg.inv(A)
        cov = s2 * (Ainv @ Ainv.T)
        rms = np.sqrt(np.array([float(np.sum((R @ xw) ** 2)) for R in Rs]) / N)
        return Estimate(
            theta,
            np.sqrt(np.diag(cov)),
            cov,
            sigma,
            rms,
            self._condition(A),
            N,
            A,
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

    def _solve(self, R: np.ndarray, names: list[str], weighted: bool) -> np.ndarray:
        """Least squares from a stacked factor ``[R_Y  r_y]``; refuse a rank-deficient one."""
        p = self.p
        F = _qr_r(R) if R.shape[0] > p + 1 else R
        A, b = F[:p, :p], F[:p, p]
        norms = np.linalg.norm(A, axis=0)
        dead = norms <= 0.0
        U, s, Vt = np.linalg.svd(A / np.where(dead, 1.0, norms), full_matrices=False)
        if dead.any() or s[-1] <= EXCITATION_RTOL * s[0]:
            v = Vt[-1] if not dead.any() else dead.astype(float)
            order = np.argsort(-np.abs(v))
            worst = [names[i] for i in order[:3] if abs(v[i]) > 0.1 * abs(v[order[0]])]
            raise InvalidInputError(
                "data",
                "the motion does not excite every base parameter (rank-deficient regressor, "
                f"condition {s[0] / max(s[-1], 1e-300):.3g}): {'; '.join(worst)} "
                "cannot be told apart; use a richer excitation "
                "(pkdyn.identification.excitation)",
            )
        return (Vt.T @ ((U.T @ b) / s)) / norms
