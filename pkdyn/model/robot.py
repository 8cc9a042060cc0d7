"""The loaded robot: Pinocchio model and data, geometry, closures, actuation, platform."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.description import (
    ActuatorSpec,
    ClosureSpec,
    CouplingSpec,
    Description,
    LinearCouplingSpec,
)
from pkdyn.model.families import FAMILIES
from pkdyn.model.platform_jacobian import PLATFORM_HINT, platform_jacobian
from solvers import ConstraintSet, PassiveForces
from solvers.numerics import null_space, rank

__all__ = ["PLATFORM_HINT", "MODELLING_JOINTS", "Robot", "length_scale_at"]

MODELLING_JOINTS = ("JointModelFreeFlyer", "JointModelPlanar")
"""Joint models that place a platform or floating base: modelling devices, not hardware."""


@dataclass(eq=False)  # identity: numpy and Pinocchio fields have no boolean ==
class Robot:
    """A closed-loop robot loaded by :func:`pkdyn.load`.

    Attributes:
        name: Robot name.
        source: Library family name or file path it was loaded from.
        model: Pinocchio model of the spanning tree.
        data: Pinocchio data of ``model``.
        visual_model: Visual geometry (coal shapes).
        collision_model: Collision geometry (coal shapes).
        description: The parsed extension elements.
        constraint_models: Pinocchio rigid constraint models (a ``hinge`` gives two points).
        constraint_owner: Closure name of each constraint model.
        constraints: The constraint layer (:class:`solvers.ConstraintSet`): the closures' rows
            (reduced to their independent rows), then one row per joint coupling; views
            ``constraints.closures`` and ``constraints.couplings``.
        actuators: Actuators in actuator order.
        actuated_joints: Joint id of each actuator.
        actuated_q: Configuration index of each actuator (nq indexing).
        actuated_v: Velocity index of each actuator (nv indexing).
        passive_v: Velocity indices of all non-actuated coordinates.
        platform_frame: Frame id of the platform / end-effector frame, or ``None``.
        task_rows: Controlled pose components as indices into (x, y, z, rx, ry, rz).
        q_home: An assembled reference configuration (nq,).
        params: Builder parameters for library robots, else ``None``.
        passive: Springs, dampers and friction of the joints and the two-frame springs
            (:mod:`pkdyn.model.passive`), or ``None`` when there are none.
        missing_meshes: Mesh files of the description that were not found: their shapes are
            left out of ``visual_model`` and ``collision_model`` (collision checks refuse to
            run, the viewer warns, both naming them).
        dropped_collisions: Collision elements of the description left out because their
            numbers were malformed (collision checks refuse to run, naming them).

    """

    name: str
    source: str
    model: pin.Model
    data: pin.Data
    visual_model: pin.GeometryModel
    collision_model: pin.GeometryModel
    description: Description
    constraint_models: pin.StdVec_RigidConstraintModel
    constraint_owner: list[str]
    constraints: ConstraintSet
    actuators: tuple[ActuatorSpec, ...]
    actuated_joints: np.ndarray
    actuated_q: np.ndarray
    actuated_v: np.ndarray
    passive_v: np.ndarray
    platform_frame: int | None
    task_rows: np.ndarray
    q_home: np.ndarray
    params: Any = None
    passive: PassiveForces | None = None
    missing_meshes: tuple[str, ...] = ()
    dropped_collisions: tuple[str, ...] = ()

    @functools.cached_property
    def length_scale(self) -> float:
        """Characteristic length [m]: the diagonal of the box of the joint origins at home.

        Makes translations and rotations commensurate where a test compares them (singularity
        margins, continuation steps), so that results do not depend on the robot's size.
        """
        return length_scale_at(self.model, self.model.createData(), self.q_home)

    def closure_tolerance(self, rtol: float) -> float:
        """The closure residual [m or rad] that is ``rtol`` of the robot's size.

        ``rtol * min(1, length_scale)``: a gap in metres judged against the robot's length, a
        gap in radians (a weld's rotation, a coupling) against one radian, whichever is the
        stricter, so that a millimetre robot is assembled as closely, relative to its size, as
        a metre one.

        Args:
            rtol: Relative tolerance (e.g. 1e-10).

        Returns:
            The tolerance [m or rad].

        Raises:
            InvalidInputError: ``rtol`` not a finite number > 0.

        """
        from pkdyn.inputs import positive

        return positive("rtol", rtol) * min(1.0, self.length_scale)

    @property
    def nq(self) -> int:
        """Size of the configuration vector."""
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        """Size of the velocity vector."""
        return int(self.model.nv)

    @property
    def family(self) -> str | None:
        """Library family that built the robot, ``None`` for a robot its user described.

        The family is ``robot.source`` for a robot built by :func:`pkdyn.load` from a family
        name, or the ``<pkdyn:family>`` of a file written by ``pkdyn urdf FAMILY`` (checked to
        be the builder's output when loaded); other descriptions have none.

        Code that has a closed form for some families keeps a registry keyed by this name (e.g.
        :data:`pkdyn.analysis.screws.RECIPROCAL_SCREWS`); robots of no family take the general
        path.
        """
        if self.params is None:
            return None
        spec = self.description.family
        name = spec.name if spec is not None else self.source
        return name if name in FAMILIES else None

    @property
    def closures(self) -> tuple[ClosureSpec, ...]:
        """Loop closures of the description."""
        return self.description.closures

    @property
    def couplings(self) -> tuple[CouplingSpec | LinearCouplingSpec, ...]:
        """Joint couplings of the description (sums, gears, mimic joints, locked joints)."""
        return self.description.couplings

    @property
    def closure_set(self) -> ConstraintSet:
        """The former constraint layer (kept for one release): :attr:`constraints` with every row.

        ``constraints.unreduced``: the rows of ``constraint_models`` (a hinge is two points,
        planar loops keep their out-of-plane rows), then the couplings'; ``nc`` counts the
        closure rows only.
        """
        return self.constraints.unreduced

    @property
    def row_owners(self) -> list[str]:
        """Closure or coupling name of each constraint of ``constraints`` (its ``names``)."""
        return list(self.constraints.names)

    @property
    def actuator_prismatic(self) -> np.ndarray:
        """Whether each actuator drives a prismatic joint (n_a,) bool (a copy).

        Prismatic actuators have positions in m, speeds in m/s and efforts in N; revolute ones
        rad, rad/s and N m.
        """
        return self._actuator_prismatic.copy()

    @functools.cached_property
    def actuator_scale(self) -> np.ndarray:
        """Characteristic size of each actuated coordinate (n_a,), read-only.

        1 rad for revolute actuators, :attr:`length_scale` [m] for prismatic ones.
        """
        out = np.where(self._actuator_prismatic, self.length_scale, 1.0)
        out.flags.writeable = False
        return out

    @functools.cached_property
    def _actuator_prismatic(self) -> np.ndarray:
        return np.array(
            [_prismatic(self.model.joints[int(j)]) for j in self.actuated_joints], dtype=bool
        )

    @property
    def actuator_names(self) -> list[str]:
        """Names of the actuators (the transmissions, e.g. ``motor1``), in actuator order."""
        return [a.name for a in self.actuators]

    @property
    def actuated_joint_names(self) -> list[str]:
        """Names of the actuated joints (e.g. ``arm1``), in actuator order."""
        return [a.joint for a in self.actuators]

    @property
    def encoder_gains(self) -> np.ndarray:
        """Joint coordinate per unit of each actuator's reading (n_a,) (``pkdyn:encoder gain``)."""
        return np.array([float(a.encoder_gain) for a in self.actuators])

    @property
    def encoder_offsets(self) -> np.ndarray:
        """Joint coordinate at a zero reading, per actuator (n_a,) [rad or m]."""
        return np.array([float(a.encoder_offset) for a in self.actuators])

    def joint_coordinates(self, readings: Any, rates: bool = False) -> np.ndarray:
        """Actuated joint coordinates of actuator readings: **the one readings rule**.

        ``qa = encoder_gain * reading + encoder_offset`` per actuator (the description's
        ``<pkdyn:encoder gain offset>``; 1 and 0 unless a calibration wrote them). Every
        feature that reads actuator readings (``qa_<actuator>`` columns of measurement,
        motion and trajectory files; ``--readings``) turns them into joint coordinates here;
        the joints coupled to the actuated ones (``robot.couplings``) then follow by assembly.

        Args:
            readings: Readings (..., n_a) [rad or m], or their rates / accelerations with
                ``rates`` (the offset drops out: ``qa_dot = gain * reading_dot``).
            rates: The values are time derivatives of readings.

        Returns:
            Joint coordinates (or their derivatives), same shape.

        Raises:
            InvalidInputError: Not finite numbers, or not ``n_a`` per row.

        """
        r = self._readings_array("readings", readings, rates)
        g = self.encoder_gains
        return r * g if rates else r * g + self.encoder_offsets

    def readings(self, qa: Any, rates: bool = False) -> np.ndarray:
        """Actuator readings of actuated joint coordinates (the inverse of joint_coordinates).

        Args:
            qa: Joint coordinates (..., n_a) [rad or m] (their derivatives with ``rates``).
            rates: The values are time derivatives.

        Returns:
            Readings, same shape.

        Raises:
            InvalidInputError: Not finite numbers, or not ``n_a`` per row.

        """
        q = self._readings_array("qa", qa, rates)
        g = self.encoder_gains
        return q / g if rates else (q - self.encoder_offsets) / g

    def _readings_array(self, name: str, value: Any, rates: Any = False) -> np.ndarray:
        if not isinstance(rates, bool | np.bool_):
            raise InvalidInputError("rates", f"expected True or False, got {rates!r:.40}")
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise InvalidInputError(name, f"expected numbers, got {value!r:.60}") from None
        n_a = len(self.actuators)
        if arr.ndim == 0 or arr.shape[-1] != n_a:
            raise InvalidInputError(
                name,
                f"expected {n_a} values per row ({', '.join(self.actuator_names)}), got shape "
                f"{arr.shape}",
            )
        if not np.all(np.isfinite(arr)):
            raise InvalidInputError(name, "expected finite numbers, got NaN or infinity")
        return arr

    def components(self) -> list[int]:
        """Connected component of each joint's body over physical edges (union-find).

        Physical edges are the tree joints except free-flyer and planar joints (modelling devices
        for a platform or a floating base, not hardware) and the loop closures.

        Returns:
            A representative joint id per joint id (0..njoints-1).

        """
        model = self.model
        parent = list(range(model.njoints))

        def find(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for a, b in self._physical_edges():
            parent[find(a)] = find(b)
        return [find(j) for j in range(model.njoints)]

    def _physical_edges(self) -> list[tuple[int, int]]:
        model = self.model
        edges = [
            (j, model.parents[j])
            for j in range(1, model.njoints)
            if model.joints[j].shortname() not in MODELLING_JOINTS
        ]
        owners = dict(zip(self.constraint_owner, self.constraint_models, strict=True))
        edges += [(cm.joint1_id, cm.joint2_id) for cm in owners.values()]  # one per closure
        return edges

    @property
    def loops(self) -> int:
        """Number of independent kinematic loops of the mechanism (graph cyclomatic number).

        Bodies are vertices (the ground included); physical joints and closures are edges (see
        :meth:`components`). ``loops = edges - vertices + connected components``; for the Delta
        with 12 ball joints it gives Clavel's 5.
        """
        return len(self._physical_edges()) - self.model.njoints + len(set(self.components()))

    def constraint_data(self) -> pin.StdVec_RigidConstraintData:
        """Fresh Pinocchio constraint data for ``constraint_models``."""
        out = pin.StdVec_RigidConstraintData()
        for cm in self.constraint_models:
            out.append(cm.createData())
        return out

    def dof(self, q: np.ndarray | None = None, tol: float = 1e-9) -> int:
        """Degrees of freedom of the platform at ``q`` (default ``q_home``): the Delta's 3.

        The word's one meaning, as ``pkdyn info`` prints it: the motions allowed by the
        closures that move the platform's controlled pose components (:meth:`mobility_split`);
        without a platform, every motion the closures allow. :meth:`mobility` counts the
        internal mobilities too (the Delta's six bar spins: 9).

        Args:
            q: Configuration (nq,).
            tol: Relative singular-value threshold of the ranks.

        Returns:
            Number of degrees of freedom of the platform.

        """
        return self.mobility_split(q, tol)[0]

    def mobility(self, q: np.ndarray | None = None, tol: float = 1e-9) -> int:
        """Mobility at ``q`` (default ``q_home``): nv minus the rank of the closure Jacobian.

        The constraint Jacobian includes the joint couplings' rows.

        Args:
            q: Configuration (nq,).
            tol: Relative tolerance of the rank (:mod:`solvers.numerics` rule, scale 1: the
                closure Jacobian's entries are of order one in SI units).

        Returns:
            Number of independent motions, internal mobilities included
            (``dof + internal`` of :meth:`mobility_split`).

        """
        qq, tol = self._q_tol(q, tol)
        if self.constraints.n == 0:
            return self.nv
        _, J = self.constraints.residual_and_jacobian(self.data, qq)
        return self.nv - rank(J, tol, scale=1.0)

    def mobility_split(self, q: np.ndarray | None = None, tol: float = 1e-9) -> tuple[int, int]:
        """Degrees of freedom of the platform and internal mobilities at ``q`` (default home).

        The motions allowed by the closures (null space of the closure Jacobian) are split into
        those that move the platform's controlled pose components (``dof``) and those that
        leave them still (``internal``, e.g. the spin of a Delta's ball-jointed bars).
        ``dof + internal == self.mobility(q)``. A robot without a platform frame has no
        internal mobility by this definition.

        Args:
            q: Configuration (nq,).
            tol: Relative tolerance of the ranks (:mod:`solvers.numerics` rule, scale 1, as
                :meth:`mobility`).

        Returns:
            ``(dof, internal)``.

        """
        qq, tol = self._q_tol(q, tol)
        if self.constraints.n:
            _, Jc = self.constraints.residual_and_jacobian(self.data, qq)
            N = null_space(Jc, tol, scale=1.0)
        else:
            N = np.eye(self.nv)
        total = N.shape[1]
        if self.platform_frame is None or total == 0:
            return total, 0
        Jx = platform_jacobian(self, qq, angular="platform")[self.task_rows] @ N
        useful = rank(Jx, tol, scale=1.0)
        return useful, total - useful

    def __repr__(self) -> str:
        task = " ".join(self.description.platform.task) if self.description.platform else "-"
        return (
            f"<Robot {self.name!r} from {self.source!r}: nq={self.nq} nv={self.nv}, "
            f"{len(self.actuators)} actuators ({', '.join(a.name for a in self.actuators)}), "
            f"{len(self.closures)} closures, {self.loops} loops"
            + (f", {len(self.couplings)} couplings" if self.couplings else "")
            + f", platform task: {task}>"
        )

    def _q_tol(self, q: Any, tol: Any) -> tuple[np.ndarray, float]:
        """A configuration (default home) and a relative tolerance, checked."""
        from pkdyn.inputs import positive, vector

        qq = self.q_home if q is None else vector("q", q, self.nq, "rad or m")
        return qq, positive("tol", tol)

    def platform_placement(self, q: np.ndarray) -> pin.SE3:
        """World placement of the platform frame at ``q``.

        Args:
            q: Configuration (nq,).

        Returns:
            Platform placement (a copy).

        """
        if self.platform_frame is None:
            raise PkdynError(f"{self.name} declares no platform frame; {PLATFORM_HINT}")
        from pkdyn.inputs import vector

        q = vector("q", q, self.nq, "rad or m")
        pin.framesForwardKinematics(self.model, self.data, q)
        return pin.SE3(self.data.oMf[self.platform_frame])


def _prismatic(jm: pin.JointModel) -> bool:
    """A 1-DOF prismatic joint model (``JointModelP{X,Y,Z}``, ``JointModelPrismaticUnaligned``)."""
    name = str(jm.shortname())
    return name.startswith("JointModelP") and not name.startswith("JointModelPlanar")


def length_scale_at(model: pin.Model, data: pin.Data, q: np.ndarray) -> float:
    """:attr:`Robot.length_scale` of a model at ``q`` (nq,), computed in ``data`` [m]."""
    pin.forwardKinematics(model, data, q)
    P = np.array([M.translation for M in data.oMi])
    return max(float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))), 1e-9)
