"""Robot-agnostic algorithms on a Pinocchio model with rigid constraint models.

Nothing here knows about Deltas or hexapods: inputs are a ``pin.Model``, rigid constraint models
(3D point or 6D weld) and index sets. Depends on pinocchio, numpy (and proxsuite) only.

Modules: :mod:`~solvers.closure` (closure residuals, Jacobians, drift), :mod:`~solvers.lm`
(Levenberg-Marquardt on the configuration manifold), :mod:`~solvers.pose_task`,
:mod:`~solvers.actuation` (actuation selection, drives), :mod:`~solvers.passive` (springs,
dampers, friction), :mod:`~solvers.integrators`
(Runge-Kutta tableaux), :mod:`~solvers.projection` (state projection onto the closures),
:mod:`~solvers.recording` (what a simulation records), :mod:`~solvers.forward_dynamics` (time
stepping), :mod:`~solvers.sampled` (kinematics and closure errors of many sampled states at once),
:mod:`~solvers.inverse_dynamics` (constrained inverse dynamics, proxsuite QP) and
:mod:`~solvers.numerics` (rank decisions, null spaces, least squares: the one cut-off rule).
"""

from solvers.actuation import Actuation, Drives
from solvers.closure import ClosureSet
from solvers.forward_dynamics import ForwardDynamics, IntegrationError, simulate
from solvers.inverse_dynamics import (
    InconsistentMotionError,
    InfeasibleError,
    InverseDynamics,
    InverseResult,
    InverseTrajectory,
)
from solvers.lm import SolveResult, solve_lm
from solvers.passive import FrameSpring, PassiveForces
from solvers.pose_task import FramePoseTask
from solvers.recording import ForwardResult
from solvers.sampled import SampledKinematics

__all__ = [
    "Actuation",
    "ClosureSet",
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
    "PassiveForces",
    "SampledKinematics",
    "SolveResult",
    "simulate",
    "solve_lm",
]
