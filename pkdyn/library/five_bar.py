"""Planar five-bar linkage (closed RRRRR chain) with two actuated base revolutes.

Base points ``A_1 = (-d/2, 0)`` and ``A_2 = (d/2, 0)`` in the plane z = 0; proximal links ``l1``
driven about z at ``A_j`` (absolute angle ``theta_j`` from the base x axis); distal links ``l2``
from the elbows ``C_j = A_j + l1 (cos theta_j, sin theta_j)`` meet at the end-effector point
``E = (x, y)``. Defaults: ``d = 0.2``, ``l1 = 0.2``, ``l2 = 0.3`` m, home ``E = (0, y_home)``
(derived: the middle of the reach along the axis) in the working mode with both elbows outward
(``working_mode = "+-"``).

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

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.closed_form.five_bar import MODES, _wrap, elbow_points, forward, inverse
from pkdyn.exceptions import ParameterError
from pkdyn.library._check import in_range, middle_of_reach, positive, within_limits
from pkdyn.library._colors import GREY
from pkdyn.library._planar import check_chain, write_rr_chain
from pkdyn.library._render import builder_text
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter

__all__ = [
    "NAME",
    "SUMMARY",
    "Params",
    "assembly_mode",
    "build_urdf",
    "forward_position",
    "home",
    "inverse_actuators",
    "layout",
    "resolved",
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
        x_home: End-effector x at the home configuration [m] (default 0: midway between the
            base points).
        y_home: End-effector y at the home configuration [m]; ``None`` (default) derives it
            from the lengths: the middle of the end-effector's reach along ``x = x_home``
            above the base, within the actuator limits, rounded to two significant digits.
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
    y_home: float | None = None
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
        check_chain(NAME, self)
        positive(NAME, d=self.d, effector_mass=self.effector_mass)
        in_range(NAME, "x_home", self.x_home, -math.inf, math.inf)
        if self.y_home is not None:
            in_range(NAME, "y_home", self.y_home, -math.inf, math.inf)
        if self.working_mode not in MODES:
            raise ParameterError(
                NAME,
                "working_mode",
                f"must be one of {', '.join(MODES)}, got {self.working_mode!r}",
            )
        if self.y_home is None:
            self._derived  # noqa: B018  (raises if nothing is reachable)
            return
        theta, ok = inverse(self, self.home_point)
        if not ok[0]:
            raise ParameterError(
                NAME,
                "y_home",
                f"home point ({self.x_home}, {self.y_home}) m is out of reach with these lengths "
                "(each base point must lie between |l1 - l2| and l1 + l2 from it); leave y_home "
                "unset to derive it",
            )
        within_limits(NAME, theta[0], self.q_min, self.q_max)

    def _reachable(self, y: np.ndarray) -> np.ndarray:
        theta, ok = inverse(self, np.column_stack([np.full_like(y, self.x_home), y]))
        with np.errstate(invalid="ignore"):
            inside = np.all((theta >= self.q_min) & (theta <= self.q_max), axis=1)
        return ok & inside

    @functools.cached_property
    def _derived(self) -> float:
        return middle_of_reach(NAME, "y_home", 0.0, self.l1 + self.l2, self._reachable)

    def home_height(self) -> float:
        """Home end-effector y [m]: ``y_home``, or the middle of the reach above the base."""
        return float(self.y_home) if self.y_home is not None else self._derived

    @property
    def base_xy(self) -> np.ndarray:
        """Base points ``A_1, A_2``, shape (2, 2) [m]."""
        return np.array([[-0.5 * self.d, 0.0], [0.5 * self.d, 0.0]])

    @property
    def home_point(self) -> np.ndarray:
        """Home end-effector point ``(x, y)`` [m]."""
        return np.array([self.x_home, self.home_height()])


def home(p: Params) -> list[float]:
    """Actuated angles ``theta_1, theta_2`` [rad] with the end-effector at the home point."""
    theta, _ = inverse(p, p.home_point)
    return [float(v) for v in theta[0]]


def assembly_mode(
    p: Params, theta: np.ndarray | None = None, point: np.ndarray | None = None
) -> int:
    """Assembly mode of a configuration (default: home): +1 with E left of ``C_1 -> C_2``.

    As ``assembly`` of :func:`pkdyn.closed_form.five_bar.forward`.

    Args:
        p: Parameters.
        theta: Actuated angles (2,) [rad] (default: home).
        point: End-effector point (2,) [m] there (default: home).

    """
    th = np.array(home(p)) if theta is None else np.asarray(theta, dtype=float)
    E = p.home_point if point is None else np.asarray(point, dtype=float)[:2]
    C = elbow_points(p, th)[0]
    u, w = C[1] - C[0], E - C[0]
    return 1 if u[0] * w[1] - u[1] * w[0] >= 0.0 else -1


def forward_position(
    p: Params, qa: np.ndarray, reference: tuple[np.ndarray, np.ndarray] | None = None
) -> np.ndarray | None:
    """End-effector position [m] in the assembly mode of ``reference`` (default home)."""
    mode = assembly_mode(p) if reference is None else assembly_mode(p, *reference)
    E, ok = forward(p, np.asarray(qa, dtype=float), mode)
    return np.array([E[0, 0], E[0, 1], 0.0]) if ok[0] else None


def inverse_actuators(p: Params, pose: pin.SE3) -> np.ndarray | None:
    """Actuated angles [rad] of an end-effector point in ``working_mode``, or ``None``."""
    theta, ok = inverse(p, np.asarray(pose.translation, dtype=float)[:2])
    return theta[0] if ok[0] else None


def resolved(p: Params) -> Params:
    """The parameters with the derived ones (``y_home``) computed."""
    return dataclasses.replace(p, y_home=p.home_height())


def layout(p: Params) -> UrdfWriter:
    """The elements of the pkdyn description of a five-bar with parameters ``p``.

    :func:`build_urdf` renders them; :mod:`pkdyn.model.candidate` reads their numbers.
    """
    w = UrdfWriter("five_bar")
    r = p.link_radius
    z_prox, z_dist = 0.0, 2.5 * r  # display layers; the kinematics is in z = 0
    A = p.base_xy
    w.link(
        "base",
        visuals=[Shape("box", (p.d + 6 * r, 4 * r, 2 * r), (0.0, 0.0, -2 * r), rgba=GREY)],
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
        visuals=[Shape("sphere", (r_e,), (0.0, 0.0, z_dist), rgba=GREY)],
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
    return w


def build_urdf(p: Params) -> str:
    """URDF text, with pkdyn extension elements, of a five-bar with parameters ``p``."""
    return builder_text(layout(p), __name__)
