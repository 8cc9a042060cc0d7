"""Geometric calibration of closed-loop robots.

- :mod:`~pkdyn.calibration.measurements`: what was measured (full pose, position, or implicit:
  the platform on an unknown point or plane), CSV files;
- :mod:`~pkdyn.calibration.identifiability`: QR with pivoting, unidentifiable combinations,
  observability indices O1-O5 and the noise amplification index;
- :mod:`~pkdyn.calibration.solve`: robust Levenberg-Marquardt through the loops, held-out
  validation (:func:`calibrate`).

The parameter models and the identification Jacobian are those of :mod:`pkdyn.precision`
(placements, family shortcuts, family dimensions; :func:`pkdyn.precision.sensitivity.
pose_sensitivity`).

Layering: may import :mod:`pkdyn.precision` and everything below it.
"""

from pkdyn.calibration.identifiability import Identifiability, identifiability, observability
from pkdyn.calibration.measurements import Measurements, read_csv, write_csv
from pkdyn.calibration.solve import CalibrationResult, ErrorStats, calibrate

__all__ = [
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
