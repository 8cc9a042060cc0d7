"""Geometric calibration of any loaded robot: the procedure (:func:`calibrate`).

:func:`calibrate` estimates the errors ``p`` of a :class:`~pkdyn.precision.parameters.
ParameterModel` (placements, family shortcuts or family dimensions, actuator offsets and gains)
from :class:`~pkdyn.calibration.measurements.Measurements`:

1. the readings become the nominal robot's joint coordinates (:meth:`pkdyn.Robot.
   joint_coordinates`: a description calibrated before has its gains applied); the
   measurements are split into a calibration set and a held-out validation set (``holdout``,
   within each group for implicit kinds), or a validation set is given;
2. the nominal robot (:mod:`~pkdyn.calibration.analysis`): its forward geometry at the
   calibration readings gives the configurations, and the problem
   (:mod:`~pkdyn.calibration.problem`) the identification Jacobian;
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
from collections.abc import Sequence

import numpy as np

from pkdyn.calibration.analysis import Nominal, analyse, parameter_scale
from pkdyn.calibration.identifiability import RTOL
from pkdyn.calibration.measurements import Measurements
from pkdyn.calibration.problem import Problem, nominal_configurations
from pkdyn.calibration.result import CalibrationResult, ErrorStats, error_stats
from pkdyn.calibration.robust import ROBUST, RobustFit
from pkdyn.calibration.trust import (
    CORRECTION_LIMIT,
    RESIDUAL_LIMIT,
    parameter_tolerances,
    untrusted_reasons,
)
from pkdyn.exceptions import CalibrationError, InvalidInputError, PkdynError
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel, parameter_model
from pkdyn.threads import one_blas_thread

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
    limits = (
        positive("residual_limit", residual_limit, "x the noise", bound=1e6),
        positive("correction_limit", correction_limit, "x the tolerance", bound=1e6),
    )
    pm = parameter_model(robot, model, gains) if isinstance(model, str) else model
    tol = parameter_tolerances(robot, pm, tolerance)
    sigma, known = _sigma(robot, noise)
    cal, val, cal_rows, val_rows = _calibration_and_validation(
        robot, measurements, validation, holdout, seed
    )
    cal.check_groups()
    nominal = analyse(robot, pm, cal, sigma, tol, rtol, prior, val_rows.size, holdout)
    fit = nominal.fit(robust, known, max_iter, prior)
    prob, state0, y0 = nominal.problem, nominal.state, nominal.y0
    cols = nominal.cols
    p, y = nominal.unpack(fit.z)
    std = np.full(pm.size, np.nan)
    std[cols] = fit.std[: cols.size]
    res_before = prob.residuals(state0, y0)
    res_after = prob.residuals(fit.state, y)
    before, after = error_stats(cal.kind, res_before), error_stats(cal.kind, res_after)
    val_before, val_after, val_res, unreachable = _validate(robot, pm, val, nominal, p, y)
    reasons = _reasons(
        robot, pm, cal.kind, fit, after, p, cols, tol, val_after, sigma, known, limits
    ) + ([unreachable] if unreachable else [])
    why = (nominal.cause() or _fallback_cause(reasons, known)) if reasons else ""
    result = CalibrationResult(
        robot=fit.state.perturbed.robot,
        gains=fit.state.perturbed.gains,
        nominal=robot,
        model=pm,
        p=p,
        std=std,
        identifiability=nominal.full_identifiability(),
        not_assembling=nominal.not_assembling,
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


def _calibration_and_validation(
    robot: Robot,
    measurements: Measurements,
    validation: Measurements | None,
    holdout: float,
    seed: int,
) -> tuple[Measurements, Measurements, np.ndarray, np.ndarray]:
    """The calibration and validation sets, readings as the nominal robot's joint coordinates.

    The one readings rule (:meth:`pkdyn.Robot.joint_coordinates`): a robot calibrated before has
    its gains applied; the relative gains estimated here multiply them.
    """
    meas = measurements.with_readings(robot.joint_coordinates(measurements.qa))
    if validation is not None:
        val = validation.with_readings(robot.joint_coordinates(validation.qa))
        groups = np.zeros(0) if meas.group is None else meas.group
        if val.group is not None and not np.isin(val.group, groups).all():
            raise InvalidInputError(
                "validation", "holds groups the calibration measurements do not (their unknowns)"
            )
        return meas, val, np.arange(len(meas)), np.arange(len(val))
    cal_rows, val_rows = _split(meas, holdout, seed)
    return meas.subset(cal_rows), meas.subset(val_rows), cal_rows, val_rows


def _validate(
    robot: Robot,
    pm: ParameterModel,
    val: Measurements,
    nominal: Nominal,
    p: np.ndarray,
    y: np.ndarray,
) -> tuple[ErrorStats | None, ErrorStats | None, tuple[np.ndarray, np.ndarray] | None, str]:
    """Errors of the nominal and the calibrated robot on the validation set.

    Returns:
        The errors before and after, the residuals ``(before, after)``, and why the calibrated
        robot cannot be evaluated there (``""``: it can).

    """
    if not len(val):
        return None, None, None, ""
    prob = nominal.problem
    vprob = Problem(
        robot, pm, val, prob.sigma, nominal_configurations(robot, val), prob.planes, prob.groups
    )
    vstate0 = vprob.evaluate(np.zeros(pm.size))
    before = vprob.residuals(vstate0, nominal.y0)
    try:
        vstate = vprob.evaluate(p, vstate0)
    except PkdynError as err:
        why = f"the calibrated robot cannot be assembled at the held-out readings ({err})"
        return error_stats(val.kind, before), None, None, why
    after = vprob.residuals(vstate, y)
    return error_stats(val.kind, before), error_stats(val.kind, after), (before, after), ""


def _reasons(
    robot: Robot,
    pm: ParameterModel,
    kind: str,
    fit: RobustFit,
    after: ErrorStats,
    p: np.ndarray,
    cols: np.ndarray,
    tol: np.ndarray,
    val_after: ErrorStats | None,
    sigma: tuple[float, float],
    known: bool,
    limits: tuple[float, float],
) -> list[str]:
    """The trust rules (:mod:`pkdyn.calibration.trust`) on a fit."""
    inliers = np.repeat(fit.weights >= 0.5, fit.r.size // max(fit.weights.size, 1))
    kept = fit.r[inliers] if inliers.any() else fit.r  # (all outliers: all of them)
    floor = sigma[1] if kind == "joints" else sigma[0]
    return untrusted_reasons(
        converged=fit.converged,
        iterations=fit.iterations,
        inlier_scale=float(np.sqrt(np.mean(kept**2))),
        outliers=float(np.mean(fit.weights < 0.5)),
        known=known,
        after_rms=after.position_rms,
        robot=robot,
        names=pm.names,
        units=pm.units,
        p=p,
        estimated=cols,
        tolerance=tol,
        validation=None if val_after is None else (val_after.rms, max(after.rms, floor), kind),
        residual_limit=limits[0],
        correction_limit=limits[1],
    )
