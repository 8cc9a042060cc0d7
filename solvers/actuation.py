"""Actuation selection: actuator efforts as generalized forces on the velocity coordinates.

Joint friction, dampers and springs are :mod:`solvers.passive`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["Actuation"]


class Actuation:
    """Actuated velocity coordinates and their transmission gains.

    The generalized force of actuator efforts ``tau`` (n_a,) is ``S^T tau`` with
    ``S[i, v_index[i]] = gains[i]``: ``gains`` are reductions when ``tau`` is a motor-side
    effort, ones (default) when ``tau`` is the joint-side effort.

    Args:
        v_index: Velocity index of each actuator (n_a,), distinct.
        gains: Transmission gain of each actuator (n_a,) (default: ones).
        names: Actuator names, for error messages (default ``a0, a1, ...``).

    Raises:
        ValueError: Repeated or negative indices, or sizes that do not match.

    """

    def __init__(
        self,
        v_index: Sequence[int] | np.ndarray,
        gains: Sequence[float] | np.ndarray | None = None,
        names: Sequence[str] | None = None,
    ) -> None:
        self.v_index = np.asarray(v_index, dtype=int).reshape(-1)
        n = self.v_index.size
        if np.unique(self.v_index).size != n or np.any(self.v_index < 0):
            raise ValueError(
                f"actuated velocity indices must be distinct and >= 0: {self.v_index.tolist()}"
            )
        self.gains = np.ones(n) if gains is None else np.asarray(gains, dtype=float).reshape(-1)
        if self.gains.size != n:
            raise ValueError(f"{self.gains.size} gains for {n} actuators")
        self.names = [f"a{i}" for i in range(n)] if names is None else list(names)
        if len(self.names) != n:
            raise ValueError(f"{len(self.names)} names for {n} actuators")

    @property
    def n(self) -> int:
        """Number of actuators."""
        return int(self.v_index.size)

    def matrix(self, nv: int) -> np.ndarray:
        """Selection matrix ``S`` (n_a, nv): the generalized force is ``S^T tau``.

        Args:
            nv: Size of the velocity vector.

        Returns:
            ``S``.

        """
        S = np.zeros((self.n, nv))
        S[np.arange(self.n), self.v_index] = self.gains
        return S

    def generalized(self, tau: np.ndarray, nv: int) -> np.ndarray:
        """Generalized force ``S^T tau`` (nv,) [N m or N] of actuator efforts ``tau`` (n_a,)."""
        out = np.zeros(nv)
        out[self.v_index] = self.gains * tau
        return out

    def velocity(self, v: np.ndarray) -> np.ndarray:
        """Actuator-side velocities ``S v`` (n_a,) conjugate to ``tau`` [rad/s or m/s]."""
        return self.gains * v[self.v_index]
