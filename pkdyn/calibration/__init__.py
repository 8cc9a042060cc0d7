"""Geometric calibration of closed-loop robots.

- :mod:`~pkdyn.calibration.measurements`: what was measured (full pose, position, or implicit:
  the platform on an unknown point or plane, encoders on passive joints), table files;
- :mod:`~pkdyn.calibration.identifiability`: which parameters the poses identify (the project's
  one analysis, :mod:`pkdyn.identifiability`), observability indices O1-O5 and the noise
  amplification index;
- :mod:`~pkdyn.calibration.problem`: residuals and Jacobian of the measurements through the
  loops; :mod:`~pkdyn.calibration.analysis`: what the nominal robot says of them (the fit it
  sets up);
- :mod:`~pkdyn.calibration.robust`: the estimator (robust Levenberg-Marquardt with a weakly
  informative prior);
- :mod:`~pkdyn.calibration.solve`: the procedure (:func:`calibrate`), held-out validation;
- :mod:`~pkdyn.calibration.trust` and :mod:`~pkdyn.calibration.diagnosis`: when not to trust a
  calibration, and the likely cause (units, axis order, orientation convention, the nominal
  robot);
- :mod:`~pkdyn.calibration.result`: :class:`CalibrationResult` (table, JSON, plot, the
  calibrated description: :mod:`~pkdyn.calibration.writer`);
- :mod:`~pkdyn.calibration.selection` and :mod:`~pkdyn.calibration.planner`: where to measure,
  and how many poses and how accurate a measurement a target needs (simulated with the same
  estimator).

The parameter models and the identification Jacobian are those of :mod:`pkdyn.precision`
(placements, family shortcuts, family dimensions; :func:`pkdyn.precision.sensitivity.
pose_sensitivity`).

Layering: may import :mod:`pkdyn.precision`, :mod:`pkdyn.identification` and everything below
them.
"""

from pkdyn.calibration.identifiability import Identifiability, identifiability, observability
from pkdyn.calibration.measurements import Measurements, read_csv, write_csv
from pkdyn.calibration.result import CalibrationResult, ErrorStats
from pkdyn.calibration.solve import calibrate
from pkdyn.exceptions import CalibrationError

__all__ = [
    "CalibrationError",
    "CalibrationResult",
    "ErrorStats",
    "Identifiability",
    "Measurements",
    "calibrate",
    "identifiability",
    "observability",
    "read_csv",
    "write_csv",
]
