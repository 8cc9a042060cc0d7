"""Perturbed descriptions written as text: an independent truth for sensitivities and calibration.

A test edits the numbers of a URDF (a joint's ``<origin>``, a ``<pkdyn:frame>``, the
``<pkdyn:platform>``) with ElementTree and loads the result with :func:`pkdyn.load_string`: the
perturbed robot is built by the loader from text, not by :mod:`pkdyn.precision.perturbation`.
"""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

import pkdyn
from pkdyn.model.description import NAMESPACE
from pkdyn.model.families import FAMILIES

NS = "{" + NAMESPACE + "}"


def family_xml(robot: pkdyn.Robot) -> str:
    """The builder's URDF of a library robot (no ``<pkdyn:family>``)."""
    return FAMILIES[robot.family].build_urdf(robot.params)


def _element(root: ET.Element, where: str) -> ET.Element:
    """``joint:NAME``, ``closure:NAME:1|2`` or ``platform`` -> the element holding xyz / rpy."""
    kind, _, rest = where.partition(":")
    if kind == "joint":
        el = next(j for j in root.findall("joint") if j.get("name") == rest)
        origin = el.find("origin")
        if origin is None:
            origin = ET.SubElement(el, "origin")
        return origin
    if kind == "closure":
        name, side = rest.rsplit(":", 1)
        cl = next(c for c in root.findall(NS + "closure") if c.get("name") == name)
        return cl.findall(NS + "frame")[int(side) - 1]
    return root.find(NS + "platform")


def placement(xml: str, where: str) -> pin.SE3:
    """The placement an element of the text holds."""
    el = _element(ET.fromstring(xml), where)
    xyz = np.array([float(t) for t in el.get("xyz", "0 0 0").split()])
    rpy = np.array([float(t) for t in el.get("rpy", "0 0 0").split()])
    return pin.SE3(pin.rpy.rpyToMatrix(rpy), xyz)


def edited(xml: str, edits: dict[str, tuple[np.ndarray | None, np.ndarray | None]]) -> str:
    """The text with ``xyz += dxyz`` and ``rpy := rpy(R_old @ R(drot))`` applied per element.

    Args:
        xml: URDF text.
        edits: ``{where: (dxyz (3,) in the parent frame or None, drot (3,) rotation vector in
            the placed frame or None)}``.

    """
    ET.register_namespace("pkdyn", NAMESPACE)
    root = ET.fromstring(xml)
    for where, (dxyz, drot) in edits.items():
        el = _element(root, where)
        xyz = np.array([float(t) for t in el.get("xyz", "0 0 0").split()])
        rpy = np.array([float(t) for t in el.get("rpy", "0 0 0").split()])
        if dxyz is not None:
            xyz = xyz + np.asarray(dxyz, dtype=float)
        if drot is not None:
            R = pin.rpy.rpyToMatrix(rpy) @ pin.exp3(np.asarray(drot, dtype=float))
            rpy = pin.rpy.matrixToRpy(R)
        el.set("xyz", " ".join(repr(float(v)) for v in xyz))
        el.set("rpy", " ".join(repr(float(v)) for v in rpy))
    return ET.tostring(root, encoding="unicode")


def load_like(xml: str, nominal: pkdyn.Robot, moved: bool = False) -> pkdyn.Robot:
    """Load perturbed text, assembled from the nominal robot's home (same assembly mode).

    The loader's notes that the home had to move are expected (the text is perturbed); a
    closure frame moved to absorb an inconsistency ("CAD rounding") would change the truth and
    fails the test unless ``moved``.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = pkdyn.load_string(xml, "perturbed.urdf", geometry=False, home=nominal.q_home)
    frames = [str(w.message) for w in caught if "frames were moved" in str(w.message)]
    assert moved or not frames, frames
    return robot


def pose_error(M0: pin.SE3, M: pin.SE3) -> np.ndarray:
    """``[p - p0; log3(R0^T R)]`` (6,)."""
    return np.concatenate([M.translation - M0.translation, pin.log3(M0.rotation.T @ M.rotation)])


def twist(xml0: str, xml1: str, where: str) -> np.ndarray:
    """The right twist ``log6(M0^-1 M1)`` an edit made of one placement (placed frame)."""
    return pin.log6(placement(xml0, where).actInv(placement(xml1, where))).vector


def where_of(pl) -> str:
    """The :func:`edited` key of a :class:`pkdyn.precision.parameters.Placement`."""
    if pl.kind == "joint":
        return f"joint:{pl.name}"
    if pl.kind == "closure":
        return f"closure:{pl.closure}:{pl.side}"
    return "platform"


def with_twists(xml: str, twists: dict[str, np.ndarray]) -> str:
    """The text with placements ``M`` replaced by ``M exp(xi)`` (written as xyz / rpy)."""
    ET.register_namespace("pkdyn", NAMESPACE)
    root = ET.fromstring(xml)
    for where, xi in twists.items():
        el = _element(root, where)
        xyz = np.array([float(t) for t in el.get("xyz", "0 0 0").split()])
        rpy = np.array([float(t) for t in el.get("rpy", "0 0 0").split()])
        M = pin.SE3(pin.rpy.rpyToMatrix(rpy), xyz) * pin.exp6(pin.Motion(np.asarray(xi, float)))
        el.set("xyz", " ".join(repr(float(v)) for v in M.translation))
        el.set("rpy", " ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(M.rotation)))
    return ET.tostring(root, encoding="unicode")
