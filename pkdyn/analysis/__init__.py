"""Kinematic analysis of a loaded robot (seeds 000 and 001).

Modules: :mod:`~pkdyn.analysis.mobility` (Grübler and rank-based mobility),
:mod:`~pkdyn.analysis.actuation_map` (closed-loop legs in serial-equivalent form),
:mod:`~pkdyn.analysis.kinematics` (A and B matrices, J, J_inv, twists),
:mod:`~pkdyn.analysis.screws` (reciprocal screws of the library families),
:mod:`~pkdyn.analysis.singularity` (serial / parallel classification),
:mod:`~pkdyn.analysis.maps` (vectorised conditioning maps), :mod:`~pkdyn.analysis.statics`
(tau = -J^T F, closure reactions), :mod:`~pkdyn.analysis.dexterity` (manipulability,
conditioning indices) and :mod:`~pkdyn.analysis.collisions` (coal distances between bodies).

The package exports the main entry points; ``mobility`` and ``dexterity`` are modules of the
same name as their functions: import those from the modules.

Layering: may import :mod:`pkdyn.model`, :mod:`pkdyn.closed_form`, :mod:`pkdyn.library` and
:mod:`solvers`; never dynamics, workspace, tripod, design, viewer, plotting or the CLI.
"""

from pkdyn.analysis.actuation_map import ActuationMap, MapSamples, actuation_map
from pkdyn.analysis.collisions import CollisionReport, distance_report
from pkdyn.analysis.kinematics import KinematicModels, kinematic_models, platform_jacobian
from pkdyn.analysis.mobility import MobilityResult
from pkdyn.analysis.singularity import SingularityReport, classify
from pkdyn.analysis.statics import StaticsResult, static_equilibrium

__all__ = [
    "ActuationMap",
    "CollisionReport",
    "KinematicModels",
    "MapSamples",
    "MobilityResult",
    "SingularityReport",
    "StaticsResult",
    "actuation_map",
    "classify",
    "distance_report",
    "kinematic_models",
    "platform_jacobian",
    "static_equilibrium",
]
