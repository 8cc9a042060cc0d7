"""Geometric parameters of a robot: the placements manufacturing errors move, and models of them.

The placements (:mod:`pkdyn.precision.placements`): every tree joint's origin in its parent
body, each closure frame in its body, the platform frame; an error of one is a twist of the
frame it places (``M -> M exp(xi)``). A **parameter model**
(:class:`~pkdyn.precision.parameter_model.ParameterModel`) maps parameters ``p`` to those twists
and to actuator gains, linearly. Three models, one module each:

- :func:`placement_parameters` (:mod:`~pkdyn.precision.placement_parameters`): 6 parameters per
  placement (its twist components ``tx ty tz rx ry rz`` in the placed frame), an actuated joint's
  axis component named ``<actuator>.offset``; optionally one gain per actuator
  (``<actuator>.gain``);
- :func:`family_shortcuts` (:mod:`~pkdyn.precision.shortcuts`): the dimensions people calibrate
  on a library family: per-chain Clavel parameters of a Delta, the joint centres and leg offsets
  of a Gough-Stewart platform;
- :func:`family_parameters` (:mod:`~pkdyn.precision.family_parameters`): the family builder's
  own parameters (``la``, ``A``...), derivatives by central differences of the builder.

:func:`parameter_model` picks one by name. Every name of the three modules is importable from
here too.
"""

from __future__ import annotations

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.robot import Robot
from pkdyn.precision.family_parameters import built_placements, family_parameters, family_values
from pkdyn.precision.parameter_model import ParameterModel
from pkdyn.precision.placement_parameters import placement_parameters
from pkdyn.precision.placements import (
    COMPONENTS,
    Placement,
    local_placement,
    placement_frames,
    placements,
)
from pkdyn.precision.shortcuts import SHORTCUTS, family_shortcuts

__all__ = [
    "COMPONENTS",
    "MODELS",
    "SHORTCUTS",
    "Placement",
    "ParameterModel",
    "built_placements",
    "family_parameters",
    "family_shortcuts",
    "family_values",
    "local_placement",
    "parameter_model",
    "placement_frames",
    "placement_parameters",
    "placements",
]

MODELS = ("placements", "shortcuts", "family")
"""Names of the parameter models (:func:`parameter_model`)."""


def parameter_model(robot: Robot, kind: str = "auto", gains: bool = False) -> ParameterModel:
    """A parameter model by name.

    Args:
        robot: The robot.
        kind: ``placements`` (:func:`placement_parameters`), ``shortcuts``
            (:func:`family_shortcuts`), ``family`` (:func:`family_parameters`) or ``auto``
            (shortcuts for the families that have them, else placements).
        gains: Add one relative gain per actuator.

    Returns:
        The model.

    Raises:
        InvalidInputError: Unknown kind, or a kind the robot does not have.

    """
    if kind == "auto":
        kind = "shortcuts" if robot.family in SHORTCUTS else "placements"
    if kind == "placements":
        return placement_parameters(robot, gains)
    if kind == "shortcuts":
        return family_shortcuts(robot, gains)
    if kind == "family":
        return family_parameters(robot, gains=gains)
    raise InvalidInputError(
        "parameters", f"unknown model '{kind}'; use auto or {', '.join(MODELS)}"
    )
