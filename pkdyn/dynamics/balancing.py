r"""Spring balancing: stiffness and preload of springs that minimise the actuator torques.

Springs between two frames (:class:`~pkdyn.model.description.SpringSpec`: attachment points
given, e.g. from a post above a Delta arm's pivot to a point on the arm, or along a hexapod leg),
grouped so that springs of one group share their stiffness ``k`` and free length ``L_0`` (the
three arms of a Delta). The tension of spring ``s`` is ``T_s = k L_s(q) - c`` with ``c = k L_0``,
its generalized force ``-T_s (\partial L_s / \partial q)^T``: **linear in** ``(k, c)``. With a
non-redundant actuation the actuator torques are linear in the generalized forces, so along a
duty cycle (inverse dynamics) or over configurations at rest (statics with gravity)

.. math::

    \tau(t) = \tau_0(t) + \sum_g k_g\, A_g(t) + c_g\, B_g(t)

where ``A_g``, ``B_g`` are the torque responses to a unit stiffness and a unit ``c``, computed by
pkdyn's own inverse dynamics / statics on the robot carrying unit springs. The design is then
a small convex problem in ``x = (k_g, c_g)``:

- ``metric="rms"``: minimise the sum over actuators of the time-mean square torque (the
  RMS that sizes a motor's continuous torque; trapezoidal weights, as :mod:`~pkdyn.dynamics.sizing`;
  equal weights over configurations at rest) - a bounded least-squares problem, or a QP
  (proxsuite) with ``tension_only``;
- ``metric="peak"``: minimise the largest ``|tau_i(t)|`` - a linear program (HiGHS);

under ``k_g >= 0``, bounds on the free length ``L_min <= L_0 <= L_max`` (linear:
``k_g L_min <= c_g <= k_g L_max``; default ``0 <= L_0 <=`` twice the longest spring length over
the samples; a negative ``L_min`` admits extension springs with initial tension), optionally
``k_g <= max_stiffness`` and ``tension_only`` (``T_s >= 0`` at every sample: springs that never
push). The balanced robot is then re-evaluated by the full inverse dynamics / statics:
the reported torques are computed, not predicted.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.analysis.mobility import mobility
from pkdyn.dynamics.inverse import inverse_dynamics
from pkdyn.dynamics.payload import with_payload
from pkdyn.dynamics.trajectory import JointTrajectory
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.description import FrameRef, SpringSpec
from pkdyn.model.passive import with_passive
from pkdyn.model.robot import Robot
from pkdyn.results import Result, jsonable
from solvers import numerics

__all__ = [
    "BalancingResult",
    "balance_springs",
    "delta_balancing_springs",
    "gough_stewart_balancing_springs",
    "torque_metrics",
]

METRICS = ("rms", "peak")


@dataclass(frozen=True)
class BalancingResult(Result):
    """Springs chosen by :func:`balance_springs` and the torques with and without them.

    Attributes:
        robot: The robot carrying the chosen springs (payload not included).
        springs: The chosen springs (stiffness and free length set).
        groups: Group index of each spring.
        stiffness: Stiffness per group [N/m].
        rest_length: Free length per group [m].
        preload: Tension of each spring at the robot's home configuration [N].
        tension: Smallest and largest tension of each spring over the samples (S, 2) [N].
        metric: ``rms`` or ``peak``.
        tau_before: Actuator torques without the springs (N, n_a) [N m or N].
        tau_after: Actuator torques with them (N, n_a), recomputed by the full model.
        weights: Sample weights of the RMS (N,) (sum 1).

    """

    robot: Robot
    springs: tuple[SpringSpec, ...]
    groups: tuple[int, ...]
    stiffness: np.ndarray
    rest_length: np.ndarray
    preload: np.ndarray
    tension: np.ndarray
    metric: str
    tau_before: np.ndarray
    tau_after: np.ndarray
    weights: np.ndarray

    @property
    def rms_before(self) -> np.ndarray:
        """RMS torque per actuator without the springs (n_a,)."""
        return np.sqrt(self.weights @ self.tau_before**2)

    @property
    def rms_after(self) -> np.ndarray:
        """RMS torque per actuator with the springs (n_a,)."""
        return np.sqrt(self.weights @ self.tau_after**2)

    @property
    def peak_before(self) -> np.ndarray:
        """Peak ``|torque|`` per actuator without the springs (n_a,)."""
        return np.max(np.abs(self.tau_before), axis=0)

    @property
    def peak_after(self) -> np.ndarray:
        """Peak ``|torque|`` per actuator with the springs (n_a,)."""
        return np.max(np.abs(self.tau_after), axis=0)

    def to_json(self) -> dict[str, Any]:
        """The springs and the torques with and without them.

        Returns:
            ``groups`` (``stiffness`` [N/m], ``rest_length`` [m], member ``springs``),
            ``preload`` [N] per spring, and per actuator the RMS and peak torques before and
            after [N m or N].

        """
        return jsonable(
            {
                "robot": self.robot.name,
                "metric": self.metric,
                "groups": [
                    {
                        "stiffness": float(k),
                        "rest_length": float(L0),
                        "springs": [
                            s.name
                            for s, gi in zip(self.springs, self.groups, strict=True)
                            if gi == g
                        ],
                    }
                    for g, (k, L0) in enumerate(zip(self.stiffness, self.rest_length, strict=True))
                ],
                "preload": dict(zip([s.name for s in self.springs], self.preload, strict=True)),
                "actuators": list(self.robot.actuator_names),
                "rms_before": self.rms_before,
                "rms_after": self.rms_after,
                "peak_before": self.peak_before,
                "peak_after": self.peak_after,
            }
        )

    def table(self) -> str:
        """A readable summary: springs, then torques before / after per actuator."""
        rows = [
            f"{'group':<6} {'stiffness':>10} {'free len':>9}  springs (preload at home)",
            f"{'':<6} {'[N/m]':>10} {'[m]':>9}",
        ]
        for g, (k, L0) in enumerate(zip(self.stiffness, self.rest_length, strict=True)):
            members = ", ".join(
                f"{s.name} ({p:.1f} N)"
                for s, gi, p in zip(self.springs, self.groups, self.preload, strict=True)
                if gi == g
            )
            rows.append(f"{g:<6} {k:10.1f} {L0:9.4f}  {members}")
        rows.append(
            f"{'actuator':<10} {'rms':>8} {'-> rms':>8} {'peak':>8} {'-> peak':>8}   [N m or N]"
        )
        names = self.robot.actuator_names
        for i, name in enumerate(names):
            rows.append(
                f"{name:<10} {self.rms_before[i]:8.3f} {self.rms_after[i]:8.3f} "
                f"{self.peak_before[i]:8.3f} {self.peak_after[i]:8.3f}"
            )
        return "\n".join(rows)


def torque_metrics(
    robot: Robot,
    samples: JointTrajectory | np.ndarray,
    payload: float = 0.0,
    passive: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Actuator torques over a duty cycle or over configurations at rest, and their RMS / peak.

    A design metric: the figure :func:`balance_springs` minimises, for any robot.

    Args:
        robot: The robot.
        samples: A joint trajectory (inverse dynamics with gravity) or assembled configurations
            (N, nq) at rest (statics with gravity).
        payload: Payload at the platform frame [kg].
        passive: Include the robot's passive elements.

    Returns:
        ``(tau (N, n_a), rms (n_a,), peak (n_a,))`` [N m or N].

    """
    tau = _efforts(with_payload(robot, payload) if payload else robot, samples, passive)
    w = _weights(samples, tau.shape[0])
    return tau, np.sqrt(w @ tau**2), np.max(np.abs(tau), axis=0)


def _weights(samples: JointTrajectory | np.ndarray, n: int) -> np.ndarray:
    if isinstance(samples, JointTrajectory) and n > 1:
        dt = np.diff(samples.t)
        w = np.zeros(n)
        w[:-1] += 0.5 * dt
        w[1:] += 0.5 * dt
        return w / w.sum()
    return np.full(n, 1.0 / n)


def _efforts(robot: Robot, samples: JointTrajectory | np.ndarray, passive: bool) -> np.ndarray:
    """Inverse dynamics along a trajectory, or at rest (v = a = 0: statics) at configurations."""
    if not isinstance(samples, JointTrajectory):
        Q = np.atleast_2d(np.asarray(samples, dtype=float))
        if Q.ndim != 2 or Q.shape[1] != robot.nq or not np.all(np.isfinite(Q)):
            raise InvalidInputError(
                "samples", f"expected finite configurations (N, {robot.nq}), got {Q.shape}"
            )
        zero = np.zeros((Q.shape[0], robot.nv))
        samples = JointTrajectory(
            np.arange(float(Q.shape[0])), Q, zero, zero, robot.actuated_q, robot.actuated_v,
            name="configurations at rest",
        )  # fmt: skip
    return inverse_dynamics(robot, samples, passive=passive, progress=False).tau


def _lengths(robot: Robot, springs: Sequence[SpringSpec], Q: np.ndarray) -> np.ndarray:
    """Length of each spring (N, S) [m] at configurations ``Q`` (N, nq)."""
    probe = with_passive(robot, springs=[_unit(s) for s in springs], keep=False).passive
    assert probe is not None
    return np.array([[L for L, _ in probe.spring_state(q)] for q in Q])


def _unit(s: SpringSpec, rest_length: float = 0.0) -> SpringSpec:
    return SpringSpec(s.name, s.frame1, s.frame2, 1.0, rest_length)


def balance_springs(
    robot: Robot,
    springs: Sequence[SpringSpec],
    samples: JointTrajectory | np.ndarray,
    metric: str = "rms",
    groups: Sequence[int] | None = None,
    payload: float = 0.0,
    tension_only: bool = False,
    max_stiffness: float | None = None,
    rest_length: tuple[float | None, float | None] = (0.0, None),
) -> BalancingResult:
    """Choose the stiffness and preload (free length) of balancing springs.

    Args:
        robot: The robot (its other passive elements are kept; springs of the same names as
            ``springs`` are replaced).
        springs: The springs' attachment frames (their stiffness and free length are ignored).
        samples: A duty cycle (joint trajectory: inverse dynamics) or assembled configurations
            (N, nq) over the workspace at rest (statics), gravity included.
        metric: ``rms`` (sum over actuators of the mean square torque) or ``peak`` (largest
            ``|torque|``).
        groups: Group index of each spring; a group shares stiffness and free length (default:
            one group).
        payload: Payload at the platform frame [kg] during the samples.
        tension_only: Springs that only pull (tension >= 0 at every sample).
        max_stiffness: Upper bound of the stiffness [N/m] (default: none).
        rest_length: Bounds ``(L_min, L_max)`` of the free length [m]; ``None``: ``L_min`` 0,
            ``L_max`` twice the largest length any spring reaches over the samples (a free
            length above the spring's length is a compression spring). A negative
            ``L_min`` admits extension springs with initial tension (``L_0 = L_f - T_i / k``).

    Returns:
        The springs, the balanced robot and the torques before / after.

    Raises:
        InvalidInputError: Unknown metric, bad groups or bounds, no springs, redundant
            actuation (the torques are then not linear in the springs).
        PkdynError: The optimisation failed.

    """
    if metric not in METRICS:
        raise InvalidInputError("metric", f"unknown {metric!r}; use rms or peak")
    if not springs:
        raise InvalidInputError("springs", "give at least one spring to balance with")
    S = len(springs)
    grp = np.zeros(S, dtype=int) if groups is None else np.asarray(groups, dtype=int)
    if grp.shape != (S,) or grp.min() < 0:
        raise InvalidInputError("groups", f"expected {S} group indices >= 0, got {groups}")
    G = int(grp.max()) + 1
    if sorted(set(grp.tolist())) != list(range(G)):
        raise InvalidInputError("groups", f"group indices must be 0..{G - 1}, each used")
    if max_stiffness is not None and not max_stiffness > 0.0:
        raise InvalidInputError("max_stiffness", f"must be > 0 N/m, got {max_stiffness}")
    _check_linear(robot)
    names = {s.name for s in springs}
    own = robot.description.springs
    base = robot
    if names & {s.name for s in own}:  # springs of the same names are being redesigned
        kept = [s for s in own if s.name not in names]
        base = with_passive(robot, list(robot.description.passive), kept, keep=False)
    loaded = with_payload(base, payload) if payload else base
    tau0 = _efforts(loaded, samples, True)
    N, n_a = tau0.shape
    Q = samples.q if isinstance(samples, JointTrajectory) else np.atleast_2d(samples)
    L = _lengths(base, springs, Q)  # (N, S)
    # torque responses to a unit k (free length 0) and a unit c (free length 1 m minus 0 m)
    A = np.zeros((G, N, n_a))
    B = np.zeros((G, N, n_a))
    for g in range(G):
        members = [s for s, gi in zip(springs, grp, strict=True) if gi == g]
        t_k = _efforts(with_passive(loaded, springs=[_unit(s) for s in members]), samples, True)
        t_c = _efforts(
            with_passive(loaded, springs=[_unit(s, 1.0) for s in members]), samples, True
        )
        A[g] = t_k - tau0
        B[g] = t_c - t_k  # T = k L - c: a unit c is a tension of -1 N (T_c = T_k - 1)
    w = _weights(samples, N)
    M = np.stack([A, B], axis=1).reshape(2 * G, N * n_a).T  # columns k_0, c_0, k_1, ...
    y0 = tau0.reshape(-1)
    w_rows = np.repeat(w, n_a)
    L_min = 0.0 if rest_length[0] is None else float(rest_length[0])
    L_max = 2.0 * float(np.max(L)) if rest_length[1] is None else float(rest_length[1])
    if not (math.isfinite(L_min) and math.isfinite(L_max) and L_min <= L_max):
        raise InvalidInputError(
            "rest_length", f"expected finite bounds min <= max, got {rest_length}"
        )
    # inequality rows (C x <= 0): k L_min - c <= 0, c - k L_max <= 0, tension c - k L_s(t) <= 0
    rows = []
    for g in range(G):
        for a, b in ((L_min, -1.0), (-L_max, 1.0)):
            r = np.zeros(2 * G)
            r[2 * g], r[2 * g + 1] = a, b
            rows.append(r)
    if tension_only:
        for s in range(S):
            g = int(grp[s])
            for t in range(N):
                r = np.zeros(2 * G)
                r[2 * g], r[2 * g + 1] = -L[t, s], 1.0
                rows.append(r)
    C = np.array(rows)
    lower = np.zeros(2 * G)
    lower[1::2] = -np.inf  # c = k L_0 takes the sign of L_0
    upper = np.full(2 * G, np.inf)
    if max_stiffness is not None:
        upper[0::2] = max_stiffness
    x = _solve(metric, M, y0, w_rows, C, lower, upper)
    k, c = x[0::2], x[1::2]
    L0 = np.clip(np.where(k > 0.0, c / np.where(k > 0.0, k, 1.0), 0.0), L_min, L_max)
    chosen = tuple(
        SpringSpec(s.name, s.frame1, s.frame2, float(k[g]), float(L0[g]))
        for s, g in zip(springs, grp, strict=True)
    )
    balanced = with_passive(base, springs=list(chosen))
    tau_after = _efforts(with_payload(balanced, payload) if payload else balanced, samples, True)
    L_home = _lengths(base, springs, robot.q_home[None])[0]
    preload = np.array([k[g] * (L_home[s] - L0[g]) for s, g in enumerate(grp)])
    T = k[grp][None, :] * (L - L0[grp][None, :])
    return BalancingResult(
        robot=balanced,
        springs=chosen,
        groups=tuple(int(g) for g in grp),
        stiffness=k,
        rest_length=L0,
        preload=preload,
        tension=np.column_stack([T.min(axis=0), T.max(axis=0)]),
        metric=metric,
        tau_before=tau0,
        tau_after=tau_after,
        weights=w,
    )


def _check_linear(robot: Robot) -> None:
    """The torques are linear in the spring forces only for a non-redundant actuation."""
    if len(robot.actuators) > mobility(robot).useful:
        raise InvalidInputError(
            "robot",
            f"{robot.name} is redundantly actuated: its torques are not linear in the springs' "
            "forces (least-effort allocation); balance a non-redundant variant",
        )


def _solve(
    metric: str,
    M: np.ndarray,
    y0: np.ndarray,
    w: np.ndarray,
    C: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> np.ndarray:
    """The convex problem of the module docstring, on columns scaled to unit norm."""
    scale = np.linalg.norm(M, axis=0)
    scale = np.where(scale > 0.0, scale, 1.0)
    Ms = M / scale
    Cs = C / scale
    lb, ub = lower * scale, upper * scale
    n = M.shape[1]
    if metric == "rms":
        from proxsuite import proxqp

        sw = np.sqrt(w)
        Aw = Ms * sw[:, None]
        bw = y0 * sw
        H = Aw.T @ Aw
        g = Aw.T @ bw
        Cin = np.vstack([np.eye(n), Cs])
        lo = np.concatenate([np.where(np.isfinite(lb), lb, -1e20), np.full(Cs.shape[0], -1e20)])
        hi = np.concatenate([np.where(np.isfinite(ub), ub, 1e20), np.zeros(Cs.shape[0])])
        qp = proxqp.dense.QP(n, 0, Cin.shape[0])
        qp.settings.eps_abs = 1e-10 * max(1.0, float(np.abs(g).max()))
        qp.settings.eps_rel = 0.0
        qp.settings.max_iter = 10000
        qp.settings.verbose = False
        qp.init(H, g, None, None, Cin, lo, hi)
        qp.solve()
        if qp.results.info.status != proxqp.QPSolverOutput.PROXQP_SOLVED:
            raise PkdynError(
                f"spring balancing: the QP did not converge ({qp.results.info.status})"
            )
        z = _polish(H, g, Cin, lo, hi, np.array(qp.results.x))
    else:
        from scipy.optimize import linprog

        # variables (z, s): minimise s, -s <= y0 + Ms z <= s
        ones = np.ones((Ms.shape[0], 1))
        A_ub = np.vstack(
            [
                np.hstack([Ms, -ones]),
                np.hstack([-Ms, -ones]),
                np.hstack([Cs, np.zeros((Cs.shape[0], 1))]),
            ]
        )
        b_ub = np.concatenate([-y0, y0, np.zeros(Cs.shape[0])])
        bounds = [
            (float(a) if math.isfinite(a) else None, float(b) if math.isfinite(b) else None)
            for a, b in zip(lb, ub, strict=True)
        ] + [(0.0, None)]
        res = linprog(np.r_[np.zeros(n), 1.0], A_ub=A_ub, b_ub=b_ub, bounds=bounds, method="highs")
        if res.status != 0:
            raise PkdynError(f"spring balancing: the linear program failed ({res.message})")
        z = np.asarray(res.x[:n])
    return np.clip(z, lb, ub) / scale


def _polish(
    H: np.ndarray, g: np.ndarray, C: np.ndarray, lo: np.ndarray, hi: np.ndarray, z: np.ndarray
) -> np.ndarray:
    """Solve the QP again on the active set of the iterative solution (exact to round-off).

    Rows of ``lo <= C z <= hi`` within a small tolerance of a bound are kept as equalities; the
    equality-constrained least squares (KKT system) replaces ``z`` when it is feasible and
    not worse.
    """
    Cz = C @ z
    tol = 1e-7 * max(1.0, float(np.max(np.abs(Cz))))
    at_lo = np.abs(Cz - lo) <= tol
    at_hi = np.abs(Cz - hi) <= tol
    E = C[at_lo | at_hi]
    e = np.where(at_lo, lo, hi)[at_lo | at_hi]
    n, m = H.shape[0], E.shape[0]
    K = np.block([[H, E.T], [E, np.zeros((m, m))]])
    sol = numerics.lstsq(K, np.concatenate([-g, e]), numerics.machine_rtol(K))
    z2 = sol[:n]
    Cz2 = C @ z2
    feasible = np.all(Cz2 >= lo - tol) and np.all(Cz2 <= hi + tol)
    better = 0.5 * z2 @ H @ z2 + g @ z2 <= 0.5 * z @ H @ z + g @ z + 1e-12 * max(1.0, abs(g @ z))
    return z2 if feasible and better else z


# ---------------------------------------------------------------------------------- layouts


def delta_balancing_springs(
    robot: Robot, anchor_height: float = 0.1, arm_point: float | None = None
) -> list[SpringSpec]:
    """One spring per Delta arm: from a post above the arm's pivot to a point on the arm.

    With a zero free length, the spring's moment about the pivot is ``k h d cos(alpha)``, the
    shape of the arm's own gravity moment (perfect balancing of a pendulum when
    ``k h d = m g r``).

    Args:
        robot: A Delta of the library (``pkdyn.load("delta")``).
        anchor_height: Height ``h`` of the anchor above the pivot [m].
        arm_point: Distance ``d`` of the attachment from the pivot along the arm [m]
            (default: half the arm length).

    Returns:
        Springs ``balance1``... (stiffness 0: to be chosen by :func:`balance_springs`).

    Raises:
        InvalidInputError: Not a Delta, or a non-positive height / distance.

    """
    if robot.family != "delta":
        raise InvalidInputError("robot", f"{robot.name} is not a Delta of the library")
    p = robot.params
    d = 0.5 * p.la if arm_point is None else float(arm_point)
    for what, x in (("anchor_height", anchor_height), ("arm_point", d)):
        if not (math.isfinite(x) and x > 0.0):
            raise InvalidInputError(what, f"must be > 0 m, got {x}")
    out = []
    for i, th in enumerate(p.theta, start=1):
        pivot = p.ra * np.array([math.cos(th), math.sin(th), 0.0])
        anchor = FrameRef("base", pin.SE3(np.eye(3), pivot + np.array([0.0, 0.0, anchor_height])))
        attach = FrameRef(f"arm{i}", pin.SE3(np.eye(3), np.array([d, 0.0, 0.0])))
        out.append(SpringSpec(f"balance{i}", anchor, attach, 0.0, 0.0))
    return out


def gough_stewart_balancing_springs(robot: Robot) -> list[SpringSpec]:
    """One spring per Gough-Stewart leg, between its base and platform joint centres A_i, B_i.

    The spring lies along the leg: its tension adds to the leg actuator's force.

    Args:
        robot: A Gough-Stewart platform of the library (``pkdyn.load("gough_stewart")``).

    Returns:
        Springs ``leg1_spring``... (stiffness 0: to be chosen by :func:`balance_springs`).

    Raises:
        InvalidInputError: Not a Gough-Stewart platform of the library.

    """
    if robot.family != "gough_stewart":
        raise InvalidInputError("robot", f"{robot.name} is not a Gough-Stewart of the library")
    model = robot.model
    by_name = {c.name: c for c in robot.closures}
    out = []
    for i in range(1, len(robot.actuators) + 1):
        A = model.jointPlacements[model.getJointId(f"leg{i}_U")].translation
        B = by_name[f"S{i}"].frame2
        base = FrameRef("base", pin.SE3(np.eye(3), A.copy()))
        out.append(SpringSpec(f"leg{i}_spring", base, B, 0.0, 0.0))
    return out
