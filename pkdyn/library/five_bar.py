"""Planar five-bar linkage (closed RRRRR chain) with two actuated base revolutes.

Base points ``A_1 = (-d/2, 0)`` and ``A_2 = (d/2, 0)`` in the plane z = 0; proximal links ``l1``
driven about z at ``A_j`` (absolute angle ``theta_j`` from the base x axis); distal links ``l2``
from the elbows ``C_j = A_j + l1 (cos theta_j, sin theta_j)`` meet at the end-effector point
``E = (x, y)``. Defaults: ``d = 0.2``, ``l1 = 0.2``, ``l2 = 0.3`` m, home ``E = (0, 0.3)`` in the
working mode with both elbows outward (``working_mode = "+-"``).

Closed forms (vectorised, :mod:`pkdyn.closed_form.five_bar`): with ``K = E - A_j``,
``K_x cos theta_j + K_y sin theta_j = K_3 = (|K|^2 + l1^2 - l2^2) / (2 l1)``, hence
``theta_j = atan2(K_y, K_x) + s_j acos(K_3 / |K|)``, where ``s_j = +1`` puts elbow ``C_j`` on
the left of ``A_j -> E`` (counter-clockwise) and ``-1`` on its right. ``E`` is the intersection
of the circles of radius ``l2`` about ``C_1`` and ``C_2``; the ``+1`` assembly mode takes it on
the left of ``C_1 -> C_2``.

Model: tree ``base -> proximal1 -> distal1`` (end-effector at the tip of ``distal1``, which also
carries the fixed link ``effector``, a point mass) and ``base -> proximal2 -> distal2``, closed
by the ``hinge`` closure ``loop`` (axis z) between the two distal tips. Actuated joints
``proximal1``, ``proximal2`` (actuators ``motor1``, ``motor2``, in that order; coordinate
``theta_j``); passive joints ``distal1``, ``distal2`` have their frames turned by the home
relative angle, so their neutral coordinates are the home configuration. Platform frame on the
tip of ``distal1``; task ``x y``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pkdyn.closed_form.five_bar import MODES, _wrap, elbow_points, inverse
from pkdyn.exceptions import ParameterError
from pkdyn.library._check import in_range, positive
from pkdyn.library._planar import write_rr_chain
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter

__all__ = [
    "NAME",
    "SUMMARY",
    "Params",
    "build_urdf",
    "home",
]

NAME = "five_bar"
"""Family name (``pkdyn.load`` and the CLI take it)."""
SUMMARY = "Planar five-bar, two actuated base revolutes, end-effector where the distal links meet"
"""One-line description of the family (``pkdyn info``, the family registry)."""


@dataclass(frozen=True)
class Params:
    """Five-bar parameters (SI units).

    Attributes:
        d: Distance between the two base revolutes [m].
        l1: Proximal (actuated) link length [m].
        l2: Distal link length [m].
        x_home: End-effector x at the home configuration [m].
        y_home: End-effector y at the home configuration [m].
        working_mode: Elbow side of chains 1 and 2, ``s_1 s_2`` among ``+-`` (both elbows
            outward, default), ``-+`` (both inward), ``++``, ``--``; ``+`` is the left of
            ``A_j -> E``.
        proximal_mass: Mass of a proximal link [kg].
        distal_mass: Mass of a distal link [kg].
        effector_mass: Point mass at the end-effector (tool), carried by ``distal1`` [kg].
        link_radius: Link tube radius (inertia, display, collision) [m].
        q_min: Lower limit of the actuated angles ``theta_j`` [rad].
        q_max: Upper limit of the actuated angles ``theta_j`` [rad].
        effort: Joint-side actuator torque limit [N m].
        velocity: Joint-side actuator speed limit [rad/s].
        reduction: Gear reduction between motor and proximal link.

    """

    d: float = 0.20
    l1: float = 0.20
    l2: float = 0.30
    x_home: float = 0.0
    y_home: float = 0.30
    working_mode: str = "+-"
    proximal_mass: float = 0.20
    distal_mass: float = 0.15
    effector_mass: float = 0.10
    link_radius: float = 0.010
    q_min: float = -math.pi
    q_max: float = math.pi
    effort: float = 5.0
    velocity: float = 10.0
    reduction: float = 10.0

    def __post_init__(self) -> None:
        positive(
            NAME,
            d=self.d,
            l1=self.l1,
            l2=self.l2,
            proximal_mass=self.proximal_mass,
            distal_mass=self.distal_mass,
            effector_mass=self.effector_mass,
            link_radius=self.link_radius,
            effort=self.effort,
            velocity=self.velocity,
            reduction=self.reduction,
        )
        in_range(NAME, "x_home", self.x_home, -math.inf, math.inf)
        in_range(NAME, "y_home", self.y_home, -math.inf, math.inf)
        if self.working_mode not in MODES:
            raise ParameterError(
                NAME,
                "working_mode",
                f"must be one of {', '.join(MODES)}, got {self.working_mode!r}",
            )
        in_range(NAME, "q_min", self.q_min, -math.pi, self.q_max)
        in_range(NAME, "q_max", self.q_max, self.q_min, math.pi)
        theta, ok = inverse(self, self.home_point)
        if not ok[0]:
            raise ParameterError(
                NAME,
                "y_home",
                f"home point ({self.x_home}, {self.y_home}) m is out of reach with these lengths "
                "(each base point must lie between |l1 - l2| and l1 + l2 from it)",
            )
        out = [float(v) for v in theta[0] if not self.q_min <= v <= self.q_max]
        if out:
            raise ParameterError(
                NAME,
                "q_min" if out[0] < self.q_min else "q_max",
                f"home actuated angle {out[0]:.6g} rad lies outside [q_min, q_max]",
            )

    @property
    def base_xy(self) -> np.ndarray:
        """Base points ``A_1, A_2``, shape (2, 2) [m]."""
        return np.array([[-0.5 * self.d, 0.0], [0.5 * self.d, 0.0]])

    @property
    def home_point(self) -> np.ndarray:
        """Home end-effector point ``(x, y)`` [m]."""
        return np.array([self.x_home, self.y_home])


def home(p: Params) -> list[float]:
    """Actuated angles ``theta_1, theta_2`` [rad] with the end-effector at the home point."""
    theta, _ = inverse(p, p.home_point)
    return [float(v) for v in theta[0]]


def build_urdf(p: Params) -> str:
    """Write the pkdyn description of a five-bar.

    Args:
        p: Parameters.

    Returns:
        URDF text with pkdyn extension elements.

    """
    w = UrdfWriter("five_bar")
    grey = (0.6, 0.6, 0.65, 1.0)
    r = p.link_radius
    z_prox, z_dist = 0.0, 2.5 * r  # display layers; the kinematics is in z = 0
    A = p.base_xy
    w.link(
        "base",
        visuals=[Shape("box", (p.d + 6 * r, 4 * r, 2 * r), (0.0, 0.0, -2 * r), rgba=grey)],
        collisions=[Shape("box", (p.d + 6 * r, 4 * r, 2 * r), (0.0, 0.0, -2 * r))],
    )
    theta = np.array(home(p))
    C = elbow_points(p, theta)[0]
    E = p.home_point
    for j in range(2):
        k = j + 1
        beta = math.atan2(E[1] - C[j, 1], E[0] - C[j, 0])
        # elbow frame turned by the home relative angle: neutral = home configuration
        write_rr_chain(
            w,
            p,
            k,
            (float(A[j, 0]), float(A[j, 1])),
            float(_wrap(np.array(beta - theta[j]))),
            z_prox,
            z_dist,
        )
    r_e = 1.5 * r
    I_e = np.eye(3) * 0.4 * p.effector_mass * r_e**2
    w.link(
        "effector",
        p.effector_mass,
        (0.0, 0.0, 0.0),
        I_e,
        visuals=[Shape("sphere", (r_e,), (0.0, 0.0, z_dist), rgba=grey)],
        collisions=[Shape("sphere", (r_e,), (0.0, 0.0, z_dist))],
    )
    w.joint("effector", "fixed", "distal1", "effector", xyz=(p.l2, 0.0, 0.0))
    w.closure(
        "loop",
        "hinge",
        ("distal1", (p.l2, 0.0, 0.0), (0.0, 0.0, 0.0)),
        ("distal2", (p.l2, 0.0, 0.0), (0.0, 0.0, 0.0)),
        axis=(0.0, 0.0, 1.0),
    )
    w.platform("distal1", ("x", "y"), xyz=(p.l2, 0.0, 0.0))
    return w.to_string(
        comment="generated by pkdyn.library.five_bar; edit the builder, not this file"
    )
