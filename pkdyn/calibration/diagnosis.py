"""Why measurements do not fit the nominal robot: units, axes, orientations, another robot.

A calibration corrects errors of the size of manufacturing tolerances. When the nominal robot is
farther from the measurements than its tolerances explain, the likely cause is in the data or in
the nominal robot, not in the robot's geometry, and :func:`likely_cause` names it from the data:

1. the error the tolerances can explain: at each pose, ``sqrt(sum_k (K_k t_k)^2)`` of the
   nominal identification Jacobian ``K`` and the tolerances ``t`` (independent errors of the
   size of their tolerances), plus the noise;
2. each hypothesis below is applied to the measurements and the nominal residual recomputed (no
   fit: the nominal robot is the reference); the first, in this order, that brings the residuals
   within :data:`EXPLAINED` times what the tolerances explain, and at least ten times down, is
   named:

   - **units** of the positions: centimetres, millimetres, inches (times 0.01, 0.001, 0.0254);
   - **axis order**: the position columns permuted (x and y swapped, ...) or negated, alone and
     with a unit;
   - **orientation convention** (``pose``): angles in degrees, the roll, pitch, yaw columns in
     the reverse order, the rotation of the other frame (transposed), the intrinsic x-y-z
     convention ``R = Rx Ry Rz``;
   - **another frame**: the best rigid motion of the measured positions onto the nominal ones
     (a tracker frame not the robot's world frame);

3. otherwise, when the nominal residuals exceed what the tolerances explain, **the nominal
   robot**: the measured positions' centre and spread are compared with the nominal robot's at
   the same readings (a robot of another size: check ``--param`` or the description).

What actuator readings the robot cannot be assembled at look like (degrees, millimetres) is
:func:`pkdyn.identification.checks.readings_hint`.
"""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin

from pkdyn.model.robot import Robot
from pkdyn.units import quantity, vector

__all__ = ["EXPLAINED", "likely_cause", "tolerance_error"]

_UNITS = ((1e-2, "centimetres"), (1e-3, "millimetres"), (0.0254, "inches"))
EXPLAINED = 3.0
"""Residuals within this many times what the tolerances explain (plus the noise) are explained."""
_GAIN = 10.0  # and a hypothesis brings them at least this many times down


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum(np.atleast_2d(x) ** 2, axis=-1)))) if x.size else 0.0


def tolerance_error(K: np.ndarray, tolerance: np.ndarray) -> np.ndarray:
    """Error (N, rows) the tolerances explain at each pose: ``sqrt(sum_k (K_k t_k)^2)``.

    Args:
        K: Unweighted identification Jacobian of the nominal robot (N, rows, n_par).
        tolerance: Tolerance of each parameter (n_par,) [m, rad, -].

    Returns:
        Per pose and residual row [m or rad].

    """
    Kt = K * np.asarray(tolerance, dtype=float)
    return np.sqrt(np.einsum("nrk,nrk->nr", Kt, Kt))


def _angles(R_a: np.ndarray, R_b: np.ndarray) -> np.ndarray:
    """Rotation angle (N,) [rad] between two sets of rotations (N, 3, 3)."""
    c = (np.einsum("nij,nij->n", R_a, R_b) - 1.0) / 2.0
    return np.arccos(np.clip(c, -1.0, 1.0))


def _rotations(rpy: np.ndarray, intrinsic: bool = False) -> np.ndarray:
    if intrinsic:  # R = Rx(r) Ry(p) Rz(y)
        return np.array(
            [
                pin.rpy.rpyToMatrix(r, 0, 0)
                @ pin.rpy.rpyToMatrix(0, p, 0)
                @ pin.rpy.rpyToMatrix(0, 0, y)
                for r, p, y in rpy
            ]
        )
    return np.array([pin.rpy.rpyToMatrix(*v) for v in rpy])


def _kabsch(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """``P`` (N, 3) moved by the rigid motion that best maps it onto ``Q``."""
    cp, cq = P.mean(axis=0), Q.mean(axis=0)
    H = (P - cp).T @ (Q - cq)
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, float(np.sign(np.linalg.det(Vt.T @ U.T))) or 1.0])
    R = Vt.T @ D @ U.T
    return (P - cp) @ R.T + cq


def _position_hypotheses() -> list[tuple[str, list[int], np.ndarray, float]]:
    """``(what, column order, signs, unit factor)``: units, then axes, then both."""
    out = [
        (f"the positions look like {unit} (times {s:g} they fit)", [0, 1, 2], np.ones(3), s)
        for s, unit in _UNITS
    ]
    axes = "xyz"
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            if perm == (0, 1, 2) and signs == (1.0, 1.0, 1.0):
                continue
            label = ", ".join(
                f"{'-' if sg < 0 else ''}{axes[p]}" for p, sg in zip(perm, signs, strict=True)
            )
            what = f"the position columns are in another axis order or sign (read as {label})"
            out.append((what, list(perm), np.array(signs), 1.0))
            out += [(f"{what}, in {unit}", list(perm), np.array(signs), s) for s, unit in _UNITS]
    return out


def likely_cause(
    robot: Robot,
    kind: str,
    measured: np.ndarray | None,
    nominal: np.ndarray,
    rpy: np.ndarray | None,
    nominal_rotations: np.ndarray | None,
    error_bound: np.ndarray,
    sigma: tuple[float, float],
) -> str:
    """The likely cause of measurements the nominal robot is far from (module docstring).

    Args:
        robot: The nominal robot.
        kind: Measurement kind (``pose``, ``position``; implicit kinds are not diagnosed).
        measured: Measured positions (N, 3) [m], or ``None``.
        nominal: The nominal robot's platform positions at the readings (N, 3) [m].
        rpy: Measured roll, pitch, yaw (N, 3) [rad] (``pose``), or ``None``.
        nominal_rotations: The nominal robot's platform rotations (N, 3, 3) (``pose``).
        error_bound: Worst-case error the tolerances cause at each pose (N, rows)
            (:func:`tolerance_error`) [m, rad].
        sigma: Measurement standard deviations ``(position [m], orientation [rad])``.

    Returns:
        One phrase naming the likely cause, or ``""`` when the nominal residuals are within what
        the tolerances explain (the cause is then not in the data's units or frame).

    """
    if kind not in ("pose", "position") or measured is None:
        return ""
    found = []
    bound_p = _rms(error_bound[:, :3]) + sigma[0] * np.sqrt(3.0)
    found.append(_positions(robot, measured, nominal, _rms(measured - nominal), bound_p))
    if kind == "pose" and rpy is not None and nominal_rotations is not None:
        bound_r = _rms(error_bound[:, 3:]) + sigma[1] * np.sqrt(3.0)
        a0 = float(np.sqrt(np.mean(_angles(_rotations(rpy), nominal_rotations) ** 2)))
        found.append(_orientations(rpy, nominal_rotations, a0, bound_r))
    return "; ".join(f for f in found if f)


def _positions(robot: Robot, P: np.ndarray, P0: np.ndarray, e0: float, bound: float) -> str:
    for what, perm, signs, factor in _position_hypotheses():
        e = _rms(P[:, perm] * signs * factor - P0)
        if e <= EXPLAINED * bound and e * _GAIN <= e0:
            return (
                f"{what}: {quantity(e, 'm')} RMS from the nominal robot instead of "
                f"{quantity(e0, 'm')}"
            )
    e = _rms(_kabsch(P, P0) - P0)
    if e <= EXPLAINED * bound and e * _GAIN <= e0:
        return (
            f"the positions are in another frame (a rigid motion of them fits the nominal robot "
            f"to {quantity(e, 'm')} RMS instead of {quantity(e0, 'm')}): express them in the "
            "robot's world frame"
        )
    if e0 <= EXPLAINED * bound:
        return ""
    c, c0 = P.mean(axis=0), P0.mean(axis=0)
    spread = _rms(P - c)
    spread0 = _rms(P0 - c0)
    return (
        f"the nominal robot: the measured positions lie {quantity(e0, 'm')} RMS from the nominal "
        f"{robot.name}'s, more than its tolerances explain ({quantity(bound, 'm')}); they spread "
        f"{quantity(spread, 'm')} about {vector(c, 'm', 3)}, the nominal robot's "
        f"{quantity(spread0, 'm')} about {vector(c0, 'm', 3)} at the same readings: measurements "
        "of another robot or size (check --param or the description)"
    )


def _orientations(rpy: np.ndarray, R0: np.ndarray, a0: float, bound: float) -> str:
    hyps = (
        (
            "the orientations look like degrees (give roll, pitch, yaw in radians)",
            np.deg2rad(rpy),
            False,
            False,
        ),
        (
            "the orientation columns are in the reverse order (rz, ry, rx given as rx, ry, rz)",
            rpy[:, ::-1],
            False,
            False,
        ),
        ("the orientations are of the other frame (the inverse rotation)", rpy, False, True),
        (
            "the orientations follow the intrinsic x-y-z convention (R = Rx Ry Rz), not roll, "
            "pitch, yaw about fixed axes",
            rpy,
            True,
            False,
        ),
        (
            "the orientations look like degrees in the reverse order",
            np.deg2rad(rpy[:, ::-1]),
            False,
            False,
        ),
    )
    for what, angles, intrinsic, inverse in hyps:
        R = _rotations(angles, intrinsic)
        if inverse:
            R = np.swapaxes(R, 1, 2)
        a = float(np.sqrt(np.mean(_angles(R, R0) ** 2)))
        if a <= EXPLAINED * bound and a * _GAIN <= a0:
            return f"{what}: {a:.3g} rad RMS from the nominal robot instead of {a0:.3g} rad"
    if a0 <= EXPLAINED * bound:
        return ""
    return (
        f"the orientations: {a0:.3g} rad RMS from the nominal robot's, more than its tolerances "
        f"explain ({bound:.3g} rad): check the orientation convention (roll, pitch, yaw [rad] "
        "about the fixed x, y, z axes of the robot's world frame)"
    )
