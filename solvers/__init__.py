"""Robot-agnostic algorithms on a Pinocchio model with rigid constraint models.

Nothing here knows about Deltas or hexapods: inputs are a ``pin.Model``, rigid constraint models
(3D point or 6D weld) and index sets. Depends on pinocchio, numpy (and proxsuite) only.
"""

from solvers.closure import ClosureSet
from solvers.forward_dynamics import (
    Actuation,
    ForwardDynamics,
    ForwardResult,
    JointFriction,
    SimulationError,
    simulate,
)
from solvers.inverse_dynamics import (
    InfeasibleError,
    InverseDynamics,
    InverseResult,
    InverseTrajectory,
)
from solvers.lm import SolveResult, solve_lm
from solvers.pose_task import FramePoseTask

__all__ = [
    "Actuation",
    "ClosureSet",
    "ForwardDynamics",
    "ForwardResult",
    "FramePoseTask",
    "InfeasibleError",
    "InverseDynamics",
    "InverseResult",
    "InverseTrajectory",
    "JointFriction",
    "SimulationError",
    "SolveResult",
    "simulate",
    "solve_lm",
]
