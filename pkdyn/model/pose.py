"""Platform poses as vectors: position [m] and roll, pitch, yaw [rad] (fixed axes x, y, z)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError

__all__ = ["as_configuration", "as_finite", "pose_from_vector", "pose_to_vector"]


def as_finite(
    name: str, values: Sequence[float] | np.ndarray, size: int | None = None
) -> np.ndarray:
    """Validate a numeric input: right size, no NaN or infinity.

    Args:
        name: Name of the input, for the error message.
        values: The values.
        size: Expected length, or ``None`` for any.

    Returns:
        A float array copy.

    Raises:
        InvalidInputError: Wrong size or non-finite values.

    """
    try:
        arr = np.array(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidInputError(name, f"expected numbers, got {values!r}") from None
    if size is not None and arr.size != size:
        raise InvalidInputError(name, f"expected {size} values, got {arr.size}")
    if not np.isfinite(arr).all():
        bad = np.flatnonzero(~np.isfinite(arr))
        raise InvalidInputError(name, f"value #{bad[0] + 1} is {arr[bad[0]]}; give finite numbers")
    return arr


UNIT_NORM_TOL = 1e-3
"""Largest departure from 1 of the norm of a joint's quaternion (or cosine-sine pair) that
:func:`as_configuration` normalises; beyond it the configuration is refused."""


def _unit_part(j: pin.JointModel) -> slice | None:
    """Coordinates of a joint that must have norm 1 (quaternion, cosine-sine), if any."""
    kind = j.shortname()
    if kind == "JointModelFreeFlyer":
        return slice(3, 7)
    if kind == "JointModelPlanar":
        return slice(2, 4)
    if j.nq > j.nv:  # spherical (quaternion), unbounded revolute (cos, sin)
        return slice(0, j.nq)
    return None


def as_configuration(model: pin.Model, name: str, q: Sequence[float] | np.ndarray) -> np.ndarray:
    """Validate a configuration: ``nq`` finite values, unit quaternions (normalised).

    Args:
        model: The kinematic tree.
        name: Name of the input, for the message (``q0``).
        q: The configuration (nq,).

    Returns:
        A float copy, each quaternion or cosine-sine pair normalised.

    Raises:
        InvalidInputError: Wrong size, non-finite values, or a joint whose quaternion (or
            cosine-sine pair) is zero or does not have norm 1 to :data:`UNIT_NORM_TOL`.

    """
    arr = as_finite(name, q, model.nq)
    for jid in range(1, model.njoints):
        j = model.joints[jid]
        part = _unit_part(j)
        if part is None:
            continue
        seg = arr[j.idx_q + part.start : j.idx_q + part.stop]
        norm = float(np.linalg.norm(seg))
        what = "quaternion" if seg.size == 4 else "cosine-sine pair"
        if not abs(norm - 1.0) <= UNIT_NORM_TOL:
            raise InvalidInputError(
                name,
                f"joint '{model.names[jid]}': its {what} {np.round(seg, 6).tolist()} has norm "
                f"{norm:.6g}; a rotation needs norm 1 (coordinates {j.idx_q + part.start}.."
                f"{j.idx_q + part.stop - 1} of the configuration)",
            )
        seg /= norm
    return arr


def pose_from_vector(pose: Sequence[float] | np.ndarray | pin.SE3) -> pin.SE3:
    """Placement from ``[x, y, z]`` or ``[x, y, z, roll, pitch, yaw]`` (or an SE3, passed on).

    Args:
        pose: Position [m] and optional roll, pitch, yaw [rad] (R = Rz(yaw) Ry(pitch) Rx(roll)).

    Returns:
        The placement.

    Raises:
        InvalidInputError: Wrong length or non-finite values.

    """
    if isinstance(pose, pin.SE3):
        return pin.SE3(pose)
    arr = as_finite("pose", pose)
    if arr.size not in (3, 6):
        raise InvalidInputError(
            "pose", f"expected 3 or 6 values (x y z [roll pitch yaw]), got {arr.size}"
        )
    R = pin.rpy.rpyToMatrix(arr[3:]) if arr.size == 6 else np.eye(3)
    return pin.SE3(R, arr[:3])


def pose_to_vector(M: pin.SE3) -> tuple[np.ndarray, np.ndarray]:
    """Position [m] and roll, pitch, yaw [rad] of a placement.

    Args:
        M: The placement.

    Returns:
        ``(position, rpy)``.

    """
    return np.array(M.translation), np.array(pin.rpy.matrixToRpy(M.rotation))
