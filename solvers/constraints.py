"""The constraint layer: the rows of a mechanism's closures and couplings, at an explicit state.

A :class:`ConstraintSet` stacks the rows of named constraints of two kinds, closures first:

- **closures** (:mod:`solvers.closure`): ``point`` (3 rows), ``hinge`` (5), ``weld`` (6), planar
  closures reduced to their in-plane rows (2 or 3);
- **couplings** (:mod:`solvers.coupling`): one row each, linear relations over any number of
  1-DoF joint coordinates and polynomial laws between two.

Each row has its residual ``r(q)``, its exact Jacobian ``J(q)`` (derivative for a velocity
increment applied by ``pin.integrate``) and its acceleration drift ``gamma(q, v)``
(``d^2 r/dt^2 = J a + gamma``). Every evaluation takes the configuration (and velocity)
explicitly: nothing is remembered from one call to the next but the kinematics the caller
keeps in its ``pin.Data`` (:meth:`ConstraintSet.jacobian_after_residual` reads them).

Sizes: ``n`` rows in all, ``nc`` closure rows (``[0, nc)``), ``nk`` coupling rows (``[nc, n)``).
The views :attr:`ConstraintSet.closures` and :attr:`ConstraintSet.couplings` are the sets of
one kind (their own names, sizes and offsets), for a caller that needs one kind only (a closure
gap in m and rad, a coupling gap in rad or m).

Multipliers ``lambda`` (n,) of the rows (``J^T lambda`` in the dynamics): the closures'
(:meth:`ConstraintSet.reactions`: one force and one moment per closure), then the couplings'
generalized forces [N m or N] (:meth:`ConstraintSet.coupling_forces`).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from solvers.closure import Closure, ClosureRows
from solvers.coupling import Coupling, CouplingRows

__all__ = ["ClosureSet", "ConstraintSet", "constraint_set"]


class ConstraintSet:
    """Closures and couplings of a mechanism on a Pinocchio model (see the module docstring).

    Args:
        model: The kinematic tree.
        closures: Loop closures (:class:`solvers.closure.Closure`, or Pinocchio rigid
            constraint models: 3D points and 6D welds).
        couplings: Joint couplings (:class:`solvers.coupling.LinearCoupling`,
            :class:`solvers.coupling.JointCoupling`), or a set whose couplings to take.
        reduce: Reduce the closures to their independent rows (hinges to 5 rows, planar
            closures to their in-plane rows); ``False``: a hinge is two points (6 rows of
            rank 5) and no row is dropped. Default: reduce, unless a closure is given as a
            Pinocchio constraint model (then every model keeps its rows, as the former closure
            set did).

    Attributes:
        model: The kinematic tree.
        names: Constraint names, closures then couplings.
        kinds: ``point``, ``hinge``, ``weld`` or ``coupling``, per constraint.
        sizes: Rows per constraint.
        offsets: Row offset of each constraint, then ``n`` (n_constraints + 1,).
        n: Number of rows.
        nc: Number of closure rows (the first ones).
        nk: Number of coupling rows (the last ones).

    Raises:
        ValueError: A malformed closure (:class:`solvers.closure.ClosureRows`) or coupling
            (:class:`solvers.coupling.CouplingRows`).

    """

    def __init__(
        self,
        model: pin.Model,
        closures: Sequence[Closure | pin.RigidConstraintModel] = (),
        couplings: Sequence[Coupling] | ConstraintSet = (),
        *,
        reduce: bool | None = None,
    ) -> None:
        self.model = model
        if isinstance(couplings, ConstraintSet):  # (a set's couplings view, as the former API)
            couplings = couplings.coupling_specs
        if reduce is None:  # Pinocchio's models are taken row for row
            reduce = all(isinstance(c, Closure) for c in closures)
        self._closure: ClosureRows | None = ClosureRows(model, closures, reduce)
        self._coupling: CouplingRows | None = (
            CouplingRows(model, couplings) if len(couplings) else None
        )
        self._setup()

    @classmethod
    def _view(
        cls, model: pin.Model, closure: ClosureRows | None, coupling: CouplingRows | None
    ) -> ConstraintSet:
        out = cls.__new__(cls)
        out.model = model
        out._closure, out._coupling = closure, coupling
        out._setup()
        return out

    def _setup(self) -> None:
        cl, cp = self._closure, self._coupling
        self.nc = cl.n if cl is not None else 0
        self.nk = cp.n if cp is not None else 0
        self.n = self.nc + self.nk
        self.names = (list(cl.names) if cl else []) + (list(cp.names) if cp else [])
        self.kinds = (list(cl.kinds) if cl else []) + ["coupling"] * self.nk
        self.sizes = (list(cl.sizes) if cl else []) + [1] * self.nk
        self.offsets = np.concatenate([[0], np.cumsum(self.sizes)]).astype(int)
        self._only_closures = self.nk == 0 and cl is not None
        self._local = cl is None or cl.identity

    # ------------------------------------------------------------------ parts

    @functools.cached_property
    def closures(self) -> ConstraintSet:
        """The closures alone (a set of the same closure rows, without couplings)."""
        if self.nk == 0:
            return self
        return ConstraintSet._view(self.model, self._closure, None)

    @functools.cached_property
    def couplings(self) -> ConstraintSet:
        """The couplings alone (a set of the same coupling rows, without closures)."""
        if self.nc == 0 and not self.closure_specs:
            return self
        return ConstraintSet._view(self.model, None, self._coupling)

    @functools.cached_property
    def unreduced(self) -> ConstraintSet:
        """The same constraints with every row (hinges as two points, planar closures whole).

        For what depends on rows that vanish only by construction of the nominal geometry: the
        sensitivity of the closures to the description's placements (an out-of-plane error
        opens a planar loop out of its plane), Pinocchio's own constraint models.
        """
        if not self.reduce or self._closure is None or self._closure.identity:
            return self  # (nothing was reduced)
        return ConstraintSet(self.model, self.closure_specs, self.coupling_specs, reduce=False)

    @property
    def closure_rows(self) -> ClosureRows | None:
        """The closures' row evaluator (``None`` in the couplings view)."""
        return self._closure

    @property
    def coupling_rows(self) -> CouplingRows | None:
        """The couplings' row evaluator (``None`` without couplings)."""
        return self._coupling

    @property
    def closure_specs(self) -> tuple[Closure, ...]:
        """The closures."""
        return self._closure.closures if self._closure is not None else ()

    @property
    def coupling_specs(self) -> tuple[Coupling, ...]:
        """The couplings."""
        return self._coupling.couplings if self._coupling is not None else ()

    @property
    def n_rigid(self) -> int:
        """The former name of :attr:`nc` (kept for one release)."""
        return self.nc

    @property
    def reduce(self) -> bool:
        """Whether the closures are reduced to their independent rows."""
        return self._closure.reduce if self._closure is not None else True

    def rebuilt(
        self,
        closures: Sequence[Closure | pin.RigidConstraintModel] | None = None,
        couplings: Sequence[Coupling] | None = None,
        model: pin.Model | None = None,
        reduce: bool | None = None,
    ) -> ConstraintSet:
        """A set of the same kind with other closures, couplings or model (default: these).

        Args:
            closures: The closures (default: this set's).
            couplings: The couplings (default: this set's).
            model: The model (default: this set's), e.g. a copy with other joint placements.
            reduce: Reduce the closures (default: as this set).

        Returns:
            The new set.

        """
        return ConstraintSet(
            self.model if model is None else model,
            self.closure_specs if closures is None else closures,
            self.coupling_specs if couplings is None else couplings,
            reduce=self.reduce if reduce is None else reduce,
        )

    @property
    def movable(self) -> bool:
        """Whether :meth:`move_closures` applies (:attr:`solvers.closure.ClosureRows.movable`)."""
        return self._closure is not None and self._closure.movable

    def move_closures(self, closures: Sequence[Closure]) -> None:
        """Put other placements on the same closures, in place (see :meth:`ClosureRows.move`).

        The set then has the rows ``rebuilt(closures)`` would have (the couplings depend on no
        placement); for the robots of a Monte Carlo, one after the other.

        Args:
            closures: The closures (same names, kinds and joints, in the same order), with the
                new placements.

        Raises:
            ValueError: The set is not :attr:`movable`, or the closures are not its own.

        """
        if self._closure is None:
            raise ValueError("a set without closures has no placements to move")
        self._closure.move(closures)

    @property
    def items(self) -> list[tuple[bool, int, pin.SE3, int, pin.SE3]]:
        """Per constraint model of the closures, unreduced: ``(is_point, joint1, placement1, ...)``.

        ``(is_point, joint1, placement1, joint2, placement2)`` of the 3D points and 6D welds of
        :attr:`unreduced` (a hinge is two points), one per Pinocchio constraint model of the
        closures as the description builds them (the former closure set's items).
        """
        rows = self.unreduced.closure_rows
        return rows.base_items if rows is not None else []

    # ------------------------------------------------------------------ evaluation

    def residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Residual at ``q`` (runs the forward kinematics).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (n,) [m, rad].

        """
        pin.forwardKinematics(self.model, data, q)
        return self._residual(data, q)

    def _residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Residual from the joint placements of ``data`` (updates the constraint datas)."""
        cl, cp = self._closure, self._coupling
        if self._only_closures:
            assert cl is not None
            return cl.residual(data)
        r = np.empty(self.n)
        if cl is not None and self.nc:
            cl.residual(data, r[: self.nc])
        if cp is not None:
            r[self.nc :] = cp.residual(np.asarray(q))
        return r

    def _jacobian(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Jacobian from ``data`` (joint Jacobians and constraint datas up to date)."""
        cl, cp = self._closure, self._coupling
        if self._only_closures:
            assert cl is not None
            return cl.jacobian(data)
        J = np.zeros((self.n, self.model.nv))
        if cl is not None and self.nc:
            cl.jacobian(data, J[: self.nc])
        if cp is not None:
            cp.jacobian(np.asarray(q), J[self.nc :])
        return J

    def residual_and_jacobian(self, data: pin.Data, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual and Jacobian at ``q`` (runs the kinematics and joint Jacobians).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (n,) [m, rad] and Jacobian (n, nv).

        """
        pin.computeJointJacobians(self.model, data, q)
        r = self._residual(data, q)
        return r, self._jacobian(data, q)

    def jacobian(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Jacobian (n, nv) at ``q`` (runs the kinematics and joint Jacobians).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Jacobian (n, nv).

        """
        pin.computeJointJacobians(self.model, data, q)
        return self.jacobian_at(data, q)

    def jacobian_at(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Jacobian (n, nv) from ``data`` after ``pin.computeJointJacobians(model, data, q)``.

        Args:
            data: Pinocchio data whose placements and joint Jacobians are those of ``q``.
            q: That configuration (nq,).

        Returns:
            Jacobian (n, nv).

        """
        cl = self._closure
        if self._only_closures:
            assert cl is not None
            return cl.jacobian_at(data)
        if cl is not None and self.nc:
            cl.calc(data)
        return self._jacobian(data, q)

    def jacobian_after_residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Jacobian (n, nv) at ``q``, where :meth:`residual` was just evaluated with ``data``.

        Only the joint Jacobians (from the placements already in ``data``) and the rows are
        computed: for solvers that evaluate the Jacobian where they have just evaluated the
        residual (:func:`solvers.solve_lm` does).

        Args:
            data: The data the last :meth:`residual` call at ``q`` used, untouched since.
            q: That configuration (nq,).

        Returns:
            Jacobian (n, nv).

        """
        pin.computeJointJacobians(self.model, data)
        return self._jacobian(data, q)

    @property
    def n_local(self) -> int:
        """Rows of :meth:`local_residual`: every closure row, then the couplings'."""
        return self.unreduced.n

    def local_residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """The residual the Newton solvers work on (runs the forward kinematics).

        Every closure row (:attr:`unreduced`: a hinge as two points, a planar loop whole, the
        same constraints as the reduced rows, redundant ones included), in the contact frame of
        ``joint1``: a point's residual is ``R_c1^T (p1 - p2)`` (the world residual rotated,
        same norm), a weld's ``log6(c2Mc1)``; with :meth:`local_jacobian_after_residual`
        (Pinocchio's ``LOCAL`` constraint Jacobian) it is exact at closure, where Newton's
        method needs it (its error is of the order of the residual: convergence stays
        quadratic, and the Levenberg-Marquardt solver settles the redundant rows). Cheaper than
        :meth:`residual`: Pinocchio's C++ and one copy per constraint model. Then the coupling
        rows (:meth:`residual`'s). Size :attr:`n_local`.

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (n_local,) [m, rad].

        """
        if not self._local:
            return self.unreduced.local_residual(data, q)
        pin.forwardKinematics(self.model, data, q)
        r = np.empty(self.n)
        if self._closure is not None and self.nc:
            self._closure.local_residual(data, r[: self.nc])
        if self._coupling is not None:
            r[self.nc :] = self._coupling.residual(np.asarray(q))
        return r

    def local_jacobian_after_residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Jacobian (n_local, nv) of :meth:`local_residual` at ``q``, exact at closure.

        Args:
            data: The data the last :meth:`local_residual` call at ``q`` used, untouched since.
            q: That configuration (nq,).

        Returns:
            Jacobian (n_local, nv).

        """
        if not self._local:
            return self.unreduced.local_jacobian_after_residual(data, q)
        pin.computeJointJacobians(self.model, data)
        cl, cp = self._closure, self._coupling
        if cp is None:
            assert cl is not None
            return cl.local_jacobian(data)
        J = np.zeros((self.n, self.model.nv))
        if cl is not None and self.nc:
            J[: self.nc] = cl.local_jacobian(data)
        cp.jacobian(np.asarray(q), J[self.nc :])
        return J

    def drift(self, data: pin.Data, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Acceleration drift ``gamma`` (n,): ``d^2 r/dt^2 = J a + gamma`` (runs the kinematics).

        A motion keeps the constraints to second order when ``J a = -gamma``. Exact for point,
        hinge, planar and coupling rows at any state; for welds when their relative velocity
        is zero (``J v = 0``).

        Args:
            data: Pinocchio data of ``model`` (its kinematics are overwritten).
            q: Configuration (nq,).
            v: Velocity (nv,).

        Returns:
            Drift (n,) [m/s^2, rad/s^2].

        """
        model = self.model
        g = np.empty(self.n)
        if self._closure is not None and self.nc:
            pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
            g[: self.nc] = self._closure.drift(data)
        if self._coupling is not None:
            g[self.nc :] = self._coupling.drift(np.asarray(q), np.asarray(v))
        return g

    def dynamics_terms(
        self, data: pin.Data, q: np.ndarray, v: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Residual, Jacobian and drift at ``(q, v)`` from one forward kinematics.

        For the dynamics, which need the three at every evaluation: ``forwardKinematics(q, v,
        0)`` then the joint Jacobians from its placements.

        Args:
            data: Pinocchio data of ``model`` (its kinematics are overwritten).
            q: Configuration (nq,).
            v: Velocity (nv,).

        Returns:
            Residual (n,), Jacobian (n, nv) and drift (n,).

        """
        model = self.model
        pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
        pin.computeJointJacobians(model, data)
        r = self._residual(data, q)
        J = self._jacobian(data, q)
        g = np.empty(self.n)
        if self._closure is not None and self.nc:
            g[: self.nc] = self._closure.drift(data)
        if self._coupling is not None:
            g[self.nc :] = self._coupling.drift(np.asarray(q), np.asarray(v))
        return r, J, g

    # ------------------------------------------------------------------ reports

    def split(self, r: np.ndarray) -> dict[str, float]:
        """Norm of the rows of each constraint, by name.

        Args:
            r: Residual (or any row vector) (n,).

        Returns:
            ``{constraint name: norm}``.

        """
        return {
            n: float(np.linalg.norm(r[self.offsets[k] : self.offsets[k + 1]]))
            for k, n in enumerate(self.names)
        }

    def reactions(
        self, data: pin.Data, q: np.ndarray, lam: np.ndarray
    ) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """One force and one moment per closure from the multipliers (runs the kinematics).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).
            lam: Multipliers (n,) [N, N m] of the rows.

        Returns:
            ``{closure name: (force [N], moment [N m], point [m])}``: the reaction on the first
            frame's body about the first frame's origin, world axes
            (:meth:`solvers.closure.ClosureRows.reactions`).

        """
        if self._closure is None or not self._closure.closures:
            return {}
        pin.forwardKinematics(self.model, data, q)
        out = self._closure.reactions(data, np.asarray(lam)[: self.nc])
        return dict(zip(self._closure.names, out, strict=True))

    def coupling_forces(self, lam: np.ndarray) -> dict[str, float]:
        """The generalized force of each coupling [N m or N] from the multipliers (n,)."""
        if self._coupling is None:
            return {}
        return {
            name: float(x)
            for name, x in zip(self._coupling.names, np.asarray(lam)[self.nc :], strict=True)
        }


def constraint_set(
    model: pin.Model,
    constraints: ConstraintSet | Sequence[Closure | pin.RigidConstraintModel],
    couplings: Sequence[Coupling] | ConstraintSet = (),
) -> ConstraintSet:
    """The constraint set of a solver's arguments: a set as given, or one built from closures.

    Args:
        model: The kinematic tree.
        constraints: A constraint set, or closures (:class:`ConstraintSet`'s argument).
        couplings: Couplings (or a set whose couplings to take), with closures only (a set
            holds its own).

    Returns:
        The set.

    Raises:
        ValueError: A set given with couplings, or a set of another model.

    """
    if isinstance(couplings, ConstraintSet):
        couplings = couplings.coupling_specs
    if isinstance(constraints, ConstraintSet):
        if len(couplings):
            raise ValueError("give the couplings inside the constraint set, not beside it")
        if constraints.model is not model and (
            constraints.model.nq != model.nq or constraints.model.nv != model.nv
        ):
            raise ValueError("the constraint set is built on another model")
        return constraints
    return ConstraintSet(model, list(constraints), couplings)


ClosureSet = ConstraintSet
"""The former name of :class:`ConstraintSet` (kept for one release)."""
