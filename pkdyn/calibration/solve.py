"""Geometric calibration of any loaded robot: the procedure (:func:`calibrate`).

:func:`calibrate` estimates the errors ``p`` of a :class:`~pkdyn.precision.parameters.
ParameterModel` (placements, family shortcuts or family dimensions, actuator offsets and gains)
from :class:`~pkdyn.calibration.measurements.Measurements`:

1. the readings become the nominal robot's joint coordinates (:meth:`pkdyn.Robot.
   joint_coordinates`: a description calibrated before has its gains applied); the
   measurements are split into a calibration set and a held-out validation set (``holdout``,
   within each group for implicit kinds), or a validation set is given;
2. the nominal robot's forward geometry at the calibration readings gives the configurations,
   and the problem (:mod:`~pkdyn.calibration.problem`) the identification Jacobian;
   parameters the mechanism cannot absorb (an over-constrained loop) are held at zero; the
   others are analysed by :func:`~pkdyn.calibration.identifiability.identifiability`: only the
   identifiable subset is estimated, the unidentifiable parameters are reported with the
   combination that absorbs them and held at zero (the nominal value), never invented;
3. the estimator (:func:`~pkdyn.calibration.robust.robust_fit`: robust Levenberg-Marquardt
   with a weakly informative prior) on the residuals *model minus measurement*, each
   evaluation rebuilding the robot with the current parameters and solving its forward
   geometry at the readings (warm-started: the assembly mode is kept), the Jacobian exact;
4. standard deviations of the estimates, errors before (nominal model) and after on both sets;
5. the trust rules (:mod:`~pkdyn.calibration.trust`): a calibration that did not converge, whose
   residuals exceed a multiple of the noise or whose corrections exceed a multiple of the
   tolerances raises :class:`pkdyn.CalibrationError` naming the likely cause
   (:mod:`~pkdyn.calibration.diagnosis`), unless ``accept``.

A weakly informative prior (:data:`PRIOR`: errors of a centimetre, 6 degrees, 1 % of gain)
is added to the least squares: it changes nothing the measurements determine, and keeps the
directions they barely see (an identifiable but ill-conditioned combination, e.g. with a few
fixed points in self-calibration) near the nominal robot instead of wandering with the noise.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np

from pkdyn.calibration.diagnosis import likely_cause, tolerance_error
from pkdyn.calibration.identifiability import RTOL, identifiability
from pkdyn.calibration.measurements import Measurements
from pkdyn.calibration.problem import GAP_TOL, Problem, State, nominal_configurations
from pkdyn.calibration.result import CalibrationResult, ErrorStats, error_stats
from pkdyn.calibration.robust import ROBUST, robust_fit
from pkdyn.calibration.trust import (
    CORRECTION_LIMIT,
    RESIDUAL_LIMIT,
    parameter_tolerances,
    untrusted_reasons,
)
from pkdyn.exceptions import CalibrationError, InvalidInputError, PkdynError
from pkdyn.identifiability import Identifiability
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel, parameter_model
from pkdyn.precision.sensitivity import pose_sensitivity
from pkdyn.threads import one_blas_thread
from solvers import numerics

__all__ = [
    "PRIOR",
    "ROBUST",
    "CalibrationResult",
    "ErrorStats",
    "calibrate",
    "parameter_scale",
]

PRIOR = (0.01, 0.1, 0.01)
"""Default prior standard deviations of the errors (length [m], angle [rad], gain): a
centimetre, 6 degrees, 1 %: far wider than any tolerance, so it only steadies the directions
the measurements barely see."""


def parameter_scale(robot: Robot, model: ParameterModel) -> np.ndarray:
    """Scale of each parameter [m per unit]: 1 for lengths, the robot's size for angles and gains.

    Makes parameters of different units commensurate (step sizes, observability indices).
    """
    L = robot.length_scale
    return np.array([1.0 if u == "m" else L for u in model.units])


def _split(m: Measurements, holdout: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    n = len(m)
    if not 0.0 <= holdout < 1.0:
        raise InvalidInputError("holdout", f"{holdout}: give a fraction in [0, 1)")
    rng = np.random.default_rng(seed)
    if holdout == 0.0:
        return np.arange(n), np.zeros(0, dtype=int)
    groups = (
        [np.arange(n)]
        if m.group is None
        else [np.flatnonzero(m.group == g) for g in np.unique(m.group)]
    )
    val: list[int] = []
    for idx in groups:
        k = int(round(holdout * idx.size))
        val += list(rng.choice(idx, k, replace=False)) if k else []
    val_arr = np.sort(np.array(val, dtype=int))
    return np.setdiff1d(np.arange(n), val_arr), val_arr


def _sigma(robot: Robot, noise: float | Sequence[float] | None) -> tuple[tuple[float, float], bool]:
    from pkdyn.inputs import vector

    if noise is None:
        s = 1e-5
        return (s, s / robot.length_scale), False
    try:
        arr = vector("noise", noise, (1, 2))
    except InvalidInputError:
        arr = np.array([np.nan])
    if arr.size not in (1, 2) or not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise InvalidInputError(
            "noise",
            f"{noise!r:.60}: give the position noise [m] and optionally the orientation "
            "noise [rad], > 0",
        )
    if arr[0] > robot.length_scale or (arr.size == 2 and arr[1] > math.pi):
        raise InvalidInputError(
            "noise",
            f"{noise!r:.60}: a measurement noise larger than the robot ({robot.length_scale:.3g} "
            "m) or than pi rad measures nothing; give the standard deviation [m] [rad]",
        )
    s_pos = float(arr[0])
    s_rot = float(arr[1]) if arr.size == 2 else s_pos / robot.length_scale
    return (s_pos, s_rot), True


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


def _prior(model: ParameterModel, prior: tuple[float, float, float]) -> np.ndarray:
    return model.tolerances(float(prior[0]), float(prior[1]), float(prior[2]))


def _robot_identifiability(
    ident: Identifiability, keep: np.ndarray, n_rob: int, pm: ParameterModel
) -> Identifiability:
    """The analysis re-indexed on the full parameter model (nuisance unknowns named after)."""
    names = pm.names + ident.names[n_rob:]
    units = tuple(pm.units) + ("m",) * (len(ident.names) - n_rob)

    def full(i: int) -> int:
        return int(keep[i]) if i < n_rob else pm.size + i - n_rob

    ids = np.array([full(int(i)) for i in ident.identifiable], dtype=int)
    un = np.array([full(int(i)) for i in ident.unidentifiable], dtype=int)
    return Identifiability(  # (the parameters the mechanism cannot absorb are in neither)
        tuple(names),
        ids,
        un,
        ident.coefficients,
        ident.r_diag,
        np.array([full(int(i)) for i in ident.weak], dtype=int),
        units,
        ident.singular_values,
        ident.indices,
        ident.poses,
    )


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


def _check_options(
    robot: Robot,
    measurements: Measurements,
    model: ParameterModel | str,
    validation: Measurements | None,
    robust: str,
    prior: tuple[float, float, float] | None,
) -> tuple[float, float, float] | None:
    from pkdyn.inputs import instance, vector

    instance("robot", robot, Robot, "a Robot (pkdyn.load)")
    instance(
        "measurements", measurements, Measurements, "Measurements (pkdyn.calibration.read_csv)"
    )
    if validation is not None:
        instance("validation", validation, Measurements, "Measurements or None")
        if validation.kind != measurements.kind:
            raise InvalidInputError("validation", "must be measurements of the same kind")
    if robust not in ROBUST:
        raise InvalidInputError("robust", f"'{robust}': use {', '.join(ROBUST)}")
    if prior is not None:
        pr = vector("prior", prior, 3, "m, rad, -", bound=1e3)
        if np.any(pr <= 0.0):
            raise InvalidInputError("prior", f"{tuple(pr)}: give three standard deviations > 0")
        prior = (float(pr[0]), float(pr[1]), float(pr[2]))
    if not isinstance(model, str | ParameterModel):
        instance("model", model, (str, ParameterModel), "a ParameterModel or its kind's name")
    for name, m in (("measurements", measurements), ("validation", validation)):
        if m is not None and m.qa.shape[1] != len(robot.actuators):
            raise InvalidInputError(
                name,
                f"{m.qa.shape[1]} actuator readings per row; {robot.name} has "
                f"{len(robot.actuators)} ({', '.join(robot.actuator_names)})",
            )
    return prior


def _fallback_cause(reasons: list[str], known: bool) -> str:
    """The likely cause when the data's units and frame are not it."""
    text = " ".join(reasons)
    if "corrections" in text:
        return (
            "the nominal robot differs from the measured one by more than manufacturing "
            "errors (check --param or the description), or the tolerances are tighter than "
            "its errors (--tolerance)"
        )
    if "residuals" in text or "outliers" in text:
        return (
            "the noise is larger than stated (--noise)"
            if known
            else "noisy measurements (state --noise)"
        ) + ", or the parameter model cannot represent the robot (--model placements)"
    return (
        "poses near a singularity, or too few and too similar poses (pkdyn.calibration.selection)"
    )


@one_blas_thread
def calibrate(
    robot: Robot,
    measurements: Measurements,
    model: ParameterModel | str = "auto",
    noise: float | Sequence[float] | None = None,
    holdout: float = 0.2,
    validation: Measurements | None = None,
    robust: str = "huber",
    rtol: float = RTOL,
    gains: bool = False,
    max_iter: int = 30,
    seed: int = 0,
    prior: tuple[float, float, float] | None = PRIOR,
    tolerance: Sequence[float] | np.ndarray | None = None,
    accept: bool = False,
    residual_limit: float = RESIDUAL_LIMIT,
    correction_limit: float = CORRECTION_LIMIT,
) -> CalibrationResult:
    """Identify a robot's geometric errors from measurements (module docstring).

    Args:
        robot: The nominal robot.
        measurements: The measurements (:func:`pkdyn.calibration.read_csv`): actuator
            readings and what was measured.
        model: A parameter model, or its name for :func:`pkdyn.precision.parameters.
            parameter_model` (``auto``: family shortcuts for the Delta and Gough-Stewart,
            else every placement).
        noise: Measurement standard deviation: position [m], or ``(position [m], orientation
            [rad])``; ``None``: unknown (weights from ``1e-5`` m, the robust scale estimated).
        holdout: Fraction of the measurements held out for validation (ignored when
            ``validation`` is given).
        validation: Separate validation measurements (same kind): errors before and after.
        robust: ``huber``, ``cauchy`` or ``none``.
        rtol: Identifiability threshold (:data:`pkdyn.calibration.identifiability.RTOL`).
        gains: With a model name: add one relative gain per actuator.
        max_iter: Largest number of Levenberg-Marquardt iterations.
        seed: Seed of the hold-out split.
        prior: Prior standard deviations of the errors ``(length [m], angle [rad], gain)``
            (:data:`PRIOR`); ``None``: none.
        tolerance: The tolerances corrections are judged against: ``(length [m], angle [rad]
            [, gain])`` or one per parameter (default :func:`pkdyn.calibration.trust.
            default_tolerance`).
        accept: Return a calibration the trust rules refuse instead of raising (its
            ``reasons`` say why).
        residual_limit: Largest residual RMS trusted, times the stated noise.
        correction_limit: Largest correction trusted, times its tolerance.

    Returns:
        The calibration.

    Raises:
        InvalidInputError: Bad options, measurements the nominal robot cannot be assembled at,
            or fewer measured values than identifiable parameters (the message says how many
            poses are needed).
        CalibrationError: A calibration not to trust (:mod:`pkdyn.calibration.trust`), unless
            ``accept``; the message names the reasons and the likely cause.

    """
    from pkdyn.inputs import count, flag, positive, real
    from pkdyn.inputs import seed as _seed

    prior = _check_options(robot, measurements, model, validation, robust, prior)
    holdout = real("holdout", holdout)
    rtol = positive("rtol", rtol, bound=0.5)
    gains = flag("gains", gains)
    accept = flag("accept", accept)
    max_iter = count("max_iter", max_iter, 1, 10_000)
    seed = _seed("seed", seed)
    residual_limit = positive("residual_limit", residual_limit, "x the noise", bound=1e6)
    correction_limit = positive("correction_limit", correction_limit, "x the tolerance", bound=1e6)
    pm = parameter_model(robot, model, gains) if isinstance(model, str) else model
    tol = parameter_tolerances(robot, pm, tolerance)
    sigma, known = _sigma(robot, noise)
    # readings -> the nominal robot's joint coordinates (the one readings rule); the relative
    # gains estimated here multiply them
    meas = measurements.with_readings(robot.joint_coordinates(measurements.qa))
    val_in = (
        None
        if validation is None
        else validation.with_readings(robot.joint_coordinates(validation.qa))
    )
    if val_in is not None:
        cal_rows, val_rows = np.arange(len(meas)), np.arange(len(val_in))
        cal, val = meas, val_in
    else:
        cal_rows, val_rows = _split(meas, holdout, seed)
        cal, val = meas.subset(cal_rows), meas.subset(val_rows)
    if len(cal) == 0:
        raise InvalidInputError("measurements", "no measurement left for the calibration")
    cal.check_groups()
    prob = Problem(robot, pm, cal, sigma, nominal_configurations(robot, cal))
    row_sigma = np.tile(prob.row_sigma(), len(cal))

    # the nominal robot: identifiability, and how far it is from the measurements
    zero = np.zeros(pm.size)
    state0 = prob.evaluate(zero)
    positions0 = np.array([M.translation for M in state0.poses])
    y0, planes = prob.fit_nuisance(positions0)
    prob = prob.with_planes(planes)
    J_all, gaps = prob.jacobian(state0, zero, y0, np.arange(pm.size))
    bound = tolerance_error(J_all[:, :, : pm.size], tol)
    rotations0 = np.array([M.rotation for M in state0.poses])

    def cause() -> str:
        return likely_cause(
            robot, cal.kind, cal.position, positions0, cal.rpy, rotations0, bound, sigma
        )

    if cal.position is not None and np.any(
        np.linalg.norm(cal.position - positions0, axis=1) > 100.0 * robot.length_scale
    ):
        _check_far(robot, cal, positions0, cause())
    keep = np.flatnonzero(gaps <= GAP_TOL)
    not_assembling = tuple(pm.names[k] for k in np.flatnonzero(gaps > GAP_TOL))
    n_rob = keep.size
    J0 = np.concatenate([J_all[:, :, keep], J_all[:, :, pm.size :]], axis=2)
    J0 = J0.reshape(len(cal) * cal.rows, -1)
    names = tuple(pm.names[k] for k in keep) + _nuisance_names(cal, prob.groups)
    scale_all = np.concatenate([parameter_scale(robot, pm)[keep], _nuisance_scale(robot, prob)])
    prior_all = None
    if prior is not None:
        prior_all = np.concatenate([_prior(pm, prior)[keep], _nuisance_prior(robot, prob)])
    ident = identifiability(J0 / row_sigma[:, None], names, len(cal), scale_all, rtol, prior_all)
    _check_poses(robot, pm, cal, state0, keep, prob, J0, ident, val_rows.size, holdout)

    # the estimated unknowns: identifiable robot parameters, then nuisance unknowns
    est = ident.identifiable
    cols = keep[np.sort(est[est < n_rob])]
    nuis_cols = np.sort(est[est >= n_rob]) - n_rob

    def unpack(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = np.zeros(pm.size)
        p[cols] = z[: cols.size]
        y = y0.copy()
        y[nuis_cols] = y[nuis_cols] + z[cols.size :]
        return p, y

    def residual(z: np.ndarray, start: State) -> tuple[State, np.ndarray]:
        p, y = unpack(z)
        state = prob.evaluate(p, start)
        return state, prob.residuals(state, y).reshape(-1) / row_sigma

    def jacobian(z: np.ndarray, state: State) -> np.ndarray:
        p, y = unpack(z)
        J, _ = prob.jacobian(state, p, y, cols)
        J = J.reshape(len(cal) * cal.rows, -1)
        return np.hstack([J[:, : cols.size], J[:, cols.size :][:, nuis_cols]]) / row_sigma[:, None]

    pw = np.zeros(cols.size + nuis_cols.size)
    if prior is not None:  # weakly informative, on the robot's errors only
        pw[: cols.size] = 1.0 / _prior(pm, prior)[cols] ** 2
    z0 = np.zeros(cols.size + nuis_cols.size)
    J_start = np.hstack(
        [J_all.reshape(len(cal) * cal.rows, -1)[:, cols], J0[:, n_rob:][:, nuis_cols]]
    )
    fit = robust_fit(
        residual,
        jacobian,
        z0,
        state0,
        prob.residuals(state0, y0).reshape(-1) / row_sigma,
        J_start / row_sigma[:, None],
        pw,
        cal.rows,
        robust,
        known,
        max_iter,
    )
    p, y = unpack(fit.z)
    std = np.full(pm.size, np.nan)
    std[cols] = fit.std[: cols.size]
    res_before = prob.residuals(state0, y0)
    res_after = prob.residuals(fit.state, y)
    before, after = error_stats(cal.kind, res_before), error_stats(cal.kind, res_after)
    val_before = val_after = None
    val_res = None
    unreachable = ""
    if len(val):
        vprob = Problem(
            robot, pm, val, sigma, nominal_configurations(robot, val), planes, prob.groups
        )
        vstate0 = vprob.evaluate(zero)
        val_before = error_stats(val.kind, vprob.residuals(vstate0, y0))
        try:
            vstate = vprob.evaluate(p, vstate0)
        except PkdynError as err:
            unreachable = (
                f"the calibrated robot cannot be assembled at the held-out readings ({err})"
            )
        else:
            val_res = (vprob.residuals(vstate0, y0), vprob.residuals(vstate, y))
            val_after = error_stats(val.kind, val_res[1])

    # trust
    inliers = np.repeat(fit.weights >= 0.5, cal.rows)
    kept = fit.r[inliers] if inliers.any() else fit.r  # (all outliers: all of them)
    inlier_scale = float(np.sqrt(np.mean(kept**2)))
    reasons = untrusted_reasons(
        converged=fit.converged,
        iterations=fit.iterations,
        inlier_scale=inlier_scale,
        outliers=float(np.mean(fit.weights < 0.5)),
        known=known,
        after_rms=after.position_rms,
        robot=robot,
        names=pm.names,
        units=pm.units,
        p=p,
        estimated=cols,
        tolerance=tol,
        validation=None
        if val_after is None
        else (
            val_after.rms,
            max(after.rms, sigma[1] if cal.kind == "joints" else sigma[0]),
            cal.kind,
        ),
        residual_limit=residual_limit,
        correction_limit=correction_limit,
    ) + ([unreachable] if unreachable else [])
    why = (cause() or _fallback_cause(reasons, known)) if reasons else ""
    result = CalibrationResult(
        robot=fit.state.perturbed.robot,
        gains=fit.state.perturbed.gains,
        nominal=robot,
        model=pm,
        p=p,
        std=std,
        identifiability=_robot_identifiability(ident, keep, n_rob, pm),
        not_assembling=not_assembling,
        nuisance=prob.nuisance_dict(y),
        sigma=sigma,
        scale=fit.scale,
        before=before,
        after=after,
        validation_before=val_before,
        validation_after=val_after,
        weights=fit.weights,
        calibration_rows=cal_rows,
        validation_rows=val_rows,
        iterations=fit.iterations,
        converged=fit.converged,
        kind=cal.kind,
        noise_known=known,
        tolerance=tol,
        residuals_before=res_before,
        residuals_after=res_after,
        validation_residuals=val_res,
        reasons=tuple(reasons),
        cause=why,
        lines=cal.lines,
    )
    if reasons and not accept:
        raise CalibrationError(robot.name, reasons, why, result)
    return result


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
