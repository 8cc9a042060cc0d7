"""The control-loop step: one semi-implicit Euler step that ends on the closures.

A controller calls the dynamics once per period ``h`` (typically 1 ms) and wants a state that
satisfies the closures. A semi-implicit Euler step ``v+ = v + h a(q, v)``, ``q+ = q (+) h v+``
leaves a closure residual of about ``h^2 gamma / 2`` (``gamma``: the closures' acceleration
drift, ``|v|^2`` over a length): 1e-8 .. 1e-4 m at 1 ms on a moving Delta, whatever the
Baumgarte gains. A full projection after each step (Levenberg-Marquardt, then a mass-metric
velocity projection) removes it but costs 15-20 dynamics evaluations' worth of Python. This
step removes it with what the dynamics computes anyway:

1. *First same as last.* The dynamics are evaluated at the END of each step, at ``(q+, v+)``
   under the step's applied force ``f``: ``pin.constraintDynamics`` leaves the closure
   residual ``e(q+)`` in its constraint datas and the factorization of the regularised KKT
   matrix ``K = [[-mu I, J], [J^T, M]]`` at ``q+`` in ``data.constraint_chol``.
2. *One Newton correction* of ``q+`` with that exact Jacobian, in the mass metric:
   ``dq = M^-1 J^T (J M^-1 J^T + mu I)^-1 (-e)``, one sparse solve with ``K``. What it
   leaves is the closures' quadratic term, ``c |dq|^2`` (``c`` below 0.3 /m on the Delta and
   the Gough-Stewart), plus ``mu |lambda|`` from the regularisation: 1e-13 m after a 1e-6 m
   residual. The evaluation at ``q+`` included the Baumgarte pull ``-Kp e`` of that residual,
   now removed: its share of the acceleration, ``K^-1 [-Kp e; 0] = Kp dq``, is taken out.
3. *Reuse.* The next call, given the state this one returned (compared byte for byte), takes
   that evaluation: under a new applied force ``f'`` the acceleration is
   ``a + K^-1 [0; f' - f]`` (the constrained dynamics are linear in the applied force; one
   solve with the regularised ``K`` is within ``mu / sigma`` of the converged change, about
   1e-8 relative on the library robots). It was made ``dq`` before the correction: the
   velocity differs from a raw step's at the corrected state by 1e-9 .. 1e-8 relative. Any
   other state is evaluated afresh.

The residual the correction leaves is estimated as ``curvature |dq|^2``; where the estimate
exceeds a quarter of the tolerance (fast motions, near singular configurations) it is
measured (forward kinematics and the closures) and chord corrections with the same
factorization follow, each measured, until it is within the tolerance. It is also measured
once every :data:`CALIBRATION_PERIOD` steps, which raises ``curvature`` to twice the ratio
seen. After :data:`MAX_CORRECTIONS` corrections, or a correction above 1e-2, the state goes
through the full projection.

Joint couplings (:mod:`solvers.coupling`) are corrected with the closures: their forces come
from the factorization of the one Pinocchio call (:mod:`solvers.coupled_dynamics`), and the
Newton correction and the force-change response made to move them as their residual requires
(``x + G mu`` with ``C (x + G mu) = -r_c``, ``G`` the hard-closure response to the couplings'
forces): the mass-metric correction of closures and couplings together, with no other solve.

The velocity is not projected: the Baumgarte gains of the dynamics hold ``J v`` (what a
semi-implicit Euler step leaves is ``O(h^2)``), and a projection would cost as much again;
the energy behaves as with the full projection (``tests/test_control_step.py``).
Cost: one dynamics evaluation, two sparse solves, two ``integrate`` and one copy of the
residual per step; measured against the raw Euler step in ``bench/dynamics.py``.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
import pinocchio as pin

from solvers.actuation import TorqueFn
from solvers.constraints import ConstraintSet
from solvers.coupled_dynamics import CoupledDynamics
from solvers.passive import PassiveForces

__all__ = ["CALIBRATION_PERIOD", "MAX_CORRECTIONS", "ProjectedEulerStep", "SteppedDynamics"]

MAX_CORRECTIONS = 4
"""Newton corrections of one step before the full projection takes over."""

CALIBRATION_PERIOD = 64
"""Steps between two measurements of the residual a correction leaves (``curvature``)."""

_POINT = pin.ContactType.CONTACT_3D
_FALLBACK = 1e-2
"""Correction [m or rad] above which Newton steps are not trusted: full projection."""


class SteppedDynamics(Protocol):
    """What the step reads of the dynamics it drives (a :class:`~solvers.ForwardDynamics`)."""

    @property
    def model(self) -> pin.Model:
        """The kinematic tree."""

    @property
    def constraints(self) -> ConstraintSet:
        """The constraint set (its coupling rows are corrected with the closures)."""

    @property
    def constraint_models(self) -> pin.StdVec_RigidConstraintModel:
        """Pinocchio's constraint models of the closures, with their Baumgarte gains."""

    @property
    def n_pin(self) -> int:
        """Rows of Pinocchio's constraint models."""

    @property
    def prox(self) -> pin.ProximalSettings:
        """Settings of Pinocchio's proximal solver."""

    @property
    def passive(self) -> PassiveForces | None:
        """Springs, dampers and friction (``None``: none)."""

    @property
    def project_tol(self) -> float:
        """Closure residual the step ends within [m or rad]."""

    @property
    def _pd(self) -> tuple[float, float]:
        """The Baumgarte gains ``(Kp [1/s^2], Kd [1/s])`` in force."""

    @property
    def _auto_gains(self) -> bool:
        """The gains follow the step (:meth:`_euler_gains`)."""

    @property
    def _gains_step(self) -> float:
        """The step [s] the automatic gains were set for."""

    def _euler_gains(self, h: float) -> None:
        """Set the automatic gains for the step ``h`` [s]."""

    def _generalized(
        self, t: float, q: np.ndarray, v: np.ndarray, tau_fn: TorqueFn | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Actuator efforts (n_a,) and their generalized force (nv,)."""

    def _project_state(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` projected onto the closures (the full projection)."""


class ProjectedEulerStep:
    """Semi-implicit Euler steps that end on the closures (see the module docstring).

    Args:
        fd: The forward dynamics (its model, constraint models with their Baumgarte gains,
            proximal settings, actuation, passive forces, ``project_tol`` and projection).

    Attributes:
        steps: Steps taken.
        corrections: Newton corrections made.
        measured: Residual measurements beyond the one the dynamics give.
        projections: Full projections (fallbacks).
        curvature: ``c`` of the estimate ``c |dq|^2`` of the residual a correction leaves
            [1/m]: the robot's reach (largest distance of a joint from the base at the first
            state, at least 0.1 m), raised by the measurements.

    """

    def __init__(self, fd: SteppedDynamics) -> None:
        model = fd.model
        self.fd = fd
        self.data = model.createData()
        self.datas = pin.StdVec_RigidConstraintData()
        for cm in fd.constraint_models:
            self.datas.append(cm.createData())
        if fd.n_pin:
            pin.initConstraintDynamics(model, self.data, fd.constraint_models, self.datas)
        rows = fd.constraints.coupling_rows
        self._rows = rows
        # with couplings: their forces from the factorization of the one Pinocchio call
        self._cd = (
            None
            if rows is None
            else CoupledDynamics(
                model, rows, fd.constraint_models, self.datas, self.data, fd.prox, fd._pd
            )
        )
        self._rk = np.zeros(0 if rows is None else rows.n)  # the couplings' residual
        self._points = all(cm.type == _POINT for cm in fd.constraint_models)
        # live numpy views on the constraint datas' members (Pinocchio returns the members by
        # reference): the residual is copied by one concatenate, not read closure by closure.
        # The views stay valid as long as ``self.datas`` lives and is not resized.
        cds = list(self.datas)
        self._c1Mc2 = [cd.c1Mc2 for cd in cds]
        self._trans = [M.translation for M in self._c1Mc2]
        self._errors = [
            cd.contact_placement_error.linear
            if cm.type == _POINT
            else cd.contact_placement_error.vector
            for cm, cd in zip(list(fd.constraint_models), cds, strict=True)
        ]
        self._pairs = [
            (cm.type == _POINT, cm, cd)
            for cm, cd in zip(list(fd.constraint_models), cds, strict=True)
        ]
        nc, nv = fd.n_pin, model.nv
        self._nc = nc
        # right-hand sides of the solves with K: [target; 0] (correction), [0; df] (forces)
        self._rhs = np.zeros(nc + nv)
        self._head = self._rhs[:nc]
        self._rhs_f = np.zeros(nc + nv)
        self._tail_f = self._rhs_f[nc:]
        self._zero = np.zeros(nv)
        # the state the last step returned, the dynamics there and the force they assumed
        self._key: tuple[bytes, bytes, float] | None = None
        self._a = self._zero
        self._f: np.ndarray | None = None
        self._kp = 0.0  # the Baumgarte stiffness of the closures [1/s^2]
        self.curvature = 0.0
        self.steps = 0
        self.corrections = 0
        self.measured = 0
        self.projections = 0

    def _target(self) -> None:
        """Minus the closure residual of the last dynamics evaluation, into the head.

        Pinocchio's placement error of a point closure is ``-c1Mc2.translation``, of a weld
        ``-log6(c1Mc2)``, and its constraint Jacobian ``J`` their derivative: the correction
        ``dq`` solves ``J dq = c1Mc2.translation`` (or ``log6(c1Mc2)``).
        """
        if self._points:
            np.concatenate(self._trans, out=self._head)
        else:
            np.concatenate(self._errors, out=self._head)
            np.negative(self._head, out=self._head)

    def _measure(self, q: np.ndarray) -> float:
        """The closure residual at ``q`` (2-norm, kinematics only); minus it into the head."""
        model, data, head = self.fd.model, self.data, self._head
        pin.forwardKinematics(model, data, q)
        for _, cm, cd in self._pairs:
            cm.calc(model, data, cd)
        if not self._nc:
            pass
        elif self._points:
            np.concatenate(self._trans, out=head)
        else:
            o = 0
            for (point, _, _), M, p in zip(self._pairs, self._c1Mc2, self._trans, strict=True):
                n = 3 if point else 6
                head[o : o + n] = p if point else pin.log6(M).vector
                o += n
        self.measured += 1
        if self._rows is None:
            return math.sqrt(float(head @ head))
        self._rk = self._rows.residual(q)
        return math.sqrt(float(head @ head) + float(self._rk @ self._rk))

    def _dynamics(self, q: np.ndarray, v: np.ndarray, f: np.ndarray) -> np.ndarray:
        """The dynamics at ``(q, v)`` under ``f``; their factorization stays in ``data``."""
        if self._cd is not None:
            self._cd.gains = self.fd._pd
            a = self._cd.acceleration(q, v, f)
            self._rk = self._rows.residual(q) if self._rows is not None else self._rk
            return a
        fd = self.fd
        return pin.constraintDynamics(
            fd.model, self.data, q, v, f, fd.constraint_models, self.datas, fd.prox
        )

    def _correct(self) -> np.ndarray:
        """The Newton correction (nv,) of the residual in the head (and of the couplings').

        ``K^-1 [target; 0]`` for the closures (the factorization of the last dynamics
        evaluation); with couplings, made to undo their residual too, in the mass metric.
        """
        nc = self._nc
        x = self.data.constraint_chol.solve(self._rhs)[nc:] if nc else np.zeros(self.fd.model.nv)
        if self._cd is None:
            return x
        return self._cd.couple(x, -self._rk)

    def _force_response(self, df: np.ndarray) -> np.ndarray:
        """The change (nv,) of the last evaluation's acceleration under a force change ``df``."""
        nc = self._nc
        if nc:
            self._tail_f[:] = df
            x = self.data.constraint_chol.solve(self._rhs_f)[nc:]
        else:
            assert self._cd is not None and self._cd.Minv is not None
            x = self._cd.Minv.dot(df)
        if self._cd is None:
            return x
        return self._cd.couple(x, np.zeros(self._rk.size))

    def _reach(self, q: np.ndarray) -> None:
        data = self.data
        pin.forwardKinematics(self.fd.model, data, q)
        reach = max(np.linalg.norm(data.oMi[j].translation) for j in range(len(data.oMi)))
        self.curvature = max(0.1, float(reach))

    def step(
        self, t: float, q: np.ndarray, v: np.ndarray, dt: float, tau: TorqueFn | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Advance ``(q, v)`` by ``dt`` and bring ``q`` back on the closures.

        Args:
            t: Time [s].
            q: Configuration (nq,).
            v: Velocity (nv,).
            dt: Step [s].
            tau: Actuator efforts ``tau(t, q, v) -> (n_a,)`` (``None``: zero).

        Returns:
            ``(q, v)`` at ``t + dt``, closure residual within ``project_tol``.

        Raises:
            IntegrationError: The closures cannot be restored.

        """
        fd = self.fd
        model, data, datas, cms, prox, cd = (
            fd.model,
            self.data,
            self.datas,
            fd.constraint_models,
            fd.prox,
            self._cd,
        )
        if fd._auto_gains and dt != fd._gains_step:
            fd._euler_gains(dt)
            self._key = None
        if self._key is None:
            self._kp = float(fd._pd[0])
        f = None if tau is None else fd._generalized(t, q, v, tau)[1]
        if fd.passive is not None:
            f = fd.passive.force(q, v) if f is None else f + fd.passive.force(q, v)
        ff = self._zero if f is None else f
        key = self._key
        if key is None or key[2] != dt or key[0] != q.tobytes() or key[1] != v.tobytes():
            q = np.asarray(q, dtype=float)
            v = np.asarray(v, dtype=float)
            if cd is None:
                a = pin.constraintDynamics(model, data, q, v, ff, cms, datas, prox)
            else:
                a = self._dynamics(q, v, ff)
            if not self.curvature:
                self._reach(q)
        elif f is None:
            a = self._a
        else:
            f0 = self._f
            df = f if f0 is None else f - f0
            if cd is None:
                self._tail_f[:] = df
                a = self._a + data.constraint_chol.solve(self._rhs_f)[self._nc :]
            else:
                a = self._a + self._force_response(df)
        v = v + dt * a
        q = pin.integrate(model, q, dt * v)
        # first same as last: the dynamics at the new state, under the same force
        # (a view on data.ddq, used before the next evaluation overwrites it)
        if cd is None:
            self._a = pin.constraintDynamics(model, data, q, v, ff, cms, datas, prox)
        else:
            self._a = self._dynamics(q, v, ff)
        self._f = f
        # one Newton correction with the factorization at the new state
        if cd is None:
            self._target()
            dq = data.constraint_chol.solve(self._rhs)[self._nc :]
        else:
            if self._nc:
                self._target()
            dq = self._correct()
        q = pin.integrate(model, q, dq)
        # that evaluation pulled the closures by the Baumgarte term -Kp e, which the
        # correction removed: K^-1 [-Kp e; 0] = Kp dq (the same solve), taken out of it
        self._a -= self._kp * dq
        dq2 = float(dq @ dq)
        self.steps += 1
        self.corrections += 1
        if self.curvature * dq2 > 0.25 * fd.project_tol or self.steps % CALIBRATION_PERIOD == 1:
            q, restored = self._restore(q, dq2)
            if not restored:
                q, v = fd._project_state(q, v)
                self.projections += 1
                self._key = None
                return q, v
        self._key = (q.tobytes(), v.tobytes(), dt)
        return q, v

    def _restore(self, q: np.ndarray, dq2: float) -> tuple[np.ndarray, bool]:
        """Check ``q`` after a first correction ``|dq|^2``; correct more if needed.

        The estimate ``curvature |dq|^2`` holds for the first correction, made with the
        Jacobian at the point it starts from; the next ones reuse it (chord steps) and are
        measured. The first measurement after the first correction raises ``curvature`` to
        twice the ratio it shows.

        Returns:
            The configuration and whether it is within the tolerance (else: project it).

        """
        tol = self.fd.project_tol
        model = self.fd.model
        if not dq2 <= _FALLBACK * _FALLBACK:  # (NaN included)
            return q, False
        r = self._measure(q)
        if r > 0.01 * tol and dq2 > 0.0:
            self.curvature = max(self.curvature, 2.0 * r / dq2)
        for _ in range(MAX_CORRECTIONS - 1):
            if r <= tol:
                return q, True
            dq = self._correct()
            q = pin.integrate(model, q, dq)
            self.corrections += 1
            if not float(dq @ dq) <= _FALLBACK * _FALLBACK:
                return q, False
            r = self._measure(q)
        return q, r <= tol
