"""The calibration problem: residuals and Jacobian of measurements as functions of the errors.

A :class:`Problem` holds what does not change while the parameters ``p`` (errors of a
:class:`~pkdyn.precision.parameters.ParameterModel`) and the unknowns ``y`` of implicit
measurements move: the nominal robot, the model, the measurements (their readings already turned
into the nominal robot's joint coordinates), the standard deviations and, for ``plane``
measurements, the frame each plane's unknowns are expressed in. Evaluations return new values
(:class:`State`) and never change the problem.

Residuals, *model minus measurement* (unweighted; :meth:`Problem.row_sigma` gives each row's
standard deviation): ``pose``: ``[p_model - p_measured; log3(R_measured^T R_model)]``;
``position``: the first three; ``point``: ``p_model - c_g`` (``c_g`` the group's unknown
point); ``plane``: ``n_g . p_model - d_g`` (the group's unknown unit normal and offset);
``joints``: the measured passive joints' coordinates minus the model's (angles wrapped).

The Jacobian is exact: :func:`pkdyn.precision.sensitivity.pose_sensitivity` at the perturbed
robot (the loops eliminated), composed with the residuals' own derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.calibration.measurements import Measurements
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel
from pkdyn.precision.perturbation import Perturbed, perturbed
from pkdyn.precision.sensitivity import pose_sensitivity

__all__ = ["GAP_TOL", "PlaneFrames", "Problem", "State", "nominal_configurations"]

GAP_TOL = 1e-9
"""Closure gap [m or rad per unit parameter] above which an error is one the mechanism cannot
absorb (an over-constrained loop): held at zero."""


@dataclass(frozen=True, eq=False)  # numpy fields
class State:
    """The perturbed robot at parameters ``p``, and its configurations and platform poses.

    Attributes:
        perturbed: The robot with the errors applied and its actuator gains.
        qs: Assembled configurations (N) at the measurements' readings.
        poses: Platform placements (N).

    """

    perturbed: Perturbed
    qs: list[np.ndarray]
    poses: list[pin.SE3]


@dataclass(frozen=True, eq=False)  # numpy fields
class PlaneFrames:
    """Reference normals and tangent bases of the planes of ``plane`` measurements.

    Each plane's unknowns are a rotation of its reference normal (two tangent components) and
    its offset [m].

    Attributes:
        normals: Reference unit normals (G, 3).
        tangents: Tangent bases (G, 3, 2).

    """

    normals: np.ndarray
    tangents: np.ndarray


def nominal_configurations(robot: Robot, m: Measurements) -> list[np.ndarray]:
    """The robot's assembled configurations at the measurements' readings (joint coordinates).

    Raises:
        InvalidInputError: A row the robot cannot be assembled at (named), with what the readings
            look like when that explains it (degrees, a gain).

    """
    from pkdyn.identification.checks import readings_hint

    qs = []
    for i, reading in enumerate(m.qa):
        try:
            qs.append(forward_geometry(robot, reading, check_limits=False).q)
        except PkdynError as err:
            hint = readings_hint(robot, m.qa)
            raise InvalidInputError(
                "measurements",
                f"{m.where(i)}: the nominal {robot.name} cannot be assembled at these "
                f"actuator readings ({err}){hint}",
            ) from None
    return qs


class Problem:
    """Residuals and Jacobian of one set of measurements (module docstring).

    Args:
        robot: The nominal robot.
        model: The parameter model.
        m: The measurements, readings as the nominal robot's joint coordinates.
        sigma: Standard deviations ``(position [m], orientation [rad])``.
        qs: Start configurations (N) of the forward geometry (the assembly mode followed).
        planes: Plane frames (``plane`` measurements; :meth:`fit_nuisance` makes them).
        groups: The groups of implicit measurements the unknowns belong to, in the order of
            the unknowns (default: those of ``m``; a validation set passes the calibration's).

    """

    def __init__(
        self,
        robot: Robot,
        model: ParameterModel,
        m: Measurements,
        sigma: tuple[float, float],
        qs: list[np.ndarray],
        planes: PlaneFrames | None = None,
        groups: np.ndarray | None = None,
    ) -> None:
        self.robot, self.model, self.m = robot, model, m
        self.sigma = sigma
        self.qs = list(qs)
        if groups is None:
            groups = np.unique(m.group) if m.group is not None else np.zeros(0, int)
        self.groups = groups
        self.n_nuis = {"point": 3, "plane": 3}.get(m.kind, 0) * self.groups.size
        self.planes = planes
        self.jq = np.zeros(0, dtype=int)
        self.jv = np.zeros(0, dtype=int)
        self.revolute = np.zeros(0, dtype=bool)
        if m.kind == "joints":
            ids = [robot.model.getJointId(j) for j in m.joints]
            joints = [robot.model.joints[i] for i in ids]
            self.jq = np.array([j.idx_q for j in joints], dtype=int)
            self.jv = np.array([j.idx_v for j in joints], dtype=int)
            self.revolute = np.array(["Prismatic" not in j.shortname() for j in joints])

    @property
    def rows(self) -> int:
        """Residual rows per measurement."""
        return self.m.rows

    # -- unknowns of implicit measurements -----------------------------------------------

    def fit_nuisance(self, positions: np.ndarray) -> tuple[np.ndarray, PlaneFrames | None]:
        """Initial unknowns from platform positions (N, 3) of the nominal robot.

        Points: each group's centroid. Planes: the least-squares plane of each group, which also
        fixes the frame its unknowns are expressed in (zero tilt, its offset).

        Returns:
            The unknowns ``y`` (n_nuis,) and the plane frames (``plane``), else ``None``.

        """
        out, normals, tangents = [], [], []
        for g in self.groups:
            assert self.m.group is not None
            P = positions[self.m.group == g]
            c = P.mean(axis=0)
            if self.m.kind == "point":
                out.append(c)
                continue
            _, _, Vt = np.linalg.svd(P - c)
            n, t1 = Vt[-1], Vt[0]
            normals.append(n)
            tangents.append(np.column_stack([t1, np.cross(n, t1)]))
            out.append(np.array([0.0, 0.0, float(n @ c)]))
        y = np.concatenate(out) if out else np.zeros(0)
        if self.m.kind != "plane":
            return y, None
        return y, PlaneFrames(
            np.array(normals).reshape(-1, 3), np.array(tangents).reshape(-1, 3, 2)
        )

    def with_planes(self, planes: PlaneFrames | None) -> Problem:
        """The same problem with the plane frames set (a new problem)."""
        return Problem(self.robot, self.model, self.m, self.sigma, self.qs, planes, self.groups)

    def _plane(self, k: int, y: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
        """Unit normal, offset and d(normal)/d(tilt) (3, 2) of plane ``k`` from its unknowns."""
        assert self.planes is not None
        n0, T = self.planes.normals[k], self.planes.tangents[k]
        w = T @ y[:2]
        R = pin.exp3(w)
        n = R @ n0
        dn = -R @ pin.skew(n0) @ pin.Jexp3(w) @ T
        return n, float(y[2]), dn

    def nuisance_dict(self, y: np.ndarray) -> dict[str, np.ndarray]:
        """Points (G, 3) or planes (G, 4: unit normal, offset [m]) from the unknowns."""
        if self.m.kind == "point":
            return {"points": y.reshape(-1, 3)}
        if self.m.kind == "plane":
            planes = []
            for k in range(self.groups.size):
                n, d, _ = self._plane(k, y[3 * k : 3 * k + 3])
                planes.append(np.concatenate([n, [d]]))
            return {"planes": np.array(planes)}
        return {}

    # -- model evaluation ----------------------------------------------------------------

    def evaluate(self, p: np.ndarray, start: State | None = None) -> State:
        """The perturbed robot, its configurations and platform poses at the readings.

        Args:
            p: Parameter errors (n_par,).
            start: A previous state whose configurations start the forward geometry (the
                assembly mode kept); default the problem's start configurations.

        Raises:
            PkdynError: A reading the perturbed robot cannot be assembled at.

        """
        P = perturbed(self.robot, self.model, p)
        q0s = self.qs if start is None else start.qs
        qs, poses = [], []
        for q0, reading in zip(q0s, self.m.qa, strict=True):
            g = forward_geometry(
                P.robot, P.joint_coordinates(reading), q_init=q0, check_limits=False
            )
            assert g.placement is not None
            qs.append(g.q)
            poses.append(g.placement)
        return State(P, qs, poses)

    def residuals(self, state: State, y: np.ndarray) -> np.ndarray:
        """Unweighted residuals (N, rows) [m, rad] (module docstring)."""
        m = self.m
        poses = state.poses
        out = np.zeros((len(poses), m.rows))
        if m.kind == "joints":
            assert m.q is not None
            Q = np.array([q[self.jq] for q in state.qs]).reshape(len(poses), -1)
            d = Q - m.q
            return np.where(self.revolute, np.angle(np.exp(1j * d)), d)
        for i, M in enumerate(poses):
            if m.kind in ("pose", "position"):
                assert m.position is not None
                out[i, :3] = M.translation - m.position[i]
                if m.kind == "pose":
                    out[i, 3:] = pin.log3(m.rotations[i].T @ M.rotation)
            elif m.kind == "point":
                assert m.group is not None
                k = int(np.searchsorted(self.groups, m.group[i]))
                out[i] = M.translation - y[3 * k : 3 * k + 3]
            else:
                assert m.group is not None
                k = int(np.searchsorted(self.groups, m.group[i]))
                n, d, _ = self._plane(k, y[3 * k : 3 * k + 3])
                out[i, 0] = n @ M.translation - d
        return out

    def row_sigma(self) -> np.ndarray:
        """Standard deviation of each residual row (rows,) [m or rad]."""
        s_pos, s_rot = self.sigma
        if self.m.kind == "joints":
            return np.where(self.revolute, s_rot, s_pos)
        return np.array([s_pos, s_pos, s_pos, s_rot, s_rot, s_rot])[: self.m.rows]

    def jacobian(
        self, state: State, p: np.ndarray, y: np.ndarray, cols: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Unweighted Jacobian of the raw residuals, and the closure gap of each parameter.

        Args:
            state: The evaluation at ``p``.
            p: Parameter errors (n_par,).
            y: Unknowns of implicit measurements (n_nuis,).
            cols: The parameters to differentiate with respect to.

        Returns:
            ``J`` (N, rows, len(cols) + n_nuis) and the largest closure gap (n_par,) of each
            parameter over the poses (> :data:`GAP_TOL`: not absorbed by the mechanism).

        """
        m = self.m
        N, d = len(state.qs), m.rows
        out = np.zeros((N, d, cols.size + self.n_nuis))
        gap = np.zeros(self.model.size)
        for i, (q, M) in enumerate(zip(state.qs, state.poses, strict=True)):
            sens = pose_sensitivity(state.perturbed.robot, q, self.model, at=p)
            if sens.gap.size:
                gap = np.maximum(gap, np.max(np.abs(sens.gap), axis=0))
            K = sens.K[:, cols]
            if m.kind == "joints":
                assert sens.joints is not None
                out[i, :, : cols.size] = sens.joints[self.jv][:, cols]
                continue
            if m.kind in ("pose", "position"):
                out[i, :3, : cols.size] = K[:3]
                if m.kind == "pose":
                    E = m.rotations[i].T @ M.rotation
                    out[i, 3:, : cols.size] = pin.Jlog3(E) @ K[3:]
            elif m.kind == "point":
                assert m.group is not None
                k = int(np.searchsorted(self.groups, m.group[i]))
                out[i, :, : cols.size] = K[:3]
                out[i, :, cols.size + 3 * k : cols.size + 3 * k + 3] = -np.eye(3)
            else:
                assert m.group is not None
                k = int(np.searchsorted(self.groups, m.group[i]))
                n, _, dn = self._plane(k, y[3 * k : 3 * k + 3])
                out[i, 0, : cols.size] = n @ K[:3]
                out[i, 0, cols.size + 3 * k : cols.size + 3 * k + 2] = M.translation @ dn
                out[i, 0, cols.size + 3 * k + 2] = -1.0
        return out, gap
