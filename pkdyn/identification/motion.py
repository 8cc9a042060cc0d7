"""Joint motions of the whole mechanism from measured actuator motions, batch after batch.

Identification reads actuator positions ``qa`` (and rates, accelerations) only; the regressor
needs the configuration, velocity and acceleration ``(q, v, a)`` of every joint:

- ``q``: the actuators at ``qa``, the other coordinates solved onto the closures by Newton's
  method (minimum-norm steps on the passive coordinates). The assembly mode of the start
  configuration (default ``robot.q_home``) is followed. Along a densely sampled motion most
  samples are solved together: every ``S``-th sample (an *anchor*, ``S`` such that anchors
  lie :data:`ANCHOR_SPACING` apart, at most :data:`MAX_STRIDE` samples) is solved one after
  the other from a quadratic extrapolation of the previous anchors (sample by sample, with
  Levenberg-Marquardt from the previous sample when Newton stalls, where that fails); the
  samples between two anchors start from the cubic Hermite interpolation of the anchors'
  configurations and velocities (in the tangent space of the left anchor) and are solved all at
  once, each Newton step one Pinocchio call per sample (``computeJointJacobians``) and the
  closure residuals, Jacobians and steps batched with numpy
  (:meth:`solvers.SampledKinematics.residuals_and_jacobians`). A sample the batched Newton
  does not converge on is solved alone from its predecessor. Without rates, or with times that
  do not increase, every sample is an anchor;
- ``v``: ``J v = 0`` with the actuator rates imposed, ``a``: ``J a = -gamma`` with the actuator
  accelerations imposed (``gamma``: the closures' acceleration drift, computed for a batch of
  samples at once by :class:`solvers.SampledKinematics`). The passive coordinates get the
  least-squares solution ``v_p = -J_p^+ J_a qa_dot``: unique when the actuators determine the
  mechanism; where internal mobilities remain (the spin of a Delta's ball-jointed bars, which no
  sensor measures) the solution of least norm, i.e. no spin relative to the neighbouring bodies.

Per sample only Pinocchio's C++ runs (joint Jacobians, ``integrate``, ``rnea``); the closure
equations and the velocity and acceleration solves are batched with numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import TrajectoryError
from pkdyn.model.robot import Robot
from solvers import SampledKinematics, numerics, solve_lm

__all__ = [
    "ANCHOR_SPACING",
    "ASSEMBLY_RTOL",
    "ASSEMBLY_TOL",
    "BATCH",
    "MAX_STRIDE",
    "MotionBatch",
    "SINGULAR_RTOL",
    "MotionSampler",
    "passive_solve",
]

ASSEMBLY_RTOL = 1e-10
"""Closure residual each sample is assembled to, relative to the robot's size
(:meth:`pkdyn.Robot.closure_tolerance`: a millimetre robot as closely as a metre one)."""

ASSEMBLY_TOL = ASSEMBLY_RTOL
"""The former name of :data:`ASSEMBLY_RTOL` (kept for one release)."""

BATCH = 256
"""Samples per batch."""

ANCHOR_SPACING = 0.032
"""Time [s] between the samples solved one after the other (anchors) on a dense motion."""

MAX_STRIDE = 32
"""Most samples from one anchor to the next."""

SINGULAR_RTOL = 1e-8
"""Closure velocity error, relative to the largest joint rate (at least 1), of a singular
sample (the actuators cannot move independently)."""

_NEWTON_STEPS = 12


@dataclass(eq=False)  # numpy fields
class MotionBatch:
    """Joint motion of a batch of consecutive samples.

    Attributes:
        q: Configurations (n, nq).
        v: Velocities (n, nv).
        a: Accelerations (n, nv).
        J: Closure Jacobians (n, nc, nv) (:class:`solvers.ConstraintSet` convention).
        first: Index of the first sample in the whole series.
        passive_map: ``J_p^+ J_a`` (n, n_p, n_a) when computed (``v_p = -J_p^+ J_a qa_dot``),
            else ``None``.

    """

    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    J: np.ndarray
    first: int = 0
    passive_map: np.ndarray | None = None


def passive_solve(Jp: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Least-squares, least-norm solutions ``J_p^+ x`` of a batch (the passive-joint elimination).

    :func:`solvers.numerics.passive_elimination`: the one rule of the kinematic models and the
    sensitivities (redundant closure rows dropped by the scale-aware cut-off).

    Args:
        Jp: Passive columns of the closure Jacobians (n, nc, n_p).
        x: Right-hand sides (n, nc) or (n, nc, k).

    Returns:
        ``J_p^+ x``: (n, n_p) or (n, n_p, k).

    """
    return numerics.passive_solve(Jp, x)


def _step(Jp: np.ndarray, r: np.ndarray) -> np.ndarray:
    """One sample's least-squares, least-norm ``J_p^+ r`` (as :func:`passive_solve`)."""
    return numerics.passive_elimination(Jp).solve(r)


def _hermite(s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cubic Hermite basis ``h10, h01, h11`` at ``s`` in [0, 1] (``h00``'s node is zero)."""
    s2, s3 = s * s, s * s * s
    return s3 - 2.0 * s2 + s, 3.0 * s2 - 2.0 * s3, s3 - s2


class MotionSampler:
    """Turns actuator motions into joint motions batch after batch (see the module doc).

    Args:
        robot: The robot.
        q_init: Start configuration (default ``robot.q_home``): the assembly mode followed.

    """

    def __init__(self, robot: Robot, q_init: np.ndarray | None = None) -> None:
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.cs = robot.constraints
        self.kin = SampledKinematics(robot.model, robot.constraints, (), BATCH)
        self.va = np.asarray(robot.actuated_v, dtype=int)
        self.aq = np.asarray(robot.actuated_q, dtype=int)
        self.vp = np.setdiff1d(np.arange(robot.nv), self.va)
        self.tol = robot.closure_tolerance(ASSEMBLY_RTOL)  # [m or rad]
        q0 = robot.q_home if q_init is None else q_init
        self.restart(q0)

    def restart(self, q: np.ndarray) -> None:
        """Forget the previous samples: the next one starts from ``q`` (nq,)."""
        self._history: list[tuple[int, np.ndarray]] = [(0, np.array(q, dtype=float))]
        self._fresh = True
        self._last: tuple[float, np.ndarray, np.ndarray] | None = None  # t, q, v

    # -- one sample at a time (anchors, fall-backs) ---------------------------------------

    def _guess(self, k: int) -> np.ndarray:
        """Quadratic (Lagrange) extrapolation of the anchors to global sample ``k``."""
        h = self._history
        if self._fresh or len(h) == 1:
            return h[-1][1].copy()
        x0, q0 = h[-1]
        nodes = [x for x, _ in h]
        delta = np.zeros(self.model.nv)
        for j, (xj, qj) in enumerate(h[:-1]):
            L = np.prod([(k - xm) / (xj - xm) for m, xm in enumerate(nodes) if m != j])
            delta += L * pin.difference(self.model, q0, qj)
        return pin.integrate(self.model, q0, delta)

    def _push(self, k: int, q: np.ndarray) -> None:
        self._history = [(k, q)] if self._fresh else [*self._history[-2:], (k, q)]
        self._fresh = False

    def _newton(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, float]:
        """Newton steps on the passive coordinates: ``(q, J at q or None, residual)``."""
        model, data, cs, vp = self.model, self.data, self.cs, self.vp
        dq = np.zeros(model.nv)
        err = np.inf
        for _ in range(_NEWTON_STEPS):
            r, J = cs.residual_and_jacobian(data, q)
            err_new = float(np.abs(r).max(initial=0.0))
            if err_new <= self.tol:
                return q, J, err_new
            if err_new > 0.9 * err:  # not converging: let Levenberg-Marquardt take over
                return q, None, err_new
            err = err_new
            dq[vp] = -_step(J[:, vp], r)
            q = pin.integrate(model, q, dq)
        return q, None, err

    def _solve_one(
        self, k: int, qa: np.ndarray, t: float, first: int, lm: bool = True
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Sample ``k`` (in the batch) from the extrapolated anchors.

        ``None`` when Newton fails and ``lm`` is false. The joint Jacobians of ``self.data`` are
        left at ``q``.
        """
        q = self._guess(first + k)
        q[self.aq] = qa
        q, Jk, _ = self._newton(q)
        if Jk is None:
            if not lm:
                return None
            start = self._history[-1][1].copy()
            start[self.aq] = qa
            cs = self.cs
            sol = solve_lm(
                self.model,
                start,
                residual_and_jacobian=lambda x: cs.residual_and_jacobian(self.data, x),
                free=self.vp,
                tol=self.tol,
            )
            if not sol.converged:
                raise TrajectoryError(
                    f"the actuator positions cannot be assembled (closure residual "
                    f"{sol.error:.3g}): out of reach, or a jump between samples",
                    first + k,
                    t,
                )
            q = sol.q
            _, Jk = cs.residual_and_jacobian(self.data, q)
        self._push(first + k, q)
        return q, Jk

    # -- many samples at once -------------------------------------------------------------

    def _stride(self, t: np.ndarray, rates: bool) -> int:
        """Samples from one anchor to the next (1: every sample is an anchor)."""
        if not rates or t.size < 3:
            return 1
        dt = np.diff(t)
        if not np.all(dt > 0.0) or not np.all(np.isfinite(dt)):
            return 1
        if self._last is not None and not t[0] > self._last[0]:
            return 1
        return int(np.clip(round(ANCHOR_SPACING / float(np.median(dt))), 1, MAX_STRIDE))

    def _velocities(self, J: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Joint velocities (n, nv) of assembled samples with the actuator rates ``qd``."""
        V = np.zeros((J.shape[0], self.model.nv))
        V[:, self.va] = qd
        if J.shape[1] and self.vp.size:
            V[:, self.vp] = -passive_solve(J[:, :, self.vp], J[:, :, self.va] @ qd[..., None])[
                ..., 0
            ]
        return V

    def newton_batch(self, Q: np.ndarray, rows: np.ndarray, J: np.ndarray) -> np.ndarray:
        """Newton's method on many samples at once, from their guesses.

        Args:
            Q: Configurations (n, nq): the guesses of ``rows``, replaced by the solutions.
            rows: Samples (m,) to solve (< :data:`BATCH`; also their rows of the
                :class:`solvers.SampledKinematics` buffers, left at the solutions).
            J: Closure Jacobians (n, nc, nv), filled at the solved samples.

        Returns:
            The samples (a subset of ``rows``) on which Newton did not converge.

        """
        model, vp = self.model, self.vp
        active = np.asarray(rows, dtype=int)
        prev = np.full(active.size, np.inf)
        dq = np.zeros(model.nv)
        failed: list[np.ndarray] = []
        for it in range(_NEWTON_STEPS + 1):
            if not active.size:
                break
            for i in active:
                self.kin.capture_configuration(int(i), Q[i])
            r, Jb = self.kin.residuals_and_jacobians(active)
            err = np.abs(r).max(axis=1, initial=0.0)
            ok = err <= self.tol
            J[active[ok]] = Jb[ok]
            go = ~ok & (err <= 0.9 * prev)
            failed.append(active[~ok & ~go])
            if it == _NEWTON_STEPS:
                failed.append(active[go])
                break
            steps = -passive_solve(Jb[go][:, :, vp], r[go])
            active, prev = active[go], err[go]
            for i, s in zip(active, steps, strict=True):
                dq[vp] = s
                Q[i] = pin.integrate(model, Q[i], dq)
        return np.sort(np.concatenate([np.zeros(0, dtype=int), *failed]))

    def configurations(
        self, qa: np.ndarray, t: np.ndarray, first: int = 0, qd: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Assembled configurations and closure Jacobians of consecutive samples.

        Args:
            qa: Actuator positions (n, n_a) [rad or m].
            t: Their times (n,) [s].
            first: Index of the first sample in the whole series.
            qd: Actuator rates (n, n_a) [rad/s or m/s]; without them every sample is solved
                after the previous one (module doc).

        Returns:
            ``(Q (n, nq), J (n, nc, nv))``. When ``n`` <= :data:`BATCH`, the buffers of
            ``self.kin`` hold the samples' placements and joint Jacobians.

        Raises:
            TrajectoryError: A sample cannot be assembled.

        """
        n = qa.shape[0]
        if n > BATCH:
            parts = [
                self.configurations(
                    qa[s : s + BATCH],
                    t[s : s + BATCH],
                    first + s,
                    None if qd is None else qd[s : s + BATCH],
                )
                for s in range(0, n, BATCH)
            ]
            return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
        model, cs = self.model, self.cs
        Q = np.empty((n, model.nq))
        J = np.empty((n, cs.n, model.nv))
        if not cs.n:
            for k in range(n):
                q = self._guess(first + k)
                q[self.aq] = qa[k]
                Q[k] = q
                self._push(first + k, q)
            return Q, J
        S = self._stride(t, qd is not None)
        anchors = list(range(n - 1, -1, -S))[::-1]
        if qd is None:
            self._last = None
        if self._last is None and anchors[0] != 0:
            anchors.insert(0, 0)
        solved = np.zeros(n, dtype=bool)
        prev = -1
        for a in anchors:  # one after the other; where Newton fails, sample by sample
            out = self._solve_one(a, qa[a], float(t[a]), first, lm=a - prev == 1)
            if out is None:
                for k in range(prev + 1, a + 1):
                    Q[k], J[k] = self._solve_one(k, qa[k], float(t[k]), first)  # type: ignore[misc]
                    self.kin.capture_configuration(k, Q[k])
                    solved[k] = True
            else:
                Q[a], J[a] = out
                self.kin.capture_configuration(a, Q[a])
                solved[a] = True
            prev = a
        if S > 1:
            self._between_anchors(Q, J, solved, qa, t, qd, first)  # type: ignore[arg-type]
        if qd is not None:
            V = self._velocities(J[-1:], qd[-1:])
            self._last = (float(t[-1]), Q[-1].copy(), V[0])
        return Q, J

    def _between_anchors(
        self,
        Q: np.ndarray,
        J: np.ndarray,
        solved: np.ndarray,
        qa: np.ndarray,
        t: np.ndarray,
        qd: np.ndarray,
        first: int,
    ) -> None:
        """Solve the samples between the anchors together (module doc)."""
        model = self.model
        nodes = np.flatnonzero(solved)
        V = self._velocities(J[nodes], qd[nodes])
        ends = [(float(t[k]), Q[k], V[i]) for i, k in enumerate(nodes)]
        if self._last is not None:
            nodes = np.concatenate([[-1], nodes])
            ends.insert(0, self._last)
        rows = np.flatnonzero(~solved)
        right = np.searchsorted(nodes, rows)
        for j in np.unique(right):
            (t0, q0, v0), (t1, q1, v1) = ends[j - 1], ends[j]
            h = t1 - t0
            d = pin.difference(model, q0, q1)
            v1 = pin.dDifference(model, q0, q1, pin.ArgumentPosition.ARG1) @ v1
            inside = rows[right == j]
            h10, h01, h11 = _hermite((t[inside] - t0) / h)
            delta = np.outer(h * h10, v0) + np.outer(h01, d) + np.outer(h * h11, v1)
            for i, dl in zip(inside, delta, strict=True):
                Q[i] = pin.integrate(model, q0, dl)
        Q[rows[:, None], self.aq] = qa[rows]
        failed = self.newton_batch(Q, rows, J)
        if not failed.size:
            return
        history, fresh = self._history, self._fresh
        for i in failed:  # alone, from the predecessor
            k = int(i)
            before = Q[k - 1].copy() if k else self._last[1]  # type: ignore[index]
            self._history, self._fresh = [(first + k - 1, before)], False
            Q[k], J[k] = self._solve_one(k, qa[k], float(t[k]), first)  # type: ignore[misc]
            self.kin.capture_configuration(k, Q[k])
        self._history, self._fresh = history, fresh

    def batch(
        self, t: np.ndarray, qa: np.ndarray, qd: np.ndarray, qdd: np.ndarray, first: int = 0
    ) -> MotionBatch:
        """Joint motion of consecutive samples (at most :data:`BATCH`).

        Args:
            t: Times (n,) [s].
            qa: Actuator positions (n, n_a) [rad or m].
            qd: Actuator rates (n, n_a) [rad/s or m/s].
            qdd: Actuator accelerations (n, n_a) [rad/s^2 or m/s^2].
            first: Index of the first sample in the whole series.

        Returns:
            The batch's ``(q, v, a)`` and closure Jacobians.

        Raises:
            TrajectoryError: A sample cannot be assembled, or the actuators cannot move
                independently there (a singular configuration).

        """
        if qa.shape[0] > BATCH:
            raise ValueError(f"at most {BATCH} samples per batch, not {qa.shape[0]}")
        Q, J = self.configurations(qa, t, first, qd)
        b, err = self.rates(Q, J, qd, qdd)
        bad = np.flatnonzero(err > SINGULAR_RTOL)
        if bad.size:
            k = int(bad[0])
            raise TrajectoryError(
                "the actuators cannot move independently here (singular configuration): "
                f"the closures keep a velocity error of {err[k]:.3g}",
                first + k,
                float(t[k]),
            )
        b.first = first
        return b

    def rates(
        self, Q: np.ndarray, J: np.ndarray, qd: np.ndarray, qdd: np.ndarray
    ) -> tuple[MotionBatch, np.ndarray]:
        """Velocities and accelerations of assembled samples (module doc).

        Args:
            Q: Configurations (n, nq), n <= :data:`BATCH`, captured in the rows ``0..n-1`` of
                ``self.kin`` (:meth:`solvers.SampledKinematics.capture_configuration`).
            J: Their closure Jacobians (n, nc, nv).
            qd: Actuator rates (n, n_a) [rad/s or m/s].
            qdd: Actuator accelerations (n, n_a) [rad/s^2 or m/s^2].

        Returns:
            The joint motion, and per sample (n,) the closures' velocity error ``max |J v|``
            relative to ``max(1, max |v|)``: above :data:`SINGULAR_RTOL` the actuators cannot
            move independently there (a singular configuration).

        """
        model, cs = self.model, self.cs
        n = Q.shape[0]
        V = np.zeros((n, model.nv))
        A = np.zeros((n, model.nv))
        V[:, self.va] = qd
        A[:, self.va] = qdd
        err = np.zeros(n)
        X = None
        if cs.n and self.vp.size:
            Jp, Ja = J[:, :, self.vp], J[:, :, self.va]
            X = passive_solve(Jp, Ja)
            V[:, self.vp] = -(X @ qd[..., None])[..., 0]
            err = np.abs((J @ V[..., None])[..., 0]).max(axis=1)
            err /= np.maximum(1.0, np.abs(V).max(axis=1))
            kin = self.kin
            kin.update_placements(np.arange(n))
            for i in range(n):
                kin.capture_drift(i, Q[i], V[i])
            gamma = kin.acceleration_errors(n, V)
            rhs = -((Ja @ qdd[..., None])[..., 0] + gamma)
            A[:, self.vp] = passive_solve(Jp, rhs)
        return MotionBatch(Q, V, A, J, 0, X), err
