"""pkdyn: kinematics and dynamics of parallel and closed-loop robots, on Pinocchio 4."""

from pkdyn.assembly import (
    GeometryResult,
    assembly_modes,
    closure_residual,
    forward_geometry,
    inverse_geometry,
    project,
)
from pkdyn.exceptions import (
    AssemblyError,
    DescriptionError,
    InvalidInputError,
    JointLimitError,
    ParameterError,
    PkdynError,
    SingularConfigurationError,
    UnknownRobotError,
    UnreachablePoseError,
)
from pkdyn.loader import load, load_string
from pkdyn.robot import Robot

__all__ = [
    "AssemblyError",
    "DescriptionError",
    "GeometryResult",
    "InvalidInputError",
    "JointLimitError",
    "ParameterError",
    "PkdynError",
    "Robot",
    "SingularConfigurationError",
    "UnknownRobotError",
    "UnreachablePoseError",
    "assembly_modes",
    "closure_residual",
    "forward_geometry",
    "inverse_geometry",
    "load",
    "load_string",
    "project",
]
__version__ = "0.1.0"
