"""The revolute-revolute chain shared by the planar library robots (five-bar, 3-RRR)."""

from __future__ import annotations

import math
from typing import Protocol

from pkdyn.library._check import in_range, positive
from pkdyn.library._links import driven_rod, passive_rod
from pkdyn.model.formats.urdf_writer import UrdfWriter

__all__ = ["check_chain", "write_rr_chain"]


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


def check_chain(family: str, p: ChainParams) -> None:
    """Check the chain's parameters: lengths, masses, radius, drive, actuator range.

    The lengths, masses, radius, effort, velocity and reduction must be positive, and
    ``-pi <= q_min <= q_max <= pi``.

    Raises:
        ParameterError: The first parameter that breaks these rules, named.

    """
    positive(
        family,
        l1=p.l1,
        l2=p.l2,
        proximal_mass=p.proximal_mass,
        distal_mass=p.distal_mass,
        link_radius=p.link_radius,
        effort=p.effort,
        velocity=p.velocity,
        reduction=p.reduction,
    )
    in_range(family, "q_min", p.q_min, -math.pi, p.q_max)
    in_range(family, "q_max", p.q_max, p.q_min, math.pi)


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
    r, z = p.link_radius, (0.0, 0.0, 1.0)
    driven_rod(
        w,
        prox,
        "base",
        ((0, 0, z_prox), (p.l1, 0, z_prox)),
        p.proximal_mass,
        r,
        xyz=(float(base_xy[0]), float(base_xy[1]), 0.0),
        axis=z,
        limit=(p.q_min, p.q_max, p.effort, p.velocity),
        actuator=f"motor{k}",
        reduction=p.reduction,
    )
    passive_rod(
        w,
        dist,
        prox,
        ((0, 0, z_dist), (p.l2, 0, z_dist)),
        p.distal_mass,
        r,
        xyz=(p.l1, 0.0, 0.0),
        rpy=(0.0, 0.0, elbow_rpy_z),
        axis=z,
    )
    return prox, dist
