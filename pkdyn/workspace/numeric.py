"""Workspace limits of any robot by the general numeric path, pose by pose.

Each position is solved with the general inverse geometric model
(:func:`pkdyn.inverse_geometry`, warm-started from the previous solution, retried from
``q_home``), then checked: actuated coordinates against their joint limits, passive joints
against their cones and pyramids (:func:`pkdyn.workspace.limits.passive_joint_margins`) and
the collision geometry with coal (:class:`pkdyn.analysis.collisions.CollisionChecker`). Slow (about
a millisecond per pose) but valid for every description; the closed-form evaluators are checked
against it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pkdyn.analysis.collisions import CollisionChecker
from pkdyn.exceptions import AssemblyError
from pkdyn.model.assembly import inverse_geometry
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.workspace.limits import (
    LIMIT_KINDS,
    REACHABLE,
    PoseEvaluator,
    passive_joint_margins,
)

__all__ = ["NumericEvaluator", "configuration_violation"]


def configuration_violation(
    robot: Robot,
    q: np.ndarray,
    kinds: tuple[str, ...],
    margin: float,
    checker: CollisionChecker | None = None,
) -> int:
    """First limit kind an assembled configuration breaks (``reach`` excluded).

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        kinds: Kinds to check.
        margin: Safety distance [m] for ``interference``.
        checker: Coal checker (required for ``interference``).

    Returns:
        Index in :data:`LIMIT_KINDS`, or :data:`REACHABLE`.

    """
    if "stroke" in kinds:
        iq = robot.actuated_q
        lo, hi = robot.model.lowerPositionLimit[iq], robot.model.upperPositionLimit[iq]
        if np.any((q[iq] < lo) | (q[iq] > hi)):
            return LIMIT_KINDS.index("stroke")
    if "joint" in kinds:
        if any(m < 0.0 for m in passive_joint_margins(robot, q).values()):
            return LIMIT_KINDS.index("joint")
    if "interference" in kinds:
        assert checker is not None
        if np.min(checker.distances(q)) < margin:
            return LIMIT_KINDS.index("interference")
    return REACHABLE


class NumericEvaluator(PoseEvaluator):
    """General numeric limits (see the module docstring).

    Args:
        robot: Any robot with a platform frame (with geometry for ``interference``).
        progress: Progress bar over the poses: ``True`` / ``False`` force it on / off,
            ``None`` shows it when stderr is a terminal (default off: the workspace samplers
            show their own).
        warm_start: Start each solve from the previous solution (then from ``q_home``).

    """

    method = "numeric (inverse geometric model and coal, pose by pose)"

    def __init__(
        self, robot: Robot, progress: bool | None = False, warm_start: bool = True
    ) -> None:
        super().__init__(robot)
        self.progress = progress
        self.warm_start = warm_start
        self._checker: CollisionChecker | None = None
        self.q = robot.q_home.copy()

    def checker(self) -> CollisionChecker:
        """The coal checker (built on first use)."""
        if self._checker is None:
            self._checker = CollisionChecker(self.robot)
        return self._checker

    def solve(self, M: pin.SE3, q0: np.ndarray) -> np.ndarray | None:
        """Assembled configuration with the platform at ``M`` from ``q0``, or ``None``."""
        try:
            return inverse_geometry(self.robot, M, q_init=q0, check_limits=False).q
        except AssemblyError:
            return None

    def classify_pose(self, M: pin.SE3, kinds: tuple[str, ...], margin: float) -> int:
        """First limit broken with the platform at ``M`` (see :meth:`violations`).

        Solved from the previous solution; when that breaks a limit or fails, solved again from
        ``q_home``, which keeps the assembly mode of the home configuration where a warm start
        would have jumped to another one.
        """
        checker = self.checker() if "interference" in kinds else None
        code = LIMIT_KINDS.index("reach")
        starts = (self.q, self.robot.q_home) if self.warm_start else (self.robot.q_home,)
        for q0 in starts:
            q = self.solve(M, q0)
            if q is None:
                continue
            code = configuration_violation(self.robot, q, kinds, margin, checker)
            if code == REACHABLE:
                self.q = q
                break
        return code

    def violations(
        self, P: np.ndarray, R: np.ndarray, kinds: tuple[str, ...], margin: float
    ) -> np.ndarray:
        """See :meth:`PoseEvaluator.violations`."""
        P = np.atleast_2d(np.asarray(P, dtype=float))
        out = np.full(P.shape[0], REACHABLE, dtype=np.int8)
        for k in progress_bar(range(P.shape[0]), "poses", "pose", self.progress, leave=False):
            out[k] = self.classify_pose(pin.SE3(R, P[k]), kinds, margin)
        return out

    def default_bounds(self, R: np.ndarray) -> np.ndarray:
        """Home platform position +- the robot's size (farthest joint from the platform)."""
        data = self.robot.model.createData()
        pin.forwardKinematics(self.robot.model, data, self.robot.q_home)
        c = self.robot.platform_placement(self.robot.q_home).translation
        size = max(float(np.linalg.norm(M.translation - c)) for M in data.oMi)
        return np.column_stack([c - size, c + size])
