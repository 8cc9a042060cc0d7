"""Inverse dynamics of a closed-loop mechanism: actuator efforts and closure forces.

Given a state and an acceleration ``(q, v, a)`` consistent with the closures, find actuator
efforts ``tau`` (n_a,) and constraint forces ``lambda`` (n,) with

    M(q) a + h(q, v) = S^T tau + J^T lambda + f_ext,

where ``M a + h`` comes from ``pin.rnea``, ``S`` from the :class:`~solvers.Actuation`
selection, ``J`` is :meth:`ConstraintSet.jacobian <solvers.constraints.ConstraintSet.jacobian>` and
``f_ext`` (nv,) an optional generalized external force (``J_frame^T F`` of a wrench ``F`` applied
to the mechanism, e.g. a machining wrench or a payload's weight).
``lambda`` holds the multipliers of the constraint rows (:mod:`solvers.closure`: for point
rows the world-frame force [N] applied at the contact point of ``joint1``'s body, the opposite
force acting on ``joint2``'s body; for a weld the wrench [N, N m] applied on ``joint2``'s body at
its contact frame, expressed in that frame; :meth:`ConstraintSet.reactions
<solvers.constraints.ConstraintSet.reactions>` gives one force and one moment per closure;
:mod:`solvers.coupling`: a coupling's generalized force [N m or N]). Among all multipliers the
minimum-norm one is returned (the limit of a vanishing regularisation ``eps |lambda|^2``), which
settles redundant closures (an over-constrained loop).

Method (null-space reduction, exact and well conditioned):

1. SVD of ``J``: ``Z`` spans its null space (the motions the closures allow); projecting the
   equation on ``Z`` removes ``lambda``: ``(Z^T S^T) tau = Z^T (M a + h)``;
2. SVD of ``G = Z^T S^T``: its range rows give ``rank(G)`` independent equations on ``tau``;
   its left null space gives consistency conditions that no actuator can influence
   (unactuated internal mobilities, e.g. the spin of a ball-ended bar, or a parallel
   singularity): if ``a`` violates them, :class:`InfeasibleError` is raised with no actuator;
3. non-redundant actuation (``rank(G) = n_a``): ``tau`` is unique and solved directly;
   redundant actuation (``rank(G) < n_a``): ``tau`` minimises ``sum w_i tau_i^2`` under the
   equations and the effort bounds, a QP solved by proxsuite, warm-started from the previous
   sample along a trajectory (the QP object is kept). This includes actuators whose effort the
   closures take entirely (an actuator locked by a weld): they get the least effort;
4. ``lambda`` is the minimum-norm solution of ``J^T lambda = M a + h - S^T tau``.

Fast path (same solution, fewer operations): when the passive columns ``J_p`` of ``J`` have
full row rank with a safe margin (estimated from the norm of ``(J_p J_p^T)^-1`` itself: the
norm of ``(J_p J_p^T)^-1 J_p`` stays moderate when ``J_p`` loses rank, which let the
redundantly actuated four-armed Delta with ball-jointed bars through with antagonistic
efforts of hundreds of N m), ``lambda`` is unique and
solves the passive rows ``J_p^T lambda = b_p`` in the least-squares sense (semi-normal equations
with one refinement step; their residual is the unreachable part of the equation), then
``tau = (b_a - J_a^T lambda) / gains``. The margins guarantee that the general method would find
the same ranks (``J`` of full row rank, ``G`` of rank ``n_a``); otherwise, or when the equation
cannot be satisfied or a bound is violated, the general method runs (and raises). The Jacobian
is :class:`~solvers.constraints.ConstraintSet`'s (Pinocchio's C++ ``getConstraintsJacobian``).

The direct QP over ``(tau, lambda)`` with the full equation as its equality constraint and a
tiny weight on ``lambda`` gives the same solution in the limit, but proxsuite does not converge
on it for the Delta (its spin rows make the equality nearly degenerate); the reduction above
keeps the QP small (``n_a`` variables) and well conditioned (orthonormal equality rows).

Units: SI; ``tau`` in the units of the actuation (joint-side N m or N with unit gains).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from proxsuite import proxqp

from solvers import numerics
from solvers.actuation import Actuation
from solvers.closure import Closure
from solvers.constraints import ConstraintSet, constraint_set
from solvers.coupling import Coupling
from solvers.energy import KineticEnergy
from solvers.sampled import SampledKinematics

_BATCH = 256  # samples per batch of :meth:`InverseDynamics.trajectory`

__all__ = [
    "InconsistentMotionError",
    "InfeasibleError",
    "InverseDynamics",
    "InverseResult",
    "InverseTrajectory",
]


class InfeasibleError(Exception):
    """No actuator efforts within the bounds (or none at all) produce the requested motion.

    Attributes:
        sample: Index of the trajectory sample, or ``None`` for a single state.
        actuator: Index of the actuator at fault (largest bound violation, relative to its
            half range, of the least-loaded solution), or ``None`` when the dynamics equation
            itself cannot be satisfied (motion not dynamically consistent, or singular
            configuration).
        name: Name of that actuator, or ``None``.
        required: Effort that actuator would need [N m or N], or ``None``.
        lower: Its lower bound, or ``None``.
        upper: Its upper bound, or ``None``.
        residual: Residual of the dynamics equation without bounds [N m or N].

    """

    def __init__(
        self,
        message: str,
        sample: int | None = None,
        actuator: int | None = None,
        name: str | None = None,
        required: float | None = None,
        lower: float | None = None,
        upper: float | None = None,
        residual: float = 0.0,
    ) -> None:
        self.sample = sample
        self.actuator = actuator
        self.name = name
        self.required = required
        self.lower = lower
        self.upper = upper
        self.residual = residual
        super().__init__(message)


class InconsistentMotionError(Exception):
    """A trajectory sample does not satisfy the closures (position, velocity or acceleration).

    Attributes:
        sample: Index of the sample.
        what: ``configuration``, ``velocity`` or ``acceleration``.
        closure: Name of the closure with the largest error there.
        error: Largest error component [m, m/s, m/s^2 or rad, rad/s, rad/s^2].

    """

    def __init__(self, message: str, sample: int, what: str, closure: str, error: float) -> None:
        self.sample = sample
        self.what = what
        self.closure = closure
        self.error = error
        super().__init__(message)


@dataclass
class InverseResult:
    """Solution of the inverse dynamics at one state.

    Attributes:
        tau: Actuator efforts (n_a,) [N m or N].
        constraint_forces: Closure multipliers ``lambda`` (nc,) [N, N m] (module convention).
        residual: ``max |M a + h - S^T tau - J^T lambda|`` [N m or N].
        redundancy: Degree of actuation redundancy (``n_a - rank``; 0: ``tau`` is unique).
        iterations: QP iterations (0 when ``tau`` is unique).

    """

    tau: np.ndarray
    constraint_forces: np.ndarray
    residual: float
    redundancy: int
    iterations: int


@dataclass
class InverseTrajectory:
    """Inverse dynamics along a trajectory, one row per sample.

    Attributes:
        tau: Actuator efforts (N, n_a) [N m or N].
        constraint_forces: Closure multipliers (N, nc) [N, N m].
        residual: Dynamics equation residual per sample (N,) [N m or N].
        kinetic: Kinetic energy per sample (N,) [J].
        potential: Gravitational potential energy per sample (N,) [J] (``model.gravity``).

    """

    tau: np.ndarray
    constraint_forces: np.ndarray
    residual: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray


class InverseDynamics:
    """Actuator efforts and closure forces of a closed-loop mechanism (see the module doc).

    Args:
        model: The kinematic tree.
        constraints: The constraint set (closures and couplings), or the closures alone
            (:class:`~solvers.closure.Closure` or CONTACT_3D / CONTACT_6D rigid constraint
            models).
        actuation: Actuated coordinates and gains.
        lower: Lower effort bounds (n_a,) [N m or N] (default: none).
        upper: Upper effort bounds (n_a,) [N m or N] (default: none).
        weights: Weights ``w`` (n_a,) of the effort norm minimised under redundant actuation
            (default: ones; ``1 / effort_limit^2`` balances the actuators' loads).
        rank_tol: Relative tolerance of the ranks (rule of :mod:`solvers.numerics`) of ``J``
            (judged against itself) and of ``Z^T S^T`` (scale: the largest actuation gain, at
            least 1).
        consistency_tol: Largest acceptable residual of the dynamics equation, relative to
            ``max(1, |M a + h|)``.
        eps: Absolute accuracy of the QP [N m or N].
        max_iter: Iteration cap of the QP.
        couplings: Joint couplings (:mod:`solvers.coupling`) when ``constraints`` are closures:
            rows of ``J`` after the closures; their multipliers are generalized forces
            [N m or N] (:mod:`solvers.coupling`).

    Raises:
        ValueError: Inconsistent sizes or bounds.

    """

    def __init__(
        self,
        model: pin.Model,
        constraints: ConstraintSet | Sequence[Closure | pin.RigidConstraintModel],
        actuation: Actuation,
        lower: Sequence[float] | np.ndarray | None = None,
        upper: Sequence[float] | np.ndarray | None = None,
        weights: Sequence[float] | np.ndarray | None = None,
        rank_tol: float = 1e-9,
        consistency_tol: float = 1e-7,
        eps: float = 1e-11,
        max_iter: int = 200,
        couplings: Sequence[Coupling] | ConstraintSet = (),
    ) -> None:
        self.model = model
        self.data = model.createData()
        self._kin = model.createData()
        self.constraints = constraint_set(model, constraints, couplings)
        self.actuation = actuation
        n = actuation.n
        if n == 0:
            raise ValueError("inverse dynamics needs at least one actuator")
        if int(actuation.v_index.max()) >= model.nv:
            raise ValueError(f"actuated velocity index out of range (nv = {model.nv})")
        self.S = actuation.matrix(model.nv)
        self.lower = _vector(lower, n, -np.inf, "lower")
        self.upper = _vector(upper, n, np.inf, "upper")
        if np.any(self.lower > self.upper):
            k = int(np.flatnonzero(self.lower > self.upper)[0])
            raise ValueError(f"actuator {actuation.names[k]}: lower bound above upper bound")
        self.weights = _vector(weights, n, 1.0, "weights")
        if np.any(self.weights <= 0.0):
            raise ValueError("effort weights must be > 0")
        self.rank_tol = rank_tol
        self.consistency_tol = consistency_tol
        self.eps = eps
        self.max_iter = max_iter
        self._g_scale = max(1.0, float(np.max(np.abs(actuation.gains))))
        self._g_tol = rank_tol * self._g_scale
        self._bounded = bool(np.any(np.isfinite(self.lower) | np.isfinite(self.upper)))
        self._qp: proxqp.dense.QP | None = None
        self._qp_rank = -1
        self._va = actuation.v_index
        self._vp = np.setdiff1d(np.arange(model.nv), self._va)
        self._perm = np.concatenate([self._vp, self._va])
        self._gmin = float(np.min(np.abs(actuation.gains)))
        self._sampled: SampledKinematics | None = None
        self._kinetic = KineticEnergy(model)

    @property
    def closure_set(self) -> ConstraintSet:
        """The former name of :attr:`constraints` (kept for one release)."""
        return self.constraints

    def reset(self) -> None:
        """Forget the last solve: the next one starts as a new solver's (no QP warm start).

        A solver kept for many trajectories (its Pinocchio datas and kinematic buffers made
        once) gives, after :meth:`reset`, the efforts a new one gives.
        """
        self._qp = None
        self._qp_rank = -1

    def passive_forces(self, q: np.ndarray, v: np.ndarray) -> np.ndarray | None:
        """Generalized forces (nv,) of everything but the actuators, closures and wrenches.

        The hook for non-actuator force terms of the dynamics equation (``M a + h =
        S^T tau + J^T lambda + f_ext + passive_forces``) the solver would evaluate itself: none
        (``None``); pkdyn passes a robot's springs, dampers and friction
        (:class:`solvers.PassiveForces`, evaluated on the whole trajectory at once) in
        ``f_ext``.

        Args:
            q: Configuration (nq,).
            v: Velocity (nv,).

        Returns:
            The forces [N m or N], or ``None``.

        """
        return None

    def _jacobian(self, q: np.ndarray) -> np.ndarray:
        """Constraint Jacobian (n, nv) at ``q`` (:class:`ConstraintSet`)."""
        return self.constraints.jacobian(self._kin, q)

    # ------------------------------------------------------------------ one state

    def solve(
        self,
        q: np.ndarray,
        v: np.ndarray,
        a: np.ndarray,
        sample: int | None = None,
        f_ext: np.ndarray | None = None,
    ) -> InverseResult:
        """Actuator efforts and closure forces at one state.

        Args:
            q: Configuration (nq,), assembled.
            v: Velocity (nv,), consistent with the closures.
            a: Acceleration (nv,), consistent with the closures (``J a = -Jdot v``).
            sample: Trajectory index reported by :class:`InfeasibleError`.
            f_ext: Generalized external force (nv,) acting on the mechanism [N m or N].

        Returns:
            ``tau``, ``lambda`` and the residual of the dynamics equation.

        Raises:
            InfeasibleError: No efforts within the bounds produce ``a``, or the dynamics
                equation cannot be satisfied at all.

        """
        model = self.model
        b = np.array(pin.rnea(model, self.data, q, v, a))
        if f_ext is not None:
            b -= np.asarray(f_ext, dtype=float).reshape(model.nv)
        f = self.passive_forces(q, v)
        if f is not None:
            b -= f
        J = self._jacobian(q) if self.constraints.n else np.zeros((0, model.nv))
        return self._solve_state(b, J, sample)

    def _solve_state(self, b: np.ndarray, J: np.ndarray, sample: int | None) -> InverseResult:
        """:meth:`solve` given ``b = M a + h - f_ext`` (nv,) and the closure Jacobian (nc, nv)."""
        model = self.model
        cs = self.constraints
        if cs.n:
            fast = self._solve_unique(b, J)
            if fast is not None:
                return fast
            U, s, Vt = np.linalg.svd(J)
            r = numerics.rank_of(s, self.rank_tol)
            Z = Vt[r:].T
        else:
            U, s, Vt, r = np.zeros((0, 0)), np.zeros(0), np.eye(model.nv), 0
            Z = np.eye(model.nv)
        G = Z.T @ self.S.T  # (d, n_a)
        f0 = Z.T @ b
        Ug, sg, Vgt = np.linalg.svd(G, full_matrices=False)
        # |G| <= max gain (Z has orthonormal columns): judged against that scale, not against
        # itself, so that actuators that cannot move anything (all their effort taken by the
        # closures) are recognised
        rg = numerics.rank_of(sg, self.rank_tol, scale=self._g_scale)
        # rank(G) independent equations E tau = f with orthonormal rows E
        E = Vgt[:rg]
        f = (Ug[:, :rg].T @ f0) / sg[:rg]
        scale = max(1.0, float(np.max(np.abs(b))))
        # the part of Z^T (M a + h) no actuator reaches: the residual of the dynamics equation
        Ur = Ug[:, :rg]
        unreachable = float(np.max(np.abs(Z @ (f0 - Ur @ (Ur.T @ f0))), initial=0.0))
        if unreachable > self.consistency_tol * scale:
            raise InfeasibleError(
                f"{_where(sample)}the dynamics equation cannot be satisfied (residual "
                f"{unreachable:.3g}): the acceleration is not consistent with the closures and "
                "the unactuated mobilities, or the configuration is singular",
                sample=sample,
                residual=unreachable,
            )
        redundancy = self.actuation.n - rg
        iterations = 0
        if redundancy == 0:
            tau = E.T @ f
            if self._bounded:
                self._check_bounds(tau, E, f, sample)
        elif rg == 0:  # no actuator influences the motion: the least effort within the bounds
            tau = np.clip(np.zeros(self.actuation.n), self.lower, self.upper)
        else:
            tau, iterations = self._qp_solve(E, f, scale, sample)
        y = b - self.S.T @ tau
        lam = U[:, :r] @ ((Vt[:r] @ y) / s[:r]) if r else np.zeros(cs.n)
        residual = float(np.max(np.abs(y - J.T @ lam), initial=0.0))
        return InverseResult(tau, lam, residual, redundancy, iterations)

    def _solve_unique(self, b: np.ndarray, J: np.ndarray) -> InverseResult | None:
        """Fast path of :meth:`solve` (see the module doc), or ``None`` where it does not apply.

        Args:
            b: ``M a + h - f_ext`` (nv,).
            J: Closure Jacobian (nc, nv).

        Returns:
            The solution, or ``None``: ``J_p`` not of full row rank with margin, actuation
            redundant, equation not satisfiable, or a bound violated (the general path decides).

        """
        n_p = self._vp.size
        nc = J.shape[0]
        if n_p == 0:
            return None
        Jr = J[:, self._perm]  # passive columns, then actuated ones
        Jp, Ja = Jr[:, :n_p], Jr[:, n_p:]
        wide = nc <= n_p  # J_p of full row rank (else: of full column rank)
        G = Jp.dot(Jp.T) if wide else Jp.T.dot(Jp)
        try:  # the inverse itself: (J_p J_p^T)^-1 J_p stays moderate when J_p loses rank
            Y = np.linalg.inv(G)  # (its blow-up is along directions J_p does not reach), so
        except np.linalg.LinAlgError:  # the margin is read on the inverse, not on X
            return None
        y = math.sqrt(float(np.vdot(Y, Y)))  # |Y|_F >= 1 / sigma_min(J_p)^2
        if not math.isfinite(y) or y <= 0.0:
            return None
        # X: the pseudo-inverse of J_p^T (wide) or of J_p
        X = Y.dot(Jp) if wide else Y.dot(Jp.T)
        jp2 = float(np.vdot(Jp, Jp))
        ja2 = float(np.vdot(Ja, Ja))
        if not y * jp2 < 1e8:  # cond(J_p)^2 small enough for the semi-normal equations
            return None
        s_lb = y**-0.5  # lower bound of sigma_min(J_p), and of the rank-th singular value of J
        j_norm = math.sqrt(jp2 + ja2)
        if s_lb <= 1e3 * self.rank_tol * j_norm:  # rank(J) >= rank(J_p), with margin
            return None
        if not wide:  # rank(J) = rank(J_p) iff J_a lies in range(J_p); |J_a - J_p X J_a| bounds
            E = Ja - Jp.dot(X.dot(Ja))  # the next singular value of J
            if math.sqrt(float(np.vdot(E, E))) > 1e-3 * self.rank_tol * j_norm / math.sqrt(nc):
                return None
            X = X.T  # lambda = J_p (J_p^T J_p)^-1 b_p: the minimum-norm solution
        # sigma_min(Z^T S^T) >= g_min s / (s + |J_a|): rank n_a, with margin
        if self._gmin * s_lb <= 1e3 * self._g_tol * (s_lb + math.sqrt(ja2)):
            return None
        bp = b[self._vp]
        lam = X.dot(bp)
        lam += X.dot(bp - lam.dot(Jp))  # one step of iterative refinement
        scale = max(1.0, float(np.abs(b).max()))
        if float(np.abs(bp - lam.dot(Jp)).max()) > self.consistency_tol * scale:
            return None
        gains = self.actuation.gains
        tau = (b[self._va] - lam.dot(Ja)) / gains
        if self._bounded:
            tol = self.eps * max(1.0, float(np.abs(tau).max()))
            if (tau < self.lower - tol).any() or (tau > self.upper + tol).any():
                return None
        y = b - lam.dot(J)
        y[self._va] -= gains * tau
        return InverseResult(tau, lam, float(np.abs(y).max()), 0, 0)

    def _check_bounds(
        self, tau: np.ndarray, E: np.ndarray, f: np.ndarray, sample: int | None
    ) -> None:
        tol = self.eps * max(1.0, float(np.max(np.abs(tau))))
        if np.all(tau >= self.lower - tol) and np.all(tau <= self.upper + tol):
            return
        self._raise_bounds(E, f, sample)

    def _raise_bounds(self, E: np.ndarray, f: np.ndarray, sample: int | None) -> None:
        """Name the actuator at fault from the least-loaded solution, and raise.

        The least-loaded solution minimises ``sum ((tau_i - c_i) / d_i)^2`` under the
        equations, with ``c`` the middle of the bounds and ``d`` their half range (a one-sided
        bound is its own centre, with unit scale); the actuator at fault is the one that
        exceeds its bounds most, relative to ``d``.
        """
        lo, hi = self.lower, self.upper
        f_lo, f_hi = np.isfinite(lo), np.isfinite(hi)
        both = f_lo & f_hi
        center = np.where(both, 0.5 * (lo + hi), np.where(f_lo, lo, np.where(f_hi, hi, 0.0)))
        D = np.where(both, 0.5 * (hi - lo), 1.0)
        D = np.maximum(D, 1e-12 * max(1.0, float(np.max(np.abs(center)))))
        s_opt = numerics.lstsq(E * D, f - E @ center, numerics.machine_rtol(E))
        tau = center + D * s_opt
        rel = np.maximum(lo - tau, tau - hi) / D
        k = int(np.argmax(rel))
        if not rel[k] > 0.0:  # the bounds admit a solution: the QP itself failed
            raise InfeasibleError(
                f"{_where(sample)}the effort QP did not converge although the bounds admit a "
                "solution",
                sample=sample,
            )
        name = self.actuation.names[k]
        raise InfeasibleError(
            f"{_where(sample)}actuator '{name}' would need {tau[k]:.6g}, outside its bounds "
            f"[{lo[k]:.6g}, {hi[k]:.6g}] (least-loaded solution); the motion is too demanding "
            "for the actuators",
            sample=sample,
            actuator=k,
            name=name,
            required=float(tau[k]),
            lower=float(lo[k]),
            upper=float(hi[k]),
        )

    def _qp_solve(
        self, E: np.ndarray, f: np.ndarray, scale: float, sample: int | None
    ) -> tuple[np.ndarray, int]:
        """Minimum weighted-norm efforts under ``E tau = f`` and the bounds (proxsuite)."""
        n = self.actuation.n
        rg = E.shape[0]
        H = np.diag(self.weights)
        g = np.zeros(n)
        lo = np.where(np.isfinite(self.lower), self.lower, -1e20)
        hi = np.where(np.isfinite(self.upper), self.upper, 1e20)
        n_in = n if self._bounded else 0
        C = np.eye(n) if n_in else None
        qp = self._qp
        if qp is None or self._qp_rank != rg:
            qp = proxqp.dense.QP(n, rg, n_in)
            qp.settings.eps_rel = 0.0
            qp.settings.max_iter = self.max_iter
            qp.settings.verbose = False
            qp.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
            qp.settings.eps_abs = self.eps * scale
            if n_in:
                qp.init(H, g, E, f, C, lo, hi)
            else:
                qp.init(H, g, E, f)
            self._qp, self._qp_rank = qp, rg
        else:
            qp.settings.eps_abs = self.eps * scale
            qp.update(A=E, b=f)
        qp.solve()
        status = qp.results.info.status
        tau = np.array(qp.results.x)
        ok = status == proxqp.QPSolverOutput.PROXQP_SOLVED
        if ok and n_in:
            tol = 1e3 * self.eps * scale
            ok = bool(np.all(tau >= self.lower - tol) and np.all(tau <= self.upper + tol))
        if not ok:
            self._qp = None  # a failed solve is no warm start
            if n_in:
                self._raise_bounds(E, f, sample)
            raise InfeasibleError(
                f"{_where(sample)}the effort QP did not converge ({status})", sample=sample
            )
        return tau, int(qp.results.info.iter)

    # ------------------------------------------------------------------ trajectories

    def trajectory(
        self,
        q: np.ndarray,
        v: np.ndarray,
        a: np.ndarray,
        f_ext: np.ndarray | None = None,
        *,
        wrench: tuple[int, np.ndarray] | None = None,
        check_tol: float | None = None,
        first_sample: int = 0,
    ) -> InverseTrajectory:
        """Inverse dynamics at every sample of a trajectory, in batches.

        Per sample only Pinocchio's C++ runs (``rnea``, the joint Jacobians, the constraint
        Jacobian, the energies) and its results are copied into
        arrays; the closure check (:class:`~solvers.sampled.SampledKinematics`) and the
        passive-row elimination of :meth:`solve` (same margins, same solution) are vectorised
        over a batch of samples. Samples where the elimination does not apply (redundant
        actuation, violated bounds, rank margins) are solved one by one by :meth:`solve`'s
        general path, in order (the QP stays warm-started along the trajectory).

        Args:
            q: Configurations (N, nq).
            v: Velocities (N, nv).
            a: Accelerations (N, nv).
            f_ext: Generalized external forces (N, nv) [N m or N] (default: none).
            wrench: ``(frame id, W)``: wrenches (N, 6) applied on the frame's body at the
                frame origin, force in world axes [N] then moment in the frame's axes [N m]
                (added to ``f_ext``).
            check_tol: When given, refuse samples that do not satisfy the closures: residual
                above ``check_tol`` [m or rad], velocity error above ``check_tol max(1, |v|)``,
                acceleration error above ``check_tol max(1, |a|)`` (largest components).
            first_sample: Index of the first row in the whole trajectory (for the errors).

        Returns:
            Efforts, closure forces, residuals and energies per sample.

        Raises:
            InconsistentMotionError: At the first sample that breaks the check (checked first).
            InfeasibleError: At the first sample that cannot be realised (``.sample`` set).

        """
        q, v, a = np.atleast_2d(q), np.atleast_2d(v), np.atleast_2d(a)
        N = q.shape[0]
        if v.shape[0] != N or a.shape[0] != N:
            raise ValueError(
                f"{N} configurations, {v.shape[0]} velocities, {a.shape[0]} accelerations"
            )
        model = self.model
        nv, nc = model.nv, self.constraints.n
        out = InverseTrajectory(
            np.empty((N, self.actuation.n)),
            np.empty((N, nc)),
            np.empty(N),
            np.empty(N),
            np.empty(N),
        )
        if f_ext is not None:
            f_ext = np.asarray(f_ext, dtype=float).reshape(N, nv)
        frames: tuple[int, ...] = () if wrench is None else (int(wrench[0]),)
        kin = self._sampled
        if kin is None or tuple(kin._frame_slot) != frames:
            kin = self._sampled = SampledKinematics(model, self.constraints, frames, _BATCH)
        for s in range(0, N, _BATCH):
            e = min(N, s + _BATCH)
            b, J = self._sample_terms(kin, q[s:e], v[s:e], a[s:e], out, s)
            n = e - s
            if f_ext is not None:
                b -= f_ext[s:e]
            if wrench is not None:
                b -= kin.frame_force(n, int(wrench[0]), np.asarray(wrench[1], dtype=float)[s:e])
            stop = n
            bad = None
            if check_tol is not None and nc:
                bad = self._first_inconsistent(kin, q[s:e], v[s:e], a[s:e], check_tol)
                if bad is not None:
                    stop = bad[0]
            done = self._solve_unique_batch(b[:stop], J[:stop], out, s)
            for i in np.flatnonzero(~done).tolist():
                res = self._solve_state(b[i], J[i], first_sample + s + i)
                out.tau[s + i], out.constraint_forces[s + i] = res.tau, res.constraint_forces
                out.residual[s + i] = res.residual
            if bad is not None:
                i, what, name, worst = bad
                raise InconsistentMotionError(
                    f"sample {first_sample + s + i}: the {what} does not satisfy closure "
                    f"'{name}' (error {worst:.3g})",
                    sample=first_sample + s + i,
                    what=what,
                    closure=name,
                    error=worst,
                )
        return out

    def _sample_terms(
        self,
        kin: SampledKinematics,
        q: np.ndarray,
        v: np.ndarray,
        a: np.ndarray,
        out: InverseTrajectory,
        s: int,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Per-sample C++ work of a batch: ``b = M a + h`` (n, nv) and closure Jacobians.

        The Jacobians are (n, nc, nv); the energies go into ``out`` from row ``s``; ``kin``
        captures the kinematics of the closure check.
        """
        model, kd = self.model, self._kin
        n = q.shape[0]
        nc = self.constraints.n
        b = np.empty((n, model.nv))
        J = np.empty((n, nc, model.nv))
        rnea, jac = pin.rnea, pin.computeJointJacobians
        kinetic, potential = pin.computeKineticEnergy, pin.computePotentialEnergy
        jacobian_at, capture = self.constraints.jacobian_at, kin.capture
        ke, pe = out.kinetic[s:], out.potential[s:]
        passive = self.passive_forces
        for i in range(n):
            qi, vi = q[i], v[i]
            b[i] = rnea(model, kd, qi, vi, a[i])  # also the joint velocities, accelerations
            f = passive(qi, vi)
            if f is not None:
                b[i] -= f
            ke[i] = kinetic(model, kd)
            jac(model, kd, qi)  # placements and world Jacobian
            pe[i] = potential(model, kd)
            if nc:
                capture(i, kd)
                J[i] = jacobian_at(kd, qi)
        if self._kinetic.active:  # the armature Pinocchio's kinetic energy leaves out
            ke[:n] += self._kinetic.missing_batch(v)
        return b, J

    def _first_inconsistent(
        self, kin: SampledKinematics, q: np.ndarray, v: np.ndarray, a: np.ndarray, tol: float
    ) -> tuple[int, str, str, float] | None:
        """First sample of a batch breaking the closure check, the kind, closure and error."""
        n = q.shape[0]
        r, ev, ea = kin.closure_errors(n, v, q, a)
        checks = (
            ("configuration", r, np.ones(n)),
            ("velocity", ev, np.maximum(1.0, np.abs(v).max(axis=1))),
            ("acceleration", ea, np.maximum(1.0, np.abs(a).max(axis=1))),
        )
        worst = [np.abs(err).max(axis=1) for _, err, _ in checks]
        bad = [~(w <= tol * scale) for w, (_, _, scale) in zip(worst, checks, strict=True)]
        hit = np.flatnonzero(bad[0] | bad[1] | bad[2])
        if not hit.size:
            return None
        i = int(hit[0])
        c = next(c for c in range(3) if bad[c][i])
        per = self.constraints.split(checks[c][1][i])
        name = max(per, key=lambda k: per[k])
        return i, checks[c][0], name, float(worst[c][i])

    def _solve_unique_batch(
        self, b: np.ndarray, J: np.ndarray, out: InverseTrajectory, s: int
    ) -> np.ndarray:
        """:meth:`_solve_unique` on a batch (same margins and operations).

        Results go into ``out`` from row ``s``; returns where the elimination applied (n,).
        """
        n = b.shape[0]
        done = np.zeros(n, dtype=bool)
        n_p = self._vp.size
        nc = self.constraints.n
        if n and nc == 0:
            return self._solve_free_batch(b, out, s)
        if n == 0 or n_p == 0:
            return done
        Jp, Ja = J[:, :, self._vp], J[:, :, self._va]
        JpT = np.swapaxes(Jp, 1, 2)
        wide = nc <= n_p
        try:  # Ginv = (J_p J_p^T)^-1 (wide) or (J_p^T J_p)^-1; trace(Ginv) = |X|_F^2
            Ginv = np.linalg.inv(Jp @ JpT if wide else JpT @ Jp)
        except np.linalg.LinAlgError:  # one of them singular: let the one-by-one path decide
            return done
        x2 = np.trace(Ginv, axis1=1, axis2=2)
        jp2 = np.einsum("nij,nij->n", Jp, Jp)
        ja2 = np.einsum("nij,nij->n", Ja, Ja)
        with np.errstate(divide="ignore", invalid="ignore"):
            ok = x2 * jp2 < 1e8
            s_lb = x2**-0.5
            j_norm = np.sqrt(jp2 + ja2)
            ok &= s_lb > 1e3 * self.rank_tol * j_norm
            if not wide:
                E = Ja - Jp @ (Ginv @ (JpT @ Ja))
                e_norm = np.sqrt(np.einsum("nij,nij->n", E, E))
                ok &= e_norm <= 1e-3 * self.rank_tol * j_norm / math.sqrt(nc)
            ok &= self._gmin * s_lb > 1e3 * self._g_tol * (s_lb + np.sqrt(ja2))
        bp = b[:, self._vp]

        def X(r: np.ndarray) -> np.ndarray:  # X r: Ginv J_p r (wide) or J_p Ginv r
            return _mv(Ginv, _mv(Jp, r)) if wide else _mv(Jp, _mv(Ginv, r))

        lam = X(bp)
        lam += X(bp - _mv(JpT, lam))  # one step of iterative refinement
        scale = np.maximum(1.0, np.abs(b).max(axis=1))
        ok &= np.abs(bp - _mv(JpT, lam)).max(axis=1) <= self.consistency_tol * scale
        gains = self.actuation.gains
        tau = (b[:, self._va] - _mv(np.swapaxes(Ja, 1, 2), lam)) / gains
        if self._bounded:
            tol = self.eps * np.maximum(1.0, np.abs(tau).max(axis=1))[:, None]
            ok &= ~((tau < self.lower - tol) | (tau > self.upper + tol)).any(axis=1)
        y = b - _mv(np.swapaxes(J, 1, 2), lam)
        y[:, self._va] -= gains * tau
        done[:] = ok
        out.tau[s : s + n][ok] = tau[ok]
        out.constraint_forces[s : s + n][ok] = lam[ok]
        out.residual[s : s + n][ok] = np.abs(y[ok]).max(axis=1)
        return done

    def _solve_free_batch(self, b: np.ndarray, out: InverseTrajectory, s: int) -> np.ndarray:
        """:meth:`_solve_state` on a batch without constraint rows (same margins, same solution).

        Without rows ``Z = I`` and ``G = S^T``, whose columns are the distinct actuated axes
        scaled by the gains: its singular values are ``|gains|``, so ``rank(G) = n_a`` when the
        smallest gain clears the rank tolerance (with :meth:`_solve_unique`'s margin), the
        unreachable part of ``b`` is its passive entries and ``tau = b_a / gains``. Samples
        whose passive entries exceed the consistency tolerance or whose efforts break a bound
        are left to the general path (which raises).

        Results go into ``out`` from row ``s``; returns where this applied (n,).
        """
        n = b.shape[0]
        if not self._gmin > 1e3 * self._g_tol:
            return np.zeros(n, dtype=bool)
        scale = np.maximum(1.0, np.abs(b).max(axis=1))
        bp = np.abs(b[:, self._vp]).max(axis=1, initial=0.0)
        ok = bp <= self.consistency_tol * scale
        gains = self.actuation.gains
        tau = b[:, self._va] / gains
        if self._bounded:
            tol = self.eps * np.maximum(1.0, np.abs(tau).max(axis=1))[:, None]
            ok &= ~((tau < self.lower - tol) | (tau > self.upper + tol)).any(axis=1)
        ya = np.abs(b[:, self._va] - gains * tau).max(axis=1, initial=0.0)
        out.tau[s : s + n][ok] = tau[ok]
        out.residual[s : s + n][ok] = np.maximum(bp, ya)[ok]
        return ok


def _vector(
    x: Sequence[float] | np.ndarray | None, n: int, default: float, what: str
) -> np.ndarray:
    if x is None:
        return np.full(n, default)
    out = np.asarray(x, dtype=float).reshape(-1)
    if out.size != n:
        raise ValueError(f"{what}: {out.size} values for {n} actuators")
    return out


def _mv(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Batched matrix-vector products ``M_k x_k``: (n, i, j), (n, j) -> (n, i)."""
    return (M @ x[:, :, None])[:, :, 0]


def _where(sample: int | None) -> str:
    return "" if sample is None else f"sample {sample}: "
