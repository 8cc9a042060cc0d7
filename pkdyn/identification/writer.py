"""Identified parameters written back as a pkdyn description (URDF), and as a robot in memory.

The description is the robot's own (a library family's URDF, or the URDF file it was loaded
from) with, for every identified body, the ``<inertial>`` of its link replaced (mass, centre of
mass, inertia about it; a payload is added to the platform's link), the ``<inertial>`` of links
merged into it by fixed joints removed (the identified body is the whole), and the actuators'
``<pkdyn:rotor_inertia>`` and ``<pkdyn:motor_friction>`` set; ``<pkdyn:efficiency>`` is removed
(identification lumps the gearbox losses into the friction: unit efficiency). A
``<pkdyn:family>`` element is dropped (the file no longer is the family's) and
``<pkdyn:home q>`` records the home configuration, so that the file loads in the assembly mode
the robot was identified in. It loads, assembles and sizes like any other description.
"""

from __future__ import annotations

import dataclasses
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.files import atomic_write
from pkdyn.identification.parameters import ParameterSet, body_links, placement_map
from pkdyn.model.description import NAMESPACE
from pkdyn.model.robot import Robot

__all__ = [
    "MAX_SOURCE_BYTES",
    "body_inertias",
    "identified_robot",
    "identified_urdf",
    "source_urdf",
    "write_urdf",
]

_NS = "{" + NAMESPACE + "}"


def _num(x: float) -> str:
    return repr(float(x)) if x != 0.0 else "0"


def body_inertias(robot: Robot, ps: ParameterSet, theta: np.ndarray) -> dict[int, pin.Inertia]:
    """Body inertias (joint frames) of standard parameters, payload included in its body.

    Args:
        robot: The robot.
        ps: Its parameter set.
        theta: Standard parameters (p,).

    Returns:
        ``{joint id: inertia}`` for the bodies that change (identified or carrying a payload).

    """
    out: dict[int, pin.Inertia] = {}
    ident = ps.identified
    for k, j in enumerate(ps.bodies):
        s = ps.body_slice(k)
        if ident[s].any():
            out[j] = pin.Inertia.FromDynamicParameters(np.asarray(theta[s], dtype=float))
    pay = np.asarray(theta[ps.payload_slice], dtype=float)
    if ps.payload_joint is not None and np.any(pay != 0.0):
        j = ps.payload_joint
        base = out.get(j, robot.model.inertias[j])
        total = base.toDynamicParameters() + placement_map(ps.payload_placement) @ pay
        out[j] = pin.Inertia.FromDynamicParameters(total)
    return out


def _drives(ps: ParameterSet, theta: np.ndarray, robot: Robot) -> list[dict[str, float]]:
    return [
        {f: float(theta[ps.drive_column(i, f)]) for f in ("viscous", "coulomb", "rotor_inertia")}
        for i in range(len(robot.actuators))
    ]


def identified_robot(robot: Robot, ps: ParameterSet, theta: np.ndarray) -> Robot:
    """A copy of ``robot`` with the standard parameters ``theta`` (for predictions).

    Args:
        robot: The robot (unchanged).
        ps: Its parameter set.
        theta: Standard parameters (p,).

    Returns:
        The robot with the new inertias, rotor inertias (armature) and motor friction, at unit
        gearbox efficiency.

    """
    model = pin.Model(robot.model)
    for j, I in body_inertias(robot, ps, theta).items():
        model.inertias[j] = I
    acts = []
    arm = np.array(model.armature)
    for i, (a, d) in enumerate(zip(robot.actuators, _drives(ps, theta, robot), strict=True)):
        iv = int(robot.actuated_v[i])
        arm[iv] += a.reduction**2 * (d["rotor_inertia"] - a.rotor_inertia)
        acts.append(
            dataclasses.replace(a, efficiency=1.0, backdrive_efficiency=None, **d)  # type: ignore[arg-type]
        )
    model.armature = arm
    desc = dataclasses.replace(robot.description, actuators=tuple(acts), family=None)
    return dataclasses.replace(
        robot, model=model, data=model.createData(), actuators=tuple(acts), description=desc
    )


MAX_SOURCE_BYTES = 64_000_000
"""Largest URDF file read back to write an identified or calibrated description [bytes]."""


def source_urdf(robot: Robot, purpose: str = "identified parameters") -> str:
    """The URDF text a robot was built from: its family builder's output, or its URDF file.

    Calibration and identification write their results into this text.

    Args:
        robot: The robot.
        purpose: What is written, for the message.

    Returns:
        The URDF text.

    Raises:
        InvalidInputError: The robot came from another format (MJCF, SDFormat) or from text that
            is not at hand.

    """
    from pkdyn.files import read_text
    from pkdyn.model.families import FAMILIES

    if robot.params is not None and robot.family is not None:
        return str(FAMILIES[robot.family].build_urdf(robot.params))
    path = Path(robot.source)
    if path.is_file():
        text = read_text(
            path, MAX_SOURCE_BYTES, lambda msg: InvalidInputError("robot", f"{path} {msg}")
        )
        if text.lstrip().startswith("<?xml") or "<robot" in text[:2000]:
            try:
                root = ET.fromstring(text)
            except ET.ParseError:
                root = None
            if root is not None and root.tag == "robot":
                return text
        raise InvalidInputError(
            "robot",
            f"{robot.source} is not a URDF: {purpose} are written into the robot's own URDF "
            "(convert the model to URDF first)",
        )
    raise InvalidInputError(
        "robot",
        f"the description of {robot.name} ({robot.source}) is not at hand: {purpose} are "
        "written into URDF descriptions (a library family or a URDF file)",
    )


def _inertial(link: ET.Element, I: pin.Inertia, M: pin.SE3) -> None:
    """Replace a link's ``<inertial>`` by ``I`` given in a frame placed at ``M`` in the link."""
    for old in link.findall("inertial"):
        link.remove(old)
    if I.mass <= 0.0:
        return
    In = M.act(I)  # in the link frame
    el = ET.Element("inertial")
    ET.SubElement(el, "origin", xyz=" ".join(_num(x) for x in In.lever), rpy="0 0 0")
    ET.SubElement(el, "mass", value=_num(In.mass))
    C = np.asarray(In.inertia)
    ET.SubElement(
        el,
        "inertia",
        ixx=_num(C[0, 0]),
        ixy=_num(C[0, 1]),
        ixz=_num(C[0, 2]),
        iyy=_num(C[1, 1]),
        iyz=_num(C[1, 2]),
        izz=_num(C[2, 2]),
    )
    el.tail = link.text
    link.insert(0, el)


def identified_urdf(robot: Robot, ps: ParameterSet, theta: np.ndarray) -> str:
    """The robot's URDF with the identified parameters (module doc).

    Args:
        robot: The robot identified.
        ps: Its parameter set.
        theta: Physically consistent standard parameters (p,).

    Returns:
        URDF text.

    Raises:
        InvalidInputError: The robot was not loaded from a URDF (family or file).

    """
    ET.register_namespace("pkdyn", NAMESPACE)
    root = ET.fromstring(source_urdf(robot))
    for fam in root.findall(_NS + "family"):
        root.remove(fam)
    links = {el.get("name"): el for el in root.findall("link")}
    names = body_links(robot)
    model = robot.model
    for j, I in body_inertias(robot, ps, theta).items():
        own, *merged = names.get(j, [str(model.names[j])])
        body = pin.FrameType.BODY
        frame = model.frames[model.getFrameId(own, body)] if model.existFrame(own, body) else None
        M = frame.placement.inverse() if frame is not None else pin.SE3.Identity()
        if own in links:
            _inertial(links[own], I, M)
        for other in merged:
            if other in links:
                for old in links[other].findall("inertial"):
                    links[other].remove(old)
    drives = _drives(ps, theta, robot)
    by_name = {a.name: d for a, d in zip(robot.actuators, drives, strict=True)}
    for t in root.findall("transmission"):
        act = t.find("actuator")
        holder = t if act is None else act
        name = holder.get("name", t.get("name", "")) if act is not None else t.get("name", "")
        d = by_name.get(name or "")
        if d is None:
            continue
        for tag in ("rotor_inertia", "motor_friction", "efficiency"):
            for old in holder.findall(_NS + tag):
                holder.remove(old)
        ET.SubElement(holder, _NS + "rotor_inertia", value=_num(d["rotor_inertia"]))
        ET.SubElement(
            holder, _NS + "motor_friction", viscous=_num(d["viscous"]), coulomb=_num(d["coulomb"])
        )
    for old in root.findall(_NS + "home"):
        root.remove(old)
    home = ET.SubElement(root, _NS + "home")  # the assembly mode it was identified in
    home.set("q", " ".join(repr(float(v)) for v in robot.q_home))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


def write_urdf(
    path: str | os.PathLike[str], robot: Robot, ps: ParameterSet, theta: np.ndarray
) -> str:
    """Write :func:`identified_urdf` atomically (temporary file, then rename).

    Returns:
        The text written.

    Raises:
        OutputError: The file cannot be written (an existing file is left intact).

    """
    text = identified_urdf(robot, ps, theta)
    with atomic_write(path) as fh:
        fh.write(text)
    return text
