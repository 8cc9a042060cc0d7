"""Drake's loop-closing custom elements, in URDF and in SDFormat.

- ``<drake:ball_constraint>`` (Drake's syntax): ``drake:ball_constraint_body_A``,
  ``drake:ball_constraint_p_AP``, ``drake:ball_constraint_body_B``,
  ``drake:ball_constraint_p_BQ`` -- in a URDF as ``name`` / ``value`` attributes, in SDFormat as
  element text, all four required (as Drake's parser requires them). Points P on A and Q on B
  coincide: a ``point`` closure.
- ``<drake:weld_constraint>``: in SDFormat, ``<parent>`` and ``<child>`` frames that coincide
  (the form of Drake's ``four_bar_weld.sdf``); in both formats, like the ball constraint,
  ``drake:weld_constraint_body_A`` / ``_X_AP`` / ``_body_B`` / ``_X_BQ`` with poses
  ``x y z roll pitch yaw``. A ``weld`` closure.

Closures are named ``ball_constraint1``, ``weld_constraint1``... in file order.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.description import ClosureSpec, FrameRef
from pkdyn.model.formats.xmldoc import finite_numbers

__all__ = ["closure", "implicit_world", "urdf_constraints"]


def _local(tag: str) -> str:
    """Local name of a tag: ``{ns}name`` or ``prefix:name`` -> ``name``."""
    return tag.rsplit("}", 1)[-1].rsplit(":", 1)[-1]


def _is_drake(tag: str) -> bool:
    return "drake" in tag.split("}")[0].lower() or tag.startswith("drake:")


def closure(
    el: ET.Element,
    k: int,
    source: str,
    where: str,
    read: Callable[[ET.Element], str | None],
    frames: Callable[[str, ET.Element], FrameRef] | None = None,
) -> ClosureSpec:
    """A Drake ball or weld constraint element as a closure.

    Args:
        el: The ``drake:ball_constraint`` or ``drake:weld_constraint`` element.
        k: Its number (1-based) among elements of its kind, for the closure name.
        source: File, for messages.
        where: How messages name the element.
        read: Value of a child element (text in SDFormat, ``name``/``value`` attribute in URDF).
        frames: SDFormat only: resolves a frame name (``<parent>``/``<child>`` welds).

    Returns:
        The closure; frames name bodies (or SDFormat frames resolved by ``frames``).

    Raises:
        DescriptionError: Missing or malformed children.

    """
    kind = _local(el.tag)
    prefix = "ball_constraint" if kind == "ball_constraint" else "weld_constraint"
    children = {_local(c.tag): c for c in el}
    if kind == "weld_constraint" and "parent" in children and frames is not None:
        if "child" not in children:
            raise DescriptionError(source, where, "needs <parent> and <child> frames")
        f1 = frames((children["parent"].text or "").strip(), children["parent"])
        f2 = frames((children["child"].text or "").strip(), children["child"])
        return ClosureSpec(f"{prefix}{k}", "weld", f1, f2)
    out = []
    for body, offset in (
        ("body_A", "p_AP" if kind == "ball_constraint" else "X_AP"),
        ("body_B", "p_BQ" if kind == "ball_constraint" else "X_BQ"),
    ):
        b = children.get(f"{prefix}_{body}")
        value = read(b) if b is not None else None
        name = value.strip() if value else ""
        if not name:
            raise DescriptionError(source, where, f"missing drake:{prefix}_{body}")
        o = children.get(f"{prefix}_{offset}")
        if o is None:  # Drake's parser reports the missing tag: no default point
            raise DescriptionError(
                source,
                where,
                f"missing drake:{prefix}_{offset} (Drake requires both points of a constraint)",
            )
        if kind == "ball_constraint":
            p = finite_numbers(source, f"{where} {offset}", read(o), 3)
            M = pin.SE3(np.eye(3), p)
        else:
            x = finite_numbers(source, f"{where} {offset}", read(o), 6)
            M = pin.SE3(pin.rpy.rpyToMatrix(x[3:]), x[:3])
        out.append(FrameRef(name, M))
    kind_ = "point" if kind == "ball_constraint" else "weld"
    return ClosureSpec(f"{prefix}{k}", kind_, out[0], out[1])


def urdf_constraints(root: ET.Element, source: str) -> list[ClosureSpec]:
    """Drake ball and weld constraints of a URDF (namespace-aware tree).

    Args:
        root: The ``<robot>`` element, parsed with namespaces.
        source: File, for messages.

    Returns:
        The closures.

    """
    counts = {"ball_constraint": 0, "weld_constraint": 0}
    out = []
    for el in root:
        if not isinstance(el.tag, str) or not _is_drake(el.tag):
            continue
        kind = _local(el.tag)
        if kind not in counts:
            continue
        counts[kind] += 1

        def read(c: ET.Element) -> str | None:
            return c.get("name") if c.get("name") is not None else c.get("value")

        out.append(closure(el, counts[kind], source, f"<drake:{kind}> #{counts[kind]}", read))
    return out


def implicit_world(xml: str, root: ET.Element) -> str:
    """The URDF with Drake's implicit ``world`` link declared when a joint names it.

    Drake's parser knows a ``world`` link without its ``<link name="world"/>``; the URDF parser
    does not ("no link of that name"). The declaration is added just after the ``<robot>``
    start tag (on the same line: line numbers are kept). Links that are no joint's child float
    in Drake: each gets a ``floating`` joint from the world, named ``<link>_root_joint``.

    Args:
        xml: The URDF text.
        root: Its parsed ``<robot>`` element.

    Returns:
        The text, with ``<link name="world"/>`` when a joint's parent is an undeclared
        ``world``.

    """
    if any(el.get("name") == "world" for el in root.findall("link")):
        return xml
    used = any(p.get("link") == "world" for j in root.findall("joint") for p in j.findall("parent"))
    if not used:
        return xml
    from pkdyn.model.formats.xmldoc import root_start

    m = root_start(xml)
    end = xml.find(">", m.end()) if m is not None else -1
    if end < 0:
        return xml
    if xml[end - 1] == "/":  # <robot/>: nothing to add to
        return xml
    children = {c.get("link") for j in root.findall("joint") for c in j.findall("child")}
    roots = [str(el.get("name")) for el in root.findall("link") if el.get("name") not in children]
    added = '<link name="world"/>' + "".join(
        f'<joint name="{r}_root_joint" type="floating"><parent link="world"/>'
        f'<child link="{r}"/></joint>'
        for r in roots
    )
    return xml[: end + 1] + added + xml[end + 1 :]
