"""Clavel's workspace of the Delta (seed 000, section 1.4), closed form and numeric.

Clavel's two limits (Fig. 16 angles, reduced chain of Fig. 17):

- limit 1: ``|gamma_i| <= gamma_max`` (ball-joint travel; 40 deg on the prototypes), where
  ``gamma_i`` is the angle between the vertical plane ``pi_i`` of arm ``i`` and its bars;
- limit 2: ``(alpha+beta)_min <= alpha_i + beta_i <= 180 deg`` (30 deg: arm/bar interference;
  above 180 deg: the other inverse-model branch), ``alpha_i + beta_i`` being the elbow angle
  between the arm and the bars' projection on ``pi_i``.

Limit 1 alone bounds the nacelle to a right hexagonal prism (three slabs ``|P . t_i| <=
lb sin gamma_max``); the workspace is that prism cut by three bodies of revolution (Fig. 18).
Closed-form figures (dimensionless by ``la``: ``r = (ra - rb)/la``, ``b = lb/la``):

- inscribed cylinder ``d = 2 b sin gamma_max``, hexagon area ``s = 2 sqrt(3) sin^2 gamma_max b^2``;
- top of the complete prism ``z_h = -sqrt(1 + b^2 - 2 b cos (alpha+beta)_min)`` (Fig. 19);
- bottom ``z_b = max(z_T, z_T')`` (Fig. 20) with ``z_T = -sqrt((1+b)^2 - (r + 2 b sin g/sqrt 3)^2)``
  (vertex opposite an arm, bars in ``pi_i``) and ``z_T' = -sqrt((1 + b cos g)^2 - (r + b sin g /
  sqrt 3)^2)`` (adjacent vertices, ``gamma = gamma_max``; the seed prints it without the minus
  sign, a typo: the point lies below the base);
- ``h = z_h - z_b``, ``h_max = sqrt((1+b)^2 - r^2) + z_h`` (lowest point, on the axis), ``v = s h``.

:func:`clavel_numeric` measures the same quantities on the mechanism: it samples nacelle
positions, solves Clavel's inverse model (:mod:`pkdyn.closed_form.delta`), measures
``gamma_i`` and ``alpha_i + beta_i`` from the elbow points, and finds the hexagon (projection
of the workspace) and the complete prism from the samples by bisection.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from pkdyn.closed_form.delta import THETA, DeltaGeometry, elbow_points, inverse
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.arguments import public
from pkdyn.progress import progress_steps
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.units import columns, quantity

__all__ = [
    "ClavelComparison",
    "clavel_comparison",
    "GAMMA_MAX",
    "AB_MIN",
    "ClavelFigures",
    "clavel_angles",
    "clavel_valid",
    "clavel_closed_form",
    "clavel_numeric",
]

GAMMA_MAX = math.radians(40.0)
"""Clavel's ball-joint limit gamma_max [rad]."""
AB_MIN = math.radians(30.0)
"""Clavel's elbow limit (alpha + beta)_min [rad]."""


@dataclass(frozen=True)
class ClavelFigures(Result):
    """Clavel's workspace figures (SI) and their dimensionless forms (divided by ``la``).

    Attributes:
        D: Diameter of the inscribed vertical cylinder [m].
        S: Area of the hexagon (horizontal projection of the workspace) [m^2].
        H: Height of the complete hexagonal prism [m].
        Hmax: Height from the prism top to the lowest reachable point [m].
        V: Volume of the complete prism ``S H`` [m^3].
        zh: Height of the prism top [m] (negative: below the base).
        zb: Height of the prism bottom [m].
        la: Reference length [m].

    """

    D: float
    S: float
    H: float
    Hmax: float
    V: float
    zh: float
    zb: float
    la: float

    def dimensionless(self) -> dict[str, float]:
        """``d, s, h, hmax, v, z_h, z_b``: the figures divided by ``la`` to their dimension."""
        la = self.la
        return {
            "d": self.D / la,
            "s": self.S / la**2,
            "h": self.H / la,
            "hmax": self.Hmax / la,
            "v": self.V / la**3,
            "z_h": self.zh / la,
            "z_b": self.zb / la,
        }

    as_json = deprecated_alias("as_json", "to_json")

    def to_json(self) -> dict[str, Any]:
        """SI figures plus a ``dimensionless`` sub-dictionary."""
        out: dict[str, Any] = {k: float(v) for k, v in asdict(self).items() if k != "la"}
        out["dimensionless"] = self.dimensionless()
        return jsonable(out)

    def table(self) -> str:
        """Each figure with its unit and its dimensionless form (divided by ``la``)."""
        dl = self.dimensionless()
        rows = [["", "SI", "/ la^k"]]
        rows += [
            [name, quantity(getattr(self, name), unit, 6), quantity(dl[key], "", 6)]
            for name, unit, key in _FIGURES
        ]
        return columns(rows)


_FIGURES = (
    ("D", "m", "d"),
    ("S", "m^2", "s"),
    ("H", "m", "h"),
    ("Hmax", "m", "hmax"),
    ("V", "m^3", "v"),
    ("zh", "m", "z_h"),
    ("zb", "m", "z_b"),
)
"""Clavel's figures: name, unit, key of the dimensionless form."""


@dataclass(frozen=True)
class ClavelComparison(Result):
    """Clavel's closed-form figures beside the ones measured on the mechanism.

    Attributes:
        closed_form: :func:`clavel_closed_form`.
        numeric: :func:`clavel_numeric`'s figures.
        V_workspace: Volume of the whole workspace [m^3] (the prism, the dome above and the
            cap below).
        gamma_max: Limit 1 [rad].
        ab_min: Limit 2, (alpha + beta)_min [rad].

    """

    closed_form: ClavelFigures
    numeric: ClavelFigures
    V_workspace: float
    gamma_max: float
    ab_min: float

    def to_json(self) -> dict[str, Any]:
        """``closed_form``, ``numeric`` (with ``V_workspace``), ``limits``, ``difference``."""
        cf, nu = self.closed_form.to_json(), self.numeric.to_json()
        nu["V_workspace"] = self.V_workspace
        return jsonable(
            {
                "closed_form": cf,
                "numeric": nu,
                "limits": {"gamma_max": self.gamma_max, "ab_min": self.ab_min, "ab_max": math.pi},
                "difference": {k: nu[k] - cf[k] for k, _, _ in _FIGURES if k != "zb"},
            }
        )

    def table(self) -> str:
        """The figures side by side with their difference, and the whole volume."""
        rows = [["", "closed form", "numeric", "difference"]]
        for name, unit, _ in _FIGURES:
            a, b = getattr(self.closed_form, name), getattr(self.numeric, name)
            rows.append(
                [name, quantity(a, unit, 7), quantity(b, unit, 7), quantity(b - a, unit, 2)]
            )
        V = self.closed_form.V
        ratio = f" = {self.V_workspace / V:.3f} V" if V > 0 else ""
        return (
            columns(rows)
            + f"\nwhole workspace volume (numeric): {quantity(self.V_workspace, 'm^3')}{ratio} "
            "(the prism misses the dome above and the cap below)"
        )


def clavel_comparison(
    g: DeltaGeometry,
    gamma_max: float = GAMMA_MAX,
    ab_min: float = AB_MIN,
    rays: int = 72,
    progress: bool | None = None,
) -> ClavelComparison:
    """Clavel's closed-form figures and the same measured on the mechanism (``workspace --clavel``).

    Args:
        g: Delta geometry (ra, rb, la, lb) [m].
        gamma_max: Limit 1 [rad].
        ab_min: Limit 2 [rad].
        rays: Directions sampled by :func:`clavel_numeric`.
        progress: Progress bar (``None``: when stderr is a terminal).

    Returns:
        Both sets of figures.

    Raises:
        InvalidInputError: Limits out of range or too few rays.
        PkdynError: No complete prism, or no valid position on the axis.

    """
    cf = clavel_closed_form(g, gamma_max, ab_min)
    nu, v_ws = clavel_numeric(g, gamma_max, ab_min, rays=rays, progress=progress)
    return ClavelComparison(cf, nu, v_ws, gamma_max, ab_min)


def _check_geometry(g: Any) -> None:
    """``g`` has Clavel's lengths ``ra, rb, la, lb`` [m] (a Delta's parameters)."""
    from pkdyn.inputs import non_negative, positive

    if not all(hasattr(g, a) for a in ("ra", "rb", "la", "lb")):
        raise InvalidInputError(
            "g", f"expected a Delta geometry (ra, rb, la, lb; robot.params), got {g!r:.60}"
        )
    for a in ("ra", "la", "lb"):
        positive(f"g.{a}", getattr(g, a), "m")
    non_negative("g.rb", g.rb, "m")


def _check_limits(gamma_max: float, ab_min: float) -> None:
    from pkdyn.inputs import real

    gamma_max = real("gamma_max", gamma_max, "rad")
    ab_min = real("ab_min", ab_min, "rad")
    if not 0.0 < gamma_max < math.pi / 2:
        raise InvalidInputError("gamma_max", f"{gamma_max} rad: need 0 < gamma_max < pi/2")
    if not 0.0 <= ab_min < math.pi:
        raise InvalidInputError("ab_min", f"(alpha+beta)_min = {ab_min} rad: need 0 <= value < pi")


def clavel_closed_form(
    g: DeltaGeometry, gamma_max: float = GAMMA_MAX, ab_min: float = AB_MIN
) -> ClavelFigures:
    """Clavel's closed-form workspace figures (seed 000, section 1.4, Figs. 18-20).

    Args:
        g: Delta geometry (ra, rb, la, lb) [m].
        gamma_max: Limit 1, bar angle to the arm plane [rad].
        ab_min: Limit 2, minimum elbow angle (alpha + beta) [rad].

    Returns:
        The figures.

    Raises:
        InvalidInputError: Limits out of range.
        PkdynError: The hexagon is wider than the arms and bars reach: no complete prism.

    """
    _check_geometry(g)
    _check_limits(gamma_max, ab_min)
    la = g.la
    r, b = (g.ra - g.rb) / la, g.lb / la
    sg, cg = math.sin(gamma_max), math.cos(gamma_max)
    d = 2.0 * b * sg
    s = 2.0 * math.sqrt(3.0) * sg**2 * b**2
    z_h = -math.sqrt(1.0 + b * b - 2.0 * b * math.cos(ab_min))
    t = (1.0 + b) ** 2 - (r + 2.0 * b * sg / math.sqrt(3.0)) ** 2
    tp = (1.0 + b * cg) ** 2 - (r + b * sg / math.sqrt(3.0)) ** 2
    low = (1.0 + b) ** 2 - r**2
    if min(t, tp) <= 0.0:
        raise PkdynError(
            f"gamma_max = {gamma_max:.4g} rad: the hexagon's corners are beyond the reach of "
            "arms and bars; no complete prism (lower gamma_max)"
        )
    z_b = max(-math.sqrt(t), -math.sqrt(tp))
    h = max(z_h - z_b, 0.0)  # z_h below z_b: the hexagon is nowhere complete
    hmax = math.sqrt(low) + z_h
    return ClavelFigures(
        D=d * la,
        S=s * la**2,
        H=h * la,
        Hmax=hmax * la,
        V=s * h * la**3,
        zh=z_h * la,
        zb=z_b * la,
        la=la,
    )


def clavel_angles(g: DeltaGeometry, P: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Clavel's angles of every arm for nacelle positions, on the working branch.

    Args:
        g: Delta geometry (ra, rb, la, lb) [m].
        P: Nacelle positions (N, 3) [m].

    Returns:
        ``(alpha, alpha_plus_beta, gamma)``, each (N, 3) [rad], NaN where unreachable.
        ``gamma_i`` is the signed angle of the bars to the arm plane ``pi_i``;
        ``alpha_i + beta_i`` the elbow angle between the arm and the bars' projection on ``pi_i``.

    """
    P = np.atleast_2d(np.asarray(P, dtype=float))
    alpha, _ = inverse(g, P)
    C = elbow_points(g, alpha)  # (N, 3 arms, 3)
    u = (P[:, None, :] - C) / g.lb
    c, s = np.cos(THETA), np.sin(THETA)
    u_r = u[..., 0] * c + u[..., 1] * s
    u_t = -u[..., 0] * s + u[..., 1] * c
    gamma = np.arcsin(np.clip(u_t, -1.0, 1.0))
    beta = np.arctan2(-u[..., 2], -u_r)
    return alpha, alpha + beta, gamma


def clavel_valid(
    g: DeltaGeometry, P: np.ndarray, gamma_max: float = GAMMA_MAX, ab_min: float = AB_MIN
) -> np.ndarray:
    """Whether nacelle positions satisfy Clavel's limits 1 and 2 (and are reachable).

    Args:
        g: Delta geometry [m].
        P: Nacelle positions (N, 3) [m].
        gamma_max: Limit 1 [rad].
        ab_min: Lower bound of limit 2 [rad] (the upper bound is pi).

    Returns:
        Boolean mask (N,).

    """
    _, ab, gamma = clavel_angles(g, P)
    with np.errstate(invalid="ignore"):
        ok = (np.abs(gamma) <= gamma_max) & (ab >= ab_min) & (ab <= math.pi)
    return np.asarray(ok.all(axis=1))


class _Sampler:
    """Column queries on the mechanism with Clavel's limits (validity by the inverse model)."""

    def __init__(
        self, g: DeltaGeometry, gamma_max: float, ab_min: float, heights: int, tol: float
    ) -> None:
        self.g, self.gamma_max, self.ab_min, self.tol = g, gamma_max, ab_min, tol
        self.reach = g.la + g.lb
        self.z = np.linspace(-1e-6, -self.reach, heights)

    def valid(self, P: np.ndarray) -> np.ndarray:
        return clavel_valid(self.g, P, self.gamma_max, self.ab_min)

    def columns(self, xy: np.ndarray) -> np.ndarray:
        """Validity of the height samples on columns ``xy`` (M, 2) -> (M, heights)."""
        M, K = xy.shape[0], self.z.size
        P = np.empty((M, K, 3))
        P[..., :2] = xy[:, None, :]
        P[..., 2] = self.z[None, :]
        return self.valid(P.reshape(-1, 3)).reshape(M, K)

    def edge_radius(self, phi: np.ndarray) -> np.ndarray:
        """Per direction ``phi`` [rad], the largest radius whose column has a valid height."""
        dirs = np.column_stack([np.cos(phi), np.sin(phi)])
        r_in, r_out = np.zeros(len(phi)), np.full(len(phi), self.reach + self.g.ra)
        while np.max(r_out - r_in) > self.tol:
            mid = 0.5 * (r_in + r_out)
            ok = self.columns(dirs * mid[:, None]).any(axis=1)
            r_in, r_out = np.where(ok, mid, r_in), np.where(ok, r_out, mid)
        return r_in

    def _bisect(self, xy: np.ndarray, z_in: np.ndarray, z_out: np.ndarray) -> np.ndarray:
        P = np.column_stack([xy, np.zeros(len(xy))])
        z_in, z_out = z_in.copy(), z_out.copy()
        while np.max(np.abs(z_out - z_in)) > self.tol:
            P[:, 2] = 0.5 * (z_in + z_out)
            ok = self.valid(P)
            z_in = np.where(ok, P[:, 2], z_in)
            z_out = np.where(ok, z_out, P[:, 2])
        return z_in

    def interval(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Top and bottom of the valid heights on columns ``xy`` (M, 2) [m], and valid runs.

        The run count is the number of separate valid intervals seen in the samples (1 when
        the column is vertically convex).
        """
        z, n = self.z, self.z.size
        valid = self.columns(xy)
        if not valid.any(axis=1).all():
            raise PkdynError("a column of the hexagon has no valid height; raise 'heights'")
        first = valid.argmax(axis=1)
        last = n - 1 - valid[:, ::-1].argmax(axis=1)
        above = np.where(first > 0, z[np.maximum(first - 1, 0)], 0.0)
        below = np.where(last < n - 1, z[np.minimum(last + 1, n - 1)], -self.reach - 1.0)
        runs = valid[:, 0].astype(int) + np.sum(np.diff(valid.astype(int), axis=1) == 1, axis=1)
        return self._bisect(xy, z[first], above), self._bisect(xy, z[last], below), runs

    def extremum(self, phi: float, f: float, dphi: float, df: float, which: str) -> float:
        """Pattern search over (direction, radial fraction), from a sample.

        ``which``: the lowest top (``top``), the highest bottom (``bottom``) or the lowest
        bottom (``lowest``) [m].
        """
        sign = 1.0 if which in ("top", "lowest") else -1.0
        k = 0 if which == "top" else 1
        steps = np.arange(-2, 3)
        best = None
        while dphi * self.reach > self.tol or df * self.reach > self.tol:
            phis = phi + steps * dphi
            fs = np.clip(f + steps * df, 0.0, 1.0)
            r = self.edge_radius(phis)
            PH, FF = np.meshgrid(np.arange(5), fs, indexing="ij")
            rad = r[PH] * FF
            xy = np.column_stack(
                [(rad * np.cos(phis[PH])).ravel(), (rad * np.sin(phis[PH])).ravel()]
            )
            val = sign * self.interval(xy)[k]
            i = int(np.argmin(val))
            if val[i] >= val[12]:
                i = 12
            best = float(sign * val[i])
            if i == 12:  # the centre stays best: zoom in
                dphi, df = 0.5 * dphi, 0.5 * df
            phi, f = float(phis[PH.ravel()[i]]), float(FF.ravel()[i])
        assert best is not None
        return best


@public
def clavel_numeric(
    g: DeltaGeometry,
    gamma_max: float = GAMMA_MAX,
    ab_min: float = AB_MIN,
    rays: int = 72,
    fractions: int = 21,
    heights: int = 100,
    tol: float = 1e-10,
    refine: bool = True,
    progress: bool | None = None,
) -> tuple[ClavelFigures, float]:
    """Clavel's figures measured on the mechanism by sampling with the same limits.

    The hexagon is the projection of the workspace on a horizontal plane: along ``rays``
    directions from the axis, the largest radius with a valid height somewhere on its column
    (``heights`` samples from the base down to the full reach, then bisection to ``tol``);
    ``D`` is twice the smallest such radius, ``S`` the area of the polygon. On ``rays x
    fractions`` columns of the hexagon (its edges included) the top and bottom of the valid
    heights are found by bisection; the complete prism spans from the lowest top (``zh``) to
    the highest bottom (``zb``), each refined from the best sample by a pattern search over
    direction and radial fraction. ``Hmax`` runs from ``zh`` to the lowest valid point.

    Args:
        g: Delta geometry (ra, rb, la, lb) [m].
        gamma_max: Limit 1 [rad].
        ab_min: Lower bound of limit 2 [rad].
        rays: Number of directions.
        fractions: Radial samples per direction, from the axis to the projection's edge.
        heights: Height samples per column before bisection.
        tol: Bisection and pattern-search tolerance [m].
        refine: Refine ``zh``, ``zb`` and the lowest point by pattern search (else: the best
            column sample).
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default)
            shows it when stderr is a terminal.

    Returns:
        ``(figures, V_workspace)``: the measured figures and the volume of the whole workspace
        [m^3] (the prism plus the dome above it and the cap below), integrated over the columns.

    Raises:
        InvalidInputError: Limits out of range or too few samples.
        PkdynError: No valid position on the axis.

    """
    from pkdyn.inputs import count, positive

    _check_geometry(g)
    _check_limits(gamma_max, ab_min)
    rays = count("rays", rays, 12)
    fractions = count("fractions", fractions, 3)
    heights = count("heights", heights, 20)
    tol = positive("tol", tol, "m")
    if tol < 1e-13 * g.la:
        raise InvalidInputError(
            "tol", f"{tol:g} m: below what floating point resolves on a {g.la:g} m arm (1e-13 la)"
        )
    if rays * fractions * heights > 50_000_000:
        raise InvalidInputError(
            "sampling",
            f"rays x fractions x heights = {rays * fractions * heights:.3g} samples before "
            "bisection (tens of minutes); at most 5e7: fewer rays",
        )
    smp = _Sampler(g, gamma_max, ab_min, heights, tol)
    if not smp.columns(np.zeros((1, 2))).any():
        raise PkdynError("no valid nacelle position on the axis with these limits")
    with progress_steps(5, "Clavel workspace", "stage", progress) as advance:
        phi = 2.0 * np.pi * np.arange(rays) / rays
        r_edge = smp.edge_radius(phi)
        advance()
        x, y = r_edge * np.cos(phi), r_edge * np.sin(phi)
        S = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
        D = 2.0 * float(r_edge.min())
        f = np.linspace(0.0, 1.0, fractions)
        rad = r_edge[:, None] * f[None, :]
        xy = np.stack([rad * np.cos(phi)[:, None], rad * np.sin(phi)[:, None]], axis=-1)
        z_top, z_bot, runs = smp.interval(xy.reshape(-1, 2))
        advance()
        if np.any(runs > 1):
            import warnings

            warnings.warn(
                f"{int(np.sum(runs > 1))} columns have several valid height intervals; the "
                "workspace volume counts their envelope",
                stacklevel=2,
            )
        # whole-workspace volume: int dphi r(phi)^2 int f (z_top - z_bot) df (trapezoids)
        length = (z_top - z_bot).reshape(rays, fractions)
        inner = np.trapezoid(f[None, :] * length, f, axis=1)
        V_ws = float(np.sum(r_edge**2 * inner) * 2.0 * np.pi / rays)
        dphi, df = 2.0 * np.pi / rays, 1.0 / (fractions - 1)
        found = []
        for which, arr, pick in (
            ("top", z_top, np.argmin),
            ("bottom", z_bot, np.argmax),
            ("lowest", z_bot, np.argmin),
        ):
            i = int(pick(arr))
            if not refine:
                found.append(float(arr[i]))
                advance()
                continue
            found.append(
                smp.extremum(float(phi[i // fractions]), float(f[i % fractions]), dphi, df, which)
            )
            advance()
    zh, zb, z_low = found
    H = max(zh - zb, 0.0)
    return ClavelFigures(D=D, S=S, H=H, Hmax=zh - z_low, V=S * H, zh=zh, zb=zb, la=g.la), V_ws
