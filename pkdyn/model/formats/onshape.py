"""onshape-to-robot exports: loop closures from ``closing_<name>_1`` / ``closing_<name>_2`` frames.

onshape-to-robot turns a CAD mate named ``closing_<name>`` into two frames, one on each of the
two parts the mate joins (in a URDF: dummy links on fixed joints; in MJCF: sites, usually with
an ``<equality>`` already). pkdyn recognises such pairs without any sidecar:

- a pair ``closing_<name>_1`` / ``closing_<name>_2`` becomes a ``point`` closure named
  ``closing_<name>`` (the frames' origins coincide: a ball mate, and the safe reading of a
  URDF that does not say the mate's type);
- when the exporter also wrote ``closing_<name>_1_z`` / ``closing_<name>_2_z`` (its mark of a
  revolute mate: points 0.1 m along the frames' z axes), the closure is a ``hinge`` about the
  frames' z axis and the ``_z`` frames are not used.

A fastened (weld) mate cannot be told from a ball mate in a URDF: declare it in a sidecar
(``type: ['6D']``) or a ``pkdyn:closure``. Frames already used by another closure are skipped.
"""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin

from pkdyn.model.description import ClosureSpec, FrameRef

__all__ = ["closing_closures"]

_PAIR = re.compile(r"^closing_(.+)_1$")


def closing_closures(model: pin.Model) -> list[ClosureSpec]:
    """Closures of the ``closing_`` frame pairs of a model (see the module docstring).

    Args:
        model: The Pinocchio model (its body and operational frames are searched).

    Returns:
        One closure per complete pair, in frame order.

    """
    kinds = (pin.FrameType.BODY, pin.FrameType.OP_FRAME)
    names = [f.name for f in model.frames if f.type in kinds]
    present = set(names)
    out = []
    for name in names:
        m = _PAIR.match(name)
        if m is None or name.endswith("_z"):
            continue
        base = m.group(1)
        other = f"closing_{base}_2"
        if other not in present:
            continue
        hinge = f"closing_{base}_1_z" in present and f"closing_{base}_2_z" in present
        out.append(
            ClosureSpec(
                f"closing_{base}",
                "hinge" if hinge else "point",
                FrameRef(name),
                FrameRef(other),
                np.array([0.0, 0.0, 1.0]),
            )
        )
    return out
