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

The constraints are a :class:`~solvers.constraints.ConstraintSet`. Without couplings the
accelerations are Pinocchio's ``pin.constraintDynamics`` on the fewest 3D points and 6D welds
with the set's closures (:meth:`solvers.closure.ClosureRows.pin_closures`: a planar hinge is one
point, a spatial hinge two): one call per evaluation. Joint couplings (:mod:`solvers.coupling`),
which ``pin.constraintDynamics`` cannot take (it accepts 3D / 6D rigid constraints only and
rejects mimic joints), act through their forces, found with the factorization of that one call
(:class:`solvers.coupled_dynamics.CoupledDynamics`: one Pinocchio call and a few
back-substitutions, the same Baumgarte gains and proximal treatment of redundant rows),
whatever the number of couplings.

Units: SI. Pinocchio's constraint forces (``data.lambda_c``, for ``J =
pin.getConstraintsJacobian``) are, per constraint model, the force (3D) or wrench (6D) on
``joint1``'s body at its contact frame, expressed in that frame. The recorded
``constraint_forces`` are the multipliers of the set's rows, converted to the convention of
:mod:`solvers.closure`
and of the inverse dynamics (:func:`ForwardDynamics.closure_forces`): 3D, the world-frame force
[N] on ``joint1``'s body; 6D, the wrench [N, N m] on ``joint2``'s body in its contact frame.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from solvers import numerics
from solvers.actuation import Actuation, TorqueFn
from solvers.closure import Closure, ClosureRows
from solvers.conditioning import (
    LEAVE,
    NEAR_SINGULAR,
    THROUGH,
    Conditioning,
    Passages,
    SingularityEvent,
    reach,
)
from solvers.constraints import ConstraintSet, constraint_set
from solvers.control_step import ProjectedEulerStep
from solvers.coupled_dynamics import CoupledDynamics
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
    "SingularityEvent",
    "TorqueFn",
    "simulate",
]

_ARG1 = pin.ArgumentPosition.ARG1
_NO_Q = np.zeros(0)  # (closure rows need no configuration beyond the kinematics in the data)
_POINT = pin.ContactType.CONTACT_3D

COLLAPSE = 0.25
"""A ``dopri5`` substep over which the conditioning ``kappa`` falls below this fraction of its
value at the start is rejected and shortened (see :meth:`ForwardDynamics.simulate`)."""

CHECK_PERIOD = 8
"""Largest number of output steps of ``euler`` and ``rk4`` between two checks of the
conditioning of the closure forces in :meth:`ForwardDynamics.simulate`; fewer while it falls,
every step near a singularity (:meth:`ForwardDynamics._observe`)."""

ADAPTIVE_CHECK_PERIOD = 32
"""The same for the substeps of ``dopri5``, which also checks at once when the proximal solver
needs more iterations than at the last check (the free proxy between checks,
:meth:`ForwardDynamics._due`; a check costs about one of the six evaluations of a substep)."""

STEP_CHECK_PERIOD = 32
"""The same for the fixed steps of :meth:`ForwardDynamics.step` (a control loop, where a check,
about one dynamics evaluation, must not double the cost of a step)."""

WATCH = 10.0 * LEAVE * NEAR_SINGULAR
"""Below this conditioning it is checked at every step."""


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
        length_scale: The robot's length [m], the weight of the welds' angular rows in the
            conditioning figure (:mod:`solvers.conditioning`; default: the largest distance of
            a joint from the origin at the neutral configuration, at least 0.1 m).
        closure_rank: Generic rank of the rigid closures (default: their rank at the first
            state evaluated, by the cut-off rule at :data:`solvers.conditioning.SINGULAR`).
        datas: Two Pinocchio datas of ``model`` to compute in (the dynamics', the
            kinematics'), kept by the caller between runs (their size grows like nv^3);
            default: new ones.

    Attributes:
        conditioning: The conditioning ``kappa`` at the last check (1 without rigid closures);
            the passages near or through singularities since the last :meth:`simulate` (or
            since construction, for :meth:`step`) are :attr:`events`.

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
        datas: tuple[pin.Data, pin.Data] | None = None,
        length_scale: float | None = None,
        closure_rank: int | None = None,
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
        if datas is None:
            datas = (model.createData(), model.createData())
        self.data = datas[0]
        self._kin = datas[1]  # kinematics for residuals, energies, projections
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
        # Pinocchio's constraint models: the fewest points and welds with the set's closures
        cr = cs.closure_rows
        pin_rows = ClosureRows(model, cr.pin_closures() if cr is not None else [], reduce=False)
        self._pin_rows = pin_rows
        base = pin_rows.base_models()
        for c in base:
            c.setBaumgarteCorrectorParameters(corrector)
            self.constraint_models.append(c)
            self.constraint_datas.append(c.createData())
        self.nc = cs.n  # constraint rows: closures, then couplings
        self.n_pin = pin_rows.n  # Pinocchio's constraint rows
        # (the set's closures are those points and welds: Pinocchio's forces as they are)
        self._same_rows = cr is None or (cr.identity and pin_rows.n == cr.n)
        self._coupled = cs.nk > 0
        self._pd = (float(gains[0]), float(gains[1]))
        # conversion of Pinocchio's multipliers to the rows' convention (see the module doc)
        pts = [k for k, cm in enumerate(self.constraint_models) if cm.type == _POINT]
        offsets = pin_rows.base_offsets
        self._pt_rows = np.array([offsets[k] for k in pts], dtype=int)
        self._pt_joint1 = [self.constraint_models[k].joint1_id for k in pts]
        self._pt_rot1 = np.array(
            [self.constraint_models[k].joint1_placement.rotation for k in pts]
        ).reshape(-1, 3, 3)
        self.prox = pin.ProximalSettings(prox_accuracy, prox_accuracy, prox_mu, prox_max_iter)
        self._max_iter = int(prox_max_iter)
        if cs.nc:
            pin.initConstraintDynamics(
                model, self.data, self.constraint_models, self.constraint_datas
            )
        # with couplings: their forces from the factorization of one Pinocchio call
        self._schur = (
            CoupledDynamics(
                model,
                cs.coupling_rows,
                self.constraint_models,
                self.constraint_datas,
                self.data,
                self.prox,
                self._pd,
            )
            if cs.coupling_rows is not None
            else None
        )
        self._rigid = self._schur is None and self.nc > 0  # Pinocchio's call alone evaluates
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
        # conditioning of the closure forces (solvers.conditioning) and the singular passages
        if length_scale is None:
            length_scale = reach(model, self._kin, pin.neutral(model))
        self.conditioner = Conditioning(list(self.constraint_models), length_scale, closure_rank)
        self.passages = Passages()
        self.conditioning = 1.0  # kappa at the last check
        self._watch = len(self.constraint_models) > 0
        self._cond_t = math.nan  # time of the last check [s]
        self._cond_rate = 0.0  # d kappa / dt between the last two checks [1/s]
        self._h_cond = math.inf  # dopri5 substep limit from the conditioning [s]
        self._cond_due = -math.inf  # time from which the next check is due [s]
        self._since_check = 0  # steps since the last check
        self._iter_seen = 0  # proximal iterations of the state last checked
        self._cond_log: tuple[array, array] | None = None  # (t, kappa) of simulate's checks
        self._eval_id = 0  # dynamics evaluations made (their factorization in self.data)
        self._eig_id = -1  # the evaluation whose kappa a refinement computed
        self._eig_kappa = 1.0

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
        if self._schur is not None:
            self._schur.gains = self._pd
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
        if self._rigid:  # (:meth:`_solve` inline: one Python call less per evaluation)
            a = pin.constraintDynamics(
                self.model,
                self.data,
                q,
                v,
                tau,
                self.constraint_models,
                self.constraint_datas,
                self.prox,
            )
            self._eval_id += 1
            if self.prox.iter >= self._max_iter:
                return self._capped(a)
            return a
        if self._schur is not None:
            return self._schur.acceleration(q, v, tau)
        return pin.aba(self.model, self.data, q, v, tau)

    def _solve(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """``pin.constraintDynamics``, made exact where its proximal iterations stop short.

        The proximal solver's iterations converge like ``(mu / (mu + g_min))^k`` (``g_min``: the
        smallest eigenvalue of the Delassus matrix): near a singularity of the closures
        ``g_min`` falls below ``mu`` and the iteration cap leaves the closures' acceleration
        equations unsolved (a closure acceleration error of up to 1e2 m/s^2 on the falling
        Delta), which the error control cannot see. Such an evaluation is finished by
        :meth:`_refine` (:meth:`_capped`).
        """
        a = pin.constraintDynamics(
            self.model,
            self.data,
            q,
            v,
            tau,
            self.constraint_models,
            self.constraint_datas,
            self.prox,
        )
        self._eval_id += 1
        if self.prox.iter >= self._max_iter:
            return self._capped(a)
        return a

    def _capped(self, a: np.ndarray) -> np.ndarray:
        """An evaluation whose proximal iterations hit their cap: refined where unsolved.

        Iteration ``k`` of Pinocchio's proximal solver solves ``(G + mu I) x_k = b + mu
        x_{k-1}`` for the closure forces (``G = J M^-1 J^T``, ``b`` the closures' desired
        acceleration), and the acceleration from the same solve: the closures' acceleration
        residual it leaves is ``J a - b = mu (x_{k-1} - x_k)``, whose largest component is
        ``mu`` times the ``relative_residual`` Pinocchio reports. Within the solver's absolute
        accuracy the acceleration is solved (redundant closures, the two points of a hinge or
        a planar loop's out-of-plane rows, make the iterations hit their cap while their forces
        drift by round-off in the closures' null space): nothing to do, no Jacobian needed.
        Else :meth:`_refine`, which measures the residual itself.
        """
        prox = self.prox
        if prox.mu * prox.relative_residual <= prox.absolute_accuracy:
            return a
        return self._refine(a)

    def _refine(self, a: np.ndarray) -> np.ndarray:
        """Finish an evaluation whose proximal iterations hit their cap (exact least squares).

        With ``b`` the closures' desired acceleration (``data.primal_rhs_contact``) and
        ``r = J a - b`` what the iterations left, the exact forces are ``lambda + delta`` with
        ``G delta = -r`` (``G = J M^-1 J^T``), solved in the eigenbasis of ``S G S``
        (:class:`~solvers.conditioning.Conditioning`, eigenvalues ``g_i``) with the gains
        ``g_i / (g_i^2 + g_c^2)`` instead of ``1 / g_i``, ``g_c = THROUGH^2 g_max``
        (:data:`~solvers.conditioning.THROUGH`): exact to ``(THROUGH / kappa)^4`` relative
        (1e-4 at the threshold of near passages, ``kappa`` = 1e-4), and a force along a
        direction the closures lose (below ``THROUGH``) is let go smoothly instead of growing
        like ``1 / kappa^2`` beyond what an error control can follow (a cut-off would make the
        acceleration jump). The acceleration changes by ``M^-1 J^T delta``, one solve with the
        factorization: ``K^-1 [(G + mu I) delta; 0]``. Also sets the conditioning of this
        evaluation.

        Nothing is done when ``r`` is within the proximal solver's accuracy (absolute, plus
        relative to ``|J a| + |b|``): redundant closures make it hit its cap while their
        forces drift in the null space of ``J``, the acceleration solved.

        Args:
            a: The acceleration the proximal iterations returned (nv,).

        Returns:
            The acceleration (nv,); ``data.lambda_c`` updated.

        """
        data, cond, prox = self.data, self.conditioner, self.prox
        nc = cond.nc  # the rows of Pinocchio's constraint models (the KKT system)
        J = pin.getConstraintsJacobian(
            self.model, data, self.constraint_models, self.constraint_datas
        )
        Ja, b = J.dot(a), data.primal_rhs_contact
        r = Ja - b
        scale = float(np.max(np.abs(Ja), initial=0.0) + np.max(np.abs(b), initial=0.0))
        if float(np.max(np.abs(r), initial=0.0)) <= (
            prox.absolute_accuracy + prox.relative_accuracy * scale
        ):
            # solved after all: the cap was hit by the forces of redundant closures (the two
            # points of a hinge), which drift in the closures' null space without effect
            return a
        G_mu, G = cond.delassus(data, prox.mu)
        g, V = np.linalg.eigh(G)
        self._eig_id, self._eig_kappa = self._eval_id, cond.kappa(g)
        if not (np.all(np.isfinite(r)) and g[-1] > 0.0):
            return a
        g_c = THROUGH * THROUGH * g[-1]
        gain = g / (g * g + g_c * g_c)  # 1 / g, filtered smoothly below g_c
        delta = cond.scale * V.dot(gain * V.T.dot(-cond.scale * r))
        rhs = np.zeros(nc + self.model.nv)
        rhs[:nc] = G_mu.dot(delta)
        da = data.constraint_chol.solve(rhs)[nc:]
        lam = data.lambda_c
        lam += delta
        return a + da

    # ------------------------------------------------------------------ conditioning

    def reference_rank(self, q: np.ndarray) -> int:
        """Take the rank of the rigid closures at ``q`` as their generic rank.

        The conditioning (:mod:`solvers.conditioning`) is judged on the closures' ``r``-th
        singular value, ``r`` their generic rank: by default the rank at the first state
        evaluated, which is too low for a motion that starts at a singularity. A regular
        configuration of the mechanism (its home) gives it.

        Args:
            q: A regular configuration (nq,), assembled.

        Returns:
            The rank (0 without rigid closures).

        """
        if not self._watch:
            return 0
        zero = self._zero_nv
        self.conditioner.rank = None
        self._solve(np.asarray(q, dtype=float), zero, zero)
        self.conditioner(self.data, self.prox.mu)  # sets the rank
        return int(self.conditioner.rank or 0)

    @property
    def events(self) -> list[SingularityEvent]:
        """Passages near or through singularities of the closures, in time order.

        (:class:`~solvers.conditioning.SingularityEvent`; since the last :meth:`simulate`, or
        since construction for :meth:`step`.)
        """
        return self.passages.events

    def _kappa(self, data: pin.Data | None = None) -> float:
        """The conditioning of the last evaluation made with ``data`` (default ``self.data``)."""
        if data is None:
            if self._eig_id == self._eval_id:
                return self._eig_kappa
            data = self.data
        return self.conditioner(data, self.prox.mu)

    def _observe(self, t: float, kappa: float) -> None:
        """Record the conditioning ``kappa`` of the state at ``t`` [s] and plan the next check.

        Updates the passages, the rate of ``kappa`` since the last check, and the time the
        next check is due: at once near a singularity (``kappa`` below :data:`WATCH`); while
        ``kappa`` falls, after a quarter of the time its rate would take to bring it to
        :data:`~solvers.conditioning.NEAR_SINGULAR`; else after :data:`CHECK_PERIOD` steps, or
        sooner (:meth:`_due`). The proximal iterations of the last evaluation (that of the state
        observed) are the reference of :meth:`_due`'s proxy.
        """
        if t > self._cond_t:
            self._cond_rate = (kappa - self.conditioning) / (t - self._cond_t)
        elif not t == self._cond_t:  # the first check, or a caller stepping back in time
            self._cond_rate = 0.0
        self._cond_t = t
        self.conditioning = kappa
        self.passages.observe(t, kappa)
        if self._cond_log is not None:
            self._cond_log[0].append(t)
            self._cond_log[1].append(kappa)
        self._since_check = 0
        self._iter_seen = self.prox.iter
        rate = self._cond_rate
        if kappa < WATCH:
            self._cond_due = t
        elif rate < 0.0:
            self._cond_due = t + 0.25 * (kappa - NEAR_SINGULAR) / -rate
        else:
            self._cond_due = math.inf

    def _due(self, t: float, period: int = CHECK_PERIOD) -> bool:
        """Whether a conditioning check is due at ``t`` [s] (counts the steps since the last).

        Due as :meth:`_observe` planned it, after ``period`` steps, or at once when the last
        evaluation (the state at ``t``) took more proximal iterations than the state last
        checked: a free proxy of ``kappa`` between checks. Pinocchio's iterations contract the
        closures' force error by ``mu / (mu + g)`` along each eigenvalue ``g`` of their
        Delassus matrix, the closures' ``r``-th (``kappa^2 g_max``) the slowest, and stop at
        the solver's accuracy: their number, about ``log(1 / accuracy) / log(1 + g_r / mu)``,
        grows by one each time ``g_r`` falls by a large factor on the way to a singularity (the
        Delta falling under ``dopri5``'s gains: 3 to 4 near ``kappa`` = 0.1, 5 near 4e-3, 9
        near 8e-4, the cap of 30 near 1e-4), before ``kappa`` reaches :data:`WATCH`. It may
        also grow with the forces (a check more, never one less). Under the Euler step's stiff
        gains (``0.5 / h``) it stays at 3 down to ``kappa`` = 6e-4 on the same fall: the fixed
        steps keep their short periods (:data:`CHECK_PERIOD`, :data:`STEP_CHECK_PERIOD`), and
        the Euler steps of :meth:`step` go without the proxy (a read of the solver's settings
        per step for nothing).
        """
        self._since_check += 1
        return (
            t >= self._cond_due or self._since_check >= period or self.prox.iter > self._iter_seen
        )

    def _reset_conditioning(self) -> None:
        self.passages.reset()
        self.conditioning = 1.0
        self._cond_t = math.nan
        self._cond_rate = 0.0
        self._cond_due = -math.inf
        self._since_check = 0
        self._iter_seen = 0
        self._h_cond = math.inf

    def _scheduled_check(self, t: float, data: pin.Data) -> None:
        """The conditioning check of a fixed step of :meth:`step` at ``t`` [s], when due.

        As :meth:`_due` decides, at most :data:`STEP_CHECK_PERIOD` steps apart.
        """
        if self._due(t, STEP_CHECK_PERIOD):
            self._observe(t, self._kappa(data))

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
            dynamics, zero, cap = pin.constraintDynamics, self._zero_nv, self._max_iter
            for _ in range(n - 1):
                a = dynamics(model, data, q, v, zero, cms, cds, prox)
                if prox.iter >= cap:  # (see _solve)
                    self._eval_id += 1
                    a = self._capped(a)
                v = v + h * a
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
        """Dormand-Prince 5(4) substeps with error control from ``t`` to ``t + dt``.

        With rigid closures, the conditioning ``kappa`` of the closure forces
        (:mod:`solvers.conditioning`) is checked at the end of every substep the error control
        accepts, where the last stage left its factorization: a substep over which ``kappa``
        falls below :data:`COLLAPSE` times its value at the start is rejected and shortened
        (to where the chord through the two values halves it), and while ``kappa`` falls the
        next substep goes at most half the way its current rate would take to bring it to
        zero. Approaching a singularity the substeps thus shrink with ``kappa`` and sample the
        bottom of the passage, where the closure forces peak like ``1 / kappa^2``, instead of
        stepping over it; below :data:`~solvers.conditioning.THROUGH` (through the
        singularity, where the force along the lost direction is dropped) only the error
        control decides.
        """
        model = self.model
        tab = DOPRI5
        t_end = t + dt
        w_act = w_fric = 0.0
        tries = 0
        watch = self._watch
        kappa = 1.0
        while t_end - t > 1e-12 * dt:
            tries += 1
            if tries > self.max_substeps:
                raise IntegrationError(
                    f"more than {self.max_substeps} substeps to advance one output step at "
                    f"t = {t:.9g} s (step {self._h:.3g} s): the state is stiff or blowing up; "
                    "check the model and the efforts, or use a shorter dt",
                    t,
                )
            h = min(self._h, self._h_max, t_end - t, self._h_cond)
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
            accept = err <= 1.0
            check = accept and watch and self._due(t + h, ADAPTIVE_CHECK_PERIOD)
            if check:
                kappa = self._kappa()  # at q_new: the last stage's evaluation
                k0 = self.conditioning
                if kappa < COLLAPSE * k0 and k0 > THROUGH and self._cond_t == t:
                    accept = False  # kappa collapsed within the step: resolve the passage
                    fac = 0.5 * k0 / (k0 - kappa)
            if accept:
                w = P.T.dot(h * tab.b)
                w_act += float(w[0])
                w_fric += float(w[1])
                t += h
                q, v = q_new, v_new
                first = Evaluation(A[-1], tau_new, float(P[-1, 0]), float(P[-1, 1]))
                self.steps += 1
                # a step shortened to land on t_end says nothing about the next one
                self._h = max(self._h, h * fac) if h < self._h else h * fac
                if check:
                    self._observe(t, kappa)
                    rate = self._cond_rate
                    falling = rate < 0.0 and kappa > THROUGH
                    self._h_cond = 0.5 * kappa / -rate if falling else math.inf
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
        step (``bench/dynamics.py``); joint couplings are corrected with the closures, with the
        same factorization. The other integrators check the residual after the step
        and project above ``project_tol``.

        Args:
            t: Time [s].
            q: Configuration (nq,).
            v: Velocity (nv,).
            dt: Step [s].
            tau: Actuator efforts ``tau(t, q, v) -> (n_a,)`` (default: zero).

        Returns:
            The state ``(q, v)`` at ``t + dt``.

        Each call checks the conditioning of the closure forces (:mod:`solvers.conditioning`)
        and records the passages near or through singularities in :attr:`events`: ``dopri5``
        at every substep (and it shortens its substeps through a passage, see
        :meth:`simulate`); ``euler`` and ``rk4`` at the state the step starts from (the
        control-loop step: the state it ends at), every :data:`STEP_CHECK_PERIOD` calls, sooner
        when the conditioning falls (``rk4``: or the proximal solver's iterations grow,
        :meth:`_due`), every call near a singularity
        (a passage shorter than ``dt`` is estimated from the samples around it: these steps
        have a fixed size).

        Raises:
            ValueError: ``dt`` not a finite positive number.
            IntegrationError: The closures could not be restored, or the step size of
                ``dopri5`` underflowed.

        """
        if not 0.0 < dt < math.inf:
            raise ValueError(f"dt must be a finite positive number of seconds, got {dt!r}")
        if self.integrator == "euler" and self.project and self.nc:
            if self._control is None:
                self._control = ProjectedEulerStep(self)
            q, v = self._control.step(t, q, v, dt, tau)
            if self._watch:  # (the check inline, without the iteration proxy: see _due)
                self._since_check += 1
                if t + dt >= self._cond_due or self._since_check >= STEP_CHECK_PERIOD:
                    self._observe(t + dt, self._kappa(self._control.data))
            return q, v
        if self.integrator == "euler":
            if self._auto_gains and dt != self._gains_step:
                self._euler_gains(dt)
            g = self._generalized(t, q, v, tau)[1]
            if self.passive is not None:
                g = g + self.passive.force(q, v)
            a = self._accel(q, v, g)
            if self._watch:  # (as above)
                self._since_check += 1
                if t >= self._cond_due or self._since_check >= STEP_CHECK_PERIOD:
                    self._observe(t, self._kappa(self.data))
            v = v + dt * a
            q = pin.integrate(self.model, q, dt * v)
        else:
            self._substeps = 1
            if self._h <= 0.0:
                self._h = dt
            self._h_max = dt
            first = self._evaluate(t, q, v, tau)
            if self._watch:
                self._scheduled_check(t, self.data)
            q, v, _, _, _ = self._advance(t, q, v, dt, tau, first)
        if self.project and self.nc:
            r = self.constraints.residual(self._kin, q)
            if float(np.max(np.abs(r))) > self.project_tol:
                try:
                    q, v = self._project_state(q, v)
                except IntegrationError as err:
                    raise IntegrationError(f"t = {t + dt:.6g} s: {err}", t + dt) from None
        return q, v

    def closure_forces(self, kin: pin.Data, lambda_c: np.ndarray) -> np.ndarray:
        """Pinocchio's constraint forces in the convention of the rows (:mod:`solvers.closure`).

        3D point: ``R_c1 lambda`` (world-frame force on ``joint1``'s body); 6D weld:
        ``-lambda`` (wrench on ``joint2``'s body in its contact frame, exact at closure).

        Pinocchio's constraint models hold every row of the closures (a hinge is two points);
        where the constraint set reduces them (hinges, planar closures), the multipliers of its
        rows are those that apply the same generalized force, ``J_red^T mu = J^T lambda``
        (minimum norm).

        Args:
            kin: Data whose joint placements are those of the current configuration.
            lambda_c: ``data.lambda_c`` (n_pin,) of ``pin.constraintDynamics``.

        Returns:
            The multipliers (n,) [N, N m] of the constraint rows, as returned by the inverse
            dynamics (with couplings, their forces at the last evaluation follow the closures').

        """
        lam = np.asarray(lambda_c, dtype=float)[: self.n_pin]
        if self._schur is not None:  # the closures' response to the couplings included
            lam = self._schur.lam
        rigid = self._rigid_forces(kin, lam) if self.n_pin else lam
        if not self._same_rows and self.n_pin:
            pin.computeJointJacobians(self.model, kin)  # (from the placements in kin)
            self._pin_rows.calc(kin)
            J_pin = self._pin_rows.jacobian(kin)
            J_red = self.constraints.closures.jacobian_at(kin, _NO_Q)
            rigid = numerics.lstsq(J_red.T, J_pin.T @ rigid, 1e-10)
        if self._schur is not None:
            return np.concatenate([rigid, self._schur.mu])
        return rigid

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
        return self._project_state(q, v, tol)

    def _project_state(
        self, q: np.ndarray, v: np.ndarray, tol: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`project_state` as the stepping calls it (a subclass may check the public one)."""
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
            The recorded time series, with the conditioning of the closure forces at each
            sample and the passages near or through singularities (``events``).

        Raises:
            ValueError: Non-positive ``dt``, ``duration``, ``step`` or ``record_every``.
            IntegrationError: The state became non-finite or the closures could not be restored.

        Singular passages: the conditioning ``kappa`` of the closure forces
        (:mod:`solvers.conditioning`) is checked at every ``dopri5`` substep, whose size
        follows it through a passage (:meth:`_advance_adaptive`), and at every output step of
        ``euler`` and ``rk4`` (fixed steps: a passage shorter than ``dt`` can go unseen, and
        the closure forces at its bottom be stepped over). Each passage below
        :data:`~solvers.conditioning.NEAR_SINGULAR` is an event of the result; one below
        :data:`~solvers.conditioning.THROUGH` went through the singularity, and the motion
        after it is not the exact rigid one (``ForwardResult.valid_until``).

        """
        if not (0.0 < dt < math.inf and 0.0 < duration < math.inf and record_every >= 1):
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
            q, v = self._project_state(q, v)
        self._h = self._h_max
        self.steps = self.rejected = 0
        self._reset_conditioning()
        log = (array("d"), array("d"))
        self._cond_log = log if self._watch else None
        try:
            projections = self._run(q, v, t0, dt, n_steps, record_every, tau, rec)
        finally:
            self._cond_log = None
        out = rec.result()
        out.events = list(self.passages.events)
        if self._watch:
            times, kappas = (np.frombuffer(x, dtype=float) for x in log)
            out.conditioning = np.interp(out.t, times, kappas)
        out.projections = projections
        out.extras["substeps"] = float(
            self.steps if self.integrator == "dopri5" else n_steps * self._substeps
        )
        out.extras["rejected"] = float(self.rejected)
        return out

    def _run(
        self,
        q: np.ndarray,
        v: np.ndarray,
        t0: float,
        dt: float,
        n_steps: int,
        record_every: int,
        tau: TorqueFn | None,
        rec: Recorder,
    ) -> int:
        """The output steps of :meth:`simulate`, recorded in ``rec``; returns the projections."""
        watch = self._watch
        w_act = w_fric = 0.0
        projections = 0
        t = t0
        ev: Evaluation | None = None
        residual: float | None = None  # closure residual at q, when known (kinematics in _kin)
        for k in range(n_steps + 1):
            if ev is None:
                ev = self._evaluate(t, q, v, tau)
                if watch and (k == 0 or self._due(t, CHECK_PERIOD)):
                    self._observe(t, self._kappa())
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
                        q, v = self._project_state(q, v)
                    except IntegrationError as err:
                        raise IntegrationError(f"t = {t:.6g} s: {err}", t) from None
                    projections += 1
                    ev = residual = None
        return projections


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
