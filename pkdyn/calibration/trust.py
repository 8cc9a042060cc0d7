"""When not to trust a calibration: the rules, and the tolerances they are judged against.

A calibration is **not trusted** (:func:`~pkdyn.calibration.calibrate` raises
:class:`pkdyn.CalibrationError` and ``pkdyn calibrate`` writes no model, unless it is told to
accept it) when

1. the fit did not converge;
2. its residuals exceed :data:`RESIDUAL_LIMIT` times the stated noise (RMS over the measurements
   the robust weights keep, in units of their standard deviations), or more than
   :data:`OUTLIER_LIMIT` of the measurements are outliers (weight below 1/2), or, noise not
   stated, the residual RMS exceeds :data:`UNSTATED_NOISE_LIMIT` of the robot's size;
3. a correction exceeds :data:`CORRECTION_LIMIT` times its tolerance (``tolerance``; default
   :func:`default_tolerance`): geometric errors are of the order of manufacturing tolerances,
   and a dimension changed by half its value is a measurement of another robot;
4. the calibrated model predicts held-out measurements worse than :data:`RESIDUAL_LIMIT` times
   the calibration measurements' error (an over-fit).

Each reason is stated with its figures; :func:`pkdyn.calibration.diagnosis.likely_cause` then
names the likely cause from the data (units, axis order, orientation convention, another
frame, another robot).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel
from pkdyn.units import quantity

__all__ = [
    "CORRECTION_LIMIT",
    "OUTLIER_LIMIT",
    "RESIDUAL_LIMIT",
    "UNSTATED_NOISE_LIMIT",
    "default_tolerance",
    "parameter_tolerances",
    "untrusted_reasons",
]

RESIDUAL_LIMIT = 3.0
"""Largest residual RMS accepted, times the stated noise."""

OUTLIER_LIMIT = 0.2
"""Largest fraction of outliers accepted."""

UNSTATED_NOISE_LIMIT = 1e-3
"""Largest position residual RMS accepted without a stated noise, times the robot's size."""

CORRECTION_LIMIT = 10.0
"""Largest correction accepted, times the parameter's tolerance."""


def default_tolerance(robot: Robot) -> tuple[float, float, float]:
    """The tolerances corrections are judged against when none is given.

    Lengths 0.5 % of the robot's size (:attr:`pkdyn.Robot.length_scale`; 4.2 mm for the
    default Delta), angles 0.5 degree, gains 0.5 %.

    Returns:
        ``(length [m], angle [rad], gain [-])``.

    """
    return (5e-3 * robot.length_scale, float(np.deg2rad(0.5)), 5e-3)


def parameter_tolerances(
    robot: Robot, model: ParameterModel, tolerance: Sequence[float] | np.ndarray | None
) -> np.ndarray:
    """One tolerance per parameter of ``model``.

    Args:
        robot: The nominal robot.
        model: The parameter model.
        tolerance: ``None`` (:func:`default_tolerance`), ``(length [m], angle [rad])``,
            ``(length, angle, gain)``, or one value per parameter, each > 0.

    Returns:
        Tolerances (n_par,) [m, rad, -].

    Raises:
        InvalidInputError: Not 2, 3 or n_par values > 0.

    """
    from pkdyn.inputs import vector

    if tolerance is None:
        return model.tolerances(*default_tolerance(robot))
    t = vector("tolerance", tolerance, None, "m, rad, -", bound=1e3)
    if np.any(t <= 0.0):
        raise InvalidInputError("tolerance", f"{t.tolist()}: give tolerances > 0")
    if t.size == model.size:
        return t
    if t.size in (2, 3):
        gain = float(t[2]) if t.size == 3 else default_tolerance(robot)[2]
        return model.tolerances(float(t[0]), float(t[1]), gain)
    raise InvalidInputError(
        "tolerance",
        f"{t.size} values: give (length [m], angle [rad] [, gain]) or one per parameter "
        f"({model.size})",
    )


def _correction(value: float, unit: str) -> str:
    if unit == "m":
        return quantity(value, "m")
    if unit == "rad":
        return f"{np.rad2deg(value):.3g} deg"
    return f"{100 * value:.3g} %"


def untrusted_reasons(
    *,
    converged: bool,
    iterations: int,
    inlier_scale: float,
    outliers: float,
    known: bool,
    after_rms: float,
    robot: Robot,
    names: Sequence[str],
    units: Sequence[str],
    p: np.ndarray,
    estimated: np.ndarray,
    tolerance: np.ndarray,
    validation: tuple[float, float, str] | None,
    residual_limit: float = RESIDUAL_LIMIT,
    correction_limit: float = CORRECTION_LIMIT,
) -> list[str]:
    """The reasons not to trust a calibration (module docstring); empty when trusted.

    Args:
        converged: Whether the fit converged.
        iterations: Its iterations.
        inlier_scale: RMS of the weighted residuals of the measurements the robust weights keep
            (units of their standard deviations).
        outliers: Fraction of the measurements that are outliers.
        known: The noise was stated.
        after_rms: RMS error of the calibrated model on the calibration measurements [m] (of
            positions or distances; 0 for joints).
        robot: The nominal robot.
        names: Parameter names (n_par,).
        units: Their units (n_par,).
        p: Corrections (n_par,).
        estimated: Indices of the estimated parameters.
        tolerance: Tolerances (n_par,).
        validation: ``(RMS after on the held-out measurements, RMS after on the calibration
            ones, the measurement kind)``, or ``None``.
        residual_limit: :data:`RESIDUAL_LIMIT`.
        correction_limit: :data:`CORRECTION_LIMIT`.

    Returns:
        One phrase per reason.

    """
    out = []
    if not converged:
        out.append(f"the fit did not converge in {iterations} iterations")
    if known and inlier_scale > residual_limit:
        out.append(
            f"the residuals are {inlier_scale:.3g} times the stated noise (at most "
            f"{residual_limit:g})"
        )
    if outliers > OUTLIER_LIMIT:
        out.append(f"{100 * outliers:.0f} % of the measurements are outliers")
    if not known and after_rms > UNSTATED_NOISE_LIMIT * robot.length_scale:
        out.append(
            f"the residuals are {quantity(after_rms, 'm')} RMS, more than "
            f"{UNSTATED_NOISE_LIMIT:g} of the robot's size with no noise stated (give --noise "
            "if the measurements are that noisy)"
        )
    ratio = np.abs(p[estimated]) / tolerance[estimated]
    big = np.flatnonzero(ratio > correction_limit)
    if big.size:
        order = big[np.argsort(-ratio[big])][:3]
        items = ", ".join(
            f"{names[j]} {_correction(float(p[j]), units[j])} ({ratio[k]:.3g} x its tolerance)"
            for k, j in ((int(k), int(estimated[k])) for k in order)
        )
        more = f" and {big.size - order.size} more" if big.size > order.size else ""
        out.append(f"corrections beyond {correction_limit:g} times the tolerances: {items}{more}")
    if validation is not None:
        val, cal, kind = validation
        if val > residual_limit * max(cal, 1e-300) and val > 0.0:
            figure = f"{val:.3g} rad or m" if kind == "joints" else quantity(val, "m")
            out.append(
                f"the held-out measurements are predicted to {figure} RMS, "
                f"{val / max(cal, 1e-300):.3g} times the calibration measurements' error"
            )
    return out
