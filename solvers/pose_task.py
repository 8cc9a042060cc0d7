"""Pose error of a frame with respect to a target, with its Jacobian.

The error stacks ``p - p_target`` [m] (world coordinates) and ``log3(R_target^T R)`` [rad]
(target frame coordinates); rows can be selected with a mask.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["FramePoseTask"]


class FramePoseTask:
    """Error between a frame's placement and a target placement.

    Args:
        model: The kinematic tree.
        frame_id: Frame whose pose is controlled.
        rows: Selected rows among (x, y, z, rx, ry, rz), as indices 0..5.

    """

    def __init__(self, model: pin.Model, frame_id: int, rows: np.ndarray) -> None:
        self.model = model
        self.frame_id = frame_id
        self.rows = np.asarray(rows, dtype=int)
        self.target = pin.SE3.Identity()

    def error(self, oMf: pin.SE3) -> np.ndarray:
        """Full 6D error of a placement ``oMf`` with respect to the target.

        Args:
            oMf: Frame placement in the world.

        Returns:
            (6,) error: position [m] then rotation [rad].

        """
        e = np.empty(6)
        e[:3] = oMf.translation - self.target.translation
        e[3:] = pin.log3(self.target.rotation.T @ oMf.rotation)
        return e

    def residual(self, data: pin.Data) -> np.ndarray:
        """Selected error rows; needs the joint placements of ``data`` up to date.

        Args:
            data: Pinocchio data after forward kinematics.

        Returns:
            Residual (len(rows),).

        """
        return self.error(pin.updateFramePlacement(self.model, data, self.frame_id))[self.rows]

    def jacobian(self, data: pin.Data) -> np.ndarray:
        """Jacobian of the selected rows; needs ``computeJointJacobians`` done.

        Args:
            data: Pinocchio data after ``pin.computeJointJacobians``.

        Returns:
            Jacobian (len(rows), nv).

        """
        model = self.model
        R = pin.updateFramePlacement(model, data, self.frame_id).rotation
        Jw = np.reshape(
            pin.getFrameJacobian(
                model, data, self.frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
            ),
            (6, model.nv),
        )
        J = np.empty((6, model.nv))
        J[:3] = Jw[:3]
        # d log3(Rt^T R) = Jlog3 * (R^T omega_world)
        J[3:] = pin.Jlog3(self.target.rotation.T @ R) @ (R.T @ Jw[3:])
        return J[self.rows]

    def residual_and_jacobian(self, data: pin.Data) -> tuple[np.ndarray, np.ndarray]:
        """Selected error rows and their Jacobian; needs ``computeJointJacobians`` done.

        Args:
            data: Pinocchio data after ``pin.computeJointJacobians``.

        Returns:
            Residual (len(rows),) and Jacobian (len(rows), nv).

        """
        return self.residual(data), self.jacobian(data)
