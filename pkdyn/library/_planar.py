"""The revolute-revolute chain shared by the planar library robots (five-bar, 3-RRR)."""

from __future__ import annotations

import math
from typing import Protocol

from pkdyn.library._colors import BLUE, ORANGE
from pkdyn.model.formats.urdf_writer import UrdfWriter

__all__ = ["PASSIVE_VELOCITY", "write_rr_chain"]

PASSIVE_VELOCITY = 1e3
"""Velocity limit written on passive revolute joints [rad/s] (effort 0: they are not driven)."""


class ChainParams(Protocol):
    """Parameters a planar RR chain needs (SI units)."""

    @property
    def l1(self) -> float: ...  # noqa: D102
    @property
    def l2(self) -> float: ...  # noqa: D102
    @property
    def proximal_mass(self) -> float: ...  # noqa: D102
    @property
    def distal_mass(self) -> float: ...  # noqa: D102
    @property
    def link_radius(self) -> float: ...  # noqa: D102
    @property
    def q_min(self) -> float: ...  # noqa: D102
    @property
    def q_max(self) -> float: ...  # noqa: D102
    @property
    def effort(self) -> float: ...  # noqa: D102
    @property
    def velocity(self) -> float: ...  # noqa: D102
    @property
    def reduction(self) -> float: ...  # noqa: D102


def write_rr_chain(
    w: UrdfWriter,
    p: ChainParams,
    k: int,
    base_xy: tuple[float, float],
    elbow_rpy_z: float,
    z_prox: float,
    z_dist: float,
) -> tuple[str, str]:
    """Write chain ``k``: actuated base revolute ``proximal{k}``, passive elbow ``distal{k}``.

    Both axes are vertical; the links lie along their frames' x axes (``l1``, ``l2``), drawn on
    the display layers ``z_prox`` and ``z_dist`` [m]; the elbow frame is turned by
    ``elbow_rpy_z`` [rad] so that the neutral configuration is the home one.

    Returns:
        The proximal and distal link names.

    """
    prox, dist = f"proximal{k}", f"distal{k}"
    r = p.link_radius
    w.rod(prox, p.proximal_mass, r, (0, 0, z_prox), (p.l1, 0, z_prox), BLUE)
    w.joint(
        prox,
        "revolute",
        "base",
        prox,
        xyz=(float(base_xy[0]), float(base_xy[1]), 0.0),
        axis=(0.0, 0.0, 1.0),
        limit=(p.q_min, p.q_max, p.effort, p.velocity),
    )
    w.transmission(prox, f"motor{k}", p.reduction)
    w.rod(dist, p.distal_mass, r, (0, 0, z_dist), (p.l2, 0, z_dist), ORANGE)
    w.joint(
        dist,
        "revolute",
        prox,
        dist,
        xyz=(p.l1, 0.0, 0.0),
        rpy=(0.0, 0.0, elbow_rpy_z),
        axis=(0.0, 0.0, 1.0),
        limit=(-math.pi, math.pi, 0.0, PASSIVE_VELOCITY),
    )
    return prox, dist
