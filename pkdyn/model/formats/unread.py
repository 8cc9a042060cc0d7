"""No silent trees: every element an importer does not read is named, loop-like ones refused.

A URDF, SDFormat or MJCF file may hold elements pkdyn does not read: a simulator's settings
(harmless), or the loops and couplings of a dialect pkdyn does not know (then the mechanism
would load as a tree with the wrong mobility, and every figure computed on it would be wrong).
:func:`check` looks at the elements where a mechanism is described -- the top level (children of
``<robot>``, ``<model>`` / ``<world>`` / ``<sdf>``, ``<mujoco>``) and the inside of every joint
(and of an SDFormat joint's ``<axis>``) -- and:

- an element whose name says it closes a loop or couples joints (its local name contains
  ``loop``, ``closure``, ``constraint``, ``coupling`` or ``mimic``, in any namespace) that pkdyn
  does not read is a :class:`~pkdyn.exceptions.DescriptionError` naming it and its line, unless
  the user ignores it explicitly;
- any other unread element gives one warning per element name, with its count and lines.

``ignore_elements`` (``pkdyn.load(..., ignore_elements=("loop",))``, ``--ignore-element
loop``): elements of those names (the local name, or the prefixed one such as
``drake:ball_constraint``) are removed before anything is read, wherever they are, with one
warning saying how many; a name that matches nothing is warned about too (a typo would
otherwise go unnoticed).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.formats.xmldoc import XmlDoc
from pkdyn.model.warn import warn

__all__ = ["LOOP_WORDS", "check", "ignored_names", "local", "prune"]

LOOP_WORDS = ("loop", "closure", "constraint", "coupling", "mimic")
"""Words that, in an element's local name, say it closes a loop or couples joints."""

_URDF_TOP = {"link", "joint", "transmission", "material", "gazebo"}
_URDF_PLUS = {"loop", "coupling", "constraint", "joint_constraint", "loop_constraint"}
_URDF_JOINT = {"origin", "parent", "child", "axis", "limit", "dynamics", "mimic"}
_DRAKE_READ = {"ball_constraint", "weld_constraint"}
_SDF_ROOT = {"model", "world"}
_SDF_WORLD = {"model", "include"}
_SDF_MODEL = {"link", "joint", "frame", "pose", "static", "model", "include"}
_SDF_MODEL_SEEN = {"drake:joint", "drake:linear_bushing_rpy"}  # refused / warned by the reader
_SDF_JOINT = {"parent", "child", "pose", "axis", "axis2", "thread_pitch", "gearbox_ratio"}
_SDF_JOINT |= {"gearbox_reference_body", "screw_thread_pitch"}  # of types refused by the reader
_SDF_AXIS = {"xyz", "limit", "dynamics", "use_parent_model_frame"}
_MJCF_TOP = {"compiler", "option", "default", "asset", "worldbody", "equality", "actuator"}
_MJCF_TOP |= {"keyframe", "tendon", "include"}


def local(tag: str) -> str:
    """Local name of a tag: ``{uri}name`` or ``prefix:name`` -> ``name``."""
    return tag.rsplit("}", 1)[-1].rsplit(":", 1)[-1]


def _prefix(tag: str) -> str:
    return tag.split(":", 1)[0] if ":" in tag and not tag.startswith("{") else ""


def ignored_names(names: Iterable[str] | None) -> frozenset[str]:
    """Validate ``ignore_elements``: element names (``loop``, ``drake:ball_constraint``).

    Raises:
        InvalidInputError: Not a sequence of non-empty names without spaces or angle brackets.

    """
    if names is None:
        return frozenset()
    if isinstance(names, str):
        names = (names,)
    out = []
    for n in names:
        if not isinstance(n, str) or not n.strip() or any(c in n for c in " <>/\t\n"):
            raise InvalidInputError(
                "ignore_elements",
                f"{n!r} is not an element name; give names such as 'loop' or "
                "'drake:ball_constraint' (without < >)",
            )
        out.append(n.strip())
    return frozenset(out)


def _matches(tag: str, ignore: frozenset[str]) -> bool:
    return bool(ignore) and (tag in ignore or local(tag) in ignore)


def _loop_like(tag: str) -> bool:
    name = local(tag).lower()
    return any(w in name for w in LOOP_WORDS)


def _namespaces(root: ET.Element) -> dict[str, str]:
    """Prefix -> namespace URI declared on the root (``xmlns:p="uri"``)."""
    return {k[6:]: v for k, v in root.attrib.items() if k.startswith("xmlns:")}


class _Found:
    """Unread elements, grouped by name, and the loop-like ones."""

    def __init__(self, doc: XmlDoc, ignore: frozenset[str]) -> None:
        self.doc = doc
        self.ignore = ignore
        self.groups: dict[tuple[str, str], list[ET.Element]] = {}

    def add(self, el: ET.Element, where: str) -> None:
        tag = el.tag if isinstance(el.tag, str) else ""
        if not tag or _matches(tag, self.ignore):
            return
        if _loop_like(tag):
            name = local(tag)
            raise self.doc.error(
                el,
                f"<{tag}> {where} says it closes a loop or couples joints, and pkdyn does not "
                "read it: the mechanism would load as a tree with the wrong mobility. Describe "
                "it with pkdyn's elements (urdf/README.md), or ignore it explicitly: "
                f"pkdyn.load(..., ignore_elements=('{name}',)) or --ignore-element {name}",
            )
        self.groups.setdefault((tag, where), []).append(el)

    def warn(self) -> None:
        for (tag, where), els in self.groups.items():
            lines = [self.doc.line(e) for e in els if self.doc.line(e)]
            at = ""
            if lines:
                shown = ", ".join(str(n) for n in lines[:5]) + (" ..." if len(lines) > 5 else "")
                at = f" (line{'s' if len(lines) > 1 else ''} {shown})"
            count = f"{len(els)} elements" if len(els) > 1 else "1 element"
            warn(
                f"{self.doc.source}: <{tag}> {where}: {count}{at} not read by pkdyn, left out "
                f"(ignore_elements=('{local(tag)}',) or --ignore-element {local(tag)} silences "
                "this)"
            )


def _urdf(found: _Found, root: ET.Element) -> None:
    ns = _namespaces(root)
    for el in root:
        tag = el.tag if isinstance(el.tag, str) else ""
        prefix = _prefix(tag)
        uri = ns.get(prefix, "")
        if "pkdyn" in (uri + tag).lower():
            continue  # read and checked (namespaces included) by pkdyn.model.description
        if (prefix and "drake" in (uri or prefix).lower()) or "drake.mit.edu" in tag:
            if local(tag) not in _DRAKE_READ:
                found.add(el, "at the top level")
            continue
        if prefix or tag.startswith("{"):
            found.add(el, "at the top level")
            continue
        if tag == "gazebo" and el.find("joint") is None:
            found.add(el, "at the top level (without a <joint>)")
        elif tag not in _URDF_TOP and tag not in _URDF_PLUS:
            found.add(el, "at the top level")
    for j in root.findall("joint"):
        for c in j:
            if isinstance(c.tag, str) and c.tag not in _URDF_JOINT:
                found.add(c, "in a <joint>")


def _sdf(found: _Found, root: ET.Element) -> None:
    models = []
    for el in root:
        if el.tag == "world":
            for w in el:
                if w.tag == "model":
                    models.append(w)
                elif w.tag not in _SDF_WORLD:
                    found.add(w, "in the <world>")
        elif el.tag == "model":
            models.append(el)
        elif el.tag not in _SDF_ROOT:
            found.add(el, "at the top level")
    for m in models:
        for el in m:
            tag = el.tag if isinstance(el.tag, str) else ""
            if tag in _SDF_MODEL or tag in _SDF_MODEL_SEEN:
                continue
            if tag.startswith("drake:") and local(tag) in _DRAKE_READ:
                continue
            found.add(el, "in the <model>")
        for j in m.findall("joint"):
            for c in j:
                if not isinstance(c.tag, str):
                    continue
                if c.tag not in _SDF_JOINT:
                    found.add(c, "in a <joint>")
                elif c.tag in ("axis", "axis2"):
                    for a in c:
                        if isinstance(a.tag, str) and a.tag not in _SDF_AXIS:
                            found.add(a, f"in a joint's <{c.tag}>")


def _mjcf(found: _Found, root: ET.Element) -> None:
    for el in root:
        if isinstance(el.tag, str) and el.tag not in _MJCF_TOP:
            found.add(el, "at the top level")
    for tendon in root.findall("tendon"):
        for t in tendon:
            if t.tag != "fixed":
                found.add(t, "in <tendon> (spatial tendons: stiffness, damping and limits)")


_CHECKS = {"urdf": _urdf, "sdf": _sdf, "mjcf": _mjcf}


def check(doc: XmlDoc, fmt: str, ignore: frozenset[str] = frozenset()) -> None:
    """Warn about the unread elements of a description; refuse the unread loop-like ones.

    Args:
        doc: The document (after MJCF includes are expanded).
        fmt: ``urdf``, ``sdf`` or ``mjcf``.
        ignore: Element names the user asked to ignore (:func:`ignored_names`).

    Raises:
        DescriptionError: An unread element whose name says it closes a loop or couples joints.

    """
    found = _Found(doc, ignore)
    _CHECKS[fmt](found, doc.root)
    found.warn()


def prune(doc: XmlDoc, ignore: frozenset[str], root: ET.Element | None = None) -> int:
    """Remove the elements named in ``ignore`` (anywhere below the root), with one warning.

    Args:
        doc: The document (messages).
        ignore: Element names (:func:`ignored_names`).
        root: Element to prune (default ``doc.root``).

    Returns:
        How many elements were removed.

    """
    if not ignore:
        return 0
    top = doc.root if root is None else root
    counts: dict[str, int] = {}
    stack = [top]
    while stack:
        el = stack.pop()
        for c in list(el):
            tag = c.tag if isinstance(c.tag, str) else ""
            if tag and _matches(tag, ignore):
                el.remove(c)
                counts[tag] = counts.get(tag, 0) + 1
            else:
                stack.append(c)
    if counts:
        listed = ", ".join(f"{n} <{t}>" for t, n in sorted(counts.items()))
        warn(f"{doc.source}: ignored as asked (ignore_elements): {listed}")
    unused = sorted(n for n in ignore if not any(_matches(t, frozenset([n])) for t in counts))
    if unused:
        warn(
            f"{doc.source}: ignore_elements: no element named "
            + ", ".join(f"'{n}'" for n in unused)
            + " in this description"
        )
    return sum(counts.values())
