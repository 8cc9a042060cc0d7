"""Dynamics: motion laws, task trajectories, inverse and forward dynamics, motor sizing.

Modules: :mod:`~pkdyn.dynamics.profiles` (rest-to-rest motion laws),
:mod:`~pkdyn.dynamics.trajectory` (task paths mapped to closure-consistent joint trajectories),
:mod:`~pkdyn.dynamics.actuation` (actuation and drives: rotor inertia, efficiency, motor
friction), :mod:`~pkdyn.dynamics.payload`, :mod:`~pkdyn.dynamics.energy`,
:mod:`~pkdyn.dynamics.inverse` (actuator efforts along a trajectory),
:mod:`~pkdyn.dynamics.forward` (``simulate``; ``ForwardDynamics``, the control-loop step),
:mod:`~pkdyn.dynamics.sizing` (peak/RMS efforts, margins),
:mod:`~pkdyn.dynamics.balancing` (spring balancing),
:mod:`~pkdyn.dynamics.motors` (motor and gearbox catalogs), :mod:`~pkdyn.dynamics.selection`
(motor x gearbox selection), :mod:`~pkdyn.dynamics.fastest` (the fastest motion along a path,
toppra). The robot's passive elements (``robot.passive``: springs, dampers, friction) enter
every one of them.

Layering: may import :mod:`pkdyn.model`, :mod:`pkdyn.library`, :mod:`pkdyn.analysis` and
:mod:`solvers`; never the workspace, tripod, design, viewer, plotting or CLI packages.
"""

from pkdyn.dynamics.actuation import actuation
from pkdyn.dynamics.energy import elastic_energy, mechanical_energy
from pkdyn.dynamics.forward import ForwardDynamics, simulate
from pkdyn.dynamics.inverse import EffortTrajectory, inverse_dynamics
from pkdyn.dynamics.payload import with_payload

__all__ = [
    "EffortTrajectory",
    "ForwardDynamics",
    "actuation",
    "elastic_energy",
    "inverse_dynamics",
    "mechanical_energy",
    "simulate",
    "with_payload",
]
