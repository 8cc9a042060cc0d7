"""A URDF+ file written back as a pkdyn description (``pkdyn urdf FILE.urdf``).

The URDF tree is kept as it is (links, joints, geometry, transmissions, every element pkdyn does
not read); what URDF+ says beyond it is written in pkdyn's elements (``urdf/README.md``), so
that loading the written file gives the same robot -- model, closures, couplings, actuation:

- each loop (``<loop>``, ``<constraint type="position">``, ``<loop_constraint>``) ->
  ``<pkdyn:closure name type="point">`` with its two ``<pkdyn:frame link xyz rpy>``;
- each coupling (``<coupling>``, ``<constraint type="rolling">``, ``<joint_constraint>``) ->
  ``<pkdyn:coupling name offset="0">`` with one ``<pkdyn:term joint coefficient>`` per joint of
  its two paths (``ratio`` on the predecessor's, ``-1`` on the successor's);
- the ``independent`` joints, where no transmission declares the actuators -> one
  ``SimpleTransmission`` each (reduction 1), named after its joint; the attributes are removed.

The pkdyn format is stricter than URDF about inertias: a link whose ``<inertial>`` has neither
mass nor inertia loses the element (a massless link has none); an invalid tensor (triangle
inequality, not positive semi-definite) or a point mass refuses the export, naming the link,
unless the tensors are repaired (``repair_inertias=True``: the same projection as the load,
written into the file). Elements named in ``ignore_elements`` are left out, as the load leaves
them out.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.description import NAMESPACE, ClosureSpec, LinearCouplingSpec
from pkdyn.model.formats import unread, urdfplus
from pkdyn.model.formats.urdf_writer import number_text, vector_text
from pkdyn.model.formats.xmldoc import parse_xml
from pkdyn.model.validate import inertia_problem, repair_inertias

__all__ = ["pkdyn_description"]


def _add(root: ET.Element, el: ET.Element) -> None:
    """Append ``el`` to the root, indented by two spaces like a URDF's elements."""
    ET.indent(el, space="  ", level=1)
    if len(root):
        root[-1].tail = "\n  "
    else:
        root.text = "\n  "
    el.tail = "\n"
    root.append(el)


def _closure(c: ClosureSpec) -> ET.Element:
    el = ET.Element("pkdyn:closure", {"name": c.name, "type": c.kind})
    for f in (c.frame1, c.frame2):
        attrs = {"link": f.link}
        M = f.placement
        if np.any(M.translation != 0.0):
            attrs["xyz"] = vector_text(M.translation)
        if not np.array_equal(M.rotation, np.eye(3)):
            attrs["rpy"] = vector_text(pin.rpy.matrixToRpy(M.rotation))
        ET.SubElement(el, "pkdyn:frame", attrs)
    return el


def _coupling(c: LinearCouplingSpec) -> ET.Element:
    el = ET.Element("pkdyn:coupling", {"name": c.name, "offset": number_text(c.offset)})
    for joint, coef in c.terms:
        ET.SubElement(el, "pkdyn:term", {"joint": joint, "coefficient": number_text(coef)})
    return el


def _transmission(name: str) -> ET.Element:
    el = ET.Element("transmission", {"name": name})
    ET.SubElement(el, "type").text = "transmission_interface/SimpleTransmission"
    ET.SubElement(el, "joint", {"name": name})
    act = ET.SubElement(el, "actuator", {"name": name})
    ET.SubElement(act, "mechanicalReduction").text = "1"
    return el


def _inertials(source: str, root: ET.Element) -> None:
    """Massless ``<inertial>`` elements removed; tensors the pkdyn format refuses refused."""
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        mass_el = inertial.find("mass")
        mass = float(mass_el.get("value", "0")) if mass_el is not None else 0.0
        el = inertial.find("inertia")
        keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        i = {k: float(el.get(k, "0")) if el is not None else 0.0 for k in keys}
        tensor = np.array(
            [
                [i["ixx"], i["ixy"], i["ixz"]],
                [i["ixy"], i["iyy"], i["iyz"]],
                [i["ixz"], i["iyz"], i["izz"]],
            ]
        )
        if mass == 0.0 and not np.any(tensor):
            link.remove(inertial)
            continue
        problem = inertia_problem(mass, tensor, point_mass=False)
        if problem is not None:
            raise DescriptionError(
                source,
                f"link '{link.get('name', '?')}' <inertia>",
                f"{problem}; the pkdyn format refuses it: write the description with "
                "repair_inertias=True (--repair-inertias) for the nearest valid tensor",
            )


def pkdyn_description(
    text: str,
    source: str,
    ignore_elements: Sequence[str] = (),
    repair_inertias: bool = False,
) -> str:
    """A URDF(+) description in pkdyn's format (see the module docstring).

    Args:
        text: The URDF text.
        source: File or name, for messages.
        ignore_elements: Element names to leave out (as :func:`pkdyn.load` does).
        repair_inertias: Write the nearest valid tensors in place of invalid ones.

    Returns:
        The pkdyn URDF text; ``text`` itself when it has no URDF+ element or attribute and
        nothing is left out or repaired.

    Raises:
        DescriptionError: Malformed URDF+ elements, or inertias the pkdyn format refuses.

    """
    doc = parse_xml(text, source)
    if doc.root.tag != "robot":
        raise DescriptionError(source, f"<{doc.root.tag}>", "the root element must be <robot>")
    ignore = unread.ignored_names(ignore_elements)
    changed = unread.prune(doc, ignore) > 0
    if repair_inertias and _repair(source, doc.root):
        changed = True
    plus = urdfplus.read_urdfplus(doc)
    if not plus.found and not changed:
        return text
    root = doc.root
    declared = urdfplus.independent_actuators(root, plus, ())
    has_transmissions = any(  # SimpleTransmission ones: the actuators pkdyn reads
        (t.findtext("type") or t.get("type") or "SimpleTransmission")
        .strip()
        .endswith("SimpleTransmission")
        for t in root.findall("transmission")
    )
    for el in [e for e in root if e.tag in urdfplus.ELEMENTS]:
        root.remove(el)
    for j in root.findall("joint"):
        j.attrib.pop("independent", None)
    if plus.found:
        _inertials(source, root)
    if "xmlns:pkdyn" not in root.attrib:
        root.set("xmlns:pkdyn", NAMESPACE)
    for c in plus.closures:
        _add(root, _closure(c))
    for lc in plus.couplings:
        _add(root, _coupling(lc))
    if not has_transmissions:
        for a in declared:
            _add(root, _transmission(a.joint))
    out = ET.tostring(root, encoding="unicode")
    return '<?xml version="1.0"?>\n' + out + ("\n" if not out.endswith("\n") else "")


def _repair(source: str, root: ET.Element) -> int:
    """Repair the tensors of ``root`` in place (one warning); how many changed."""
    from pkdyn.model.inertia import report

    repaired = repair_inertias(source, root)
    report(source, [], repaired, [])
    return len(repaired)
