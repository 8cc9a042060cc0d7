"""Robot-agnostic algorithms on a Pinocchio model with rigid constraint models.

Nothing here knows about Deltas or hexapods: inputs are a ``pin.Model``, rigid constraint models
(3D point or 6D weld) and index sets. Depends on pinocchio, numpy (and proxsuite) only.

Modules: :mod:`~solvers.constraints` (the constraint layer: closures and couplings, rows of named
kinds with residual, Jacobian and drift at an explicit state), :mod:`~solvers.closure` (point, hinge
and weld closures reduced to their independent rows), :mod:`~solvers.coupling` (joint couplings:
linear sums, gears, cam laws, mimic joints), :mod:`~solvers.planar` (planar motion),
:mod:`~solvers.energy` (kinetic energy with every armature), :mod:`~solvers.lm`
(Levenberg-Marquardt on the configuration manifold), :mod:`~solvers.pose_task`,
:mod:`~solvers.actuation` (actuation selection, drives), :mod:`~solvers.passive` (springs,
dampers, friction), :mod:`~solvers.integrators`
(Runge-Kutta tableaux), :mod:`~solvers.projection` (state projection onto the closures),
:mod:`~solvers.recording` (what a simulation records), :mod:`~solvers.forward_dynamics` (time
stepping), :mod:`~solvers.sampled` (kinematics and closure errors of many sampled states at once),
:mod:`~solvers.vec3` (cross products of stacked 3-vectors),
:mod:`~solvers.inverse_dynamics` (constrained inverse dynamics, proxsuite QP) and
:mod:`~solvers.numerics` (rank decisions, null spaces, least squares: the one cut-off rule).
"""

from typing import TYPE_CHECKING, Any

from solvers.closure import Closure
from solvers.constraints import ClosureSet, ConstraintSet
from solvers.coupling import JointCoupling, LinearCoupling
from solvers.lm import SolveResult, solve_lm
from solvers.pose_task import FramePoseTask

if TYPE_CHECKING:
    from solvers.actuation import Actuation, Drives
    from solvers.forward_dynamics import ForwardDynamics, IntegrationError, simulate
    from solvers.inverse_dynamics import (
        InconsistentMotionError,
        InfeasibleError,
        InverseDynamics,
        InverseResult,
        InverseTrajectory,
    )
    from solvers.passive import FrameSpring, PassiveForces
    from solvers.recording import ForwardResult
    from solvers.sampled import SampledKinematics

_LAZY = {
    "Actuation": "solvers.actuation",
    "Drives": "solvers.actuation",
    "ForwardDynamics": "solvers.forward_dynamics",
    "IntegrationError": "solvers.forward_dynamics",
    "simulate": "solvers.forward_dynamics",
    "InconsistentMotionError": "solvers.inverse_dynamics",
    "InfeasibleError": "solvers.inverse_dynamics",
    "InverseDynamics": "solvers.inverse_dynamics",
    "InverseResult": "solvers.inverse_dynamics",
    "InverseTrajectory": "solvers.inverse_dynamics",
    "FrameSpring": "solvers.passive",
    "PassiveForces": "solvers.passive",
    "ForwardResult": "solvers.recording",
    "SampledKinematics": "solvers.sampled",
}
"""Names imported on first use (dynamics and proxsuite stay out of a geometry-only import)."""


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module 'solvers' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "Actuation",
    "Closure",
    "ClosureSet",
    "ConstraintSet",
    "Drives",
    "ForwardDynamics",
    "ForwardResult",
    "FramePoseTask",
    "FrameSpring",
    "InconsistentMotionError",
    "InfeasibleError",
    "InverseDynamics",
    "InverseResult",
    "InverseTrajectory",
    "IntegrationError",
    "JointCoupling",
    "LinearCoupling",
    "PassiveForces",
    "SampledKinematics",
    "SolveResult",
    "simulate",
    "solve_lm",
]
