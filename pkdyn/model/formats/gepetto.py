"""Gepetto example-parallel-robots YAML sidecars, in full.

Keys (Gepetto's, then pkdyn's additions):

- ``closed_loop``: pairs of frame names; ``type``: their kinds, ``3D`` (point) or ``6D`` (weld);
  the closures are named ``loop1``, ``loop2``... in file order;
- ``name_mot``: names of the actuated joints, matched literally (Gepetto's loader takes joint
  names; a name that is no joint is an error, never a pattern);
- ``joint_name`` / ``joint_type``: joints replaced as Gepetto's loader does: ``SPHERICAL`` (a
  ball joint at the same place), ``UJOINT_AB`` with A, B in X, Y, Z (a universal joint about the
  joint frame's A axis then B axis, one Pinocchio joint of the same name), ``FIXED`` (the joint
  locked at zero). Without ``joint_name``, revolute joints whose names contain ``spherical``
  become ball joints, the default of Gepetto's ``generateYAML`` (one warning lists them; write
  ``joint_name: []`` to keep them revolute);
- ``free_flyer: true``: a free-flyer root joint (Gepetto's loader option for legged robots);
- ``platform: {frame, xyz, rpy, task}``: pkdyn's platform frame (a link or frame name, an
  optional placement in it, the controlled pose components, e.g. ``"x y z"``);
- ``couplings``: a list of joint couplings (gears, mimic joints), each a mapping with
  ``joint`` (the driven joint), optional ``name`` (default ``coupling1``, ``coupling2``...),
  ``source``, and either ``multiplier`` / ``offset`` or ``polycoef`` (1 to 5 coefficients,
  constant term first), optional ``joint_ref`` / ``source_ref``: the ``pkdyn:coupling`` element
  of urdf/README.md in YAML.

Sidecars are read defensively: a regular file of bounded size, YAML without anchors or aliases
(no alias bomb can expand), at most :data:`MAX_NODES` nodes, typed keys (a ``name_mot`` written
as a string is an error, not a list of characters).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
import yaml

from pkdyn.exceptions import DescriptionError
from pkdyn.model.build import replace_joints
from pkdyn.model.description import (
    TASK_COMPONENTS,
    ActuatorSpec,
    ClosureSpec,
    CouplingSpec,
    FrameRef,
    PlatformSpec,
)
from pkdyn.model.formats.xmldoc import read_text
from pkdyn.model.warn import warn

__all__ = ["MAX_NODES", "Sidecar", "apply_joint_types", "loop_frames", "read_sidecar"]

MAX_NODES = 100_000
"""Largest number of YAML nodes in a sidecar."""

MAX_DEPTH = 50
"""Deepest nesting of YAML collections in a sidecar (a sidecar nests 3 levels)."""

_TYPES = {"3d": "point", "6d": "weld"}
_KEYS = (
    "closed_loop",
    "type",
    "name_mot",
    "joint_name",
    "joint_type",
    "free_flyer",
    "platform",
    "couplings",
)
_UJOINT = re.compile(r"^UJOINT_([XYZ])([XYZ])$")


@dataclass
class Sidecar:
    """What a sidecar declares.

    Attributes:
        source: The sidecar file.
        closures: Closures (frames by name).
        actuators: Actuators (joint names; limits filled by the loader).
        joint_types: Joint replacements: name -> ``SPHERICAL``, ``UJOINT_XY``..., ``FIXED``.
        free_flyer: Add a free-flyer root joint.
        platform: Platform frame, if declared.
        by_convention: ``joint_types`` came from Gepetto's naming convention.
        couplings: Joint couplings (pkdyn's ``couplings`` key).

    """

    source: str
    closures: list[ClosureSpec] = field(default_factory=list)
    actuators: list[ActuatorSpec] = field(default_factory=list)
    joint_types: dict[str, str] = field(default_factory=dict)
    free_flyer: bool = False
    platform: PlatformSpec | None = None
    by_convention: bool = False
    couplings: list[CouplingSpec] = field(default_factory=list)


class _Loader(yaml.SafeLoader):
    """Safe YAML without anchors and aliases, and with a bounded number of nodes."""

    nodes = 0
    depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:  # noqa: D102
        if self.check_event(yaml.AliasEvent):
            line = self.peek_event().start_mark.line + 1
            raise yaml.YAMLError(
                f"YAML aliases are not allowed in a sidecar (alias at line {line})"
            )
        event = self.peek_event()
        if getattr(event, "anchor", None):
            raise yaml.YAMLError(
                f"YAML anchors are not allowed in a sidecar (anchor '&{event.anchor}' at line "
                f"{event.start_mark.line + 1})"
            )
        self.nodes += 1
        if self.nodes > MAX_NODES:
            raise yaml.YAMLError(f"more than {MAX_NODES} YAML nodes")
        self.depth += 1  # the composer recurses once per level: bounded before Python's limit
        if self.depth > MAX_DEPTH:
            raise yaml.YAMLError(
                f"nested deeper than {MAX_DEPTH} levels (line {event.start_mark.line + 1})"
            )
        try:
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1


def _strings(src: str, key: str, value: Any) -> list[str]:
    if value is None:
        return []
    if isinstance(value, str):
        raise DescriptionError(
            src,
            key,
            f"expected a list of names, got the string '{value}' (write {key}: ['{value}'])",
        )
    if not isinstance(value, list):
        raise DescriptionError(src, key, f"expected a list of names, got {type(value).__name__}")
    out = []
    for k, v in enumerate(value):
        if not isinstance(v, str | int | float) or isinstance(v, bool):
            raise DescriptionError(src, f"{key}[{k}]", f"expected a name, got {type(v).__name__}")
        out.append(str(v))
    return out


def read_sidecar(path: str | os.PathLike[str]) -> Sidecar:
    """Read a sidecar (see the module docstring).

    Args:
        path: The YAML file.

    Returns:
        What it declares.

    Raises:
        DescriptionError: Unreadable or malformed YAML (aliases, too many nodes), mistyped keys,
            mismatched lists, unknown closure or joint types.

    """
    src = str(path)
    text = read_text(path, "sidecar")
    try:
        data = yaml.load(text, Loader=_Loader)  # noqa: S506 - _Loader is a SafeLoader
    except yaml.YAMLError as err:
        raise DescriptionError(src, "YAML", f"cannot be read ({err})") from None
    if not isinstance(data, dict):
        raise DescriptionError(src, "YAML", "expected a mapping with 'closed_loop', 'type'")
    unknown = [str(k) for k in data if k not in _KEYS]
    if unknown:
        warn(f"{src}: unknown sidecar keys ignored: {', '.join(unknown)}")
    side = Sidecar(src)
    pairs = data.get("closed_loop") or []
    if not isinstance(pairs, list):
        raise DescriptionError(src, "closed_loop", "expected a list of frame-name pairs")
    kinds = _strings(src, "type", data.get("type"))
    if len(kinds) != len(pairs):
        raise DescriptionError(
            src, "type", f"{len(kinds)} types for {len(pairs)} closed_loop pairs"
        )
    for k, (pair, kind) in enumerate(zip(pairs, kinds, strict=True)):
        if (
            not isinstance(pair, list | tuple)
            or len(pair) != 2
            or not all(isinstance(p, str) for p in pair)
        ):
            raise DescriptionError(src, f"closed_loop[{k}]", "expected a pair of frame names")
        key = kind.lower()
        if key not in _TYPES:
            raise DescriptionError(src, f"type[{k}]='{kind}'", "use 3D or 6D")
        side.closures.append(
            ClosureSpec(f"loop{k + 1}", _TYPES[key], FrameRef(pair[0]), FrameRef(pair[1]))
        )
    for name in _strings(src, "name_mot", data.get("name_mot")):
        if name not in [a.joint for a in side.actuators]:
            side.actuators.append(ActuatorSpec(name, name))
    names = _strings(src, "joint_name", data.get("joint_name"))
    types = _strings(src, "joint_type", data.get("joint_type"))
    if len(names) != len(types):
        raise DescriptionError(
            src, "joint_type", f"{len(types)} joint types for {len(names)} joint names"
        )
    for k, (n, t) in enumerate(zip(names, types, strict=True)):
        if t not in ("SPHERICAL", "FIXED") and not _UJOINT.match(t):
            raise DescriptionError(
                src, f"joint_type[{k}]='{t}'", "use SPHERICAL, FIXED or UJOINT_AB (A, B in X Y Z)"
            )
        m = _UJOINT.match(t)
        if m and m.group(1) == m.group(2):
            raise DescriptionError(src, f"joint_type[{k}]='{t}'", "the two axes must differ")
        side.joint_types[n] = t
    side.by_convention = "joint_name" not in data
    ff = data.get("free_flyer", False)
    if not isinstance(ff, bool):
        raise DescriptionError(src, "free_flyer", f"expected true or false, got {ff!r}")
    side.free_flyer = ff
    if data.get("platform") is not None:
        side.platform = _platform(src, data["platform"])
    side.couplings = _couplings(src, data.get("couplings"))
    return side


_COUPLING_KEYS = (
    "name",
    "joint",
    "source",
    "multiplier",
    "offset",
    "polycoef",
    "joint_ref",
    "source_ref",
)


def _scalar(src: str, key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise DescriptionError(src, key, f"expected a number, got {value!r}")
    out = float(value)
    if not np.isfinite(out):
        raise DescriptionError(src, key, f"expected a finite number, got {value!r}")
    return out


def _couplings(src: str, value: Any) -> list[CouplingSpec]:
    """The ``couplings`` key: a list of mappings (see the module docstring)."""
    if value is None:
        return []
    if not isinstance(value, list):
        raise DescriptionError(src, "couplings", "expected a list of mappings")
    out = []
    for k, item in enumerate(value):
        key = f"couplings[{k}]"
        if not isinstance(item, dict):
            raise DescriptionError(src, key, "expected a mapping with 'joint' and 'source'")
        unknown = [str(x) for x in item if x not in _COUPLING_KEYS]
        if unknown:
            raise DescriptionError(
                src, f"{key}.{unknown[0]}", f"unknown key; use {', '.join(_COUPLING_KEYS)}"
            )
        name = str(item.get("name", f"coupling{k + 1}"))
        joint, source = item.get("joint"), item.get("source")
        if not isinstance(joint, str) or not (source is None or isinstance(source, str)):
            raise DescriptionError(src, key, "'joint' (and 'source') must be joint names")
        if "polycoef" in item:
            if "multiplier" in item or "offset" in item:
                raise DescriptionError(src, key, "give polycoef or multiplier/offset, not both")
            poly = item["polycoef"]
            if not isinstance(poly, list) or not 1 <= len(poly) <= 5:
                raise DescriptionError(
                    src, f"{key}.polycoef", f"expected a list of 1 to 5 numbers, got {poly!r}"
                )
            coef = tuple(_scalar(src, f"{key}.polycoef", c) for c in poly)
        else:
            coef = (
                _scalar(src, f"{key}.offset", item.get("offset", 0.0)),
                _scalar(src, f"{key}.multiplier", item.get("multiplier", 1.0)),
            )
        if source is None:
            coef = coef[:1]
        refs = [_scalar(src, f"{key}.{r}", item.get(r, 0.0)) for r in ("joint_ref", "source_ref")]
        out.append(CouplingSpec(name, joint, source, coef, refs[0], refs[1]))
    return out


def _numbers(src: str, key: str, value: Any, n: int) -> np.ndarray:
    if isinstance(value, str):  # "0 0 0.1": numbers in one string (never its characters)
        value = value.split()
    if not isinstance(value, list) or any(isinstance(v, bool) for v in value):
        raise DescriptionError(src, key, f"expected a list of {n} numbers, got {value!r}")
    try:
        out = np.array([float(v) for v in value], dtype=float)
    except (TypeError, ValueError):
        raise DescriptionError(src, key, f"expected {n} numbers, got {value!r}") from None
    if out.shape != (n,) or not np.all(np.isfinite(out)):
        raise DescriptionError(src, key, f"expected {n} finite numbers, got {value!r}")
    return out


def _platform(src: str, value: Any) -> PlatformSpec:
    if not isinstance(value, dict) or not isinstance(value.get("frame"), str):
        raise DescriptionError(
            src, "platform", "expected a mapping with 'frame' (and optional xyz, rpy, task)"
        )
    xyz = _numbers(src, "platform.xyz", value.get("xyz", [0, 0, 0]), 3)
    rpy = _numbers(src, "platform.rpy", value.get("rpy", [0, 0, 0]), 3)
    task = value.get("task", " ".join(TASK_COMPONENTS))
    comps = tuple(task.split()) if isinstance(task, str) else tuple(str(t) for t in task)
    bad = [t for t in comps if t not in TASK_COMPONENTS]
    if bad or not comps:
        raise DescriptionError(
            src, f"platform.task '{task}'", f"components must be among {' '.join(TASK_COMPONENTS)}"
        )
    frame = FrameRef(value["frame"], pin.SE3(pin.rpy.rpyToMatrix(rpy), xyz))
    return PlatformSpec(frame, comps)


def _convention(model: pin.Model, side: Sidecar) -> dict[str, str]:
    """Gepetto's ``generateYAML`` default: revolute joints named ``*spherical*`` are balls."""
    out = {}
    for jid in range(1, model.njoints):
        name = model.names[jid]
        jm = model.joints[jid]
        if "spherical" in name and jm.nv == 1 and jm.shortname().startswith("JointModelR"):
            if name not in [a.joint for a in side.actuators]:
                out[name] = "SPHERICAL"
    return out


def apply_joint_types(model: pin.Model, side: Sidecar, source: str) -> pin.Model:
    """The model with the sidecar's joint replacements (``joint_name`` / ``joint_type``).

    Args:
        model: Model of the URDF tree.
        side: The sidecar.
        source: Description name, for messages.

    Returns:
        A new model: replaced joints keep their names and placements; ``FIXED`` joints are
        removed (their bodies and frames move onto the parent joint).

    """
    types = dict(side.joint_types)
    if side.by_convention:
        types = _convention(model, side)
        if types:
            warn(
                f"{side.source}: no joint_name: following Gepetto's convention, {len(types)} "
                f"revolute joints named '*spherical*' become ball joints ("
                + ", ".join(list(types)[:4])
                + (" ..." if len(types) > 4 else "")
                + "); write 'joint_name: []' to keep them revolute"
            )
    if not types:
        return model
    absent = [name for name in types if not model.existJointName(name)]
    if absent:  # Gepetto's loader skips them too
        warn(
            f"{side.source}: joint_name entries that name no joint of {source} are ignored: "
            + ", ".join(absent[:4])
            + (" ..." if len(absent) > 4 else "")
        )
        types = {k: v for k, v in types.items() if k not in absent}
    return replace_joints(model, {name: _new_joint(t) for name, t in types.items()})


def _new_joint(t: str) -> pin.JointModel | None:
    """The joint model of a Gepetto ``joint_type`` (``None``: FIXED, a weld)."""
    if t == "FIXED":
        return None
    if t == "SPHERICAL":
        return pin.JointModelSpherical()
    m = _UJOINT.match(t)
    assert m is not None
    e = {c: np.eye(3)[k] for k, c in enumerate("XYZ")}
    return pin.JointModelUniversal(e[m.group(1)], e[m.group(2)])


_LOOP_FRAME = re.compile(r"^(closedloop\d+)_?([AB])(_.*)?$")


def loop_frames(model: pin.Model) -> list[str]:
    """Gepetto-style loop frame names (``closedloop<N>_A`` / ``_B``...) of a model, by pair.

    Args:
        model: The model.

    Returns:
        The ``closedloop<N>`` prefixes that have both an A and a B frame.

    """
    sides: dict[str, set[str]] = {}
    for f in model.frames:
        m = _LOOP_FRAME.match(f.name)
        if m:
            sides.setdefault(m.group(1), set()).add(m.group(2))
    return sorted(k for k, v in sides.items() if v == {"A", "B"})
