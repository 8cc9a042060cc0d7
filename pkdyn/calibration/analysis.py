"""What the nominal robot says of the calibration measurements, and the fit it sets up.

:func:`analyse` evaluates the nominal robot at the calibration readings (configurations,
platform poses, the unknowns of implicit measurements) and its identification Jacobian; holds
at zero the errors the mechanism cannot absorb; refuses measured positions more than 100 robot
sizes away (naming the likely cause); analyses identifiability
(:func:`~pkdyn.calibration.identifiability.identifiability`, the columns scaled by the prior);
warns about poses that identify less than varied poses would, and refuses fewer measured values
than identifiable parameters. The :class:`Nominal` it returns holds the residual and Jacobian of
the estimated unknowns (the identifiable errors, then the unknowns of implicit measurements) as
methods, and runs the estimator (:meth:`Nominal.fit`: :func:`~pkdyn.calibration.robust.
robust_fit`). Nothing in it changes once made.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from pkdyn.calibration.diagnosis import likely_cause, tolerance_error
from pkdyn.calibration.identifiability import RTOL, identifiability
from pkdyn.calibration.measurements import Measurements
from pkdyn.calibration.problem import GAP_TOL, Problem, State, nominal_configurations
from pkdyn.calibration.robust import RobustFit, robust_fit
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.identifiability import Identifiability
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel
from pkdyn.precision.sensitivity import pose_sensitivity
from solvers import numerics

__all__ = ["Nominal", "analyse", "parameter_scale"]


@dataclass(frozen=True, eq=False)  # numpy fields
class Nominal:
    """The nominal robot at the calibration measurements (module docstring).

    Attributes:
        robot: The nominal robot.
        model: The parameter model.
        problem: The calibration problem (plane frames set).
        state: Its evaluation at zero errors.
        y0: Initial unknowns of implicit measurements.
        J_all: Unweighted Jacobian (N, rows, n_par + n_nuis) at zero errors.
        keep: Parameters the mechanism absorbs (the others are held at zero).
        not_assembling: Names of the others.
        identifiability: The analysis, indexed on ``keep`` then the nuisance unknowns.
        cols: Estimated robot parameters (indices into the model).
        nuis_cols: Estimated nuisance unknowns (indices into ``y0``).
        row_sigma: Standard deviation of every residual row (N rows,).
        bound: Error the tolerances explain at each pose (N, rows) [m, rad].
        sigma: Measurement standard deviations ``(position [m], orientation [rad])``.

    """

    robot: Robot
    model: ParameterModel
    problem: Problem
    state: State
    y0: np.ndarray
    J_all: np.ndarray
    keep: np.ndarray
    not_assembling: tuple[str, ...]
    identifiability: Identifiability
    cols: np.ndarray
    nuis_cols: np.ndarray
    row_sigma: np.ndarray
    bound: np.ndarray
    sigma: tuple[float, float]

    @property
    def size(self) -> int:
        """Number of estimated unknowns."""
        return int(self.cols.size + self.nuis_cols.size)

    def unpack(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The errors ``p`` (n_par,) and the unknowns ``y`` of estimated unknowns ``z``."""
        p = np.zeros(self.model.size)
        p[self.cols] = z[: self.cols.size]
        y = self.y0.copy()
        y[self.nuis_cols] = y[self.nuis_cols] + z[self.cols.size :]
        return p, y

    def residual(self, z: np.ndarray, start: State) -> tuple[State, np.ndarray]:
        """The state at ``z`` (forward geometry from ``start``) and its weighted residuals."""
        p, y = self.unpack(z)
        state = self.problem.evaluate(p, start)
        return state, self.problem.residuals(state, y).reshape(-1) / self.row_sigma

    def jacobian(self, z: np.ndarray, state: State) -> np.ndarray:
        """Weighted Jacobian (rows, size) of the residuals at ``z``."""
        p, y = self.unpack(z)
        J, _ = self.problem.jacobian(state, p, y, self.cols)
        J = J.reshape(self.row_sigma.size, -1)
        c = self.cols.size
        return np.hstack([J[:, :c], J[:, c:][:, self.nuis_cols]]) / self.row_sigma[:, None]

    def fit(
        self,
        robust: str,
        known: bool,
        max_iter: int,
        prior: tuple[float, float, float] | None,
    ) -> RobustFit:
        """The estimator on the estimated unknowns, from zero errors (weighted prior on them)."""
        pw = np.zeros(self.size)
        if prior is not None:  # weakly informative, on the robot's errors only
            pw[: self.cols.size] = 1.0 / _prior(self.model, prior)[self.cols] ** 2
        n = self.model.size
        rows = self.row_sigma.size
        J = self.J_all.reshape(rows, -1)
        J_start = np.hstack([J[:, self.cols], J[:, n:][:, self.nuis_cols]])
        r0 = self.problem.residuals(self.state, self.y0).reshape(-1) / self.row_sigma
        return robust_fit(
            self.residual,
            self.jacobian,
            np.zeros(self.size),
            self.state,
            r0,
            J_start / self.row_sigma[:, None],
            pw,
            self.problem.rows,
            robust,
            known,
            max_iter,
        )

    def cause(self) -> str:
        """The likely cause of measurements far from the nominal robot (``""``: none found)."""
        m = self.problem.m
        positions = np.array([M.translation for M in self.state.poses])
        rotations = np.array([M.rotation for M in self.state.poses])
        return likely_cause(
            self.robot, m.kind, m.position, positions, m.rpy, rotations, self.bound, self.sigma
        )

    def full_identifiability(self) -> Identifiability:
        """The analysis re-indexed on the full parameter model (nuisance unknowns after)."""
        ident, keep, pm = self.identifiability, self.keep, self.model
        n_rob = keep.size
        names = pm.names + ident.names[n_rob:]
        units = tuple(pm.units) + ("m",) * (len(ident.names) - n_rob)

        def full(i: int) -> int:
            return int(keep[i]) if i < n_rob else pm.size + i - n_rob

        return Identifiability(  # (the parameters the mechanism cannot absorb are in neither)
            tuple(names),
            np.array([full(int(i)) for i in ident.identifiable], dtype=int),
            np.array([full(int(i)) for i in ident.unidentifiable], dtype=int),
            ident.coefficients,
            ident.r_diag,
            np.array([full(int(i)) for i in ident.weak], dtype=int),
            units,
            ident.singular_values,
            ident.indices,
            ident.poses,
        )


def analyse(
    robot: Robot,
    pm: ParameterModel,
    cal: Measurements,
    sigma: tuple[float, float],
    tolerance: np.ndarray,
    rtol: float,
    prior: tuple[float, float, float] | None,
    n_val: int,
    holdout: float,
) -> Nominal:
    """The nominal robot at the calibration measurements (module docstring).

    Args:
        robot: The nominal robot.
        pm: The parameter model.
        cal: The calibration measurements (readings as joint coordinates).
        sigma: Measurement standard deviations ``(position [m], orientation [rad])``.
        tolerance: Tolerance of each parameter (n_par,) (the likely cause's reference).
        rtol: Identifiability threshold.
        prior: Prior standard deviations ``(length, angle, gain)``, or ``None``.
        n_val: Number of validation measurements (for the message on too few poses).
        holdout: The hold-out fraction (for that message).

    Raises:
        InvalidInputError: Readings the nominal robot cannot be assembled at, measured
            positions more than 100 robot sizes away, or fewer measured values than
            identifiable parameters.

    """
    prob = Problem(robot, pm, cal, sigma, nominal_configurations(robot, cal))
    row_sigma = np.tile(prob.row_sigma(), len(cal))
    zero = np.zeros(pm.size)
    state0 = prob.evaluate(zero)
    positions0 = np.array([M.translation for M in state0.poses])
    y0, planes = prob.fit_nuisance(positions0)
    prob = prob.with_planes(planes)
    J_all, gaps = prob.jacobian(state0, zero, y0, np.arange(pm.size))
    keep = np.flatnonzero(gaps <= GAP_TOL)
    n_rob = keep.size
    J0 = np.concatenate([J_all[:, :, keep], J_all[:, :, pm.size :]], axis=2)
    J0 = J0.reshape(len(cal) * cal.rows, -1)
    names = tuple(pm.names[k] for k in keep) + _nuisance_names(cal, prob.groups)
    scale_all = np.concatenate([parameter_scale(robot, pm)[keep], _nuisance_scale(robot, prob)])
    prior_all = None
    if prior is not None:
        prior_all = np.concatenate([_prior(pm, prior)[keep], _nuisance_prior(robot, prob)])
    ident = identifiability(J0 / row_sigma[:, None], names, len(cal), scale_all, rtol, prior_all)
    est = ident.identifiable
    nominal = Nominal(
        robot,
        pm,
        prob,
        state0,
        y0,
        J_all,
        keep,
        tuple(pm.names[k] for k in np.flatnonzero(gaps > GAP_TOL)),
        ident,
        keep[np.sort(est[est < n_rob])],
        np.sort(est[est >= n_rob]) - n_rob,
        row_sigma,
        tolerance_error(J_all[:, :, : pm.size], tolerance),
        sigma,
    )
    if cal.position is not None and np.any(
        np.linalg.norm(cal.position - positions0, axis=1) > 100.0 * robot.length_scale
    ):
        _check_far(robot, cal, positions0, nominal.cause())
    _check_poses(robot, pm, cal, state0, keep, prob, J0, ident, n_val, holdout)
    return nominal


def parameter_scale(robot: Robot, model: ParameterModel) -> np.ndarray:
    """Scale of each parameter [m per unit]: 1 for lengths, the robot's size for angles and gains.

    Makes parameters of different units commensurate (step sizes, observability indices).
    """
    L = robot.length_scale
    return np.array([1.0 if u == "m" else L for u in model.units])


def _prior(model: ParameterModel, prior: tuple[float, float, float]) -> np.ndarray:
    return model.tolerances(float(prior[0]), float(prior[1]), float(prior[2]))


def _check_far(robot: Robot, m: Measurements, positions: np.ndarray, cause: str) -> None:
    """Refuse a measured position more than 100 robot sizes from the nominal model's."""
    if m.position is None:
        return
    gap = np.linalg.norm(m.position - positions, axis=1)
    far = np.flatnonzero(gap > 100.0 * robot.length_scale)
    if far.size:
        i = int(far[0])
        raise InvalidInputError(
            "measurements",
            f"{m.where(i)}: the measured position lies {gap[i]:.3g} m from the nominal "
            f"{robot.name}'s, more than 100 times its size ({robot.length_scale:.3g} m): "
            + (
                f"likely cause: {cause}"
                if cause
                else "a unit or frame error (positions in metres, in the robot's world frame)"
            ),
        )


def _nuisance_names(m: Measurements, groups: np.ndarray) -> tuple[str, ...]:
    if m.kind == "point":
        return tuple(f"point{g}.{c}" for g in groups for c in "xyz")
    if m.kind == "plane":
        return tuple(f"plane{g}.{c}" for g in groups for c in ("tilt1", "tilt2", "offset"))
    return ()


def _nuisance_scale(robot: Robot, prob: Problem) -> np.ndarray:
    if prob.m.kind == "plane":
        return np.tile([robot.length_scale, robot.length_scale, 1.0], prob.groups.size)
    return np.ones(prob.n_nuis)


def _nuisance_prior(robot: Robot, prob: Problem) -> np.ndarray:
    """Prior scale of the unknowns of implicit measurements: a metre, a radian (no prior)."""
    if prob.m.kind == "plane":
        return np.tile([1.0, 1.0, robot.length_scale], prob.groups.size)
    return np.full(prob.n_nuis, robot.length_scale)


def _structural_rank(
    robot: Robot, model: ParameterModel, m: Measurements, qs: list[np.ndarray], keep: np.ndarray
) -> int:
    """Rank the model reaches on many configurations interpolated between the measured ones."""
    rng = np.random.default_rng(1)
    n = max(2 * model.size // max(m.rows, 1) + 6, 12)
    rows = []
    n_meas = len(m)
    for _ in range(n):
        i, j = rng.integers(n_meas, size=2)
        t = rng.uniform(0.0, 1.0)
        qa = (1.0 - t) * m.qa[i] + t * m.qa[j]
        qa = qa + rng.normal(0.0, 0.02, qa.size) * robot.actuator_scale
        try:
            q = forward_geometry(robot, qa, q_init=qs[i], check_limits=False).q
            sens = pose_sensitivity(robot, q, model)
            if m.kind == "joints":
                assert sens.joints is not None
                ids = [robot.model.getJointId(j) for j in m.joints]
                K = sens.joints[[robot.model.joints[k].idx_v for k in ids]]
            else:
                K = sens.K[: min(m.rows, 6) if m.kind != "plane" else 3]
        except PkdynError:
            continue
        rows.append(K[:, keep])
    if not rows:
        return 0
    return numerics.column_basis(np.vstack(rows), RTOL).rank


def _check_poses(
    robot: Robot,
    pm: ParameterModel,
    cal: Measurements,
    state0: State,
    keep: np.ndarray,
    prob: Problem,
    J0: np.ndarray,
    ident: Identifiability,
    n_val: int,
    holdout: float,
) -> None:
    """Warn about poses that identify less than varied poses would; refuse too few values."""
    n_values = len(cal) * cal.rows
    own = numerics.column_basis(J0, RTOL).rank  # what these poses can tell apart, noise aside
    if own < min(n_values, keep.size + prob.n_nuis):
        r_struct = _structural_rank(robot, pm, cal, state0.qs, keep) + prob.n_nuis
        if own < r_struct:
            warnings.warn(
                f"these {len(cal)} poses identify {own} of the {r_struct} parameters that "
                f"poses spread over the workspace would ({pm.kind} model): the others are held "
                "at nominal; measure more varied poses (pkdyn.calibration.selection)",
                stacklevel=3,
            )
    if ident.rank >= n_values or n_values <= keep.size + prob.n_nuis:
        r_struct = _structural_rank(robot, pm, cal, state0.qs, keep) + prob.n_nuis
        if n_values <= r_struct:
            need = math.ceil((r_struct + 1) / cal.rows)
            n_total = need if n_val == 0 else math.ceil(need / (1.0 - holdout))
            raise InvalidInputError(
                "measurements",
                f"{len(cal)} calibration poses give {n_values} measured values for "
                f"{r_struct} identifiable parameters ({pm.kind} model, {cal.kind} "
                f"measurements): measure at least {need} poses"
                + (f" ({n_total} with the {holdout:.0%} hold-out)" if n_val else ""),
            )
