"""Explicit Runge-Kutta tableaux and the joints whose configuration space commutes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["COMMUTATIVE_JOINTS", "DOPRI5", "RK4", "Tableau"]

COMMUTATIVE_JOINTS = {
    "JointModelRX",
    "JointModelRY",
    "JointModelRZ",
    "JointModelRevoluteUnaligned",
    "JointModelRUBX",
    "JointModelRUBY",
    "JointModelRUBZ",
    "JointModelRevoluteUnboundedUnaligned",
    "JointModelPX",
    "JointModelPY",
    "JointModelPZ",
    "JointModelPrismaticUnaligned",
    "JointModelTranslation",
    "JointModelHX",
    "JointModelHY",
    "JointModelHZ",
    "JointModelHelicalUnaligned",
    "JointModelUniversal",
    "JointModelSphericalZYX",
}
"""Joints whose configuration space is a commutative group (``dDifference`` is the identity);
universal and ZYX-spherical joints are parametrised by angles added by ``integrate``."""


@dataclass(frozen=True)
class Tableau:
    """Butcher tableau of an explicit Runge-Kutta method (``e``: embedded error weights)."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    e: np.ndarray

    @property
    def stages(self) -> int:
        """Number of stages."""
        return int(self.b.size)


RK4 = Tableau(
    a=np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]]),
    b=np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6]),
    c=np.array([0, 0.5, 0.5, 1.0]),
    e=np.zeros(4),
)
"""The classical fourth-order Runge-Kutta tableau (fixed step, no error estimate)."""

DOPRI5 = Tableau(
    a=np.array(
        [
            [0, 0, 0, 0, 0, 0, 0],
            [1 / 5, 0, 0, 0, 0, 0, 0],
            [3 / 40, 9 / 40, 0, 0, 0, 0, 0],
            [44 / 45, -56 / 15, 32 / 9, 0, 0, 0, 0],
            [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0, 0],
            [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0, 0],
            [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0],
        ]
    ),
    b=np.array([35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0]),
    c=np.array([0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1, 1]),
    e=np.array([71 / 57600, 0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40]),
)
"""Dormand-Prince 5(4), first same as last: the last stage is the new state."""
