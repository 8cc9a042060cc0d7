"""Gazebo's loop-closing joints in a URDF: ``<gazebo><joint>`` (SDFormat inside URDF).

Gazebo converts a URDF to SDFormat and appends the SDFormat ``<joint>`` elements found in
top-level ``<gazebo>`` extensions: the way Gazebo's kinematic-loop tutorial and many ROS packages
close a loop that a URDF tree cannot. pkdyn reads each one as a closure between its parent and
child links:

- ``<pose>x y z roll pitch yaw</pose>``: the joint frame, relative to the child link (SDFormat's
  default; ``relative_to`` another link or ``__model__`` is honoured), placed in the URDF's zero
  configuration, where the parent's side of the closure is taken;
- ``fixed`` -> ``weld``; ``revolute`` and ``continuous`` -> ``hinge`` about ``<axis><xyz>`` (in
  the joint frame, or ``expressed_in`` a link or ``__model__``); ``ball`` -> ``point``;
- any other type (``prismatic``, ``universal``, ``revolute2``, ``screw``...) is refused, naming
  the joint: a loop pkdyn cannot close is never dropped silently.

The closures are named after the joints.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.description import ClosureSpec, FrameRef
from pkdyn.model.formats.xmldoc import finite_numbers
from pkdyn.model.validate import unit_vector

__all__ = ["gazebo_closures"]

_KINDS = {"fixed": "weld", "revolute": "hinge", "continuous": "hinge", "ball": "point"}


def _link_poses(model: pin.Model) -> dict[str, pin.SE3]:
    """World pose of every URDF link (body frame) in the zero configuration."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    out = {"world": pin.SE3.Identity(), "__model__": pin.SE3.Identity()}
    for k, f in enumerate(model.frames):
        if f.type == pin.FrameType.BODY:
            out[f.name] = pin.SE3(data.oMf[k])
    return out


def gazebo_closures(root: ET.Element, model: pin.Model, source: str) -> list[ClosureSpec]:
    """Closures of the ``<gazebo><joint>`` elements of a URDF (see the module docstring).

    Args:
        root: The ``<robot>`` element.
        model: The Pinocchio model of the URDF tree (its zero configuration places the links).
        source: File, for messages.

    Returns:
        One closure per Gazebo joint, in file order.

    Raises:
        DescriptionError: A joint without parent or child, naming a missing link, of a type
            pkdyn cannot close a loop with, or with malformed numbers.

    """
    joints = [j for g in root.findall("gazebo") for j in g.findall("joint")]
    if not joints:
        return []
    poses = _link_poses(model)
    out = []
    for k, el in enumerate(joints):
        name = el.get("name") or f"gazebo_joint{k + 1}"
        where = f"<gazebo><joint name='{name}'>"
        jtype = el.get("type", "")
        if jtype not in _KINDS:
            raise DescriptionError(
                source,
                f"{where} type '{jtype}'",
                "a loop closed by this joint type cannot be represented; pkdyn closes loops with "
                "fixed, revolute, continuous and ball joints (make this joint part of the URDF "
                "tree and close the loop elsewhere)",
            )
        parent = (el.findtext("parent") or "").strip()
        child = (el.findtext("child") or "").strip()
        if not parent or not child:
            raise DescriptionError(source, where, "needs <parent> and <child> links")
        for role, link in (("parent", parent), ("child", child)):
            if link not in poses:
                raise DescriptionError(
                    source, f"{where} <{role}>{link}</{role}>", "no link of that name"
                )
        pose_el = el.find("pose")
        rel = child
        X = pin.SE3.Identity()
        if pose_el is not None:
            v = finite_numbers(source, f"{where} <pose>", pose_el.text, 6)
            X = pin.SE3(pin.rpy.rpyToMatrix(v[3:]), v[:3])
            rel = pose_el.get("relative_to") or pose_el.get("frame") or child
            if rel not in poses:
                raise DescriptionError(
                    source, f"{where} <pose relative_to='{rel}'>", "no link of that name"
                )
        oMj = poses[rel] * X
        axis = np.array([0.0, 0.0, 1.0])
        xyz = el.find("axis/xyz")
        if xyz is not None:
            v = finite_numbers(source, f"{where} <axis><xyz>", xyz.text, 3)
            u = unit_vector(v)
            if u is None or float(np.abs(v).max()) < 1e-12:
                raise DescriptionError(source, f"{where} <axis>", "zero axis")
            axis = np.asarray(u)
            frame = xyz.get("expressed_in")
            if frame is not None:
                if frame not in poses:
                    raise DescriptionError(
                        source, f"{where} <xyz expressed_in='{frame}'>", "no link of that name"
                    )
                axis = oMj.rotation.T @ (poses[frame].rotation @ axis)
        f1 = FrameRef("universe" if parent == "world" else parent, poses[parent].actInv(oMj))
        f2 = FrameRef("universe" if child == "world" else child, poses[child].actInv(oMj))
        out.append(ClosureSpec(name, _KINDS[jtype], f1, f2, axis))
    return out
