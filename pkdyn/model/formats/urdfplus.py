"""URDF+: the loop dialect of legged robotics (``<loop>``, ``<coupling>``, ``independent``).

URDF+ (Chignoli, Slotine, Wensing, Kim, "URDF+: An Enhanced URDF for Robots with Kinematic
Loops", 2024; parser: the ``mit-biomimetics/urdfdom`` fork; dynamics: ``ROAM-Lab-ND/
generalized_rbda``) adds three things to a URDF tree, read here as its reference code reads them:

- ``<loop name type><predecessor link><origin xyz rpy/></predecessor><successor link>
  <origin/></successor><axis xyz/></loop>``: the two origins coincide. The reference
  implementation (``ClusterTreeModel::implicitPositionConstraint``) and its Pinocchio benchmark
  (``CONTACT_3D``) impose the three translation rows whatever the ``type`` (``revolute``,
  ``continuous``, ``prismatic``, ``planar``, ``fixed``) and ``axis`` say: a ``point`` closure
  here (rows that are redundant by construction, e.g. the out-of-plane row of a planar loop, are
  dropped by the constraint layer's rank rules, not here).
- ``<coupling name><predecessor link/><successor link/><ratio value/></coupling>``: one linear
  relation between *sums* of joint coordinates (``explicitRollingConstraint``): ``ratio *
  (sum of the coordinates of the joints on the path from the two links' nearest common
  ancestor down to the predecessor) = (the same sum down to the successor)``, a
  :class:`~pkdyn.model.description.LinearCouplingSpec` with coefficient ``ratio`` on the
  predecessor path and ``-1`` on the successor path (the two paths share no joint; fixed joints
  have no coordinate and add nothing). ``ratio`` defaults to 1 (urdfdom's ``clear()``).
- ``independent="true|false"`` on a ``<joint>`` (default true; urdfdom reads anything but
  ``true`` / ``True`` as false): the coordinates a user drives. Where no ``<transmission>``
  declares actuators, the independent 1-DoF joints become the actuators (named after their
  joints, reduction 1, effort and velocity limits from ``<limit>``) -- when the file gives the
  attribute at all (a file without it declares nothing).

Older spellings in the same projects' history are read the same way:
``<constraint type="position">`` (a loop) and ``<constraint type="rolling">`` (a coupling, with
``<ratio>``), ``<joint_constraint>`` with ``<parent link>``, ``<child link>`` and
``<gear_ratio value>`` (a coupling; parent = predecessor), ``<loop_constraint>`` with
``<parent link>``, ``<parent_origin>``, ``<child link>``, ``<child_origin>`` (a loop).

A URDF+ element pkdyn cannot read as its authors mean it is refused with one
:class:`~pkdyn.exceptions.DescriptionError` naming the element and its line.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pkdyn.model.description import ActuatorSpec, ClosureSpec, FrameRef, LinearCouplingSpec
from pkdyn.model.formats.xmldoc import XmlDoc
from pkdyn.model.validate import unit_vector
from pkdyn.model.warn import warn

__all__ = ["ELEMENTS", "UrdfPlus", "independent_actuators", "read_urdfplus"]

ELEMENTS = ("loop", "coupling", "constraint", "joint_constraint", "loop_constraint")
"""Top-level URDF+ elements (current and older spellings)."""

_LOOP_TYPES = ("revolute", "continuous", "prismatic", "planar", "fixed")
_ONE_DOF = ("revolute", "continuous", "prismatic")
_TRUE = ("true", "True")
_SPELLED = _TRUE + ("false", "False")
_CHILDREN = {
    "loop": ("predecessor", "successor", "axis"),
    "coupling": ("predecessor", "successor", "ratio"),
    "constraint": ("predecessor", "successor", "ratio", "axis"),
    "joint_constraint": ("parent", "child", "gear_ratio"),
    "loop_constraint": ("parent", "child", "parent_origin", "child_origin"),
}


@dataclass(frozen=True, eq=False)  # ClosureSpec fields: no boolean ==
class UrdfPlus:
    """What the URDF+ elements and attributes of a file say.

    Attributes:
        closures: One ``point`` closure per loop, named after it.
        couplings: One linear coupling per coupling, named after it.
        independent: ``independent`` flag of each joint that gives the attribute, by name.
        dependent_free: Joints declared dependent that no loop or coupling constrains.

    """

    closures: tuple[ClosureSpec, ...] = ()
    couplings: tuple[LinearCouplingSpec, ...] = ()
    independent: dict[str, bool] = field(default_factory=dict)
    dependent_free: tuple[str, ...] = ()

    @property
    def found(self) -> bool:
        """The file uses the dialect (an element or the ``independent`` attribute)."""
        return bool(self.closures or self.couplings or self.independent)


@dataclass
class _Tree:
    """The URDF tree: each link's parent link and the joint between them."""

    links: set[str]
    parent: dict[str, tuple[str, ET.Element]]

    def path(self, link: str, ancestor: str) -> list[ET.Element]:
        """Joints from ``ancestor`` (excluded) down to ``link``, child first."""
        out = []
        while link != ancestor:
            link, joint = self.parent[link]
            out.append(joint)
        return out

    def ancestors(self, link: str) -> list[str]:
        out = [link]
        while link in self.parent:
            link = self.parent[link][0]
            out.append(link)
        return out

    def common_ancestor(self, a: str, b: str) -> str | None:
        others = set(self.ancestors(b))
        return next((x for x in self.ancestors(a) if x in others), None)


def _tree(root: ET.Element) -> _Tree:
    links = {el.get("name", "") for el in root.findall("link")}
    parent = {}
    for j in root.findall("joint"):
        p, c = j.find("parent"), j.find("child")
        if p is not None and c is not None:  # validate.check_urdf names malformed joints
            parent[c.get("link", "")] = (p.get("link", ""), j)
    return _Tree(links, parent)


def _numbers(doc: XmlDoc, el: ET.Element, attr: str, default: str) -> np.ndarray:
    text = el.get(attr, default)
    try:
        v = np.array([float(t) for t in text.split()], dtype=float)
    except ValueError:
        raise doc.error(el, f"{attr}='{text}': expected 3 numbers") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise doc.error(el, f"{attr}='{text}': expected 3 finite numbers")
    return v


def _origin(doc: XmlDoc, el: ET.Element | None) -> pin.SE3:
    """Placement of an ``<origin xyz rpy>`` (identity when absent, as urdfdom reads it)."""
    if el is None:
        return pin.SE3.Identity()
    xyz = _numbers(doc, el, "xyz", "0 0 0")
    rpy = _numbers(doc, el, "rpy", "0 0 0")
    return pin.SE3(pin.rpy.rpyToMatrix(rpy), xyz)


def _name(doc: XmlDoc, el: ET.Element) -> str:
    name = el.get("name")
    if not name:
        raise doc.error(el, "missing attribute 'name' (URDF+ names every loop and coupling)")
    return name


def _link(doc: XmlDoc, el: ET.Element, tag: str, tree: _Tree) -> tuple[str, ET.Element]:
    """Link named by the child ``<tag link>`` of ``el``."""
    child = el.find(tag)
    if child is None:
        raise doc.error(el, f"missing <{tag} link=...>")
    link = child.get("link", "")
    if not link:
        raise doc.error(child, f"<{tag}> needs a link attribute")
    if link not in tree.links:
        raise doc.error(child, f"link '{link}' does not exist")
    return link, child


def _check_children(doc: XmlDoc, el: ET.Element, kind: str) -> None:
    extra = sorted({c.tag for c in el if isinstance(c.tag, str) and c.tag not in _CHILDREN[kind]})
    if extra:
        warn(
            f"{doc.source}: {doc.where(el)}: child element(s) {', '.join(f'<{t}>' for t in extra)} "
            f"not read (a URDF+ <{kind}> has {', '.join(f'<{t}>' for t in _CHILDREN[kind])})"
        )


def _loop(doc: XmlDoc, el: ET.Element, tree: _Tree, old: bool) -> ClosureSpec:
    """A ``<loop>`` (or ``<constraint type="position">``, ``<loop_constraint>``)."""
    name = _name(doc, el)
    if el.tag == "loop_constraint":
        pred, _ = _link(doc, el, "parent", tree)
        succ, _ = _link(doc, el, "child", tree)
        M1 = _origin(doc, el.find("parent_origin"))
        M2 = _origin(doc, el.find("child_origin"))
    else:
        pred, pel = _link(doc, el, "predecessor", tree)
        succ, sel = _link(doc, el, "successor", tree)
        M1, M2 = _origin(doc, pel.find("origin")), _origin(doc, sel.find("origin"))
    if pred == succ:
        raise doc.error(el, f"closes link '{pred}' on itself (predecessor = successor)")
    if tree.common_ancestor(pred, succ) is None:
        raise doc.error(el, f"links '{pred}' and '{succ}' are not in one tree")
    axis = np.array([1.0, 0.0, 0.0])  # urdfdom's default
    if not old:
        kind = el.get("type")
        if kind is None:
            raise doc.error(el, f"missing attribute 'type' (one of {', '.join(_LOOP_TYPES)})")
        if kind not in _LOOP_TYPES:
            raise doc.error(el, f"unknown loop type '{kind}'; URDF+ knows {', '.join(_LOOP_TYPES)}")
        ax = el.find("axis")
        if ax is not None and ax.get("xyz") is not None:
            u = unit_vector(_numbers(doc, ax, "xyz", "1 0 0"))
            if u is None:
                raise doc.error(ax, "the loop axis must be a non-zero vector")
            axis = np.asarray(u)
    return ClosureSpec(name, "point", FrameRef(pred, M1), FrameRef(succ, M2), axis)


def _ratio(doc: XmlDoc, el: ET.Element) -> float:
    """``<ratio value>`` (``<gear_ratio value>``, or the ``gear_ratio`` attribute, of old)."""
    tag = "gear_ratio" if el.tag == "joint_constraint" else "ratio"
    child = el.find(tag)
    if child is None and el.tag == "joint_constraint" and el.get("gear_ratio") is not None:
        text: str | None = el.get("gear_ratio")
        where = el
    elif child is None:
        if el.tag == "joint_constraint":
            raise doc.error(el, "missing <gear_ratio value=...>")
        return 1.0  # urdfdom's CouplingConstraint::clear()
    else:
        text, where = child.get("value"), child
    if text is None:
        raise doc.error(where, f"<{tag}> needs a value attribute")
    try:
        ratio = float(text)
    except ValueError:
        raise doc.error(where, f"value='{text}' is not a number") from None
    if not math.isfinite(ratio) or ratio == 0.0:
        raise doc.error(where, f"value='{text}': the ratio must be a finite non-zero number")
    return ratio


def _path_terms(
    doc: XmlDoc, el: ET.Element, joints: list[ET.Element], coefficient: float
) -> list[tuple[str, float]]:
    out = []
    for j in joints:
        kind = j.get("type", "")
        if kind == "fixed":
            continue
        if kind not in _ONE_DOF:
            raise doc.error(
                el,
                f"its path crosses joint '{j.get('name')}' ({kind}), which has no single "
                "coordinate to sum",
            )
        out.append((j.get("name", ""), coefficient))
    return out


def _coupling(
    doc: XmlDoc, el: ET.Element, tree: _Tree
) -> tuple[LinearCouplingSpec, list[ET.Element]]:
    """A ``<coupling>`` (or ``<constraint type="rolling">``, ``<joint_constraint>``)."""
    name = _name(doc, el)
    old = el.tag == "joint_constraint"
    pred, _ = _link(doc, el, "parent" if old else "predecessor", tree)
    succ, _ = _link(doc, el, "child" if old else "successor", tree)
    if pred == succ:
        raise doc.error(el, f"couples link '{pred}' to itself (predecessor = successor)")
    nca = tree.common_ancestor(pred, succ)
    if nca is None:
        raise doc.error(el, f"links '{pred}' and '{succ}' are not in one tree")
    ratio = _ratio(doc, el)
    p_joints, s_joints = tree.path(pred, nca), tree.path(succ, nca)
    terms = _path_terms(doc, el, p_joints, ratio) + _path_terms(doc, el, s_joints, -1.0)
    if not terms:
        raise doc.error(el, f"no joint coordinate lies between links '{pred}' and '{succ}'")
    return LinearCouplingSpec(name, tuple(terms), 0.0), p_joints + s_joints


def _loop_joints(tree: _Tree, c: ClosureSpec) -> list[ET.Element]:
    nca = tree.common_ancestor(c.frame1.link, c.frame2.link)
    assert nca is not None  # checked when read
    return tree.path(c.frame1.link, nca) + tree.path(c.frame2.link, nca)


def _independent(doc: XmlDoc, root: ET.Element) -> dict[str, bool]:
    flags: dict[str, bool] = {}
    odd: list[str] = []
    for j in root.findall("joint"):
        text = j.get("independent")
        if text is None:
            continue
        flags[j.get("name", "")] = text in _TRUE
        if text not in _SPELLED:
            odd.append(f"{doc.where(j)} independent='{text}'")
    if odd:
        warn(
            f"{doc.source}: {'; '.join(odd[:3])}{' ...' if len(odd) > 3 else ''}: read as "
            "false, as URDF+'s parser reads anything but 'true' or 'True'"
        )
    return flags


def read_urdfplus(doc: XmlDoc, root: ET.Element | None = None) -> UrdfPlus:
    """The URDF+ elements and attributes of a URDF (see the module docstring).

    Args:
        doc: The URDF, parsed with line numbers (:func:`~pkdyn.model.formats.xmldoc.parse_xml`).
        root: The ``<robot>`` element to read (default ``doc.root``; a copy without the
            elements the user asked to ignore).

    Returns:
        Closures, couplings and ``independent`` flags (empty when the file has none).

    Raises:
        DescriptionError: A malformed URDF+ element, naming it and its line.

    """
    root = doc.root if root is None else root
    found = [el for el in root if el.tag in ELEMENTS]
    flags = _independent(doc, root)
    if not found and not flags:
        return UrdfPlus()
    tree = _tree(root)
    closures: list[ClosureSpec] = []
    couplings: list[LinearCouplingSpec] = []
    constrained: set[str] = set()
    for el in found:
        kind = el.tag
        if kind == "constraint":
            ctype = el.get("type")
            if ctype not in ("position", "rolling"):
                raise doc.error(
                    el,
                    f"constraint type '{ctype}': URDF+'s older spelling knows 'position' (a "
                    "loop, now <loop>) and 'rolling' (a coupling, now <coupling>)",
                )
            kind = "loop" if ctype == "position" else "coupling"
        _check_children(doc, el, el.tag)
        if kind in ("loop", "loop_constraint"):
            c = _loop(doc, el, tree, old=el.tag != "loop")
            closures.append(c)
            constrained.update(j.get("name", "") for j in _loop_joints(tree, c))
        else:
            spec, joints = _coupling(doc, el, tree)
            couplings.append(spec)
            constrained.update(j.get("name", "") for j in joints)
    names = [c.name for c in closures] + [c.name for c in couplings]
    for el, n in zip(found, names, strict=True):
        if names.count(n) > 1:
            raise doc.error(el, f"name '{n}' is given to two URDF+ loops or couplings")
    free = tuple(n for n, flag in flags.items() if not flag and n not in constrained)
    if free:
        shown = ", ".join(f"'{n}'" for n in free[:4]) + (" ..." if len(free) > 4 else "")
        warn(
            f'{doc.source}: {len(free)} joint(s) declared dependent (independent="false") but '
            f"constrained by no loop or coupling of the file: {shown}; they move freely"
        )
    return UrdfPlus(tuple(closures), tuple(couplings), flags, free)


def independent_actuators(
    root: ET.Element, plus: UrdfPlus, actuators: tuple[ActuatorSpec, ...]
) -> tuple[ActuatorSpec, ...]:
    """Actuators of the independent joints, where no transmission declares any.

    Args:
        root: The ``<robot>`` element.
        plus: Its URDF+ reading.
        actuators: The actuators its ``<transmission>`` elements declare.

    Returns:
        ``actuators`` when there are any or the file gives no ``independent`` attribute; else
        one actuator per moving 1-DoF joint whose ``independent`` flag is true (the default),
        in file order.

    """
    if actuators or not plus.independent:
        return actuators
    out = []
    for j in root.findall("joint"):
        name = j.get("name", "")
        if j.get("type") not in _ONE_DOF or not plus.independent.get(name, True):
            continue
        effort = velocity = math.inf
        lim = j.find("limit")
        if lim is not None:  # validate.check_urdf has checked the numbers
            effort = float(lim.get("effort", "inf"))
            velocity = float(lim.get("velocity", "inf"))
        out.append(ActuatorSpec(name, name, 1.0, effort, velocity))
    return tuple(out)
