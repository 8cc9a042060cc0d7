"""Dextrous workspace of a leg robot (Merlet, seed 002, chapter 4).

The dextrous workspace is the set of positions of ``C`` (the platform frame origin) at which
*every* orientation of the platform is allowed. When ``C`` is fixed the platform joint ``B_i``
can be anywhere on the sphere of centre ``C`` and radius ``|C B_i|``, so:

- strokes: ``C`` lies in the spherical shell ``CS_i`` centred at ``A_i`` of radii
  ``rho_min_i + |C B_i|`` and ``rho_max_i - |C B_i|``;
- base joints (option): the whole sphere lies inside the joint's pyramid (or cone) of apex
  ``A_i``, i.e. ``C`` is at least ``|C B_i|`` inside each face plane (for a cone, the angle of
  ``C - A_i`` to the axis is at most ``half_angle - asin(|C B_i| / |C - A_i|)``).

The intersection over the legs is exact for these limits (Merlet's Fig. 4.2 draws the shell
cut by the pyramid itself; shrinking the pyramid by ``|C B_i|`` is what *every* orientation
needs). Leg interference is left out, as in the report ("plus délicate").
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.description import ConeLimit, PyramidLimit
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.workspace.legs import HexapodLegs
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE, pyramid_normals
from pkdyn.workspace.translation import TranslationWorkspace, _grid_axes

__all__ = ["dextrous_workspace", "dextrous_violations", "dextrous_json", "pyramid_normals"]


def dextrous_violations(legs: HexapodLegs, C: np.ndarray, joint_limits: bool) -> np.ndarray:
    """First limit kind broken by some orientation at each position.

    Args:
        legs: Leg geometry.
        C: Positions of the platform frame origin (N, 3) [m].
        joint_limits: Also require the base joints' cones or pyramids for every orientation.

    Returns:
        (N,) codes: ``stroke``, ``joint`` index in :data:`LIMIT_KINDS`, or -1 (dextrous).

    """
    C = np.atleast_2d(np.asarray(C, dtype=float))
    rb = np.linalg.norm(legs.B, axis=1)  # |C B_i|
    out = np.full(C.shape[0], REACHABLE, dtype=np.int8)
    d = np.linalg.norm(C[:, None, :] - legs.A[None], axis=2)  # (N, n)
    bad = np.any((d < legs.rho_min + rb) | (d > legs.rho_max - rb), axis=1)
    out[bad] = LIMIT_KINDS.index("stroke")
    if not joint_limits:
        return out
    jbad = np.zeros(C.shape[0], dtype=bool)
    for i, lim in enumerate(legs.limits):
        if lim is None:
            continue
        w = legs.sign[i] * ((C - legs.A[i]) @ legs.R0[i])  # joint frame
        if isinstance(lim, PyramidLimit):
            jbad |= np.any(w @ pyramid_normals(lim).T < rb[i], axis=1)
        else:
            assert isinstance(lim, ConeLimit)
            n = np.linalg.norm(w, axis=1)
            with np.errstate(invalid="ignore", divide="ignore"):
                ang = np.arccos(np.clip(w @ np.asarray(lim.axis) / n, -1.0, 1.0))
                room = lim.half_angle - np.arcsin(np.clip(rb[i] / n, 0.0, 1.0))
            jbad |= ~(ang <= room) | (n <= rb[i])
    out[(out == REACHABLE) & jbad] = LIMIT_KINDS.index("joint")
    return out


@public
def dextrous_workspace(
    robot: Robot,
    bounds: np.ndarray | Sequence[Sequence[float]] | None = None,
    step: float | None = None,
    samples: int = 41,
    joint_limits: bool = False,
    progress: bool | None = None,
) -> TranslationWorkspace:
    """Sample Merlet's dextrous workspace on a grid.

    Args:
        robot: A leg robot (see :mod:`pkdyn.workspace.legs`).
        bounds: Box (3, 2) [m]; default: the box of the smallest outer shell around each
            ``A_i``, above the base joints.
        step: Grid spacing [m]; default: ``samples`` per axis.
        samples: Samples per axis when ``step`` is not given.
        joint_limits: Also keep the base joints inside their cones or pyramids.
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default)
            shows it when stderr is a terminal.

    Returns:
        A :class:`pkdyn.workspace.translation.TranslationWorkspace` whose reachable samples are the
        dextrous positions (``method`` says so; ``rpy`` is meaningless and zero).

    Raises:
        PkdynError: Not a leg robot.
        InvalidInputError: Bad box or step.

    """
    legs = HexapodLegs.from_robot(robot, "the dextrous workspace")
    rb = np.linalg.norm(legs.B, axis=1)
    if bounds is None:
        r_out = legs.rho_max - rb
        lo = np.max(legs.A - r_out[:, None], axis=0)
        hi = np.min(legs.A + r_out[:, None], axis=0)
        lo[2] = max(lo[2], float(np.min(legs.A[:, 2])))
        if np.any(hi <= lo):
            hi = np.maximum(hi, lo + 1e-3)
        box = np.column_stack([lo, hi])
    else:
        from pkdyn.inputs import matrix

        box = matrix("bounds", bounds, 3, 2, "m")
    if box.shape != (3, 2) or not np.all(np.isfinite(box)):
        raise InvalidInputError("bounds", "expected 3 rows (min, max) of finite numbers [m]")
    xs, ys, zs = _grid_axes(box, step, samples, (0, 1, 2), np.zeros(3))
    codes = np.empty((xs.size, ys.size, zs.size), dtype=np.int8)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    for k in progress_bar(range(zs.size), "dextrous workspace", "plane", progress, leave=False):
        C = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, zs[k])])
        codes[:, :, k] = dextrous_violations(legs, C, joint_limits).reshape(X.shape)
    kinds = ("reach", "stroke", "joint") if joint_limits else ("reach", "stroke")
    return TranslationWorkspace(
        robot=robot.name,
        rpy=np.zeros(3),
        axes=(xs, ys, zs),
        codes=codes,
        kinds=kinds,
        margin=0.0,
        method="dextrous (Merlet ch. 4: every orientation; shells"
        + (" and shrunk pyramids)" if joint_limits else ")"),
    )


def dextrous_json(ws: TranslationWorkspace) -> dict[str, Any]:
    """JSON of a dextrous workspace: :meth:`TranslationWorkspace.to_json` (``kind`` dextrous)."""
    return ws.to_json()
