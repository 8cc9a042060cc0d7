"""The paper's geometric models of mode BE (seed 003, section 4.1): ``B_iIKMX`` and ``XFKMB_i``.

- ``B_iIKMX``: the locked joint values ``b_i`` from the nacelle pose ``x`` and the footholds, by
  the vector projections of equations (1)-(8) (:func:`pkdyn.library.tripod_cf.virtual_joints`),
  as if the locks were released (mode PP). :func:`bikmx` returns them as the model's lock
  coordinates (see :func:`pkdyn.library.tripod_cf.lockable_coordinates`: the lock of ``q3`` holds
  the knuckle on rod ``L``); :func:`bikmx_virtual` returns the paper's literal values.
- ``XFKMB_i``: with the locks engaged, when the (swinging) foot frame moves, the nacelle pose
  ``x`` that keeps every locked joint at its value: ``x = argmin |B_iKMX(x) - b_i|``, solved by
  :func:`scipy.optimize.least_squares` (6 equations, 6 unknowns). The actuator lengths then
  follow from the inverse geometric model (:func:`actuator_lengths`, closed form).

Both are checked in the tests against the general constraint machinery (the mode robots of
:mod:`pkdyn.tripod.modes` solved by :func:`pkdyn.inverse_geometry`).

For the four-branch walker (``branches=4``) :func:`bikmx` and :func:`bikmx_virtual` give the four
locked values of the swinging branch (the walker locks nothing on its supports) and
:func:`actuator_lengths` the eight lengths; ``XFKMB_i`` is the tripod's only: with the walker's
locks the nacelle keeps two degrees of freedom, which :mod:`pkdyn.tripod.redundancy` chooses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.optimize import least_squares

from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.exceptions import InvalidInputError, JointLimitError, UnreachablePoseError
from pkdyn.library import tripod
from pkdyn.model.pose import pose_from_vector
from pkdyn.results import Result, jsonable
from pkdyn.tripod.modes import Stance, support_branches
from pkdyn.units import vector

__all__ = [
    "XfkmbResult",
    "actuator_lengths",
    "bikmx",
    "bikmx_virtual",
    "xfkmb",
]


def _footholds(p: tripod.Params, stance: Stance | Sequence[pin.SE3]) -> list[pin.SE3]:
    feet = list(stance.footholds) if isinstance(stance, Stance) else list(stance)
    n = tripod_cf.branch_count(p)
    if len(feet) != n:
        raise InvalidInputError(
            "footholds", f"expected {n} foot frames (one per branch), got {len(feet)}"
        )
    return feet


def _pick(p: tripod.Params, s: np.ndarray, c: np.ndarray, branch: int) -> np.ndarray:
    """``[c_i[0..3], then column 0 of s of the tripod's support branches]``."""
    n = tripod_cf.branch_count(p)
    own = list(c[branch - 1])
    if n != 3:
        support_branches(branch, n)  # checks the branch number
        return np.array(own)
    return np.array(own + [s[b - 1, 0] for b in support_branches(branch)])


def bikmx_virtual(
    p: tripod.Params,
    x: pin.SE3 | Sequence[float] | np.ndarray,
    stance: Stance | Sequence[pin.SE3],
    branch: int,
) -> np.ndarray:
    """The paper's ``b_i = [q1_i, q2_i, q3_i, q6_i, q1_j, q1_k]`` (virtual joints, eqs. 1-8).

    Args:
        p: Tripod parameters.
        x: Nacelle placement ``R_P`` in ``R_B`` (or ``[x, y, z, roll, pitch, yaw]``).
        stance: Foot frames (the swinging foot's frame included).
        branch: Swinging branch ``i``.

    Returns:
        (6,) [rad]; the walker's (4,): ``[q1_i, q2_i, q3_i, q6_i]``.

    """
    s = tripod_cf.virtual_joints(p, x, _footholds(p, stance))
    return _pick(p, s, s[:, [0, 1, 2, 5]], branch)


def bikmx(
    p: tripod.Params,
    x: pin.SE3 | Sequence[float] | np.ndarray,
    stance: Stance | Sequence[pin.SE3],
    branch: int,
) -> np.ndarray:
    """``B_iIKMX`` in model coordinates: the values the locks of mode BE(i) take at ``x``.

    Args:
        p: Tripod parameters.
        x: Nacelle placement ``R_P`` in ``R_B`` (or ``[x, y, z, roll, pitch, yaw]``).
        stance: Foot frames (the swinging foot's frame included).
        branch: Swinging branch ``i``.

    Returns:
        (6,) model coordinates of ``[q1_i, q2_i, q3_i, q6_i, q1_j, q1_k]`` [rad], the order of
        :func:`pkdyn.tripod.modes.be_mode`'s ``values``; the walker's (4,):
        ``[q1_i, q2_i, q3_i, q6_i]``.

    """
    s = tripod_cf.virtual_joints(p, x, _footholds(p, stance))
    c = tripod_cf.lockable_coordinates(p, s)  # (n, 4): q1, q2, q3, q6
    return _pick(p, c, c, branch)


def actuator_lengths(
    p: tripod.Params,
    x: pin.SE3 | Sequence[float] | np.ndarray,
    stance: Stance | Sequence[pin.SE3],
) -> np.ndarray:
    """Inverse geometric model: ``[q_L1, q_R1, q_L2, ...] = |A_i P_Li|, |A_i P_Ri|``.

    Args:
        p: Tripod (or walker) parameters.
        x: Nacelle placement ``R_P`` in ``R_B``.
        stance: Foot frames.

    Returns:
        (2 n,) actuator lengths [m], in actuator order.

    """
    s = tripod_cf.virtual_joints(p, x, _footholds(p, stance))
    return tripod_cf.triangle_lengths(p, s).reshape(-1)


@dataclass
class XfkmbResult(Result):
    """Solution of ``XFKMB_i``.

    Attributes:
        placement: Nacelle placement ``R_P`` in ``R_B``.
        lengths: Actuator lengths at that pose (actuator order) [m].
        residual: ``max |B_iKMX(x) - b_i|`` [rad].
        evaluations: Number of ``B_iKMX`` evaluations.

    """

    placement: pin.SE3
    lengths: np.ndarray
    residual: float
    evaluations: int

    def to_json(self) -> dict[str, Any]:
        """``position`` [m], ``rotation`` (3x3), ``lengths`` [m], ``residual`` [rad]."""
        return jsonable(
            {
                "position": self.placement.translation,
                "rotation": self.placement.rotation,
                "lengths": self.lengths,
                "residual": self.residual,
                "evaluations": self.evaluations,
            }
        )

    def table(self) -> str:
        """The nacelle pose, the actuator lengths and the residual of the locked joints."""
        rpy = pin.rpy.matrixToRpy(self.placement.rotation)
        return (
            f"nacelle: position {vector(self.placement.translation, 'm', roundoff=1e-12)}, rpy "
            f"{vector(rpy, 'rad', roundoff=1e-12)}\nactuator lengths: {vector(self.lengths, 'm')}"
            f"\nlocked joints held to {self.residual:.2g} rad ({self.evaluations} evaluations)"
        )


def _pose(x0: pin.SE3, z: np.ndarray) -> pin.SE3:
    """``x0`` moved by ``z = [dp (world), dtheta (world)]``."""
    return pin.SE3(pin.exp3(z[3:]) @ x0.rotation, x0.translation + z[:3])


def xfkmb(
    p: tripod.Params,
    b: Sequence[float] | np.ndarray,
    stance: Stance | Sequence[pin.SE3],
    branch: int,
    x0: pin.SE3 | Sequence[float] | np.ndarray,
    tol: float = 1e-12,
    virtual: bool = False,
    check_limits: bool = True,
    max_evaluations: int = 600,
) -> XfkmbResult:
    """``XFKMB_i``: the nacelle pose that keeps the locked joints of mode BE(i) at ``b``.

    Minimises ``|B_iKMX(x) - b|`` over the nacelle pose ``x`` (6 unknowns, 6 equations) by
    :func:`scipy.optimize.least_squares` (trust region, central-difference Jacobian), from
    ``x0`` (e.g. the previous pose along a swing): the solution branch is the one connected to
    ``x0``.

    Args:
        p: Tripod parameters.
        b: Locked values: model coordinates from :func:`bikmx` (default), or the paper's
            virtual values from :func:`bikmx_virtual` when ``virtual`` is set [rad].
        stance: Foot frames, the swinging foot at its (new) pose.
        branch: Swinging branch ``i``.
        x0: Initial nacelle placement.
        tol: Largest accepted ``|B_iKMX(x) - b|`` [rad].
        virtual: Match the paper's virtual ``q3`` (measured from ``A P_C``) instead of the
            model's lock of ``q3`` (joint ``branch{i}_a``).
        check_limits: Raise if an actuator length falls outside the strokes.
        max_evaluations: Cap on the evaluations of ``B_iKMX`` (finite-difference Jacobians
            included; a regular solve takes about 80).

    Returns:
        The nacelle pose and the actuator lengths.

    Raises:
        UnreachablePoseError: No pose keeps the locks within ``tol`` near ``x0``.
        JointLimitError: The pose needs an actuator beyond its stroke (``check_limits``).
        InvalidInputError: The walker's parameters (its nacelle is not determined by the locks).

    """
    if tripod_cf.branch_count(p) != 3:
        raise InvalidInputError(
            "p",
            "XFKMB_i is the tripod's model: with the walker's locks the nacelle keeps two degrees "
            "of freedom (see pkdyn.tripod.redundancy)",
        )
    target = np.asarray(b, dtype=float).reshape(6)
    start = pose_from_vector(x0)
    feet = _footholds(p, stance)
    model = bikmx_virtual if virtual else bikmx

    def residual(z: np.ndarray) -> np.ndarray:
        d = model(p, _pose(start, z), feet, branch) - target
        return np.arctan2(np.sin(d), np.cos(d))

    sol = least_squares(
        residual,
        np.zeros(6),
        jac="3-point",
        method="lm",
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
        max_nfev=max_evaluations,
    )
    M = _pose(start, sol.x)
    err = float(np.max(np.abs(residual(sol.x))))
    if not err <= tol:
        raise UnreachablePoseError(
            f"branch{branch}",
            err,
            f"XFKMB_{branch}: no nacelle pose near the start keeps the locked joints "
            f"(residual {err:.3g} rad); the swinging foot is out of reach",
        )
    lengths = actuator_lengths(p, M, feet)
    if check_limits:
        bad = np.flatnonzero((lengths < p.stroke_min) | (lengths > p.stroke_max))
        if bad.size:
            k = int(bad[0])
            name = f"branch{k // 2 + 1}_q{'LR'[k % 2]}"
            raise JointLimitError(name, float(lengths[k]), p.stroke_min, p.stroke_max)
    return XfkmbResult(M, lengths, err, int(sol.nfev))
