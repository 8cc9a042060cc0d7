"""Precision: stiffness and compliance, natural frequencies, accuracy of any closed-loop robot.

- :mod:`~pkdyn.precision.material`, :mod:`~pkdyn.precision.beam`: materials and the beam model
  of a rod or tube (6x6 compliance);
- :mod:`~pkdyn.precision.links`: which links deform (beams read from the geometry, or described
  compliances);
- :mod:`~pkdyn.precision.elastic`: the virtual-joint model (actuator springs, joint springs, a
  6-DOF virtual spring per compliant link);
- :mod:`~pkdyn.precision.condensation`, :mod:`~pkdyn.precision.equilibrium`: condensation onto
  the platform, the loaded equilibrium and its tangent stiffness;
- :mod:`~pkdyn.precision.validity`: the scale-aware rule that says where a figure is defined
  (unbounded, undefined, near a singularity), behind every result;
- :mod:`~pkdyn.precision.stiffness`: :func:`stiffness` (``K``, compliance, principal
  stiffnesses, deflection);
- :mod:`~pkdyn.precision.modes`: natural frequencies and mode shapes;
- :mod:`~pkdyn.precision.grid`: the one map convention (plane, centre, extent, samples; values
  ``[i_u, i_v]``) and the map result;
- :mod:`~pkdyn.precision.vectorised`, :mod:`~pkdyn.precision.maps`: closed forms of the library
  Gough-Stewart and Delta, figures over many poses and maps over workspace slices (the design
  metrics ``stiffness_min`` and ``f1_min`` use them); :mod:`~pkdyn.precision.batched`: the
  general path's condensation over many configurations at once.
- :mod:`~pkdyn.precision.placements` and the parameter models (:mod:`~pkdyn.precision.
  parameters`: placement parameters, family shortcuts, family parameters);
- :mod:`~pkdyn.precision.perturbation`: robots with those errors, built exactly;
- :mod:`~pkdyn.precision.sensitivity`: first-order sensitivity of the platform pose to actuator
  and geometric errors through the loops (shared with :mod:`pkdyn.calibration`);
- :mod:`~pkdyn.precision.budgets`, :mod:`~pkdyn.precision.monte_carlo`,
  :mod:`~pkdyn.precision.accuracy_maps`: error budgets (worst case, RMS, ranking of the
  tolerances), their Monte Carlo check and pose-error maps; :mod:`~pkdyn.precision.accuracy`
  puts them in one report;
- :mod:`~pkdyn.precision.vibration`: :func:`vibration`, the tool's deviation from its rigid
  motion along a motion and its settling (the command: ``vibration_command``; the damping:
  ``vibration_damping``; the modal and multibody methods: ``vibration_modal``,
  ``vibration_multibody``; the library Delta's closed forms: ``vibration_closed_form``; the
  figures: ``vibration_figures``; the result: ``vibration_result``; input shaping:
  ``vibration_shaping``; the fastest settling cycle: ``vibration_fastest``; the MJCF export
  with servos and compliant links, and MuJoCo's run: ``vibration_mjcf``).

Every result derives from :class:`pkdyn.results.Result` (``table()``, ``to_json()``, ``plot()``
where a picture helps) and carries ``valid`` and ``warnings``.

Layering: may import :mod:`pkdyn.model`, :mod:`pkdyn.analysis`, :mod:`pkdyn.workspace` and
below; never design, calibration, viewer, plotting or the CLI.
"""

from pkdyn.precision.accuracy import Accuracy, accuracy_budget
from pkdyn.precision.accuracy_maps import AccuracyMap, accuracy_map
from pkdyn.precision.beam import Section, centre_compliance, tip_compliance
from pkdyn.precision.budgets import (
    ActuatorAccuracy,
    GeometricAccuracy,
    ToleranceRanking,
    actuator_errors,
    geometric_errors,
)
from pkdyn.precision.elastic import ElasticModel, actuator_stiffness, elastic_model
from pkdyn.precision.grid import GridMap, PlaneGrid
from pkdyn.precision.links import LinkCompliance, link_compliances
from pkdyn.precision.maps import PoseFigures, PrecisionMap, pose_figures, precision_map
from pkdyn.precision.material import ALUMINIUM, CARBON, MATERIALS, STEEL, Material, as_material
from pkdyn.precision.modes import Modes, mode_trajectory, modes
from pkdyn.precision.monte_carlo import MonteCarlo, monte_carlo
from pkdyn.precision.stiffness import Principal, Stiffness, stiffness, stiffness_json, transport
from pkdyn.precision.validity import PrecisionWarning, Validity
from pkdyn.precision.vibration import vibration
from pkdyn.precision.vibration_result import VibrationResult

__all__ = [
    "ALUMINIUM",
    "Accuracy",
    "AccuracyMap",
    "ActuatorAccuracy",
    "GeometricAccuracy",
    "GridMap",
    "MonteCarlo",
    "PlaneGrid",
    "PrecisionWarning",
    "ToleranceRanking",
    "Validity",
    "accuracy_budget",
    "accuracy_map",
    "actuator_errors",
    "geometric_errors",
    "monte_carlo",
    "CARBON",
    "MATERIALS",
    "STEEL",
    "ElasticModel",
    "LinkCompliance",
    "Material",
    "Modes",
    "PoseFigures",
    "PrecisionMap",
    "Principal",
    "Section",
    "Stiffness",
    "VibrationResult",
    "actuator_stiffness",
    "as_material",
    "centre_compliance",
    "elastic_model",
    "link_compliances",
    "mode_trajectory",
    "modes",
    "pose_figures",
    "precision_map",
    "stiffness",
    "stiffness_json",
    "tip_compliance",
    "transport",
    "vibration",
]
