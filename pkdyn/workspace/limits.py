"""The limits a workspace respects, and how a batch of platform poses is checked against them.

Four kinds of limit, checked in this order (a rejected sample counts for the first it breaks):

- ``reach``: no assembled configuration puts the platform there (inverse model fails);
- ``stroke``: an actuator outside its stroke or angle range (the actuated joint's limits);
- ``joint``: a passive joint outside its cone or Merlet's pyramid (``pkdyn:cone`` /
  ``pkdyn:pyramid``);
- ``interference``: two bodies closer than the safety margin (legs as cylinders for the
  closed-form evaluators, coal on the collision geometry for the numeric one).

A :class:`PoseEvaluator` classifies platform positions at a fixed platform orientation; the
closed-form evaluators (:mod:`pkdyn.workspace.legs`, :mod:`pkdyn.workspace.delta`) do it
with numpy on whole batches, :mod:`pkdyn.workspace.numeric` pose by pose with the general
inverse geometric model.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.description import ConeLimit, PyramidLimit
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as progress_bar

__all__ = [
    "LIMIT_KINDS",
    "PoseEvaluator",
    "check_kinds",
    "classify",
    "passive_joint_margins",
    "direction_margin",
    "pyramid_normals",
]

LIMIT_KINDS = ("reach", "stroke", "joint", "interference")
"""Kinds of limit, in checking order."""

REACHABLE = -1
"""Classification code of a sample that breaks no limit."""


def check_kinds(kinds: Sequence[str]) -> tuple[str, ...]:
    """Validate optional limit kinds (``reach`` is always applied).

    Args:
        kinds: Subset of ``stroke``, ``joint``, ``interference``.

    Returns:
        The kinds, ``reach`` first, in checking order.

    Raises:
        InvalidInputError: An unknown kind.

    """
    from pkdyn.inputs import names

    if not isinstance(kinds, str):  # (a single kind given as a string is that kind)
        kinds = names("limits", kinds, what="limit kind", empty=True)
    bad = [k for k in ([kinds] if isinstance(kinds, str) else kinds) if k not in LIMIT_KINDS]
    if bad:
        raise InvalidInputError("limits", f"unknown kind '{bad[0]}' (use {', '.join(LIMIT_KINDS)})")
    kinds = (kinds,) if isinstance(kinds, str) else kinds
    return tuple(k for k in LIMIT_KINDS if k == "reach" or k in kinds)


class PoseEvaluator(ABC):
    """Checks platform positions at one platform orientation against the limits.

    Attributes:
        robot: The robot.
        method: Short description of how the check is done.

    """

    method = ""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot

    @abstractmethod
    def violations(
        self, P: np.ndarray, R: np.ndarray, kinds: tuple[str, ...], margin: float
    ) -> np.ndarray:
        """First limit kind each position breaks.

        Args:
            P: Platform positions (N, 3) [m], world frame.
            R: Platform orientation (3, 3).
            kinds: Kinds to check (``reach`` first; see :func:`check_kinds`).
            margin: Safety distance for ``interference`` [m].

        Returns:
            (N,) int: index in :data:`LIMIT_KINDS` of the first kind broken, or
            :data:`REACHABLE`.

        """

    @abstractmethod
    def default_bounds(self, R: np.ndarray) -> np.ndarray:
        """A box (3, 2) [m] that contains the workspace at orientation ``R``."""

    def grid(
        self,
        xs: np.ndarray,
        ys: np.ndarray,
        z: float,
        R: np.ndarray,
        kinds: tuple[str, ...],
        margin: float,
    ) -> np.ndarray:
        """Violation codes on the plane grid ``xs x ys`` at height ``z`` (nx, ny).

        The default visits the grid in snake order (neighbours follow each other, so that an
        iterative evaluator warm-starts well) and calls :meth:`violations`; closed forms may
        override it with a broadcast evaluation.
        """
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        Y[1::2] = Y[1::2, ::-1]
        P = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)])
        c = self.violations(P, R, kinds, margin).reshape(X.shape)
        c[1::2] = c[1::2, ::-1]
        return c

    def box_grid(
        self,
        xs: np.ndarray,
        ys: np.ndarray,
        zs: np.ndarray,
        R: np.ndarray,
        kinds: tuple[str, ...],
        margin: float,
        progress: bool | None = None,
    ) -> np.ndarray:
        """Violation codes on the box grid ``xs x ys x zs`` (nx, ny, nz).

        The default evaluates plane by plane with :meth:`grid` (a progress bar over the planes);
        the numeric evaluator overrides it with a continuation over the whole grid.

        Args:
            xs: Grid coordinates along x [m].
            ys: Grid coordinates along y [m].
            zs: Grid coordinates along z [m].
            R: Platform orientation (3, 3).
            kinds: Kinds to check (``reach`` first).
            margin: Safety distance for ``interference`` [m].
            progress: Progress bar (``None``: when stderr is a terminal).

        Returns:
            (nx, ny, nz) codes (see :meth:`violations`).

        """
        codes = np.empty((xs.size, ys.size, zs.size), dtype=np.int8)
        for k in progress_bar(range(zs.size), "workspace", "plane", progress, leave=False):
            codes[:, :, k] = self.grid(xs, ys, float(zs[k]), R, kinds, margin)
        return codes


def classify(stages: Sequence[tuple[str, np.ndarray]], n: int) -> np.ndarray:
    """Combine per-kind violation masks into first-broken codes.

    Args:
        stages: ``(kind, mask)`` pairs in checking order, masks (n,) True when broken.
        n: Number of samples.

    Returns:
        (n,) codes (see :meth:`PoseEvaluator.violations`).

    """
    out = np.full(n, REACHABLE, dtype=np.int8)
    for kind, bad in stages:
        out[(out == REACHABLE) & bad] = LIMIT_KINDS.index(kind)
    return out


def direction_margin(limit: ConeLimit | PyramidLimit, d: np.ndarray) -> np.ndarray:
    """Signed angular margin of directions against a passive-joint limit, vectorised.

    Args:
        limit: Cone or pyramid, in the joint frame.
        d: Tilted axis ``R @ limit.axis`` in the joint frame (..., 3), any length.

    Returns:
        Margin (...) [rad], positive inside (same as ``limit.margin`` for one rotation).

    """
    ax = np.asarray(limit.axis, dtype=float)
    c = d @ ax
    if isinstance(limit, ConeLimit):
        n = np.linalg.norm(d, axis=-1)
        return limit.half_angle - np.arccos(np.clip(c / n, -1.0, 1.0))
    ref = np.asarray(limit.ref, dtype=float)
    a1 = np.arctan2(d @ ref, c)
    a2 = np.arctan2(d @ np.cross(ax, ref), c)
    return np.minimum(limit.half_angles[0] - np.abs(a1), limit.half_angles[1] - np.abs(a2))


def passive_joint_margins(robot: Robot, q: np.ndarray) -> dict[str, float]:
    """Margin of every limited passive joint at a configuration (general path).

    Args:
        robot: The robot.
        q: Configuration (nq,).

    Returns:
        Joint name -> signed margin [rad] (negative: outside its cone or pyramid).

    """
    model, data = robot.model, robot.data
    out: dict[str, float] = {}
    specs = [j for j in robot.description.joints if j.limit is not None]
    if not specs:
        return out
    pin.forwardKinematics(model, data, q)
    for spec in specs:
        jid = model.getJointId(spec.name)
        R = model.jointPlacements[jid].rotation.T @ data.liMi[jid].rotation
        assert spec.limit is not None
        out[spec.name] = float(spec.limit.margin(R))
    return out


def pyramid_normals(limit: PyramidLimit) -> np.ndarray:
    """Inward unit normals (4, 3) of the faces of Merlet's pyramid, joint frame.

    ``|atan2(d.ref, d.axis)| <= h0`` is ``d . (axis sin h0 -+ ref cos h0) >= 0`` (and the same
    with ``axis x ref`` and ``h1``).
    """
    a = np.asarray(limit.axis, dtype=float)
    r = np.asarray(limit.ref, dtype=float)
    m = np.cross(a, r)
    h0, h1 = limit.half_angles
    return np.array(
        [
            a * math.sin(h0) - r * math.cos(h0),
            a * math.sin(h0) + r * math.cos(h0),
            a * math.sin(h1) - m * math.cos(h1),
            a * math.sin(h1) + m * math.cos(h1),
        ]
    )
