"""Dexterity indices of the direct kinematic Jacobian ``J`` (``x_dot = J qa_dot``).

- manipulability (Yoshikawa): ``w = sqrt(det(J J^T))``, the volume of the velocity ellipsoid
  ``{J qa_dot : |qa_dot| <= 1}`` [task units per actuator unit];
- condition number ``kappa = sigma_max / sigma_min`` of ``J`` (1: isotropic), capped at
  :data:`pkdyn.analysis.kinematics.COND_MAX`;
- local conditioning index ``LCI = 1 / kappa`` in ``[0, 1]`` (0 at a singularity).

All functions accept stacks of Jacobians (``(..., m, n)``). Robots whose task mixes positions
and orientations give unit-dependent indices; pass ``length`` (a characteristic length [m]) to
use ``(v, length * omega)`` as the task velocity, which makes ``J`` homogeneous when the
actuators are all of one kind.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.analysis.kinematics import COND_MAX, kinematic_models
from pkdyn.exceptions import PkdynError, SingularConfigurationError
from pkdyn.model.assembly import inverse_geometry
from pkdyn.model.robot import Robot
from pkdyn.results import Result, jsonable
from pkdyn.units import quantity, value_range

__all__ = [
    "Dexterity",
    "DexterityMap",
    "homogenise",
    "manipulability",
    "condition_number",
    "local_conditioning_index",
    "dexterity",
    "dexterity_map",
]


def homogenise(J: np.ndarray, task: Sequence[str], length: float | None) -> np.ndarray:
    """Scale the angular rows of ``J`` by a characteristic length.

    Args:
        J: Jacobians (..., m, n).
        task: Names of the m task components (``x y z rx ry rz`` subset).
        length: Characteristic length [m]; ``None`` leaves ``J`` unchanged.

    Returns:
        ``diag(1 or length) @ J``.

    """
    if length is None:
        return np.asarray(J, dtype=float)
    scale = np.array([length if t.startswith("r") else 1.0 for t in task])
    return np.asarray(J, dtype=float) * scale[:, None]


def _sv(J: np.ndarray) -> np.ndarray:
    J = np.asarray(J, dtype=float)
    bad = ~np.isfinite(J).all(axis=(-2, -1))
    s = np.linalg.svd(np.where(bad[..., None, None], 0.0, J), compute_uv=False)
    return np.where(bad[..., None], np.nan, s)


def manipulability(J: np.ndarray) -> np.ndarray | float:
    """Yoshikawa's manipulability ``sqrt(det(J J^T))`` (product of singular values).

    Args:
        J: Jacobians (..., m, n).

    Returns:
        Manipulability, shape ``(...)`` (a float for one Jacobian); NaN for non-finite ``J``.

    """
    s = _sv(J)
    out = np.prod(s[..., : min(np.shape(J)[-2:])], axis=-1)
    return float(out) if np.ndim(out) == 0 else out


def condition_number(J: np.ndarray) -> np.ndarray | float:
    """Condition number of ``J`` (finite, capped at :data:`pkdyn.analysis.kinematics.COND_MAX`).

    Args:
        J: Jacobians (..., m, n).

    Returns:
        ``sigma_max / sigma_min``, shape ``(...)``; NaN for non-finite ``J``.

    """
    s = _sv(J)
    smax, smin = s[..., 0], s[..., -1]
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(smin > smax / COND_MAX, smax / np.where(smin > 0, smin, 1.0), COND_MAX)
    k = np.where(np.isnan(smax), np.nan, k)
    return float(k) if np.ndim(k) == 0 else k


def local_conditioning_index(J: np.ndarray) -> np.ndarray | float:
    """Local conditioning index ``1 / condition_number(J)`` in ``[0, 1]``.

    Args:
        J: Jacobians (..., m, n).

    Returns:
        LCI, shape ``(...)``; 0 at (numerically) singular Jacobians, NaN for non-finite ``J``.

    """
    k = condition_number(J)
    lci = np.where(np.asarray(k) >= COND_MAX, 0.0, 1.0 / np.asarray(k))
    return float(lci) if np.ndim(lci) == 0 else lci


@dataclass
class Dexterity(Result):
    """Dexterity of one configuration.

    Attributes:
        manipulability: ``sqrt(det(J J^T))``.
        cond: Condition number of ``J`` (finite).
        lci: Local conditioning index ``1 / cond``.
        singular: ``J`` does not exist (parallel singularity, where the manipulability and
            the condition number diverge); both are then reported as
            :data:`pkdyn.analysis.kinematics.COND_MAX` and ``lci`` as 0.

    """

    manipulability: float
    cond: float
    lci: float
    singular: bool

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict (dimensionless indices of the homogenised Jacobian)."""
        return jsonable(
            {
                "manipulability": self.manipulability,
                "cond": self.cond,
                "lci": self.lci,
                "singular": self.singular,
            }
        )

    def table(self) -> str:
        """The three indices (dimensionless: the Jacobian is homogenised by a length)."""
        if self.singular:
            return "singular (parallel singularity: J does not exist)"
        return (
            f"manipulability {quantity(self.manipulability)}, cond(J) {quantity(self.cond)}, "
            f"LCI {quantity(self.lci)} (dimensionless, homogenised J)"
        )


def dexterity(
    robot: Robot, q: Sequence[float] | np.ndarray, length: float | None = None
) -> Dexterity:
    """Dexterity indices of a robot at an assembled configuration.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        length: Characteristic length for the angular task rows [m] (see :func:`homogenise`).

    Returns:
        The indices; at a parallel singularity ``singular`` is set, ``cond`` is
        :data:`pkdyn.analysis.kinematics.COND_MAX`, ``lci`` 0 and ``manipulability`` the cap too.

    """
    km = kinematic_models(robot, q)
    try:
        J = km.J
    except SingularConfigurationError:
        return Dexterity(COND_MAX, COND_MAX, 0.0, True)
    Jh = homogenise(J, km.task, length)
    return Dexterity(
        float(manipulability(Jh)),
        float(condition_number(Jh)),
        float(local_conditioning_index(Jh)),
        False,
    )


@dataclass
class DexterityMap(Result):
    """Dexterity over a list of poses (general numeric path).

    Attributes:
        poses: Requested poses (N, 6) [m, rad].
        valid: Reached and non-singular (N,).
        manipulability: (N,) NaN where not valid.
        cond: (N,) condition numbers, NaN where not valid.
        lci: (N,) local conditioning indices, NaN where not valid.

    """

    poses: np.ndarray
    valid: np.ndarray
    manipulability: np.ndarray
    cond: np.ndarray
    lci: np.ndarray

    def to_json(self) -> dict[str, Any]:
        """Poses [m, rad], validity and the indices (``None`` where not valid)."""
        return jsonable(
            {
                "poses": self.poses,
                "valid": self.valid,
                "manipulability": self.manipulability,
                "cond": self.cond,
                "lci": self.lci,
            }
        )

    def table(self) -> str:
        """How many poses are valid, and the range of each index over them."""
        return (
            f"{int(np.count_nonzero(self.valid))} of {self.valid.size} poses reached and "
            f"regular; {value_range('LCI', self.lci)}, {value_range('cond(J)', self.cond)}, "
            f"{value_range('manipulability', self.manipulability)} (dimensionless)"
        )


def dexterity_map(
    robot: Robot,
    poses: np.ndarray,
    length: float | None = None,
    q_init: np.ndarray | None = None,
) -> DexterityMap:
    """Dexterity over poses by the general numeric path (IK warm-started along the list).

    For the Delta and the planar 3-RRR, :mod:`pkdyn.analysis.maps` does the same with the
    closed forms, vectorised and much faster.

    Args:
        robot: Any robot with a platform.
        poses: (N, 3) positions or (N, 6) positions and roll, pitch, yaw [m, rad].
        length: Characteristic length for angular task rows [m].
        q_init: First initial guess (default ``robot.q_home``).

    Returns:
        The map; unreachable or singular poses are not valid (NaN values).

    """
    P = np.atleast_2d(np.asarray(poses, dtype=float))
    n = P.shape[0]
    out = {k: np.full(n, np.nan) for k in ("w", "k", "l")}
    valid = np.zeros(n, dtype=bool)
    q = robot.q_home if q_init is None else q_init
    for i, pose in enumerate(P):
        try:
            res = inverse_geometry(robot, pose, q_init=q, check_limits=False)
        except PkdynError:
            continue
        q = res.q
        d = dexterity(robot, q, length)
        if d.singular:
            continue
        valid[i] = True
        out["w"][i], out["k"][i], out["l"][i] = d.manipulability, d.cond, d.lci
    return DexterityMap(P, valid, out["w"], out["k"], out["l"])
