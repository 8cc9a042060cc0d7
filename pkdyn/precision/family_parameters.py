"""The family parameters: a library family builder's own dimensions, as placement twists.

Each numeric parameter of the family's dataclass (``la``, ``A``...) moves placements; their
derivatives are taken by central differences of the builder (placements are affine or smooth in
them): :func:`family_parameters`. :func:`family_values` and :func:`built_placements` rebuild the
family with other values (the Monte Carlo of family dimensions).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.build import build_tree, constraint_models, resolve_frame
from pkdyn.model.candidate import CandidateBuilder
from pkdyn.model.description import parse_description
from pkdyn.model.families import FAMILIES
from pkdyn.model.reuse import kept
from pkdyn.model.robot import Robot
from pkdyn.precision.parameter_model import ParameterModel, with_gains
from pkdyn.precision.placements import Placement, placements

__all__ = ["built_placements", "family_parameters", "family_values"]


def _units_of(params_cls: type) -> dict[str, str]:
    """``{field: unit}`` read from the ``Attributes:`` section of a Params docstring."""
    doc = params_cls.__doc__ or ""
    out = {}
    for line in doc.split("\n"):
        m = re.match(r"^\s+(\w+):[^\[]*\[([^\],]+)", line)
        if m:
            out[m.group(1)] = m.group(2).strip()
    return out


def _scalar_fields(p: Any) -> list[tuple[str, tuple[int, ...], float]]:
    """Numeric fields of a Params instance: ``(field, index, value)``, tuples element-wise."""
    out: list[tuple[str, tuple[int, ...], float]] = []
    for f in dataclasses.fields(p):
        v = getattr(p, f.name)
        if isinstance(v, bool) or v is None or f.name.endswith("_home"):  # (a pose, not a size)
            continue
        if isinstance(v, float):
            out.append((f.name, (), v))
        elif isinstance(v, tuple):
            arr = np.asarray(v, dtype=object)
            try:
                arr = np.asarray(v, dtype=float)
            except (TypeError, ValueError):
                continue
            for idx in np.ndindex(arr.shape):
                out.append((f.name, idx, float(arr[idx])))
    return out


def _with_value(p: Any, name: str, idx: tuple[int, ...], value: float) -> Any:
    v = getattr(p, name)
    if not idx:
        return dataclasses.replace(p, **{name: value})
    arr = np.array(v, dtype=float)
    arr[idx] = value
    nested = arr.tolist()
    as_tuple = (
        tuple(tuple(r) for r in nested) if arr.ndim == 2 else tuple(nested)  # type: ignore[arg-type]
    )
    return dataclasses.replace(p, **{name: as_tuple})


def _built_placements(robot: Robot, xml: str, where: tuple[Placement, ...]) -> list[pin.SE3]:
    """The placements of a description built from ``xml`` (same structure as ``robot``)."""
    desc = parse_description(xml, robot.name)
    model = build_tree(xml, desc.joints, robot.name)
    cms, owner = constraint_models(model, desc.closures, robot.name)

    def platform() -> pin.SE3:
        assert desc.platform is not None
        return resolve_frame(model, desc.platform.frame, robot.name, "platform")[1]

    return _read_placements(model, cms, owner, platform, where)


def _read_placements(
    model: pin.Model,
    cms: Sequence[Any],
    owner: Sequence[str],
    platform: Callable[[], pin.SE3],
    where: tuple[Placement, ...],
) -> list[pin.SE3]:
    """The placements ``where`` names, read from a model and its constraint models.

    Args:
        model: The kinematic tree.
        cms: Its constraint models (``pin.RigidConstraintModel``).
        owner: The closure each constraint model belongs to (same order).
        platform: The platform frame's placement (called when ``where`` names it).
        where: The placements to read.

    Returns:
        One placement per entry of ``where`` (a closure's from its first constraint model).

    """
    first: dict[str, int] = {}
    for k, o in enumerate(owner):
        first.setdefault(o, k)
    out = []
    for pl in where:
        if pl.kind == "joint":
            out.append(pin.SE3(model.jointPlacements[model.getJointId(pl.name)]))
        elif pl.kind == "closure":
            cm = cms[first[pl.closure]]
            out.append(pin.SE3(cm.joint1_placement if pl.side == 1 else cm.joint2_placement))
        else:
            out.append(platform())
    return out


def built_placements(robot: Robot, params: Any) -> list[pin.SE3]:
    """The placements the robot's family builder gives with other parameters.

    Args:
        robot: A library robot.
        params: Parameters of its family.

    Returns:
        One placement per :func:`placements` entry (same order).

    """
    return _written_placements(robot, params, placements(robot))


def _written_placements(robot: Robot, params: Any, where: tuple[Placement, ...]) -> list[pin.SE3]:
    """The placements of the family's robot with ``params``, written in place.

    The family's candidate builder (:class:`pkdyn.model.candidate.CandidateBuilder`, one per
    robot and thread) writes the builder's numbers into one model: the placements the URDF
    path gives, bit for bit, without its text.
    """
    name = _family_name(robot)
    builder = kept(robot, ("family candidates", name), lambda: CandidateBuilder(name))
    model_robot = builder.unassembled(params)
    model = model_robot.model

    def platform() -> pin.SE3:
        assert model_robot.platform_frame is not None
        return pin.SE3(model.frames[model_robot.platform_frame].placement)

    return _read_placements(
        model, model_robot.constraint_models, model_robot.constraint_owner, platform, where
    )


def _family_name(robot: Robot) -> str:
    name = robot.family
    if name is None:
        raise InvalidInputError(
            "parameters",
            f"{robot.name} is of no library family, so it has no family parameters; use the "
            "placement parameters",
        )
    return name


def family_parameters(robot: Robot, step: float = 1e-6, gains: bool = False) -> ParameterModel:
    """The family builder's numeric parameters, as placement twists (central differences).

    Each parameter (tuples element-wise: ``A[2][0]`` is named ``A3x`` for a 6 x 3 array, else
    ``name[i]``; the home-pose fields ``*_home`` are not dimensions) is moved by ``+-step``
    times its magnitude (at least ``step``), the builder run (description only: no assembly),
    and every placement's change measured as a twist
    ``log6(M0^-1 M)``. Parameters that move no placement (masses, limits, the home pose of a
    free-flyer) are left out.

    Args:
        robot: A library robot.
        step: Relative finite-difference step.
        gains: Add one relative gain per actuator.

    Returns:
        The parameter model (``nominal`` holds the parameter values).

    Raises:
        InvalidInputError: The robot is of no library family.

    """
    p = _resolved(robot)
    where = placements(robot)
    base = _written_placements(robot, p, where)
    units_of = _units_of(type(p))
    cols, names, units, nominal = [], [], [], []
    for field_name, idx, value in _scalar_fields(p):
        h = step * max(abs(value), 1.0)
        twists = []
        try:
            for sgn in (1.0, -1.0):
                q = _with_value(p, field_name, idx, value + sgn * h)
                built = _written_placements(robot, q, where)
                twists.append(
                    np.concatenate(
                        [pin.log6(b0.actInv(b)).vector for b0, b in zip(base, built, strict=True)]
                    )
                )
        except Exception:  # noqa: BLE001 - a value the builder refuses: not a geometric parameter
            continue
        col = (twists[0] - twists[1]) / (2.0 * h)
        if np.max(np.abs(col)) < 1e-9:
            continue
        cols.append(col)
        names.append(_param_name(field_name, idx, p))
        units.append(units_of.get(field_name, "?"))
        nominal.append(value)
    E = np.column_stack(cols) if cols else np.zeros((6 * len(where), 0))
    G = np.zeros((len(robot.actuators), E.shape[1]))
    if gains:
        E, G = with_gains(robot, E, G, names, units)
        nominal += [0.0] * len(robot.actuators)
    return ParameterModel(
        "family parameters", tuple(names), tuple(units), where, E, G, np.array(nominal)
    )


def _resolved(robot: Robot) -> Any:
    """The robot's family parameters with the derived ones computed (once per robot)."""

    def make() -> Any:
        module = FAMILIES[_family_name(robot)]._module()
        return module.resolved(robot.params) if hasattr(module, "resolved") else robot.params

    return kept(robot, "resolved family parameters", make)


def family_values(robot: Robot, model: ParameterModel, values: np.ndarray) -> Any:
    """The family's parameters with those of a family-parameter model set to ``values``.

    Args:
        robot: The library robot of ``model``.
        model: A :func:`family_parameters` model.
        values: Values of its parameters (n_par,) (gains are ignored).

    Returns:
        The family's parameter dataclass.

    """
    p = _resolved(robot)
    where = {_param_name(f, idx, p): (f, idx) for f, idx, _ in _scalar_fields(p)}
    changes: dict[str, Any] = {}  # field -> new value (arrays for tuple fields)
    for name, value in zip(model.names, np.asarray(values, dtype=float), strict=True):
        if name in where:
            f, idx = where[name]
            if not idx:
                changes[f] = float(value)
                continue
            arr = changes.setdefault(f, np.array(getattr(p, f), dtype=float))
            arr[idx] = float(value)
    for f, v in list(changes.items()):
        if isinstance(v, np.ndarray):
            nested = v.tolist()
            changes[f] = tuple(tuple(r) for r in nested) if v.ndim == 2 else tuple(nested)
    return dataclasses.replace(p, **changes) if changes else p  # (validated once)


def _param_name(name: str, idx: tuple[int, ...], p: Any) -> str:
    if not idx:
        return name
    shape = np.asarray(getattr(p, name), dtype=float).shape
    if len(idx) == 2 and shape[1] == 3:
        return f"{name}{idx[0] + 1}{'xyz'[idx[1]]}"
    return f"{name}[{']['.join(str(i) for i in idx)}]"
