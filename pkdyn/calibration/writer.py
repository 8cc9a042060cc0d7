"""The calibrated description: the robot's URDF with the identified placements written in.

:func:`calibrated_urdf` edits the robot's own description (the family builder's output for a
library robot, else its URDF file): every placement the calibration moved becomes ``M exp(xi)``
(:mod:`pkdyn.precision.parameters`) in the element that holds it (a joint's ``<origin>``, a
closure's ``<pkdyn:frame>``, the ``<pkdyn:platform>``), identified gains become
``<pkdyn:encoder gain>`` in their transmission's ``<actuator>``, and ``<pkdyn:home q>`` records
the calibrated home configuration so that the file loads in the assembly mode it was measured in.
A ``<pkdyn:family>`` element is dropped (the dimensions are no longer the family's). The file is
a pkdyn URDF like any other: :func:`pkdyn.load` reads it, and its forward geometry at the
measured readings (times the gains) reproduces the measurements.
"""

from __future__ import annotations

import io
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from pkdyn.calibration.solve import CalibrationResult
from pkdyn.exceptions import InvalidInputError
from pkdyn.files import atomic_write
from pkdyn.model.description import NAMESPACE
from pkdyn.model.families import FAMILIES
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel

__all__ = ["calibrated_urdf", "joint_coordinates", "source_urdf", "write_calibrated"]

_NS = "{" + NAMESPACE + "}"


def source_urdf(robot: Robot) -> str:
    """The URDF text a robot was built from (the family builder's, or its file's).

    Raises:
        InvalidInputError: The robot came from another format (MJCF, SDFormat) or from text
            that is not at hand.

    """
    if robot.params is not None and robot.family is not None:
        return FAMILIES[robot.family].build_urdf(robot.params)
    path = Path(robot.source)
    if path.is_file():
        text = path.read_text(encoding="utf-8")
        if text.lstrip().startswith("<?xml") or "<robot" in text[:2000]:
            root = ET.fromstring(text)
            if root.tag == "robot":
                return text
        raise InvalidInputError(
            "robot",
            f"{robot.source} is not a URDF: the calibrated description is written as a pkdyn "
            "URDF of the robot's own URDF (convert the model to URDF first)",
        )
    raise InvalidInputError(
        "robot",
        f"the description of {robot.name} ({robot.source}) is not at hand: give its URDF text "
        "(calibrated_urdf(..., xml=...))",
    )


def _origin_of(el: ET.Element) -> tuple[ET.Element, pin.SE3]:
    origin = el.find("origin")
    if origin is None:
        origin = ET.SubElement(el, "origin")
    return origin, _read(origin)


def _read(el: ET.Element) -> pin.SE3:
    xyz = np.array([float(t) for t in el.get("xyz", "0 0 0").split()])
    rpy = np.array([float(t) for t in el.get("rpy", "0 0 0").split()])
    return pin.SE3(pin.rpy.rpyToMatrix(rpy), xyz)


def _write(el: ET.Element, M: pin.SE3) -> None:
    el.set("xyz", " ".join(repr(float(v)) for v in M.translation))
    el.set("rpy", " ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(M.rotation)))


def calibrated_urdf(result: CalibrationResult, xml: str | None = None) -> str:
    """The calibrated pkdyn URDF (module docstring).

    Args:
        result: A calibration of a robot (:func:`pkdyn.calibration.calibrate`).
        xml: The nominal robot's URDF text (default: :func:`source_urdf`).

    Returns:
        The URDF text.

    Raises:
        InvalidInputError: The nominal description is not a URDF at hand, or a moved placement
            has no element to write it in (a closure read from a sidecar).

    """
    robot = result.nominal
    text = source_urdf(robot) if xml is None else xml
    ET.register_namespace("pkdyn", NAMESPACE)
    root = ET.fromstring(text, parser=ET.XMLParser(target=ET.TreeBuilder(insert_comments=True)))
    model: ParameterModel = result.model
    twists = model.twists(result.p)
    joints = {el.get("name"): el for el in root.findall("joint")}
    closures = {el.get("name"): el for el in root.findall(_NS + "closure")}
    for pl, xi in zip(model.placements, twists, strict=True):
        if not np.any(xi != 0.0):
            continue
        step = pin.exp6(pin.Motion(xi))
        if pl.kind == "joint":
            el = joints.get(pl.name)
            if el is None:
                raise InvalidInputError("robot", f"joint '{pl.name}' is not in the URDF text")
            origin, M = _origin_of(el)
            _write(origin, M * step)
        elif pl.kind == "closure":
            cl = closures.get(pl.closure)
            frames = cl.findall(_NS + "frame") if cl is not None else []
            if len(frames) != 2:
                raise InvalidInputError(
                    "robot",
                    f"closure '{pl.closure}' is not a <pkdyn:closure> of the URDF text (a sidecar "
                    "or another format's loop): its calibrated frames cannot be written",
                )
            fr = frames[pl.side - 1]
            _write(fr, _read(fr) * step)
        else:
            plat = root.find(_NS + "platform")
            if plat is None:
                raise InvalidInputError(
                    "robot", "the platform frame is not a <pkdyn:platform> of the URDF text"
                )
            _write(plat, _read(plat) * step)
    for a, g in zip(robot.actuators, result.gains, strict=True):
        if g == 0.0:
            continue
        _set_gain(root, a.name, a.joint, float(a.encoder_gain) * (1.0 + float(g)))
    for el in root.findall(_NS + "family"):
        root.remove(el)
    for el in root.findall(_NS + "home"):
        root.remove(el)
    home = ET.SubElement(root, _NS + "home")
    home.set("q", " ".join(repr(float(v)) for v in result.robot.q_home))
    note = (
        f" calibrated by pkdyn from {result.calibration_rows.size} poses: {model.kind} model, "
        f"{result.identifiability.rank} parameters identified; RMS error "
        + (
            f"{result.before.position_rms:.3g} m -> {result.after.position_rms:.3g} m "
            if result.before.joint_rms == 0.0
            else f"(passive joints) {result.before.joint_rms:.3g} -> {result.after.joint_rms:.3g} "
        )
    )
    root.insert(0, ET.Comment(note))
    ET.indent(root, space="  ")
    buf = io.StringIO()
    ET.ElementTree(root).write(buf, encoding="unicode", xml_declaration=False)
    return '<?xml version="1.0"?>\n' + buf.getvalue() + "\n"


def _set_gain(root: ET.Element, actuator: str, joint: str, gain: float) -> None:
    for t in root.findall("transmission"):
        j = t.find("joint")
        act = t.find("actuator")
        if j is None or j.get("name") != joint:
            continue
        parent = act if act is not None else t
        el = parent.find(_NS + "encoder")
        if el is None:
            el = ET.SubElement(parent, _NS + "encoder")
        el.set("gain", repr(gain))
        return
    raise InvalidInputError("robot", f"no <transmission> of actuator '{actuator}' to hold its gain")


def write_calibrated(
    result: CalibrationResult, path: str | os.PathLike[str], xml: str | None = None
) -> str:
    """Write :func:`calibrated_urdf` to ``path`` (atomically).

    Args:
        result: The calibration.
        path: Output file.
        xml: The nominal robot's URDF text (default: :func:`source_urdf`).

    Returns:
        The text written.

    """
    text = calibrated_urdf(result, xml)
    with atomic_write(path) as fh:
        fh.write(text)
    return text


def joint_coordinates(robot: Robot, readings: np.ndarray) -> np.ndarray:
    """Actuated joint coordinates of actuator readings: ``encoder_gain * reading``.

    The gains are the ``<pkdyn:encoder gain>`` of a calibrated description (1 elsewhere).

    Args:
        robot: The robot.
        readings: Actuator readings (..., n_a) [rad or m].

    Returns:
        Joint coordinates, same shape.

    """
    g = np.array([a.encoder_gain for a in robot.actuators])
    return np.asarray(readings, dtype=float) * g
