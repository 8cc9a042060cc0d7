"""Closed-form clearances of the tripod and the walker for many nacelle poses at once.

The quantities the redundancy resolution of the four-branch walker trades
(:mod:`pkdyn.tripod.redundancy`), computed from the nacelle placement and the foot-frame origins
``A_i`` alone (no joint configuration, no coal), vectorised over the samples:

- **legs** are the collision cylinders of the library model (:mod:`pkdyn.library.tripod`) taken
  as *capsules* (the same segment and radius, rounded ends): the body of actuator ``L`` of branch
  ``i`` from ``P_L + c e`` to ``P_L + stroke_min e`` (``e`` the unit vector from ``P_L`` to
  ``A``, ``c`` :data:`pkdyn.library.tripod.MOUNT_CLEARANCE`), its rod from
  ``A - (stroke_max - stroke_min + 0.03) e`` to ``A``, the same for ``R``;
- the **nacelle** is its plate (a solid cylinder of radius ``r_p + 0.04`` and thickness 0.04 m
  centred on ``P_O``) and its spindle (radius 0.05 m, from ``P_O`` down to the tool);
- **leg to leg**: the smallest distance between the capsules of different branches (closed-form
  segment distances, negative when they overlap);
- **leg to nacelle**: the smallest distance between a leg cylinder and the plate or the spindle,
  from two subsets of the leg cylinder: the capsule of the same radius on the axis shortened by
  one radius at each end (it lies inside the cylinder; the signed distance from a point to a
  solid cylinder is convex, so its minimum along the axis is found by golden-section search) and
  :data:`RIM_POINTS` points on the rim of the end disc of each actuator body at its mount, where
  the body, inclined towards the foot, comes closest to the plate's lower edge (the other ends
  are half a metre away from the nacelle). Both are distances from points of the leg, so the
  result is never below coal's; the tests find it within a fraction of a millimetre of coal's;
  negative when the leg axis enters the nacelle;
- **stroke margins**: the smallest distance of an actuator length ``|A P_L|``, ``|A P_R|`` to its
  stroke limits;
- **conditioning**, with every foot clamped (mode PP): ``1 / cond`` of the inverse Jacobian of the
  branches as a Gough-Stewart platform (the tripod in mode PP is one: each actuator is a U-P-S
  leg from ``P_L`` or ``P_R`` to ``A``), rows ``[e^T, ((P - P_O) x e)^T / r_p]`` (rotations scaled
  by the nacelle radius), 0 at a parallel singularity; while a branch of the walker swings
  (mode BE), the ``distance`` of :func:`pkdyn.analysis.singularity.classify` on the mode's robot,
  in closed form: the three support branches give the nacelle twist ``xi_X = J_s^-1 qd_s``
  (``J_s`` as above, unscaled), the locked swinging branch moves its foot about the triangle's
  normal ``z`` through ``P_L`` (rate ``beta_dot``) and along its rod ``L``, so the foot twist is
  ``xi_F = Ad(A - P_O) xi_X + G r_dot`` (``A x_dot = B q_dot_a`` with ``A = I``,
  ``B = [Ad J_s^-1, G]``); as in :mod:`pkdyn.analysis.kinematics` the relations are
  orthonormalised and the measure is the smaller of ``1 / cond(A)`` and ``1 / cond(B)`` (the
  tests compare it with ``classify``).

Capsules enclose the cylinders, so the leg-to-leg distances here are never larger than coal's on
the collision model; the difference is at most a leg radius, at the rounded ends, and the legs of
different branches stay far apart (0.3 m or more on the default walk).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.analysis.collisions import segment_distance
from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.library.tripod import MOUNT_CLEARANCE
from pkdyn.results import Result, deprecated_alias
from pkdyn.units import quantity

__all__ = ["LEG_NAMES", "RIM_POINTS", "Clearances", "clearances", "leg_segments"]

LEG_NAMES = ("cylL", "rodL", "cylR", "rodR")
"""The bodies of a branch that make its legs (the links ``branch{i}_<name>``)."""

_PLATE_MARGIN, _PLATE_THICKNESS, _SPINDLE_RADIUS = 0.04, 0.04, 0.05
_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)

RIM_POINTS = 24
"""Points sampled on the rim of an actuator body's mount-end disc (leg-to-nacelle distances)."""


@dataclass(frozen=True)
class Clearances(Result):
    """Clearances of a sequence of poses (one row per sample).

    Attributes:
        leg_to_leg: Smallest capsule distance between legs of different branches (N,) [m].
        leg_to_nacelle: Smallest distance between a leg capsule and the nacelle (N,) [m].
        stroke_margin: Smallest distance of an actuator to its stroke limits (N,) [m].
        singularity: ``1 / cond`` of the support branches' inverse Jacobian (N,).
        lengths: Actuator lengths (N, 2 n) [m], in actuator order.
        closest: Names of the two bodies at the smallest leg distance of each sample.
        per_leg_to_nacelle: Distance of every leg body to the nacelle (N, 4 n) [m] (branch
            order, ``cylL, rodL, cylR, rodR`` in each branch).

    """

    leg_to_leg: np.ndarray
    leg_to_nacelle: np.ndarray
    stroke_margin: np.ndarray
    singularity: np.ndarray
    lengths: np.ndarray
    closest: list[tuple[str, str]]
    per_leg_to_nacelle: np.ndarray

    @property
    def distance(self) -> np.ndarray:
        """Smallest leg-to-leg or leg-to-nacelle distance (N,) [m]."""
        return np.minimum(self.leg_to_leg, self.leg_to_nacelle)

    summary = deprecated_alias("summary", "to_json")

    def table(self) -> str:
        """The smallest clearances over the samples, and where the legs come closest."""
        s = self.to_json()
        return (
            f"legs to legs {quantity(s['min_leg_to_leg'], 'm')}, legs to nacelle "
            f"{quantity(s['min_leg_to_nacelle'], 'm')}, stroke left "
            f"{quantity(s['min_stroke_margin'], 'm')}, support 1/cond "
            f"{quantity(s['min_support_conditioning'], '', 3)}; closest: "
            f"{' - '.join(s['closest_pair'])}"
        )

    def to_json(self) -> dict[str, Any]:
        """Smallest value of each quantity over the samples, and where the legs come closest."""
        k = int(np.argmin(self.distance))
        return {
            "min_leg_to_leg": float(self.leg_to_leg.min()),
            "min_leg_to_nacelle": float(self.leg_to_nacelle.min()),
            "min_stroke_margin": float(self.stroke_margin.min()),
            "min_support_conditioning": float(self.singularity.min()),
            "closest_pair": list(self.closest[k]),
        }


def leg_segments(p: Any, P: np.ndarray, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """End points of the leg capsules of one side of every branch.

    Args:
        p: Tripod parameters.
        P: Attachment points ``P_L`` (or ``P_R``) (..., n, 3) [m].
        A: Foot-frame origins (..., n, 3) [m].

    Returns:
        ``(starts, ends)`` (..., n, 2, 3): body then rod of each branch's actuator.

    """
    d = A - P
    e = d / np.linalg.norm(d, axis=-1, keepdims=True)
    rod = p.stroke_max - p.stroke_min + 0.03
    starts = np.stack([P + MOUNT_CLEARANCE * e, A - rod * e], axis=-2)
    ends = np.stack([P + p.stroke_min * e, A], axis=-2)
    return starts, ends


def _signed(rho: np.ndarray, z: np.ndarray, radius: Any, half: Any) -> np.ndarray:
    """Signed distance to a solid cylinder from radial and axial coordinates (negative inside)."""
    dr, dz = rho - radius, np.abs(z) - half
    outside = np.hypot(np.maximum(dr, 0.0), np.maximum(dz, 0.0))
    return np.where((dr <= 0.0) & (dz <= 0.0), np.maximum(dr, dz), outside)


def _segment_to_cylinders(
    a: np.ndarray,
    b: np.ndarray,
    O: np.ndarray,
    w: np.ndarray,
    bodies: np.ndarray,
    iterations: int = 16,
) -> np.ndarray:
    """Smallest signed distance from segments ``[a, b]`` (..., 3) to coaxial solid cylinders.

    The cylinders share the axis ``w`` through ``O``; ``bodies`` (k, 3) holds the radius, the
    half height and the axial offset of each centre from ``O``. Along a segment the axial
    coordinate is linear and the squared radial one quadratic in the segment parameter, and the
    signed distance to a convex body is convex along a line: golden-section search on the
    parameter, all cylinders at once.

    Returns:
        (k, ...) distances [m].

    """
    ra, rb = a - O, b - O
    za = np.einsum("...i,...i->...", ra, w)
    zb = np.einsum("...i,...i->...", rb, w)
    Pa = ra - za[..., None] * w
    Q = rb - zb[..., None] * w - Pa
    alpha = np.einsum("...i,...i->...", Pa, Pa)
    beta = np.einsum("...i,...i->...", Pa, Q)
    gamma = np.einsum("...i,...i->...", Q, Q)
    extra = (slice(None),) + (None,) * za.ndim
    radius, half, offset = (bodies[:, j][extra] for j in range(3))
    z0, dz = za[None] - offset, (zb - za)[None]

    def f(s: np.ndarray) -> np.ndarray:
        rho = np.sqrt(np.maximum(alpha + s * (2.0 * beta + s * gamma), 0.0))
        return _signed(rho, z0 + s * dz, radius, half)

    shape = (bodies.shape[0],) + za.shape
    lo, hi = np.zeros(shape), np.ones(shape)
    x1, x2 = hi - _GOLDEN, lo + _GOLDEN
    f1, f2 = f(x1), f(x2)
    for _ in range(iterations):
        left = f1 <= f2  # the minimum lies in [lo, x2]
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        new = np.where(left, hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo))
        fn = f(new)
        x1, x2, f1, f2 = (
            np.where(left, new, x2),
            np.where(left, x1, new),
            np.where(left, fn, f2),
            np.where(left, f1, fn),
        )
    ends = np.minimum(f(np.zeros(shape)), f(np.ones(shape)))
    return np.minimum(np.minimum(f1, f2), ends)


def _leg_to_nacelle(
    p: Any, S: np.ndarray, E: np.ndarray, rad: np.ndarray, R: np.ndarray, P_O: np.ndarray
) -> np.ndarray:
    """Smallest distance of each leg cylinder (N, m) to the plate or the spindle [m]."""
    w = R[:, :, 2][:, None, :]  # nacelle normal (N, 1, 3)
    O = P_O[:, None, :]
    tool = max(p.tool_offset, 1e-3)
    bodies = np.array(
        [
            [p.r_p + _PLATE_MARGIN, 0.5 * _PLATE_THICKNESS, 0.0],  # plate
            [_SPINDLE_RADIUS, 0.5 * tool, -0.5 * tool],  # spindle
        ]
    )
    axis = E - S
    length = np.sqrt(np.einsum("...i,...i->...", axis, axis))[..., None]
    e = axis / length
    cut = np.minimum(rad[:, None], 0.5 * length)  # shortened capsule, inside the cylinder
    side = _segment_to_cylinders(S + cut * e, E - cut * e, O, w, bodies).min(axis=0) - rad
    # rims of the actuator bodies' mount-end discs (bodies are legs 0 and 2 of each branch)
    body = np.arange(S.shape[1]) % 2 == 0
    eb, Sb = e[:, body], S[:, body]
    helper = np.where(np.abs(eb[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    u = np.cross(eb, helper)
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    v = np.cross(eb, u)
    ang = np.linspace(0.0, 2.0 * np.pi, RIM_POINTS, endpoint=False)
    rims = (
        Sb[..., None, :]
        + (np.cos(ang)[:, None] * u[..., None, :] + np.sin(ang)[:, None] * v[..., None, :])
        * rad[body][:, None, None]
    ) - O[..., None, :]  # (N, bodies, K, 3), from P_O
    wz = w[..., None, :]
    z = np.einsum("...i,...i->...", rims, wz)
    rho = np.linalg.norm(rims - z[..., None] * wz, axis=-1)
    rim = _signed(rho, z, bodies[0, 0], bodies[0, 1]).min(axis=-1)
    side[:, body] = np.minimum(side[:, body], rim)
    return side


def _be_distance(
    p: Any, P: np.ndarray, P_O: np.ndarray, A: np.ndarray, swinging: int
) -> np.ndarray:
    """``1 / cond`` of the walker's mode BE (see the module docstring), per sample (N,)."""
    N, n = P.shape[:2]
    i = swinging - 1
    sup = [b for b in range(n) if b != i]
    Ps = P[:, sup].reshape(N, -1, 3)  # (N, 6, 3): L, R of each support branch
    e = np.repeat(A[:, sup], 2, axis=1) - Ps
    e /= np.linalg.norm(e, axis=-1, keepdims=True)
    Js = np.concatenate([e, np.cross(Ps - P_O[:, None, :], e)], axis=-1)  # qd_s = Js xi_X
    a = A[:, i] - P_O
    Ad = np.zeros((N, 6, 6))
    Ad[:, :3, :3] = np.eye(3)
    Ad[:, 3:, 3:] = np.eye(3)
    Ad[:, 0, 4], Ad[:, 0, 5] = a[:, 2], -a[:, 1]  # v_A = v_O - [a]x omega
    Ad[:, 1, 3], Ad[:, 1, 5] = -a[:, 2], a[:, 0]
    Ad[:, 2, 3], Ad[:, 2, 4] = a[:, 1], -a[:, 0]
    # the supports' J_s is square (3 branches, 6 legs); singular: a parallel singularity (0)
    regular = np.abs(np.linalg.det(Js)) > 1e-300
    K_s = np.zeros((N, 6, 6))
    K_s[regular] = Ad[regular] @ np.linalg.solve(Js[regular], np.eye(6))
    # the locked swinging branch: its foot turns about z through P_L and slides along rod L
    P_L, P_R, A_i = P[:, i, 0], P[:, i, 1], A[:, i]
    dL, dR = A_i - P_L, A_i - P_R
    qL = np.linalg.norm(dL, axis=-1)
    qR = np.linalg.norm(dR, axis=-1)
    u = P_R - P_L
    edge = np.linalg.norm(u, axis=-1)
    z = np.cross(u, dL)
    sin_b = np.linalg.norm(z, axis=-1) / (edge * qL)
    with np.errstate(divide="ignore", invalid="ignore"):
        z /= np.linalg.norm(z, axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        db_L = -(qL**2 - edge**2 + qR**2) / (2.0 * edge * qL**2) / sin_b
        db_R = qR / (edge * qL) / sin_b
    turn = np.cross(z, dL)
    G = np.empty((N, 6, 2))
    G[:, :3, 0] = db_L[:, None] * turn + dL / qL[:, None]
    G[:, 3:, 0] = db_L[:, None] * z
    G[:, :3, 1] = db_R[:, None] * turn
    G[:, 3:, 1] = db_R[:, None] * z
    order = [2 * b + k for b in sup for k in (0, 1)] + [2 * i, 2 * i + 1]
    B = np.empty((N, 6, 2 * n))
    B[:, :, order] = np.concatenate([K_s, G], axis=-1)
    rel = np.concatenate([B, -np.broadcast_to(np.eye(6), (N, 6, 6))], axis=-1)
    ok = np.isfinite(rel).all(axis=(1, 2)) & regular  # a flat triangle: singular (0)
    rel[~ok] = 0.0
    _, _, Vt = np.linalg.svd(rel, full_matrices=False)  # orthonormal basis of the relations
    sA = np.linalg.svd(-Vt[:, :, 2 * n :], compute_uv=False)
    sB = np.linalg.svd(Vt[:, :, : 2 * n], compute_uv=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.minimum(sA[:, -1] / sA[:, 0], sB[:, -1] / sB[:, 0])
    return np.where(ok & np.isfinite(out), out, 0.0)


def clearances(
    p: Any,
    R: np.ndarray,
    P_O: np.ndarray,
    A: np.ndarray,
    swinging: int | None = None,
) -> Clearances:
    """Clearances of nacelle placements with the feet at ``A`` (see the module docstring).

    Args:
        p: Tripod (or walker) parameters.
        R: Nacelle orientations (N, 3, 3).
        P_O: Nacelle origins (N, 3) [m].
        A: Foot-frame origins (N, n, 3) [m] (branch order).
        swinging: The walker's swinging branch (mode BE), or ``None`` (mode PP).

    Returns:
        The clearances per sample.

    """
    n = tripod_cf.branch_count(p)
    N = R.shape[0]
    local = np.array([tripod_cf.attachments(p, i) for i in range(n)])  # (n, 2, 3): L, R
    P = np.einsum("kij,bsj->kbsi", R, local) + P_O[:, None, None, :]  # (N, n, 2, 3)
    starts, ends, radii = [], [], []
    for side in (0, 1):
        s, e = leg_segments(p, P[:, :, side], A)  # (N, n, 2, 3)
        starts.append(s)
        ends.append(e)
        radii.append([p.cylinder_radius, p.rod_radius])
    S = np.concatenate(starts, axis=2)  # (N, n, 4, 3): cylL, rodL, cylR, rodR
    E = np.concatenate(ends, axis=2)
    rad = np.array(radii).reshape(4)
    names = [f"branch{b + 1}_{leg}" for b in range(n) for leg in LEG_NAMES]
    # leg to leg: every pair of bodies of different branches
    ia, ib = np.triu_indices(4 * n, 1)
    other = ia // 4 != ib // 4
    ia, ib = ia[other], ib[other]
    S2, E2 = S.reshape(N, 4 * n, 3), E.reshape(N, 4 * n, 3)
    d, _, _ = segment_distance(S2[:, ia], E2[:, ia], S2[:, ib], E2[:, ib])
    d = d - rad[ia % 4] - rad[ib % 4]
    # leg to nacelle: plate, then spindle (both solid cylinders)
    dn = _leg_to_nacelle(p, S2, E2, np.tile(rad, n), R, P_O)
    # stroke margins
    L = np.linalg.norm(A[:, :, None, :] - P, axis=-1).reshape(N, 2 * n)
    margin = np.minimum(L - p.stroke_min, p.stroke_max - L).min(axis=1)
    # conditioning
    if swinging is None:
        Ps = P.reshape(N, -1, 3)
        e = np.repeat(A, 2, axis=1) - Ps
        e /= np.linalg.norm(e, axis=-1, keepdims=True)
        J = np.concatenate([e, np.cross(Ps - P_O[:, None, :], e) / p.r_p], axis=-1)
        sv = np.linalg.svd(J, compute_uv=False)
        sing = sv[:, 5] / sv[:, 0]
    else:
        sing = _be_distance(p, P, P_O, A, swinging)
    # closest bodies per sample
    closest: list[tuple[str, str]] = []
    kl, kn = np.argmin(d, axis=1), np.argmin(dn, axis=1)
    dl, dnn = d[np.arange(N), kl], dn[np.arange(N), kn]
    for k in range(N):
        if dl[k] <= dnn[k]:
            closest.append((names[ia[kl[k]]], names[ib[kl[k]]]))
        else:
            closest.append((names[kn[k]], "nacelle"))
    return Clearances(dl, dnn, margin, sing, L, closest, dn)
