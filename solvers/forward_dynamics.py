"""Time stepping of the constrained forward dynamics of a closed-loop mechanism.

The accelerations come from Pinocchio's proximal ``pin.constraintDynamics``, which solves
``M a + h = tau + J^T lambda`` with ``J a = -Jdot v - Kd J v - Kp e`` (Baumgarte) for the rigid
constraint models, including redundant (rank-deficient) sets such as the two point constraints
of a hinge closure. On top of it:

- integrators on the configuration manifold (``pin.integrate``), explicit Runge-Kutta
  schemes in the exponential chart centred at the current configuration (Runge-Kutta-Munthe-
  Kaas: stage velocities are mapped to the chart with ``pin.dDifference``, so the order holds on
  the non-commutative joints, spherical and free-flyer):

  - ``"dopri5"`` (default): Dormand-Prince 5(4) with error control; ``dt`` is the output step
    and the largest substep; substeps shrink where the dynamics are stiff (near singular
    configurations, where the constraint forces peak), six evaluations per accepted substep;
  - ``"rk4"``: classical Runge-Kutta 4 at the fixed step ``dt``, four evaluations per step;
  - ``"euler"``: semi-implicit (symplectic) Euler, ``v+ = v + h a(q, v)``,
    ``q+ = q (+) h v+``; one evaluation per step, first order (energy error ~ ``omega h``);
    for fast, rough runs, or accurate ones at small steps (a passive Delta keeps its energy to
    0.1 % over 10 s at ``h = 1e-5`` s);

  The output step ``dt`` and the integration step ``h`` are separate (``simulate(step=h)``):
  a sample is recorded (and the closures checked) once per output step, whatever the number
  of internal steps.

- drift control: Baumgarte gains on copies of the constraint models (for ``euler``, by default,
  critically damped at ``omega = 0.5 / h``: a semi-implicit Euler step leaves a closure error
  ``-gamma h^2 / 2`` (``gamma``: the closures' acceleration drift) that these gains hold at about
  ``2 gamma h^2``, where gains fixed in time would let it grow like ``gamma h / (2 Kd)``), and a
  projection of the state onto the closures after each output step whose closure residual
  exceeds a threshold (``project_tol``, 1e-9 by default: only where the gains do not suffice):
  ``q`` by minimum-norm Gauss-Newton / Levenberg-Marquardt steps on
  :class:`~solvers.constraints.ConstraintSet`, then ``v`` by the kinetic-energy-metric
  projection onto the null space of the closure Jacobian (``v+ = argmin |v+ - v|_M  s.t.
  J v+ = 0``, the velocity after a perfectly inelastic impulse, which never adds energy);
- passive elements (:class:`~solvers.passive.PassiveForces`): joint springs, viscous dampers,
  smooth Coulomb friction and two-frame springs, a separate generalized-force term; the
  springs' energy is recorded as ``elastic``, the dampers' and friction's as ``dissipated``;
- actuation: efforts ``tau(t, q, v) -> (n_a,)`` mapped to generalized forces by an
  :class:`Actuation` selection.

Joint couplings (:mod:`solvers.coupling`: gears, mimic joints), which ``pin.constraintDynamics``
cannot take (it accepts 3D / 6D rigid constraints only and rejects mimic joints): the rigid
closures stay Pinocchio's, the couplings' forces ``C^T mu`` are added to the generalized forces.
The constrained acceleration is affine in the force, ``a(tau + C^T mu) = a(tau) + G mu``; ``G``
is read from ``k`` more calls with probe forces (``k`` couplings), ``mu`` solves the couplings'
acceleration equations ``C a = -gamma_c - Kd C v - Kp r_c`` (the same Baumgarte gains, minimum
norm when couplings are redundant with the closures) and a last call at ``tau + C^T mu`` gives
the acceleration and the rigid forces; ``k + 2`` calls per evaluation (``aba`` when there are no
rigid closures). Without couplings nothing changes: one call.

Units: SI. Pinocchio's constraint forces (``data.lambda_c``, for ``J =
pin.getConstraintsJacobian``) are, per constraint model, the force (3D) or wrench (6D) on
``joint1``'s body at its contact frame, expressed in that frame. The recorded
``constraint_forces`` are converted to the convention of :mod:`solvers.closure`
and of the inverse dynamics (:func:`ForwardDynamics.closure_forces`): 3D, the world-frame force
[N] on ``joint1``'s body; 6D, the wrench [N, N m] on ``joint2``'s body in its contact frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import pinocchio as pin

from solvers import numerics
from solvers.actuation import Actuation
from solvers.closure import Closure
from solvers.constraints import ConstraintSet, constraint_set
from solvers.control_step import ProjectedEulerStep
from solvers.coupling import Coupling
from solvers.energy import KineticEnergy
from solvers.integrators import COMMUTATIVE_JOINTS, DOPRI5, RK4, Tableau
from solvers.passive import PassiveForces
from solvers.projection import ProjectionError, project_state
from solvers.recording import Evaluation, ForwardResult, Recorder

__all__ = [
    "Actuation",
    "ForwardResult",
    "ForwardDynamics",
    "IntegrationError",
    "TorqueFn",
    "simulate",
]

TorqueFn = Callable[[float, np.ndarray, np.ndarray], np.ndarray]
"""Actuator efforts ``tau(t [s], q (nq,), v (nv,)) -> (n_a,)`` [N m or N]."""

_ARG1 = pin.ArgumentPosition.ARG1
_POINT = pin.ContactType.CONTACT_3D


class IntegrationError(RuntimeError):
    """The time stepping cannot go on: non-finite state or closures that cannot be restored.

    An internal solver error: :mod:`pkdyn.dynamics` converts it into the user-facing
    ``pkdyn.exceptions.SimulationError`` (same arguments: message, then time).

    Attributes:
        time: Time at which it happened [s] (NaN when unknown).

    """

    def __init__(self, message: str, time: float) -> None:
        self.time = time
        super().__init__(message)


class ForwardDynamics:
    """Constrained forward dynamics and time stepping on a Pinocchio model.

    Args:
        model: The kinematic tree (no mimic joints: ``pin.constraintDynamics`` rejects them).
        constraints: The constraint set (closures and couplings), or the closures alone
            (:class:`~solvers.closure.Closure` or CONTACT_3D / CONTACT_6D rigid constraint
            models); the closures' constraint models are copied (the Baumgarte gains are set
            on the copies).
        actuation: Actuated coordinates (default: none).
        passive: Springs, dampers and friction (default: none).
        integrator: ``"dopri5"``, ``"rk4"`` or ``"euler"`` (see the module docstring).
        baumgarte: Baumgarte gains ``(Kp [1/s^2], Kd [1/s])`` of the closure error (default:
            critically damped at 50 rad/s for ``dopri5`` and ``rk4``, at ``0.5 / h`` for
            ``euler`` with step ``h``, see the module doc; unstabilised, the closure error of a
            free Delta grows like ``exp(45 t)``).
        project: Project ``q`` and ``v`` onto the closures (the initial state, then every
            ``project_every`` output steps if the closure residual exceeds ``project_tol``).
        project_tol: Residual above which the state is projected [m or rad].
        project_every: Output steps between two residual checks.
        rtol: Relative tolerance of ``dopri5`` on the velocity.
        atol: Absolute tolerance of ``dopri5`` on the configuration increment [m or rad] and
            the velocity [m/s or rad/s].
        prox_accuracy: Stopping threshold of the proximal solver (on the constraint
            acceleration residual, or on the change of the forces between iterations).
        prox_mu: Proximal regularisation of the solver (handles redundant closures).
        prox_max_iter: Iteration cap of the proximal solver.
        max_substeps: Largest number of ``dopri5`` substeps (accepted and rejected) within one
            output step; beyond, the run stops with :class:`IntegrationError` (a stiff or
            blowing-up state would otherwise shrink the steps without end).
        max_speed: Largest joint speed [rad/s or m/s] accepted; beyond, the state is taken as
            blowing up and the run stops with :class:`IntegrationError`.
        couplings: Joint couplings (:mod:`solvers.coupling`) when ``constraints`` are closures;
            with any, the evaluation adds their forces to the closures' (see the module
            docstring).

    Raises:
        ValueError: Unknown integrator or inconsistent sizes.

    """

    def __init__(
        self,
        model: pin.Model,
        constraints: ConstraintSet | Sequence[Closure | pin.RigidConstraintModel],
        actuation: Actuation | None = None,
        *,
        passive: PassiveForces | None = None,
        integrator: str = "dopri5",
        baumgarte: tuple[float, float] | None = None,
        project: bool = True,
        project_tol: float = 1e-9,
        project_every: int = 1,
        rtol: float = 1e-8,
        atol: float = 1e-10,
        prox_accuracy: float = 1e-12,
        prox_mu: float = 1e-6,
        prox_max_iter: int = 30,
        max_substeps: int = 100_000,
        max_speed: float = 1e4,
        couplings: Sequence[Coupling] | ConstraintSet = (),
    ) -> None:
        if integrator not in ("rk4", "dopri5", "euler"):
            raise ValueError(f"unknown integrator {integrator!r} (rk4, dopri5 or euler)")
        self.rtol = rtol
        self.atol = atol
        self.max_substeps = int(max_substeps)
        self.max_speed = float(max_speed)
        self._h = 0.0
        self.steps = 0
        self.rejected = 0
        self.model = model
        self.data = model.createData()
        self._kin = model.createData()  # kinematics for residuals, energies, projections
        self.kinetic_energy = KineticEnergy(model)
        self.actuation = actuation if actuation is not None else Actuation([])
        if self.actuation.n and int(self.actuation.v_index.max()) >= model.nv:
            raise ValueError(f"actuated velocity index out of range (nv = {model.nv})")
        self.passive = None if passive is None or passive.empty else passive
        self.integrator = integrator
        self.project = project
        self.project_tol = project_tol
        if project_every < 1:
            raise ValueError(f"project_every must be >= 1, got {project_every}")
        self.project_every = project_every
        self._auto_gains = baumgarte is None
        self._gains_step = 0.0  # the Euler step the automatic gains were set for
        gains = (2500.0, 100.0) if baumgarte is None else baumgarte
        corrector = pin.BaumgarteCorrectorParameters(float(gains[0]), float(gains[1]))
        self.constraints = constraint_set(model, constraints, couplings)
        cs = self.constraints
        self.constraint_models = pin.StdVec_RigidConstraintModel()
        self.constraint_datas = pin.StdVec_RigidConstraintData()
        base = cs.closure_rows.base_models() if cs.closure_rows is not None else []
        for c in base:
            c.setBaumgarteCorrectorParameters(corrector)
            self.constraint_models.append(c)
            self.constraint_datas.append(c.createData())
        self.nc = cs.n  # constraint rows: closures, then couplings
        self._coupled = cs.nk > 0
        self._pd = (float(gains[0]), float(gains[1]))  # Baumgarte gains of the couplings
        n_k = cs.nk
        self._C = np.zeros((n_k, model.nv))  # the couplings' Jacobian rows
        self._mu = np.zeros(n_k)  # the couplings' forces at the last evaluation
        self._probe = 1.0  # probe force [N m or N]: of the order of the couplings' forces
        # conversion of Pinocchio's multipliers to the rows' convention (see the module doc)
        pts = [k for k, cm in enumerate(self.constraint_models) if cm.type == _POINT]
        offsets = cs.closure_rows.base_offsets if cs.closure_rows is not None else [0]
        self._pt_rows = np.array([offsets[k] for k in pts], dtype=int)
        self._pt_joint1 = [self.constraint_models[k].joint1_id for k in pts]
        self._pt_rot1 = np.array(
            [self.constraint_models[k].joint1_placement.rotation for k in pts]
        ).reshape(-1, 3, 3)
        self.prox = pin.ProximalSettings(prox_accuracy, prox_accuracy, prox_mu, prox_max_iter)
        if cs.nc:
            pin.initConstraintDynamics(
                model, self.data, self.constraint_models, self.constraint_datas
            )
        self._chart = any(
            model.joints[j].shortname() not in COMMUTATIVE_JOINTS for j in range(1, model.njoints)
        )
        self._zero_tau = np.zeros(self.actuation.n)
        self._zero_nv = np.zeros(model.nv)
        self._v_index = self.actuation.v_index
        act_gains = self.actuation.gains
        self._gains = None if np.all(act_gains == 1.0) else act_gains
        self._h_max = 0.0  # largest dopri5 substep of the current run
        self._substeps = 1  # fixed steps per output step (euler, rk4)
        self._control: ProjectedEulerStep | None = None  # the Euler control-loop step

    @property
    def closure_set(self) -> ConstraintSet:
        """The former name of :attr:`constraints` (kept for one release)."""
        return self.constraints

    def _euler_gains(self, h: float) -> None:
        """Automatic Baumgarte gains of the Euler step ``h``: critically damped at ``0.5 / h``."""
        if not self._auto_gains or self.integrator != "euler" or h == self._gains_step:
            return
        w = 0.5 / h
        corrector = pin.BaumgarteCorrectorParameters(w * w, 2.0 * w)
        for cm in self.constraint_models:
            cm.setBaumgarteCorrectorParameters(corrector)
        self._pd = (w * w, 2.0 * w)
        self._gains_step = h

    # ------------------------------------------------------------------ dynamics

    def acceleration(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Constrained acceleration for generalized forces ``tau`` (nv,).

        The constraint forces are left in ``self.data.lambda_c``.

        Args:
            q: Configuration (nq,).
            v: Velocity (nv,).
            tau: Generalized forces (nv,) [N m or N] (actuation and passive forces included).

        Returns:
            Acceleration (nv,) (a copy).

        """
        return np.array(self._accel(q, v, tau))

    def _accel(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Acceleration as a view on ``data.ddq`` (overwritten by the next call)."""
        if self._coupled:
            return self._coupled_accel(q, v, tau)
        if self.nc:
            return pin.constraintDynamics(
                self.model,
                self.data,
                q,
                v,
                tau,
                self.constraint_models,
                self.constraint_datas,
                self.prox,
            )
        return pin.aba(self.model, self.data, q, v, tau)

    def _rigid(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Acceleration under the rigid closures alone (a copy); forces in ``data.lambda_c``."""
        if self.constraints.nc:
            return np.array(
                pin.constraintDynamics(
                    self.model,
                    self.data,
                    q,
                    v,
                    tau,
                    self.constraint_models,
                    self.constraint_datas,
                    self.prox,
                )
            )
        return np.array(pin.aba(self.model, self.data, q, v, tau))

    def _coupled_accel(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Acceleration with the couplings' forces added (see the module docstring).

        The couplings' forces are left in ``self._mu``, the rigid ones in ``data.lambda_c``.
        """
        rows = self.constraints.coupling_rows
        assert rows is not None
        C = rows.jacobian(q, self._C)
        kp, kd = self._pd
        c = -rows.drift(q, v) - kd * C.dot(v) - kp * rows.residual(q)
        a0 = self._rigid(q, v, tau)
        s = self._probe
        G = np.empty((C.shape[1], C.shape[0]))
        for i in range(C.shape[0]):
            G[:, i] = (self._rigid(q, v, tau + s * C[i]) - a0) / s
        CG = C.dot(G)
        b = c - C.dot(a0)
        if CG.shape == (1, 1):  # one coupling: numerics.lstsq's rule, without its SVD
            mu = b / CG[0] if CG[0, 0] != 0.0 else np.zeros(1)
        else:
            mu = numerics.lstsq(CG, b, 1e-12)
        self._mu = mu
        self._probe = max(float(np.abs(mu).max()), 1e-6)
        return self._rigid(q, v, tau + C.T.dot(mu))

    def _generalized(
        self, t: float, q: np.ndarray, v: np.ndarray, tau_fn: TorqueFn | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Actuator efforts and their generalized force (passive forces excluded)."""
        if tau_fn is None:
            return self._zero_tau, self._zero_nv
        tau_a = tau_fn(t, q, v)
        if type(tau_a) is not np.ndarray or tau_a.dtype != np.float64:
            tau_a = np.asarray(tau_a, dtype=float)
        if tau_a.shape != self._zero_tau.shape:
            tau_a = tau_a.reshape(-1)
            if tau_a.size != self.actuation.n:
                raise ValueError(
                    f"the torque function returned {tau_a.size} values for "
                    f"{self.actuation.n} actuators"
                )
        gen = np.zeros(self.model.nv)
        gen[self._v_index] = tau_a if self._gains is None else self._gains * tau_a
        return tau_a, gen

    def passive_forces(self, q: np.ndarray, v: np.ndarray) -> np.ndarray | None:
        """Generalized forces (nv,) of everything but the actuators and the closures.

        The non-actuator force terms of the dynamics evaluation (:class:`PassiveForces`:
        springs, dampers, friction; ``None`` when there are none), as the bare Euler loop and
        :meth:`step` need them (``_forces`` also books their power).

        Args:
            q: Configuration (nq,).
            v: Velocity (nv,).

        Returns:
            The forces [N m or N], or ``None``.

        """
        if self.passive is None:
            return None
        return self.passive.force(q, v)

    def _forces(
        self, t: float, q: np.ndarray, v: np.ndarray, tau_fn: TorqueFn | None
    ) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Actuator efforts, generalized force, actuator power [W], dissipated power [W]."""
        tau_a, gen = self._generalized(t, q, v, tau_fn)
        p_act = 0.0 if tau_fn is None else float(gen @ v)
        if self.passive is None:
            return tau_a, gen, p_act, 0.0
        f, p_diss = self.passive.evaluate(q, v)
        return tau_a, gen + f, p_act, p_diss

    # ------------------------------------------------------------------ stepping

    def _stages(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        h: float,
        tab: Tableau,
        tau_fn: TorqueFn | None,
        first: Evaluation,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Stages of an explicit Runge-Kutta step in the exponential chart centred at ``q``.

        Returns:
            Chart velocities ``K`` (s, nv), accelerations ``A`` (s, nv), actuator and dissipated
            powers ``P`` (s, 2), the last stage's configuration and actuator efforts.

        """
        model = self.model
        s = tab.stages
        K = np.empty((s, model.nv))
        A = np.empty((s, model.nv))
        P = np.zeros((s, 2))
        K[0], A[0], P[0] = v, first.a, (first.p_act, first.p_fric)
        qi, tau_a = q, first.tau
        ha = h * tab.a
        # per-stage Python overhead matters (a stage costs little more than one dynamics
        # evaluation): local names, and no force evaluation for a run without forces
        integrate, accel = pin.integrate, self._accel
        ddiff = pin.dDifference if self._chart else None
        forces = None if tau_fn is None and self.passive is None else self._forces
        zero = self._zero_nv
        # (x[:i].T.dot(c) is the cheapest small linear combination of rows in numpy)
        for i in range(1, s):
            row = ha[i, :i]
            qi = integrate(model, q, K[:i].T.dot(row))
            vi = v + A[:i].T.dot(row)
            if forces is None:
                A[i] = accel(qi, vi, zero)
            else:
                tau_a, g, pa, pf = forces(t + tab.c[i] * h, qi, vi, tau_fn)
                A[i] = accel(qi, vi, g)
                P[i] = pa, pf
            K[i] = vi if ddiff is None else ddiff(model, q, qi, _ARG1).dot(vi)
        return K, A, P, qi, tau_a

    def _evaluate(
        self, t: float, q: np.ndarray, v: np.ndarray, tau_fn: TorqueFn | None
    ) -> Evaluation:
        tau_a, g, pa, pf = self._forces(t, q, v, tau_fn)
        return Evaluation(self.acceleration(q, v, g), tau_a, pa, pf)

    def _advance(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        dt: float,
        tau_fn: TorqueFn | None,
        first: Evaluation,
    ) -> tuple[np.ndarray, np.ndarray, float, float, Evaluation | None]:
        """Advance the state by ``dt`` from (q, v), whose evaluation ``first`` is known.

        Returns:
            ``q+``, ``v+``, actuator work and dissipated energy over ``dt`` [J], and the evaluation
            at the new state when the scheme computed it (``dopri5``), else ``None``.

        """
        model = self.model
        n = self._substeps
        h = dt / n
        if self.integrator == "euler":
            return self._advance_euler(t, q, v, h, n, tau_fn, first)
        if self.integrator == "rk4":
            w_act = w_fric = 0.0
            hb = h * RK4.b
            for i in range(n):
                if i:
                    first = self._evaluate(t + i * h, q, v, tau_fn)
                K, A, P, _, _ = self._stages(t + i * h, q, v, h, RK4, tau_fn, first)
                w = P.T.dot(hb)
                w_act += float(w[0])
                w_fric += float(w[1])
                q, v = pin.integrate(model, q, K.T.dot(hb)), v + A.T.dot(hb)
            return q, v, w_act, w_fric, None
        return self._advance_adaptive(t, q, v, dt, tau_fn, first)

    def _advance_euler(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        h: float,
        n: int,
        tau_fn: TorqueFn | None,
        first: Evaluation,
    ) -> tuple[np.ndarray, np.ndarray, float, float, None]:
        """``n`` semi-implicit Euler steps ``h`` from (q, v), whose evaluation is ``first``."""
        model = self.model
        integrate = pin.integrate
        v = v + h * first.a
        q = integrate(model, q, h * v)
        w_act, w_fric = h * first.p_act, h * first.p_fric
        if n == 1:
            return q, v, w_act, w_fric, None
        if tau_fn is None and self.nc and self.passive is None and not self._coupled:
            # the bare loop
            data, prox = self.data, self.prox
            cms, cds = self.constraint_models, self.constraint_datas
            dynamics, zero = pin.constraintDynamics, self._zero_nv
            for _ in range(n - 1):
                v = v + h * dynamics(model, data, q, v, zero, cms, cds, prox)
                q = integrate(model, q, h * v)
            return q, v, w_act, w_fric, None
        accel, forces = self._accel, self._forces
        for i in range(1, n):
            _, g, p_a, p_f = forces(t + i * h, q, v, tau_fn)
            v = v + h * accel(q, v, g)
            q = integrate(model, q, h * v)
            w_act += h * p_a
            w_fric += h * p_f
        return q, v, w_act, w_fric, None

    def _advance_adaptive(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        dt: float,
        tau_fn: TorqueFn | None,
        first: Evaluation,
    ) -> tuple[np.ndarray, np.ndarray, float, float, Evaluation]:
        """Dormand-Prince 5(4) substeps with error control from ``t`` to ``t + dt``."""
        model = self.model
        tab = DOPRI5
        t_end = t + dt
        w_act = w_fric = 0.0
        tries = 0
        while t_end - t > 1e-12 * dt:
            tries += 1
            if tries > self.max_substeps:
                raise IntegrationError(
                    f"more than {self.max_substeps} substeps to advance one output step at "
                    f"t = {t:.9g} s (step {self._h:.3g} s): the state is stiff or blowing up; "
                    "check the model and the efforts, or use a shorter dt",
                    t,
                )
            h = min(self._h, self._h_max, t_end - t)
            K, A, P, q_new, tau_new = self._stages(t, q, v, h, tab, tau_fn, first)
            # first same as last: the last stage is the new state (its evaluation is reused)
            v_new = v + A.T.dot(h * tab.b)
            e_q = K.T.dot((h / self.atol) * tab.e)
            e_v = A.T.dot(h * tab.e) / (
                self.atol + self.rtol * np.maximum(np.abs(v), np.abs(v_new))
            )
            err = float(np.sqrt((e_q @ e_q + e_v @ e_v) / (2 * model.nv)))
            if not np.isfinite(err):
                err = 1e10
            fac = min(5.0, 0.9 * err**-0.2) if err > 0.0 else 5.0
            if err <= 1.0:
                w = P.T.dot(h * tab.b)
                w_act += float(w[0])
                w_fric += float(w[1])
                t += h
                q, v = q_new, v_new
                first = Evaluation(A[-1], tau_new, float(P[-1, 0]), float(P[-1, 1]))
                self.steps += 1
                # a step shortened to land on t_end says nothing about the next one
                self._h = max(self._h, h * fac) if h < self._h else h * fac
            else:
                self.rejected += 1
                self._h = h * max(0.1, fac)
                if self._h < 1e-12 * dt:
                    raise IntegrationError(f"step size underflow at t = {t:.9g} s", t)
        self._h = min(self._h, self._h_max)
        return q, v, w_act, w_fric, first

    def step(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        dt: float,
        tau: TorqueFn | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Advance a state by one step ``dt`` (with the projection check if ``project``).

        For a control loop: no recording. ``dopri5`` keeps its substep size between calls.
        ``euler`` with ``project`` (the control-loop step, :mod:`solvers.control_step`) ends
        every step on the closures (residual within ``project_tol``) by one Newton correction
        with the factorization of the dynamics evaluated at the new state, which the next call
        reuses when given the state this one returned; it costs less than twice a raw Euler
        step (``bench/dynamics.py``). With joint couplings the step is the general one. The
        other integrators check the residual after the step
        and project above ``project_tol``.

        Args:
            t: Time [s].
            q: Configuration (nq,).
            v: Velocity (nv,).
            dt: Step [s].
            tau: Actuator efforts ``tau(t, q, v) -> (n_a,)`` (default: zero).

        Returns:
            The state ``(q, v)`` at ``t + dt``.

        Raises:
            IntegrationError: The closures could not be restored, or the step size of
                ``dopri5`` underflowed.

        """
        if self.integrator == "euler" and self.project and self.nc and not self._coupled:
            # (the couplings' forces are not in pin.constraintDynamics' factorization: a coupled
            # robot takes the general step below, projected when its residual exceeds the
            # tolerance)
            if self._control is None:
                self._control = ProjectedEulerStep(self)
            return self._control.step(t, q, v, dt, tau)
        if self.integrator == "euler":
            if self._auto_gains and dt != self._gains_step:
                self._euler_gains(dt)
            g = self._generalized(t, q, v, tau)[1]
            f = self.passive_forces(q, v)
            v = v + dt * self._accel(q, v, g if f is None else g + f)
            q = pin.integrate(self.model, q, dt * v)
        else:
            self._substeps = 1
            if self._h <= 0.0:
                self._h = dt
            self._h_max = dt
            q, v, _, _, _ = self._advance(t, q, v, dt, tau, self._evaluate(t, q, v, tau))
        if self.project and self.nc:
            r = self.constraints.residual(self._kin, q)
            if float(np.max(np.abs(r))) > self.project_tol:
                try:
                    q, v = self.project_state(q, v)
                except IntegrationError as err:
                    raise IntegrationError(f"t = {t + dt:.6g} s: {err}", t + dt) from None
        return q, v

    def closure_forces(self, kin: pin.Data, lambda_c: np.ndarray) -> np.ndarray:
        """Pinocchio's constraint forces in the convention of the rows (:mod:`solvers.closure`).

        3D point: ``R_c1 lambda`` (world-frame force on ``joint1``'s body); 6D weld:
        ``-lambda`` (wrench on ``joint2``'s body in its contact frame, exact at closure).

        Args:
            kin: Data whose joint placements are those of the current configuration.
            lambda_c: ``data.lambda_c`` (nc,) of ``pin.constraintDynamics``.

        Returns:
            The multipliers (nc,) [N, N m], as returned by the inverse dynamics (with couplings,
            their forces at the last evaluation follow the rigid closures').

        """
        if self._coupled:
            n = self.constraints.nc
            rigid = self._rigid_forces(kin, np.asarray(lambda_c, dtype=float)[:n])
            return np.concatenate([rigid, self._mu])
        return self._rigid_forces(kin, lambda_c)

    def _rigid_forces(self, kin: pin.Data, lambda_c: np.ndarray) -> np.ndarray:
        out = -np.asarray(lambda_c, dtype=float)
        if self._pt_rows.size:
            R = np.array([kin.oMi[j].rotation for j in self._pt_joint1]) @ self._pt_rot1
            idx = self._pt_rows[:, None] + np.arange(3)
            out[idx] = np.einsum("kij,kj->ki", R, lambda_c[idx])
        return out

    def project_state(
        self, q: np.ndarray, v: np.ndarray, tol: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Project a state onto the closures (:func:`solvers.projection.project_state`).

        Args:
            q: Configuration (nq,).
            v: Velocity (nv,).
            tol: Closure residual to reach [m or rad] (default: aim at ``project_tol / 100``,
                accept ``project_tol``).

        Returns:
            The projected ``(q, v)``.

        Raises:
            IntegrationError: The closures cannot be restored.

        """
        if not self.nc:
            return q, v
        aim = self.project_tol * 1e-2 if tol is None else tol
        accept = self.project_tol if tol is None else tol
        try:
            return project_state(self.model, self._kin, self.constraints, q, v, aim, accept)
        except ProjectionError as err:
            raise IntegrationError(str(err), float("nan")) from None

    def simulate(
        self,
        q0: np.ndarray,
        v0: np.ndarray,
        duration: float,
        dt: float,
        tau: TorqueFn | None = None,
        record_every: int = 1,
        t0: float = 0.0,
        step: float | None = None,
    ) -> ForwardResult:
        """Integrate the dynamics from ``(q0, v0)`` for ``duration`` seconds.

        Args:
            q0: Initial configuration (nq,), assembled (projected first if ``project``).
            v0: Initial velocity (nv,), consistent with the closures (projected first if
                ``project``).
            duration: Simulated time [s], rounded to a whole number of output steps.
            dt: Output step [s]: the closures are checked and a sample may be recorded once
                per output step.
            tau: Actuator efforts ``tau(t, q, v) -> (n_a,)`` (default: zero).
            record_every: Record one sample every ``record_every`` output steps (first and
                last states always recorded).
            t0: Initial time [s].
            step: Integration step [s] of ``euler`` and ``rk4`` (``dt`` is divided into a
                whole number of steps, the nearest to ``dt / step``), largest substep of
                ``dopri5`` (default: ``dt``).

        Returns:
            The recorded time series.

        Raises:
            ValueError: Non-positive ``dt``, ``duration``, ``step`` or ``record_every``.
            IntegrationError: The state became non-finite or the closures could not be restored.

        """
        if not (dt > 0.0 and duration > 0.0 and record_every >= 1):
            raise ValueError("dt, duration and record_every must be positive")
        h = dt if step is None else float(step)
        if not h > 0.0:
            raise ValueError(f"step must be positive, got {step}")
        model = self.model
        n_steps = int(round(duration / dt))
        n_rec = n_steps // record_every + 1 + (1 if n_steps % record_every else 0)
        rec = Recorder(n_rec, model.nq, model.nv, self.actuation.n, self.nc)
        self._substeps = 1 if self.integrator == "dopri5" else max(1, int(round(dt / h)))
        self._h_max = min(h, dt)
        if self.integrator == "euler":
            self._euler_gains(dt / self._substeps)
        q = np.array(q0, dtype=float)
        v = np.array(v0, dtype=float)
        if self.project:
            q, v = self.project_state(q, v)
        self._h = self._h_max
        self.steps = self.rejected = 0
        w_act = w_fric = 0.0
        projections = 0
        t = t0
        ev: Evaluation | None = None
        residual: float | None = None  # closure residual at q, when known (kinematics in _kin)
        for k in range(n_steps + 1):
            if ev is None:
                ev = self._evaluate(t, q, v, tau)
            if not math.isfinite(float(ev.a @ ev.a)):
                raise IntegrationError(f"non-finite acceleration at t = {t:.6g} s", t)
            speed = float(np.max(np.abs(v), initial=0.0))
            if not speed <= self.max_speed:
                j = int(np.argmax(np.abs(v))) if np.all(np.isfinite(v)) else 0
                raise IntegrationError(
                    f"the state blows up: joint speed {speed:.3g} (velocity coordinate {j}) "
                    f"exceeds {self.max_speed:.3g} rad/s or m/s at t = {t:.6g} s; use a shorter "
                    "dt or the adaptive integrator, and check the efforts and the model",
                    t,
                )
            if k % record_every == 0 or k == n_steps:
                rec.add(self, t, q, v, ev, w_act, w_fric, residual)
            if k == n_steps:
                break
            q, v, dw_a, dw_f, ev = self._advance(t, q, v, dt, tau, ev)
            w_act += dw_a
            w_fric += dw_f
            t = t0 + (k + 1) * dt
            residual = None
            if self.project and self.nc and (k + 1) % self.project_every == 0:
                residual = float(np.max(np.abs(self.constraints.residual(self._kin, q))))
                if residual > self.project_tol:
                    try:
                        q, v = self.project_state(q, v)
                    except IntegrationError as err:
                        raise IntegrationError(f"t = {t:.6g} s: {err}", t) from None
                    projections += 1
                    ev = residual = None
        out = rec.result()
        out.projections = projections
        out.extras["substeps"] = float(
            self.steps if self.integrator == "dopri5" else n_steps * self._substeps
        )
        out.extras["rejected"] = float(self.rejected)
        return out


def simulate(
    model: pin.Model,
    constraints: Sequence[pin.RigidConstraintModel],
    q0: np.ndarray,
    v0: np.ndarray,
    duration: float,
    dt: float,
    tau: TorqueFn | None = None,
    actuation: Actuation | None = None,
    record_every: int = 1,
    step: float | None = None,
    **options: object,
) -> ForwardResult:
    """Simulate a constrained mechanism (see :class:`ForwardDynamics` for ``options``).

    Args:
        model: The kinematic tree.
        constraints: Rigid constraint models of the closures.
        q0: Initial configuration (nq,).
        v0: Initial velocity (nv,).
        duration: Simulated time [s].
        dt: Output step [s].
        tau: Actuator efforts ``tau(t, q, v) -> (n_a,)`` (default: zero).
        actuation: Actuated coordinates (needed with ``tau``).
        record_every: Record one sample every ``record_every`` output steps.
        step: Integration step [s] (see :meth:`ForwardDynamics.simulate`; default ``dt``).
        **options: Keyword arguments of :class:`ForwardDynamics`.

    Returns:
        The recorded time series.

    """
    fd = ForwardDynamics(model, constraints, actuation, **options)  # type: ignore[arg-type]
    return fd.simulate(q0, v0, duration, dt, tau, record_every, step=step)
