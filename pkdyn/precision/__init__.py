"""Precision of closed-loop robots (issue 26): how accurate, how stiff, how fast it rings.

- :mod:`~pkdyn.precision.parameters`: the placements manufacturing errors move, and parameter
  models of them (every placement, family shortcuts, family dimensions);
- :mod:`~pkdyn.precision.perturbation`: robots with those errors, built exactly;
- :mod:`~pkdyn.precision.sensitivity`: first-order sensitivity of the platform pose to actuator
  and geometric errors through the loops (shared with :mod:`pkdyn.calibration`);
- :mod:`~pkdyn.precision.accuracy`: error budgets (worst case, RMS, Monte Carlo, ranking of the
  tolerances) and pose-error maps.

Layering: may import :mod:`pkdyn.model`, :mod:`pkdyn.analysis`, :mod:`pkdyn.workspace` and
below; never design, calibration, viewer, plotting or the CLI.
"""
