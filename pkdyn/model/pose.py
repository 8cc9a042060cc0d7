"""Platform poses as vectors: position [m] and roll, pitch, yaw [rad] (fixed axes x, y, z)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError

__all__ = ["as_finite", "pose_from_vector", "pose_to_vector"]


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
