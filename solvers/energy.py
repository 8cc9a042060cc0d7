"""Kinetic energy with every joint's armature (Pinocchio 4.1 leaves some out).

``pin.computeKineticEnergy`` of Pinocchio 4.1 omits the armature (reflected rotor inertia,
``model.armature``) of ``JointModelRevoluteUnaligned`` joints, which ``crba``, ``rnea``, ``aba``
and ``constraintDynamics`` include: a model with such joints (MJCF hinges about axes such as
``-1 0 0``, with ``armature``) then loses ``0.5 armature v^2`` per joint from its energy balance.
:class:`KineticEnergy` adds it back, so that ``T = 0.5 v^T M v`` with the mass matrix the
dynamics use. Robot-agnostic (Pinocchio, numpy).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["KineticEnergy"]

_LEFT_OUT = ("JointModelRevoluteUnaligned",)
"""Joint models whose armature Pinocchio 4.1's kinetic energy omits (checked in the tests)."""


class KineticEnergy:
    """``0.5 v^T M v`` from Pinocchio's kinetic energy and the armature it leaves out.

    Args:
        model: The kinetic tree (its armature as the dynamics use it).

    """

    def __init__(self, model: pin.Model) -> None:
        idx = [
            int(model.joints[j].idx_v)
            for j in range(1, model.njoints)
            if model.joints[j].shortname() in _LEFT_OUT
            and float(model.armature[model.joints[j].idx_v]) != 0.0
        ]
        self._idx = np.array(idx, dtype=int)
        self._half_armature = 0.5 * np.asarray(model.armature, dtype=float)[self._idx]

    @property
    def active(self) -> bool:
        """Whether the model has armature Pinocchio's kinetic energy leaves out."""
        return bool(self._idx.size)

    def missing_batch(self, v: np.ndarray) -> np.ndarray:
        """:meth:`missing` of velocities (N, nv) [J] (N,)."""
        w = v[:, self._idx]
        return (w * w).dot(self._half_armature)

    def missing(self, v: np.ndarray) -> float:
        """The armature energy Pinocchio leaves out at velocity ``v`` (nv,) [J]."""
        if not self._idx.size:
            return 0.0
        w = v[self._idx]
        return float(self._half_armature.dot(w * w))

    def __call__(self, model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic energy [J] at ``(q, v)`` (runs the kinematics, as Pinocchio's does)."""
        return float(pin.computeKineticEnergy(model, data, q, v)) + self.missing(v)
