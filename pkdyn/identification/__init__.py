"""Dynamic identification of closed-loop robots: masses, inertias, friction, rotor inertias.

The actuator efforts of a closed-loop robot are linear in its dynamic parameters through the
loop equations (:mod:`~pkdyn.identification.regressor`); from one measured motion (actuator
positions, optionally rates and accelerations, and efforts) :func:`identify` finds the base
parameters with their standard deviations and a physically consistent full set, which
:meth:`IdentificationResult.write_urdf` writes back as a description that loads like any other.

Modules: :mod:`~.parameters` (standard parameters and groups), :mod:`~.motion` (joint motions
from actuator samples), :mod:`~.regressor` (the closed-loop regressor), :mod:`~.base` (base
parameters, :mod:`pkdyn.identifiability`), :mod:`~.structure` (what any motion can identify),
:mod:`~.checks` (limits, motion, closures of the recorded readings), :mod:`~.estimation`
(weighted least squares, and what the motion excites), :mod:`~.magnitudes` (plausible sizes of
the parameters), :mod:`~.physical` (physically consistent parameters), :mod:`~.filtering` (rates
from positions), :mod:`~.excitation` (optimal excitation trajectories), :mod:`~.data` (the table
columns), :mod:`~.identify` (the procedure), :mod:`~.result` and :mod:`~.writer`.

Layering: uses :mod:`pkdyn.model`, :mod:`pkdyn.dynamics` and :mod:`solvers`.
"""

from pkdyn.identification.data import Measurements, read_measurements
from pkdyn.identification.identify import identify
from pkdyn.identification.parameters import DEFAULT_GROUPS, GROUPS, parameter_set
from pkdyn.identification.result import IdentificationResult, predict_efforts

__all__ = [
    "DEFAULT_GROUPS",
    "GROUPS",
    "IdentificationResult",
    "Measurements",
    "identify",
    "parameter_set",
    "predict_efforts",
    "read_measurements",
]
