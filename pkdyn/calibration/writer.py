"""The calibrated description: the robot's URDF with the identified placements written in.

:func:`calibrated_urdf` edits the robot's own description (the family builder's output for a
library robot, else its URDF file): every placement the calibration moved becomes ``M exp(xi)``
(:mod:`pkdyn.precision.parameters`) in the element that holds it (a joint's ``<origin>``, a
closure's ``<pkdyn:frame>``, the ``<pkdyn:platform>``), identified gains become
``<pkdyn:encoder gain>`` (and a described encoder offset is scaled with it) in their
transmission's ``<actuator>``, and ``<pkdyn:home q>`` records the calibrated home configuration
so that the file loads in the assembly mode it was measured in. A ``<pkdyn:family>`` element is
dropped (the dimensions are no longer the family's). The file is a pkdyn URDF like any other:
:func:`pkdyn.load` reads it, and its forward geometry at the joint coordinates of the measured
readings (:meth:`pkdyn.Robot.joint_coordinates`) reproduces the measurements.
"""

from __future__ import annotations

import io
import os
import xml.etree.ElementTree as ET
from typing import Protocol

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.identification.writer import source_urdf
from pkdyn.model.description import NAMESPACE
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel
from pkdyn.results import deprecated

__all__ = ["Calibrated", "calibrated_urdf", "joint_coordinates", "source_urdf", "write_calibrated"]

_NS = "{" + NAMESPACE + "}"


class Calibrated(Protocol):
    """What the writer reads of a calibration (a :class:`~.result.CalibrationResult`)."""

    @property
    def nominal(self) -> Robot:
        """The nominal robot (its description is edited)."""

    @property
    def robot(self) -> Robot:
        """The calibrated robot (its home configuration is recorded)."""

    @property
    def model(self) -> ParameterModel:
        """The parameter model."""

    @property
    def p(self) -> np.ndarray:
        """Identified parameter errors (n_par,) [m, rad, -]."""

    @property
    def gains(self) -> np.ndarray:
        """Identified relative actuator gains (n_a,)."""

    def provenance(self) -> str:
        """One line: where the calibrated description comes from (a comment of the file)."""

    def write_urdf(self, path: str | os.PathLike[str], xml: str | None = None) -> str:
        """Write the calibrated description (:func:`calibrated_urdf`) to ``path``."""


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


def calibrated_urdf(result: Calibrated, xml: str | None = None) -> str:
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
    if xml is not None and not isinstance(xml, str):
        raise InvalidInputError("xml", f"expected the URDF text (str), got {type(xml).__name__}")
    robot = result.nominal
    text = source_urdf(robot, "calibrated placements") if xml is None else xml
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
            continue  # q = (1 + g) (gain r + offset): both scale
        scale = 1.0 + float(g)
        _set_encoder(root, a.name, a.joint, a.encoder_gain * scale, a.encoder_offset * scale)
    for el in root.findall(_NS + "family"):
        root.remove(el)
    for el in root.findall(_NS + "home"):
        root.remove(el)
    home = ET.SubElement(root, _NS + "home")
    home.set("q", " ".join(repr(float(v)) for v in result.robot.q_home))
    root.insert(0, ET.Comment(f" {result.provenance()} "))
    ET.indent(root, space="  ")
    buf = io.StringIO()
    ET.ElementTree(root).write(buf, encoding="unicode", xml_declaration=False)
    return '<?xml version="1.0"?>\n' + buf.getvalue() + "\n"


def _set_encoder(root: ET.Element, actuator: str, joint: str, gain: float, offset: float) -> None:
    for t in root.findall("transmission"):
        j = t.find("joint")
        act = t.find("actuator")
        if j is None or j.get("name") != joint:
            continue
        parent = act if act is not None else t
        el = parent.find(_NS + "encoder")
        if el is None:
            el = ET.SubElement(parent, _NS + "encoder")
        el.set("gain", repr(float(gain)))
        if offset != 0.0 or el.get("offset") is not None:
            el.set("offset", repr(float(offset)))
        return
    raise InvalidInputError("robot", f"no <transmission> of actuator '{actuator}' to hold its gain")


def write_calibrated(
    result: Calibrated, path: str | os.PathLike[str], xml: str | None = None
) -> str:
    """Deprecated: :meth:`CalibrationResult.write_urdf` (``result.write_urdf(path)``)."""
    deprecated("pkdyn.calibration.writer.write_calibrated", "CalibrationResult.write_urdf(path)")
    return result.write_urdf(path, xml)


def joint_coordinates(robot: Robot, readings: np.ndarray) -> np.ndarray:
    """Deprecated: :meth:`pkdyn.Robot.joint_coordinates` (``robot.joint_coordinates(r)``)."""
    deprecated("pkdyn.calibration.writer.joint_coordinates", "Robot.joint_coordinates")
    return robot.joint_coordinates(readings)
