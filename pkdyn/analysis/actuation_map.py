r"""Closed-loop legs in serial-equivalent form: actuator space <-> a chosen joint space.

A humanoid ankle driven by two motors through rods, a knee driven through a four-bar: a
controller or a designer wants to think in "joint space" (ankle pitch and roll, knee angle)
while the motors act elsewhere. :func:`actuation_map` relates ``n`` actuator coordinates
``qa`` to ``n`` chosen joint coordinates ``qj`` (any passive or actuated 1- or 2-coordinate
joints) of a closed-loop robot, over many samples at once:

- positions both ways (:meth:`ActuationMap.from_joints`, :meth:`ActuationMap.from_actuators`):
  the closures solved with the given coordinates held, warm-started from sample to sample;
- the velocity Jacobian ``J = d qj / d qa`` (``qj_dot = J qa_dot``) and its inverse;
- torque maps by virtual work: the actuator efforts that produce joint-space efforts
  ``tau_j`` are ``tau_a = J^T tau_j`` (``tau_a . qa_dot = tau_j . qj_dot`` for every motion),
  and back ``tau_j = J^{-T} tau_a``;
- the reflected inertia: the kinetic energy ``1/2 qj_dot^T M_j qj_dot`` of the whole
  mechanism moving with ``qj_dot`` (internal mobilities, e.g. the spin of a ball-ended rod,
  taking the motion of least energy), ``M_j = (C K^{-1} C^T)^{-1}`` with ``K = Z^T M Z`` the
  mass matrix on the mechanism's motions ``Z`` and ``C`` the rows of ``Z`` of the joint
  coordinates; likewise ``M_a`` in actuator space;
- a singularity flag: the actuators do not determine the joints (a motion of the chosen joints
  with the actuators held, a parallel singularity), or the joints do not determine the
  actuators (a serial one), by the project's rank rule (:mod:`solvers.numerics`).

Coordinates the map does not involve stay where they are: the other actuators of the robot and
the floating-base (free-flyer, planar) joints are held. The motions ``Z`` are the null space of
the closure Jacobian on the remaining coordinates.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import AssemblyError, InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.robot import MODELLING_JOINTS, Robot
from pkdyn.results import Result, jsonable
from pkdyn.units import quantity
from solvers import numerics, solve_lm

__all__ = ["MAX_SAMPLES", "ActuationMap", "MapSamples", "actuation_map"]

MAX_SAMPLES = 200_000
"""Most samples of one call (each is solved and ranked: about 1-5 ms)."""

RANK_RTOL = numerics.RTOL
"""Relative tolerance of the rank decisions (scale 1, as for :meth:`Robot.dof`)."""


@dataclass(frozen=True)
class MapSamples(Result):
    """The maps at ``N`` samples (``n`` actuators, ``n`` joint coordinates).

    Attributes:
        q: Full configurations (N, nq).
        qa: Actuator coordinates (N, n) [rad or m].
        qj: Joint coordinates (N, n) [rad or m].
        J: ``d qj / d qa`` (N, n, n): ``qj_dot = J qa_dot``.
        J_inv: ``d qa / d qj`` (N, n, n).
        M_joint: Reflected inertia in joint space (N, n, n) [kg m^2 or kg].
        M_act: Reflected inertia in actuator space (N, n, n).
        cond: Condition number of ``J`` (N,) (``inf`` when singular).
        singular: Singular samples (N,) (see the module docstring).
        reached: Samples that could be assembled (N,); with ``strict=False`` the rows of the
            others are NaN (and they are flagged singular).

    """

    q: np.ndarray
    qa: np.ndarray
    qj: np.ndarray
    J: np.ndarray
    J_inv: np.ndarray
    M_joint: np.ndarray
    M_act: np.ndarray
    cond: np.ndarray
    singular: np.ndarray
    reached: np.ndarray

    def to_json(self) -> dict[str, Any]:
        """Every array as nested lists (``None`` where not finite), SI units."""
        return jsonable(dict(self.__dict__))

    def table(self) -> str:
        """Samples reached and singular; the range of each coordinate and of ``cond(J)``."""
        ok = np.asarray(self.reached) & ~np.asarray(self.singular)
        cond = np.asarray(self.cond)[ok]
        lines = [
            f"{int(np.count_nonzero(self.reached))} of {len(self.reached)} samples assembled, "
            f"{int(np.count_nonzero(self.singular))} singular; "
            + (
                f"cond(J) {quantity(float(cond.min()))} .. {quantity(float(cond.max()))} "
                "(dimensionless)"
                if cond.size
                else "cond(J): none"
            )
        ]
        for what, X in (("actuator", self.qa), ("joint", self.qj)):
            X = np.asarray(X)[np.asarray(self.reached)]
            for k in range(X.shape[1] if X.ndim == 2 and X.size else 0):
                lines.append(
                    f"  {what} coordinate {k + 1}: {quantity(float(X[:, k].min()), 'rad or m')} "
                    f".. {quantity(float(X[:, k].max()), 'rad or m')}"
                )
        return "\n".join(lines)

    def actuator_torques(self, tau_joint: Sequence[float] | np.ndarray) -> np.ndarray:
        """Actuator efforts that deliver joint-space efforts, by virtual work.

        Args:
            tau_joint: Joint-space efforts, (n,) for every sample or (N, n) [N m or N].

        Returns:
            ``tau_a = J^T tau_j`` (N, n) [N m or N].

        """
        tj = _per_sample(tau_joint, self.qj.shape, "tau_joint")
        return np.einsum("kji,kj->ki", self.J, tj)

    def joint_torques(self, tau_act: Sequence[float] | np.ndarray) -> np.ndarray:
        """Joint-space efforts that actuator efforts deliver, by virtual work.

        Args:
            tau_act: Actuator efforts, (n,) for every sample or (N, n) [N m or N].

        Returns:
            ``tau_j = J^{-T} tau_a`` (N, n) [N m or N].

        """
        ta = _per_sample(tau_act, self.qa.shape, "tau_act")
        return np.einsum("kji,kj->ki", self.J_inv, ta)


def _numbers(x: Any, what: str) -> np.ndarray:
    """``x`` as a float array, or a refusal naming ``what`` (strings, mappings, ragged rows)."""
    if isinstance(x, str | bytes | dict):
        raise InvalidInputError(what, f"expected numbers, got {x!r:.60}")
    try:
        return np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(what, f"expected numbers (rows as long), got {x!r:.60}") from None


def _per_sample(x: Sequence[float] | np.ndarray, shape: tuple[int, ...], what: str) -> np.ndarray:
    a = _numbers(x, what)
    if a.shape == shape[1:]:
        a = np.broadcast_to(a, shape)
    if a.shape != shape or not np.all(np.isfinite(a)):
        raise InvalidInputError(
            what, f"expected {shape[1]} or {shape} finite values, got {a.shape}"
        )
    return a


def _coordinates(robot: Robot, names: Sequence[str], what: str) -> tuple[np.ndarray, np.ndarray]:
    """Configuration and velocity indices of joints (joint or actuator names)."""
    model = robot.model
    by_actuator = {a.name: a.joint for a in robot.actuators}
    iq: list[int] = []
    iv: list[int] = []
    for n in names:
        j = by_actuator.get(n, n) if what == "actuators" else n
        if not model.existJointName(j):
            raise InvalidInputError(
                what,
                f"'{n}' is not a {'actuator or ' if what == 'actuators' else ''}joint of "
                f"{robot.name}",
            )
        jm = model.joints[model.getJointId(j)]
        if jm.nq != jm.nv or jm.shortname() in MODELLING_JOINTS:
            raise InvalidInputError(
                what, f"joint '{j}' has no plain coordinates (ball, free-flyer or planar joint)"
            )
        iq += list(range(jm.idx_q, jm.idx_q + jm.nq))
        iv += list(range(jm.idx_v, jm.idx_v + jm.nv))
    if len(set(iv)) != len(iv):
        raise InvalidInputError(what, "a joint is named twice")
    return np.array(iq, dtype=int), np.array(iv, dtype=int)


class ActuationMap:
    """Maps between actuator and joint coordinates of a robot (see the module docstring).

    Build with :func:`actuation_map`.

    Attributes:
        robot: The robot.
        joints: Joint names of the joint space.
        actuators: Actuator names.
        joint_q: Configuration indices of the joint coordinates (n,).
        joint_v: Velocity indices of the joint coordinates (n,).
        act_q: Configuration indices of the actuator coordinates (n,).
        act_v: Velocity indices of the actuator coordinates (n,).
        held_v: Velocity indices held fixed (other actuators, floating bases).
        q_ref: Configuration the maps start from (warm start of the first sample).

    """

    def __init__(
        self,
        robot: Robot,
        joints: Sequence[str],
        actuators: Sequence[str] | None = None,
        q_ref: np.ndarray | None = None,
    ) -> None:
        from pkdyn.inputs import names
        from pkdyn.model.arguments import check_robot, configuration

        self.robot = robot = check_robot(robot)
        self.joints = list(names("joints", joints, what="joint"))
        self.actuators = (
            [a.name for a in robot.actuators]
            if actuators is None
            else list(names("actuators", actuators, what="actuator"))
        )
        self.joint_q, self.joint_v = _coordinates(robot, self.joints, "joints")
        self.act_q, self.act_v = _coordinates(robot, self.actuators, "actuators")
        if self.joint_v.size != self.act_v.size:
            raise InvalidInputError(
                "joints",
                f"{self.joint_v.size} joint coordinates for {self.act_v.size} actuators; a map "
                "needs as many of each",
            )
        model = robot.model
        held = [int(v) for v in robot.actuated_v if v not in self.act_v]
        for jid in range(1, model.njoints):
            jm = model.joints[jid]
            if jm.shortname() in MODELLING_JOINTS:
                held += list(range(jm.idx_v, jm.idx_v + jm.nv))
        self.held_v = np.array(sorted(set(held) - set(self.act_v) - set(self.joint_v)), dtype=int)
        self.moving_v = np.setdiff1d(np.arange(model.nv), self.held_v)
        self._pos_a = np.searchsorted(self.moving_v, self.act_v)
        self._pos_j = np.searchsorted(self.moving_v, self.joint_v)
        self.q_ref = robot.q_home.copy() if q_ref is None else configuration(robot, q_ref, "q_ref")
        self._data = model.createData()
        self._free = {
            "a": np.setdiff1d(self.moving_v, self.act_v),
            "j": np.setdiff1d(self.moving_v, self.joint_v),
        }

    @property
    def n(self) -> int:
        """Number of actuator (and joint) coordinates."""
        return int(self.act_v.size)

    def _solve(self, q0: np.ndarray, free: np.ndarray) -> tuple[np.ndarray, bool]:
        robot, data = self.robot, self._data
        cs = robot.constraints
        if cs.n == 0:
            return q0, True
        sol = solve_lm(
            robot.model,
            q0,
            lambda q: cs.residual(data, q),
            lambda q: cs.jacobian(data, q),
            free,
            1e-12,
            60,
        )
        return sol.q, sol.converged

    def _samples(self, values: Sequence[float] | np.ndarray, what: str) -> np.ndarray:
        v = _numbers(values, what)
        if v.ndim == 1:
            v = v[None, :]
        if v.ndim != 2 or v.shape[1] != self.n or not np.all(np.isfinite(v)):
            raise InvalidInputError(
                what, f"expected ({self.n},) or (N, {self.n}) finite values, got {np.shape(values)}"
            )
        if v.shape[0] > MAX_SAMPLES:
            raise InvalidInputError(
                what,
                f"{v.shape[0]:,} samples, more than {MAX_SAMPLES:,} (each is an assembly and a "
                f"rank decision, about 1-5 ms: {v.shape[0] * 3e-3 / 60:.0f} min); map fewer "
                "at a time",
            )
        return v

    @public
    def from_joints(
        self,
        qj: Sequence[float] | np.ndarray,
        q_init: np.ndarray | None = None,
        strict: bool = True,
    ) -> MapSamples:
        """Actuator coordinates (and everything else) from joint coordinates.

        Args:
            qj: Joint coordinates, (n,) or (N, n) [rad or m], in joint-name order.
            q_init: Configuration to start from (default :attr:`q_ref`); each sample starts
                from the previous solution.
            strict: Raise on a sample that cannot be assembled (else flag it).

        Returns:
            The maps at every sample.

        Raises:
            InvalidInputError: Malformed input, or more than :data:`MAX_SAMPLES` samples.
            AssemblyError: A sample cannot be assembled (``strict``), naming it.

        """
        return self._map(self._samples(qj, "qj"), self.joint_q, self._free["j"], q_init, strict)

    @public
    def from_actuators(
        self,
        qa: Sequence[float] | np.ndarray,
        q_init: np.ndarray | None = None,
        strict: bool = True,
    ) -> MapSamples:
        """Joint coordinates (and everything else) from actuator coordinates.

        Args:
            qa: Actuator coordinates, (n,) or (N, n) [rad or m], in actuator order.
            q_init: Configuration to start from (default :attr:`q_ref`).
            strict: Raise on a sample that cannot be assembled (else flag it).

        Returns:
            The maps at every sample.

        Raises:
            InvalidInputError: Malformed input, or more than :data:`MAX_SAMPLES` samples.
            AssemblyError: A sample cannot be assembled (``strict``), naming it.

        """
        return self._map(self._samples(qa, "qa"), self.act_q, self._free["a"], q_init, strict)

    def _map(
        self,
        values: np.ndarray,
        iq: np.ndarray,
        free: np.ndarray,
        q_init: np.ndarray | None,
        strict: bool,
    ) -> MapSamples:
        robot = self.robot
        N, n = values.shape
        Q = np.full((N, robot.nq), np.nan)
        J = np.full((N, n, n), np.nan)
        Ji = np.full((N, n, n), np.nan)
        Mj = np.full((N, n, n), np.nan)
        Ma = np.full((N, n, n), np.nan)
        cond = np.full(N, np.inf)
        singular = np.ones(N, dtype=bool)
        reached = np.zeros(N, dtype=bool)
        q = np.array(self.q_ref if q_init is None else q_init, dtype=float)
        if q.shape != (robot.nq,) or not np.all(np.isfinite(q)):
            raise InvalidInputError("q_init", f"expected {robot.nq} finite values")
        for k in range(N):
            q0 = q.copy()
            q0[iq] = values[k]
            qk, ok = self._solve(q0, free)
            if not ok:
                if strict:
                    name = ", ".join(f"{x:.6g}" for x in values[k])
                    raise AssemblyError(
                        "-",
                        float("nan"),
                        f"{robot.name}: sample {k} ({name}) cannot be assembled; pass "
                        "strict=False to flag such samples instead",
                    )
                continue
            q = qk
            Q[k] = qk
            reached[k] = True
            J[k], Ji[k], Mj[k], Ma[k], cond[k], singular[k] = self._first_order(qk)
        return MapSamples(
            Q, Q[:, self.act_q], Q[:, self.joint_q], J, Ji, Mj, Ma, cond, singular, reached
        )

    def _first_order(
        self, q: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, bool]:
        """Jacobians, reflected inertias, condition number and singularity at ``q``."""
        robot, data = self.robot, self._data
        mv = self.moving_v
        if robot.constraints.n:
            Jc = robot.constraints.jacobian(data, q)[:, mv]
            Z = numerics.null_space(Jc, RANK_RTOL, 1.0)
        else:
            Z = np.eye(mv.size)
        A = Z[self._pos_a]
        C = Z[self._pos_j]
        n = self.n
        Ua, sa, Vta = np.linalg.svd(A)
        Uc, sc, Vtc = np.linalg.svd(C)
        rank_a = numerics.rank_of(sa, RANK_RTOL, 1.0)
        rank_c = numerics.rank_of(sc, RANK_RTOL, 1.0)
        # motions with the actuators held that still move the joints: parallel singularity
        held = C @ Vta[rank_a:].T
        loose = held.size > 0 and numerics.rank(held, RANK_RTOL, 1.0) > 0
        singular = rank_a < n or rank_c < n or loose
        # C = J A on every motion: J = C A^+, J^-1 = A C^+ (cut by the rank rule)
        Jm = (C @ Vta[:rank_a].T / sa[:rank_a]) @ Ua[:, :rank_a].T
        Jmi = (A @ Vtc[:rank_c].T / sc[:rank_c]) @ Uc[:, :rank_c].T
        M = pin.crba(robot.model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        K = Z.T @ M[np.ix_(mv, mv)] @ Z
        Kinv_Ct = np.linalg.solve(K, np.column_stack([C.T, A.T]))
        Mj = _inverse_cut(C @ Kinv_Ct[:, :n])
        Ma = _inverse_cut(A @ Kinv_Ct[:, n:])
        s = np.linalg.svd(Jm, compute_uv=False)
        cond = float(s[0] / s[-1]) if not singular and s[-1] > 0 else np.inf
        return Jm, Jmi, Mj, Ma, cond, bool(singular)


def _inverse_cut(G: np.ndarray) -> np.ndarray:
    """Inverse of a symmetric positive semi-definite matrix, small singular values cut off."""
    U, s, Vt = np.linalg.svd(G)
    r = numerics.rank_of(s, RANK_RTOL, 1.0)
    return np.asarray((Vt[:r].T / s[:r]) @ U[:, :r].T)


@public
def actuation_map(
    robot: Robot,
    joints: Sequence[str],
    actuators: Sequence[str] | None = None,
    q_ref: np.ndarray | None = None,
) -> ActuationMap:
    """Maps between actuator coordinates and chosen joint coordinates (module docstring).

    Args:
        robot: A closed-loop robot.
        joints: Names of the joints whose coordinates form the joint space (revolute,
            prismatic or universal joints; passive or actuated).
        actuators: Actuator (or actuated joint) names; default every actuator of the robot.
            The others, and floating-base joints, are held.
        q_ref: Configuration the maps start from (default ``robot.q_home``); it picks the
            assembly mode.

    Returns:
        The map; call :meth:`~ActuationMap.from_joints` or
        :meth:`~ActuationMap.from_actuators` on one sample or many.

    Raises:
        InvalidInputError: Unknown names, or not as many joint coordinates as actuators.

    """
    return ActuationMap(robot, joints, actuators, q_ref)
