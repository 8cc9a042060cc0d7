"""pkdyn: kinematics and dynamics of parallel and closed-loop robots, on Pinocchio 4.

The parts, each importing only the parts listed before it (``tests/test_layering.py``):

- :mod:`pkdyn.exceptions`, :mod:`pkdyn.progress`, :mod:`pkdyn.files`: the error tree, progress
  bars, atomic output files;
- :mod:`pkdyn.model`: description format, model building, :class:`Robot`, assembly, the family
  registry, ``load``, other formats;
- :mod:`pkdyn.closed_form`: closed-form models of the families (numpy);
- :mod:`pkdyn.library`: the robot families (builders), registered with the model layer;
- :mod:`pkdyn.analysis`: mobility, kinematic models, singularities, statics, collisions;
- :mod:`pkdyn.dynamics` and :mod:`pkdyn.workspace` (side by side);
- :mod:`pkdyn.tripod`: the walking tripod;
- :mod:`pkdyn.viewer`, :mod:`pkdyn.plotting`, :mod:`pkdyn.cli`: never imported by the above.

:mod:`solvers` (robot-agnostic algorithms) never imports pkdyn.
"""

from typing import TYPE_CHECKING, Any

from pkdyn import library as _library  # noqa: F401  (registers the families with the loader)
from pkdyn.exceptions import (
    AssemblyError,
    CalibrationError,
    CatalogError,
    DescriptionError,
    InfeasibleEffortError,
    InvalidInputError,
    JointLimitError,
    LimitsExceededError,
    LoopClosureError,
    NoFeasibleDriveError,
    OutputError,
    ParameterError,
    PkdynError,
    SimulationError,
    SingularConfigurationError,
    StudyError,
    TrajectoryError,
    UnknownRobotError,
    UnreachablePoseError,
)

if TYPE_CHECKING:
    from pkdyn.analysis.actuation_map import ActuationMap, actuation_map
    from pkdyn.model.assembly import (
        GeometryResult,
        assembly_modes,
        closure_residual,
        forward_geometry,
        inverse_geometry,
        project,
    )
    from pkdyn.model.loader import load, load_string
    from pkdyn.model.robot import Robot

_LAZY = {
    "ActuationMap": "pkdyn.analysis.actuation_map",
    "actuation_map": "pkdyn.analysis.actuation_map",
    "GeometryResult": "pkdyn.model.assembly",
    "assembly_modes": "pkdyn.model.assembly",
    "closure_residual": "pkdyn.model.assembly",
    "forward_geometry": "pkdyn.model.assembly",
    "inverse_geometry": "pkdyn.model.assembly",
    "project": "pkdyn.model.assembly",
    "load": "pkdyn.model.loader",
    "load_string": "pkdyn.model.loader",
    "Robot": "pkdyn.model.robot",
}
"""Entry points imported on first use: ``import pkdyn`` (and the CLI's start) stays light."""


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module 'pkdyn' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "ActuationMap",
    "AssemblyError",
    "CalibrationError",
    "CatalogError",
    "DescriptionError",
    "GeometryResult",
    "InfeasibleEffortError",
    "LimitsExceededError",
    "InvalidInputError",
    "JointLimitError",
    "LoopClosureError",
    "NoFeasibleDriveError",
    "OutputError",
    "ParameterError",
    "PkdynError",
    "Robot",
    "SimulationError",
    "SingularConfigurationError",
    "StudyError",
    "TrajectoryError",
    "UnknownRobotError",
    "UnreachablePoseError",
    "actuation_map",
    "assembly_modes",
    "closure_residual",
    "forward_geometry",
    "inverse_geometry",
    "load",
    "load_string",
    "project",
]
__version__ = "0.1.0"
