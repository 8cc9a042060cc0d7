"""Gepetto example-parallel-robots YAML sidecar: ``closed_loop``, ``type``, ``name_mot``."""

from __future__ import annotations

import re
from pathlib import Path

import yaml

from pkdyn.exceptions import DescriptionError
from pkdyn.model.description import ActuatorSpec, ClosureSpec, FrameRef

__all__ = ["read_sidecar"]

_TYPES = {"3d": "point", "6d": "weld"}


def read_sidecar(
    path: Path, joint_names: list[str]
) -> tuple[list[ClosureSpec], list[ActuatorSpec]]:
    """Closures and actuators from a Gepetto ``robot.yaml`` sidecar.

    ``closed_loop`` lists frame-name pairs, ``type`` their kinds (``3D`` point, ``6D`` weld) and
    ``name_mot`` regular expressions matched (``re.search``) against joint names.

    Args:
        path: The YAML file.
        joint_names: Moving joint names of the model, in model order.

    Returns:
        Closure specs (frames named by Pinocchio frame name) and actuator specs.

    Raises:
        DescriptionError: Malformed YAML, mismatched lists, unknown type, or no joint matched.

    """
    src = str(path)
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as err:
        raise DescriptionError(src, "YAML", f"cannot be read ({err})") from None
    if not isinstance(data, dict):
        raise DescriptionError(src, "YAML", "expected a mapping with 'closed_loop', 'type'")
    pairs = data.get("closed_loop") or []
    kinds = data.get("type") or []
    if len(kinds) != len(pairs):
        raise DescriptionError(
            src, "type", f"{len(kinds)} types for {len(pairs)} closed_loop pairs"
        )
    closures = []
    for k, (pair, kind) in enumerate(zip(pairs, kinds, strict=True)):
        if not isinstance(pair, list | tuple) or len(pair) != 2:
            raise DescriptionError(src, f"closed_loop[{k}]", "expected a pair of frame names")
        key = str(kind).lower()
        if key not in _TYPES:
            raise DescriptionError(src, f"type[{k}]='{kind}'", "use 3D or 6D")
        closures.append(
            ClosureSpec(f"loop{k + 1}", _TYPES[key], FrameRef(str(pair[0])), FrameRef(str(pair[1])))
        )
    actuators: list[ActuatorSpec] = []
    for pattern in data.get("name_mot") or []:
        matched = [n for n in joint_names if re.search(str(pattern), n)]
        if not matched:
            raise DescriptionError(src, f"name_mot '{pattern}'", "matches no joint")
        for n in matched:
            if n not in [a.joint for a in actuators]:
                actuators.append(ActuatorSpec(n, n))
    return closures, actuators
