"""Validation of the URDF part of a description: numbers, physics and tree structure.

The URDF parser either rejects a malformed document without saying where, or silently drops
what it cannot read (a geometry with a NaN size disappears from the collision checks, a
``<inertial>`` with NaN is ignored), and it accepts values no physical robot has. Before the
model is built, :func:`check_urdf` raises one :class:`~pkdyn.exceptions.DescriptionError` naming
the link, joint or element at fault:

- every number of links and joints: a number (not text), finite; vectors of the right length
  (``<dynamics>`` is read, and checked, with the passive elements: :mod:`pkdyn.model.passive`);
- inertials (:func:`inertia_problem`, the rule every importer uses): mass > 0 (a massless link
  has no ``<inertial>``; a plain URDF may give 0, as ROS descriptions do for frames; a rotor
  may have rotational inertia without mass, as legged-robot descriptions model their motors),
  inertia tensor positive semi-definite (no negative principal moment; a thin rod's zero moment
  is a limit of real bodies) and satisfying the triangle inequality of its principal moments
  (``I1 + I2 >= I3``), not all zero with a positive mass (pkdyn descriptions; plain URDFs keep
  point masses); plain URDFs only warn for the inertia tensor (one warning naming the links),
  as many published descriptions break it; :func:`repair_inertias` (``repair_inertias=True``)
  replaces them by the nearest valid tensors (:mod:`pkdyn.model.inertia`);
- geometry: box, cylinder, sphere and capsule sizes > 0, mesh scales finite and non-zero;
- joints: a moving joint's axis is non-zero; ``lower <= upper``; effort and velocity limits
  >= 0;
- tree: every joint names existing links, no link has two parents, no joint is its own parent,
  no cycle;
- transmissions: at most one ``SimpleTransmission`` per joint.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

from pkdyn.exceptions import DescriptionError

__all__ = [
    "DATA_BYTES_PER_NV3",
    "INERTIA_SLACK",
    "MAX_DATA_BYTES",
    "MAX_TREE_DEPTH",
    "check_data_size",
    "check_urdf",
    "geometry_problems",
    "inertia_problem",
    "repair_inertias",
    "unit_vector",
]

INERTIA_SLACK = 1e-6
"""Relative tolerance (of the trace) of the inertia tests: descriptions store ~10 digits, so a
thin plate written exactly on the triangle inequality's boundary still passes."""

DATA_BYTES_PER_NV3 = 64
"""Pinocchio 4.1's ``Data`` takes about 64 nv^3 bytes (measured: 0.5 GB at nv = 200, 1.7 GB at
nv = 300, the same for a chain and a star): a 5,000-link chain would ask for 8 TB."""

MAX_DATA_BYTES = 1024**3
"""Largest Pinocchio ``Data`` pkdyn creates (1 GiB: nv up to about 250; a humanoid has ~40)."""

MAX_TREE_DEPTH = 1000
"""Deepest kinematic tree accepted: the URDF parser recurses along the tree and crashes the
process (stack overflow) on chains a few thousand links deep. Real robots are ~20 deep."""

_DOF = {"revolute": 1, "continuous": 1, "prismatic": 1, "planar": 3, "floating": 6}
_UPGRADE = {"spherical": 2, "universal": 1}  # extra velocity coordinates of a pkdyn:joint


def check_data_size(source: str, nv: int, joints: int) -> None:
    """Refuse a model whose Pinocchio ``Data`` would exhaust memory (64 nv^3 bytes).

    Args:
        source: File or robot name, for messages.
        nv: Velocity coordinates (or an estimate before the model is built).
        joints: Number of joints, for the message.

    Raises:
        DescriptionError: Above :data:`MAX_DATA_BYTES` or half of the memory available.

    """
    import os

    need = DATA_BYTES_PER_NV3 * float(nv) ** 3
    limit = float(MAX_DATA_BYTES)
    try:
        limit = min(limit, 0.5 * os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        pass
    if need > limit:
        largest = int((limit / DATA_BYTES_PER_NV3) ** (1.0 / 3.0))
        raise DescriptionError(
            source,
            f"model size ({joints} joints, nv = {nv})",
            f"Pinocchio's data for it would take about {need / 1e9:.3g} GB (64 nv^3 bytes); "
            f"pkdyn accepts up to nv = {largest} here ({limit / 1e9:.3g} GB of memory)",
        )


def _check_size(source: str, root: ET.Element, parent_of: dict[str, str]) -> None:
    """Tree depth and estimated nv, before the URDF parser and Pinocchio see the model."""
    depth: dict[str, int] = {}
    for start in parent_of:
        path, link = [], start
        while link in parent_of and link not in depth:
            path.append(link)
            link = parent_of[link]
        d = depth.get(link, 0)
        for node in reversed(path):
            d += 1
            depth[node] = d
    deepest = max(depth.values(), default=0)
    if deepest > MAX_TREE_DEPTH:
        leaf = max(depth, key=lambda k: depth[k])
        raise DescriptionError(
            source,
            f"kinematic tree ({deepest} joints from the root to link '{leaf}')",
            f"deeper than {MAX_TREE_DEPTH} joints: the URDF parser would overflow its stack",
        )
    nv = sum(_DOF.get(j.get("type", ""), 0) for j in root.findall("joint"))
    ns = "{urn:pkdyn:urdf:1}"
    nv += sum(_UPGRADE.get(j.get("type", ""), 0) for j in root.findall(ns + "joint"))
    check_data_size(source, nv, len(root.findall("joint")))


_VECTORS = {
    ("origin", "xyz"): 3,
    ("origin", "rpy"): 3,
    ("axis", "xyz"): 3,
    ("box", "size"): 3,
}
_SCALARS = {
    "mass": ("value",),
    "inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
    "limit": ("lower", "upper", "effort", "velocity"),
    "cylinder": ("radius", "length"),
    "sphere": ("radius",),
    "capsule": ("radius", "length"),
    "safety_controller": ("soft_lower_limit", "soft_upper_limit", "k_position", "k_velocity"),
}
_POSITIVE = {("box", "size"), ("cylinder", "radius"), ("cylinder", "length")}
_POSITIVE |= {("sphere", "radius"), ("capsule", "radius"), ("capsule", "length")}
_MOVING = ("revolute", "continuous", "prismatic")


def _where(kind: str, owner: ET.Element, el: ET.Element, attr: str, text: str) -> str:
    name = owner.get("name", "?")
    return f"{kind} '{name}' <{el.tag}> attribute {attr}='{text}'"


def _numbers(
    source: str, kind: str, owner: ET.Element, el: ET.Element, attr: str, n: int | None
) -> list[float]:
    text = el.get(attr, "")
    tokens = text.split()
    try:
        values = [float(t) for t in tokens]
    except ValueError:
        raise DescriptionError(
            source, _where(kind, owner, el, attr, text), "expected numbers"
        ) from None
    if n is not None and len(values) != n:
        raise DescriptionError(source, _where(kind, owner, el, attr, text), f"expected {n} numbers")
    if not all(math.isfinite(v) for v in values):
        raise DescriptionError(
            source,
            _where(kind, owner, el, attr, text),
            "NaN and infinite values are not allowed",
        )
    return values


def _count(tag: str, attr: str) -> int | None | bool:
    """How many numbers an attribute holds (``None``: 1 or 3), ``False`` if not numeric."""
    if (tag, attr) in _VECTORS:
        return _VECTORS[(tag, attr)]
    if attr in _SCALARS.get(tag, ()):
        return 1
    if (tag, attr) == ("mesh", "scale"):
        return None
    return False


def _check_element(source: str, kind: str, owner: ET.Element, el: ET.Element) -> None:
    """The numbers of one element's attributes (see :func:`_check_numbers`)."""
    tag = str(el.tag)
    for attr in el.attrib:
        n = _count(tag, attr)
        if n is False:
            continue
        values = _numbers(source, kind, owner, el, attr, n or None)
        if (tag, attr) in _POSITIVE and not all(v > 0.0 for v in values):
            raise DescriptionError(
                source,
                _where(kind, owner, el, attr, el.get(attr, "")),
                "sizes must be > 0 [m] (the body would vanish)",
            )
        if n is None and (len(values) not in (1, 3) or 0.0 in values):
            raise DescriptionError(
                source,
                _where(kind, owner, el, attr, el.get(attr, "")),
                "a mesh scale is 1 or 3 non-zero numbers",
            )


def _check_numbers(source: str, root: ET.Element) -> None:
    """Every number of every link and joint: parseable, finite, the right count, sizes > 0."""
    for kind in ("link", "joint"):
        for owner in root.findall(kind):
            for el in owner.iter():
                _check_element(source, kind, owner, el)


def geometry_problems(source: str, root: ET.Element) -> list[tuple[ET.Element, ET.Element, str]]:
    """The visual and collision elements of a URDF whose numbers are malformed.

    Args:
        source: File or robot name, for messages.
        root: The ``<robot>`` element.

    Returns:
        ``(link, element, problem)`` of each ``<visual>`` or ``<collision>`` that
        :func:`check_urdf` would refuse (a size that is no number, not finite, not > 0...).

    """
    out = []
    for link in root.findall("link"):
        for shape in link:
            if shape.tag not in ("visual", "collision"):
                continue
            try:
                for el in shape.iter():
                    _check_element(source, "link", link, el)
            except DescriptionError as err:
                out.append((link, shape, str(err).split(": ", 1)[-1]))
    return out


def _tensor(inertial: ET.Element) -> Any:
    """Rotational inertia (3, 3) of an ``<inertial>`` (zero without ``<inertia>``)."""
    import numpy as np

    el = inertial.find("inertia")
    if el is None:
        return np.zeros((3, 3))
    i = {k: float(el.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    return np.array(
        [
            [i["ixx"], i["ixy"], i["ixz"]],
            [i["ixy"], i["iyy"], i["iyz"]],
            [i["ixz"], i["iyz"], i["izz"]],
        ]
    )


def _check_inertials(source: str, root: ET.Element, strict: bool) -> None:
    """Masses and inertia tensors (numbers already checked); see the module docstring."""
    from pkdyn.model.inertia import massless_rotor, report

    odd: list[tuple[str, str]] = []
    rotors: list[str] = []
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        name = link.get("name", "?")
        mass_el = inertial.find("mass")
        text = mass_el.get("value", "0") if mass_el is not None else "0"
        mass = float(text)
        I = _tensor(inertial)
        if mass < 0.0 or (strict and mass == 0.0 and not massless_rotor(mass, I)):
            raise DescriptionError(
                source,
                f"link '{name}' <mass value='{text}'>",
                "a mass must be > 0 [kg] (a link without mass has no <inertial>; a rotor "
                "without mass has its rotational inertia)",
            )
        if inertial.find("inertia") is None:
            continue
        problem = inertia_problem(mass, I, point_mass=not strict)
        if problem is None:
            if massless_rotor(mass, I):
                rotors.append(name)
            continue
        if strict:
            raise DescriptionError(
                source,
                f"link '{name}' <inertia>",
                f"{problem} (or load with repair_inertias=True for the nearest valid tensor)",
            )
        odd.append((name, problem))
    report(source, odd, [], rotors)


def repair_inertias(source: str, root: ET.Element) -> list[tuple[str, Any, Any]]:
    """Replace the invalid inertia tensors of a URDF by the nearest valid ones, in place.

    Args:
        source: File or robot name, for messages.
        root: The ``<robot>`` element (its ``<inertia>`` attributes are rewritten).

    Returns:
        ``(link, before, after)`` (tensors (3, 3)) of every tensor changed.

    Raises:
        DescriptionError: Malformed numbers (as :func:`check_urdf`), or a negative mass.

    """
    from pkdyn.model.inertia import nearest_valid_inertia

    _check_numbers(source, root)
    out = []
    for link in root.findall("link"):
        inertial = link.find("inertial")
        el = inertial.find("inertia") if inertial is not None else None
        if inertial is None or el is None:
            continue
        mass_el = inertial.find("mass")
        mass = float(mass_el.get("value", "0")) if mass_el is not None else 0.0
        I = _tensor(inertial)
        if mass < 0.0 or inertia_problem(mass, I) is None:
            continue  # a negative mass stays an error (check_urdf says so)
        fixed = nearest_valid_inertia(I)
        for k, (a, b) in {
            "ixx": (0, 0),
            "ixy": (0, 1),
            "ixz": (0, 2),
            "iyy": (1, 1),
            "iyz": (1, 2),
            "izz": (2, 2),
        }.items():
            el.set(k, repr(float(fixed[a, b])))
        out.append((link.get("name", "?"), I, fixed))
    return out


def inertia_problem(mass: float, inertia: Any, point_mass: bool = True) -> str | None:
    """Why a rigid body's mass and inertia are not physical, or ``None``: one rule, every format.

    Every importer (pkdyn's URDF, plain URDF, MJCF, SDFormat) asks this function; each decides
    whether a problem is an error (pkdyn descriptions, MJCF and SDFormat, as MuJoCo itself) or
    a warning (plain URDF: many published ones break the triangle inequality slightly).

    Args:
        mass: Mass [kg].
        inertia: Rotational inertia about the centre of mass (3, 3) [kg m^2].
        point_mass: Accept an all-zero tensor with a positive mass (a point mass, as URDF and
            SDFormat readers do); otherwise it is refused like a negative moment.

    Returns:
        The problem (one line), or ``None``: finite numbers, mass >= 0, a symmetric positive
        semi-definite tensor satisfying the triangle inequality of its principal moments
        (``I1 + I2 >= I3``) within :data:`INERTIA_SLACK`.

    """
    import numpy as np

    M = np.asarray(inertia, dtype=float)
    if not (math.isfinite(mass) and np.all(np.isfinite(M))):
        return "mass and inertia must be finite numbers"
    if mass < 0.0:
        return f"mass {mass:g} kg is negative"
    if not np.allclose(M, M.T, rtol=0.0, atol=1e-12 * max(1.0, float(np.abs(M).max()))):
        return "the inertia tensor is not symmetric"
    if mass > 0.0 and not point_mass and not np.any(M):
        return (
            f"an all-zero inertia tensor with mass {mass:g} kg (a point mass has no rotational "
            "inertia about any axis: give the body's tensor about its centre of mass)"
        )
    scale = float(np.abs(M).max())
    ev = np.linalg.eigvalsh(M / scale) * scale if scale > 0.0 else np.zeros(3)
    slack = INERTIA_SLACK * max(float(np.trace(M)), 0.0)
    moments = ", ".join(f"{v:.4g}" for v in ev)
    if ev[0] < -slack:
        return (
            f"the inertia tensor is not positive semi-definite (principal moments {moments} "
            "kg m^2): give the tensor about the centre of mass, every principal moment >= 0"
        )
    if ev[0] + ev[1] < ev[2] - slack:
        return (
            f"the principal moments {moments} kg m^2 violate the triangle inequality "
            "I1 + I2 >= I3: no body has this inertia"
        )
    return None


def _check_joints(source: str, root: ET.Element) -> dict[str, str]:
    links = {el.get("name", "") for el in root.findall("link")}
    parent_of: dict[str, str] = {}
    joint_of: dict[str, str] = {}
    for j in root.findall("joint"):
        name = j.get("name", "?")
        jtype = j.get("type", "")
        parent_el, child_el = j.find("parent"), j.find("child")
        parent = parent_el.get("link", "") if parent_el is not None else ""
        child = child_el.get("link", "") if child_el is not None else ""
        for role, link in (("parent", parent), ("child", child)):
            if link not in links:
                raise DescriptionError(
                    source, f"joint '{name}' <{role} link='{link}'>", "no link of that name"
                )
        if parent == child:
            raise DescriptionError(
                source, f"joint '{name}'", f"link '{child}' cannot be its own parent"
            )
        if child in parent_of:
            raise DescriptionError(
                source,
                f"joint '{name}'",
                f"link '{child}' already has a parent (joint '{joint_of[child]}' from "
                f"'{parent_of[child]}'); a tree link has one parent: close loops with a "
                "<pkdyn:closure> instead",
            )
        parent_of[child] = parent
        joint_of[child] = name
        axis = j.find("axis")
        if jtype in _MOVING and axis is not None:
            values = [float(t) for t in axis.get("xyz", "1 0 0").split()]
            norm = math.sqrt(sum(v * v for v in values))
            if norm < 1e-12:
                raise DescriptionError(
                    source,
                    f"joint '{name}' <axis xyz='{axis.get('xyz')}'>",
                    "the axis of a moving joint must be a non-zero vector",
                )
            if not math.isfinite(norm):  # the URDF parser would divide by inf: a zero axis
                raise DescriptionError(
                    source,
                    f"joint '{name}' <axis xyz='{axis.get('xyz')}'>",
                    "the axis's length overflows; give a unit vector",
                )
        lim = j.find("limit")
        if lim is not None and jtype in _MOVING:
            lo, hi = lim.get("lower"), lim.get("upper")
            if (
                jtype != "continuous"
                and lo is not None
                and hi is not None
                and float(lo) > float(hi)
            ):
                raise DescriptionError(
                    source,
                    f"joint '{name}' <limit lower='{lo}' upper='{hi}'>",
                    "lower exceeds upper; swap them",
                )
            for attr in ("effort", "velocity"):
                text = lim.get(attr)
                if text is not None and float(text) < 0.0:
                    raise DescriptionError(
                        source,
                        f"joint '{name}' <limit {attr}='{text}'>",
                        f"the {attr} limit must be >= 0",
                    )
    rooted: set[str] = set()  # links whose ancestry reaches a root (linear overall)
    for start in parent_of:  # a cycle: walking up from a link comes back to it
        path = [start]
        link = start
        while link in parent_of and link not in rooted:
            link = parent_of[link]
            if link in path:
                raise DescriptionError(
                    source,
                    f"joint '{joint_of[start]}'",
                    f"the links form a cycle through '{link}': the URDF must be a tree "
                    "(close loops with a <pkdyn:closure>)",
                )
            path.append(link)
        rooted.update(path)
    return parent_of


def _check_transmissions(source: str, root: ET.Element) -> None:
    owner: dict[str, str] = {}
    for t in root.findall("transmission"):
        ttype = t.findtext("type") or t.get("type") or "SimpleTransmission"
        if not ttype.strip().endswith("SimpleTransmission"):
            continue
        tname = t.get("name", "?")
        for j in t.findall("joint"):
            jname = j.get("name", "")
            if jname in owner:
                raise DescriptionError(
                    source,
                    f"transmission '{tname}'",
                    f"joint '{jname}' is already driven by transmission '{owner[jname]}': one "
                    "actuator per joint",
                )
            owner[jname] = tname


def check_urdf(source: str, root: ET.Element, strict: bool) -> None:
    """Validate the URDF part of a description (see the module docstring).

    Args:
        source: File or robot name, for messages.
        root: The ``<robot>`` element.
        strict: A pkdyn description (with pkdyn elements): zero masses and non-physical inertia
            tensors are errors. Plain URDFs load as the URDF parser reads them, with a warning
            for non-physical inertia tensors.

    Raises:
        DescriptionError: Naming the link, joint, transmission or element at fault.

    """
    _check_numbers(source, root)
    parent_of = _check_joints(source, root)
    _check_size(source, root, parent_of)
    _check_inertials(source, root, strict)
    _check_transmissions(source, root)


def unit_vector(v: Any) -> Any:
    """``v / |v|`` computed without overflow (huge components), or ``None`` (zero, non-finite).

    Args:
        v: A vector (n,).

    Returns:
        The unit vector (n,), or ``None`` when ``v`` is zero or not finite.

    """
    import numpy as np

    a = np.asarray(v, dtype=float)
    if not np.all(np.isfinite(a)):
        return None
    top = float(np.abs(a).max()) if a.size else 0.0
    if top == 0.0:
        return None
    a = a / top  # the largest component is 1: no overflow, no underflow to zero
    return a / float(np.linalg.norm(a))
