"""``pkdyn.load``: a library robot or a description file -> :class:`pkdyn.model.robot.Robot`."""

from __future__ import annotations

import dataclasses
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import AssemblyError, DescriptionError, ParameterError, UnknownRobotError
from pkdyn.model.build import build_geometry, build_tree, constraint_models, resolve_frame
from pkdyn.model.description import TASK_COMPONENTS, ActuatorSpec, Description, parse_description
from pkdyn.model.families import FAMILIES
from pkdyn.model.formats.gepetto import read_sidecar
from pkdyn.model.robot import Robot
from solvers import ClosureSet, solve_lm

__all__ = ["load", "load_string"]


def _package_dirs(path: Path | None) -> list[str]:
    """The file's directory and its ancestors: where ``package://`` meshes usually resolve."""
    dirs: list[str] = []
    if path is not None:
        p = path.resolve().parent
        for _ in range(5):
            dirs.append(str(p))
            p = p.parent
    return dirs


def load(
    name_or_path: str | os.PathLike[str],
    sidecar: str | os.PathLike[str] | None = None,
    geometry: bool = True,
    package_dirs: list[str] | None = None,
    **params: Any,
) -> Robot:
    """Load a robot: a library family name (``delta``, ``gough_stewart``...) or a URDF file.

    Args:
        name_or_path: Library family name or path to a pkdyn / plain URDF file.
        sidecar: Gepetto-style YAML sidecar (``closed_loop``, ``type``, ``name_mot``); by default
            ``<file>.yaml`` or ``robot.yaml`` next to the URDF when present.
        geometry: Build the visual and collision geometry models.
        package_dirs: Extra directories for mesh look-up.
        **params: Builder parameters of a library family (SI units).

    Returns:
        The loaded robot, assembled at its home configuration.

    Raises:
        UnknownRobotError: Neither a family nor an existing file.
        ParameterError: Unknown or invalid builder parameter, or parameters given for a file.
        DescriptionError: Malformed description.
        AssemblyError: The home configuration cannot be assembled.

    """
    name = str(name_or_path)
    if name in FAMILIES:
        fam = FAMILIES[name]
        p = fam.make_params(params)
        xml = fam.build_urdf(p)
        home = fam.home(p)
        return load_string(xml, name, geometry=geometry, params=p, home=home)
    path = Path(name)
    if not path.is_file():
        raise UnknownRobotError(name, list(FAMILIES))
    if params:
        first = next(iter(params))
        raise ParameterError(path.name, first, "builder parameters apply to library robots only")
    try:
        xml = path.read_text()
    except (OSError, UnicodeDecodeError) as err:
        raise DescriptionError(name, "file", f"cannot be read ({err})") from None
    side = Path(sidecar) if sidecar is not None else None
    if side is None:
        for cand in (path.with_suffix(".yaml"), path.parent / "robot.yaml"):
            if cand.is_file():
                side = cand
                break
    dirs = _package_dirs(path) + list(package_dirs or [])
    return load_string(xml, name, geometry=geometry, package_dirs=dirs, sidecar=side)


def load_string(
    xml: str,
    source: str,
    geometry: bool = True,
    package_dirs: list[str] | None = None,
    sidecar: Path | None = None,
    params: Any = None,
    home: list[float] | None = None,
) -> Robot:
    """Load a robot from the text of its description.

    Args:
        xml: URDF text with optional pkdyn extension elements.
        source: Name used in messages and as ``Robot.source``.
        geometry: Build the visual and collision geometry models.
        package_dirs: Directories for mesh look-up.
        sidecar: Optional Gepetto YAML sidecar.
        params: Builder parameters to keep on the robot.
        home: Actuated coordinates of the home configuration, if known.

    Returns:
        The loaded robot.

    """
    desc = parse_description(xml, source)
    model = build_tree(xml, desc.joints, source)
    closures = list(desc.closures)
    actuators = list(desc.actuators)
    if sidecar is not None:
        moving = [model.names[j] for j in range(1, model.njoints)]
        extra_c, extra_a = read_sidecar(sidecar, moving)
        closures += extra_c
        for a in extra_a:  # effort and velocity limits from the joint's URDF <limit>
            if a.joint not in [b.joint for b in actuators]:
                iv = model.joints[model.getJointId(a.joint)].idx_v
                eff, vel = float(model.effortLimit[iv]), float(model.velocityLimit[iv])
                actuators.append(dataclasses.replace(a, effort=eff, velocity=vel))
    desc = Description(
        desc.name,
        tuple(closures),
        desc.joints,
        tuple(actuators),
        desc.platform,
        desc.links,
        desc.joint_names,
    )
    cms, owner = constraint_models(model, closures, source)
    actuated_joints, actuated_q, actuated_v = _actuation(model, actuators, source)
    platform_frame = None
    task_rows = np.arange(6)
    if desc.platform is not None:
        j, M = resolve_frame(model, desc.platform.frame, source, "pkdyn:platform")
        fname = "platform" if not model.existFrame("platform") else "pkdyn_platform"
        platform_frame = model.addFrame(pin.Frame(fname, j, M, pin.FrameType.OP_FRAME), False)
        task_rows = np.array([TASK_COMPONENTS.index(t) for t in desc.platform.task])
    dirs = package_dirs or []
    if geometry:
        visual = build_geometry(model, xml, pin.GeometryType.VISUAL, dirs, source)
        collision = build_geometry(model, xml, pin.GeometryType.COLLISION, dirs, source)
    else:
        visual, collision = pin.GeometryModel(), pin.GeometryModel()
    vec = pin.StdVec_RigidConstraintModel()
    for cm in cms:
        vec.append(cm)
    data = model.createData()
    passive = np.setdiff1d(np.arange(model.nv), actuated_v)
    robot = Robot(
        name=desc.name,
        source=source,
        model=model,
        data=data,
        visual_model=visual,
        collision_model=collision,
        description=desc,
        constraint_models=vec,
        constraint_owner=owner,
        closure_set=ClosureSet(model, cms),
        actuators=tuple(actuators),
        actuated_joints=actuated_joints,
        actuated_q=actuated_q,
        actuated_v=actuated_v,
        passive_v=passive,
        platform_frame=platform_frame,
        task_rows=task_rows,
        q_home=pin.neutral(model),
        params=params,
    )
    robot.q_home = _home(robot, home)
    return robot


def _actuation(
    model: pin.Model, actuators: list[ActuatorSpec], source: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    jids, iq, iv = [], [], []
    for a in actuators:
        if not model.existJointName(a.joint):
            raise DescriptionError(
                source,
                f"transmission of '{a.name}'",
                f"names joint '{a.joint}', which is not a moving joint",
            )
        jid = model.getJointId(a.joint)
        jm = model.joints[jid]
        if jm.nv != 1 or jm.nq != 1:
            raise DescriptionError(
                source,
                f"transmission of '{a.name}'",
                f"joint '{a.joint}' must be revolute or prismatic (1 coordinate) to be actuated",
            )
        jids.append(jid)
        iq.append(jm.idx_q)
        iv.append(jm.idx_v)
    return np.array(jids, dtype=int), np.array(iq, dtype=int), np.array(iv, dtype=int)


def _guess(model: pin.Model) -> np.ndarray:
    """Neutral configuration moved inside finite joint limits (mid-range when outside)."""
    q = pin.neutral(model)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    for jid in range(1, model.njoints):
        jm = model.joints[jid]
        if jm.nq != 1:
            continue
        i = jm.idx_q
        if (
            math.isfinite(lo[i])
            and math.isfinite(hi[i])
            and lo[i] < hi[i]
            and not lo[i] <= q[i] <= hi[i]
        ):
            q[i] = 0.5 * (lo[i] + hi[i])
    return q


def _home(robot: Robot, home: list[float] | None) -> np.ndarray:
    q0 = _guess(robot.model)
    if robot.closure_set.nc == 0:
        return q0
    free = None
    if home is not None:
        q0[robot.actuated_q] = home
        free = robot.passive_v
    cs, data = robot.closure_set, robot.data
    sol = solve_lm(
        robot.model, q0, lambda q: cs.residual(data, q), lambda q: cs.jacobian(data, q), free, 1e-12
    )
    if not sol.converged:
        per = cs.split(sol.residual)
        worst = max(per, key=lambda k: per[k])
        raise AssemblyError(
            worst,
            per[worst],
            f"{robot.source}: the home configuration cannot be assembled: closure "
            f"'{worst}' keeps a residual of {per[worst]:.3g} (check lengths and closure frames)",
        )
    return sol.q
