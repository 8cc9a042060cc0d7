"""Redundancy resolution of the four-branch walker while a branch swings (seed 003).

The paper's conclusion: with three branches the swinging foot is driven by the six actuators with
no redundancy, so the nacelle cannot choose a posture that avoids interference; a fourth branch
would give the foot a connectivity of eight, so that it follows its own path while the nacelle's
path is optimised. This module does that optimisation.

**The two free degrees of freedom.** With the walker's locks (:func:`pkdyn.tripod.modes.be_mode`:
``q1, q2, q3, q6`` of the swinging branch ``i``) the swinging branch is one rigid chain from its
foot to the nacelle whose only mobilities are its triangle's, set by its two actuator lengths
``r = (q_Li, q_Ri)``: the nacelle pose follows from the foot and ``r`` in closed form
(:class:`pkdyn.tripod.locked_branch.LockedBranch`), and the six support actuators from the nacelle
(the support branches form a tripod in mode PP). ``r(t)`` is therefore the redundancy's
coordinate: any smooth ``r(t)`` with the foot on its path is a motion of the walker, and the foot
follows its path exactly whatever ``r(t)`` is
(:func:`pkdyn.dynamics.redundant.map_redundant_trajectory` maps it with the closures, clamps and
locks to 1e-13).

**Baseline** (the nacelle path fixed by the plan, nothing optimised): ``r`` moves from its value
when the locks engage to its value at the planned end of the swing with the foot's own law
``s(t)`` (quintic): ``r_0 + s(t) (r_1 - r_0)``; ``r_1`` puts the nacelle as near as the locks allow
to the station home above the landed feet (least squares, position and ``r_p`` times rotation).

**Optimised path**: ``r(t) = r_0 + s(t) (r_1 + delta - r_0) + sum_k c_k phi_k(tau)`` with
``tau = t / T`` and the bumps ``phi_k = 64 (tau (1 - tau))^3 (2 tau - 1)^k`` (zero with their first
two derivatives at both ends, so the swing still starts and ends at rest with continuous
accelerations, and the landing pose ``delta`` moves with the rest). ``(c, delta)`` maximise the
**objective**, the smallest leg-to-leg or leg-to-nacelle distance over the whole swing
(:mod:`pkdyn.tripod.clearance`, every sample of the swing), penalised when the stroke margins
fall below ``stroke_keep``::

    Phi = min_k d_k - stroke_weight * max(0, stroke_keep - min_k m_k)

(``m_k`` the smallest stroke margin at sample ``k``; with comfortable strokes, ``Phi`` is the
smallest leg distance [m]; a path that leaves its strokes is first brought back into them),
subject to, at every sample: the mode's ``1 / cond``
``sigma_k`` (the ``distance`` of :func:`pkdyn.analysis.singularity.classify`, in closed form, see
:mod:`pkdyn.tripod.clearance`) at least ``singularity_keep`` (idem), every actuator's speed (finite
differences of its length) below ``speed_margin`` times its limit (or the baseline's speed, if
faster); with two secondary terms, a
bonus ``singularity_weight * min_k sigma_k`` (moving away from singularities) and
``mean_weight * mean_k min(d_k, distance_cap)`` (which shapes the path where ``Phi`` is pinned,
e.g. at the start, where the locks engaged). Solved by SLSQP (:func:`scipy.optimize.minimize`) in
epigraph form (maximise ``t + stroke_weight s`` under ``t`` below every leg-to-leg and every
leg-to-nacelle distance of every sample and ``stroke_keep + s`` below the stroke margins,
``s <= 0``), gradients by forward differences evaluated in one vectorised batch, on up to
``samples`` evenly spread samples (with slightly stricter constraints), then checked on all.
The result is accepted only if it does at least as well as the baseline on ``Phi`` and meets the
constraints on every sample, else the
largest fraction of its departure from the baseline that does (0.9, 0.75, 0.5, 0.25), else the
baseline is kept: the optimised path is never worse than the baseline on the objective. The
actuator forces are checked afterwards by the inverse dynamics (:mod:`pkdyn.tripod.scenario` scales
the path back towards the baseline if a force limit is exceeded).
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize

from pkdyn.dynamics.profiles import motion_law
from pkdyn.dynamics.trajectory import TaskTrajectory
from pkdyn.exceptions import InvalidInputError
from pkdyn.results import Result, deprecated_alias
from pkdyn.tripod.clearance import Clearances, clearances
from pkdyn.tripod.locked_branch import LockedBranch, foot_frames
from pkdyn.tripod.modes import Stance
from pkdyn.units import quantity

__all__ = [
    "RedundancySettings",
    "SwingSolution",
    "bumps",
    "plan_swing",
]

_SAFETY = (0.002, 0.002, 0.02)
"""Extra stroke margin [m], ``1 / cond`` and speed fraction the optimisation keeps on its
subsampled swing, so that the whole swing meets the constraints."""


@dataclass(frozen=True)
class RedundancySettings:
    """Objective and solver settings of the redundancy resolution (see the module docstring).

    Attributes:
        stroke_keep: Stroke margin the path should keep [m].
        stroke_weight: Penalty per metre of stroke margin missing below ``stroke_keep`` in the
            objective (10: a millimetre of margin is worth 10 mm of leg distance).
        singularity_keep: ``1 / cond`` of mode BE the path must keep (the baseline's smallest
            when that is smaller).
        singularity_weight: Bonus per unit of the smallest ``1 / cond`` [m]: moves the path
            away from singularities (0.1: a gain of 0.01 is worth 1 mm of leg distance).
        mean_weight: Weight of the mean leg distance (capped at ``distance_cap``) beside the
            smallest one, which shapes the path where the smallest is pinned.
        distance_cap: Cap of the per-sample leg distance in the mean [m].
        bumps: Number of bump functions per redundant coordinate.
        speed_margin: Fraction of each actuator's speed limit allowed.
        max_iter: SLSQP iteration cap.
        samples: Largest number of samples the optimisation evaluates (the swing is subsampled
            evenly; the result is then checked on every sample).
        optimise: Optimise (``False``: keep the baseline).

    """

    stroke_keep: float = 0.08
    stroke_weight: float = 10.0
    singularity_keep: float = 0.1
    singularity_weight: float = 0.1
    mean_weight: float = 0.1
    distance_cap: float = 0.1
    bumps: int = 2
    speed_margin: float = 0.95
    max_iter: int = 15
    samples: int = 16
    optimise: bool = True

    def __post_init__(self) -> None:
        for name in ("stroke_keep", "singularity_keep", "distance_cap"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0.0):
                raise InvalidInputError(name, f"must be > 0, got {value!r}")
        for name in ("singularity_weight", "mean_weight", "stroke_weight"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0.0):
                raise InvalidInputError(name, f"must be >= 0, got {value!r}")
        if not 0.0 < self.speed_margin <= 1.0:
            raise InvalidInputError("speed_margin", f"must be in (0, 1], got {self.speed_margin}")
        for name in ("bumps", "max_iter", "samples"):
            value = getattr(self, name)
            if int(value) != value or value < (0 if name == "bumps" else 2):
                raise InvalidInputError(name, f"must be a positive integer, got {value!r}")

    def objective(self, c: Clearances) -> float:
        """``Phi`` of a path's clearances [m] (see the module docstring).

        The smallest leg distance, less ``stroke_weight`` times the stroke margin missing below
        ``stroke_keep``.
        """
        missing = max(0.0, self.stroke_keep - float(c.stroke_margin.min()))
        return float(c.distance.min()) - self.stroke_weight * missing


def bumps(tau: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bump functions ``phi_k(tau)`` and their first two derivatives in ``tau``.

    Args:
        tau: Normalised times (N,) in ``[0, 1]``.
        count: Number of bumps.

    Returns:
        Three (N, count) arrays.

    """
    w = tau * (1.0 - tau)
    wd = 1.0 - 2.0 * tau
    b = 64.0 * w**3
    bd = 192.0 * w**2 * wd
    bdd = 384.0 * w * wd**2 - 384.0 * w**2
    z = 2.0 * tau - 1.0
    out = [np.zeros((tau.size, count)) for _ in range(3)]
    for k in range(count):
        zk = z**k
        zk1 = k * z ** (k - 1) * 2.0 if k >= 1 else np.zeros_like(z)
        zk2 = k * (k - 1) * z ** (k - 2) * 4.0 if k >= 2 else np.zeros_like(z)
        out[0][:, k] = b * zk
        out[1][:, k] = bd * zk + b * zk1
        out[2][:, k] = bdd * zk + 2.0 * bd * zk1 + b * zk2
    return out[0], out[1], out[2]


@dataclass
class SwingSolution(Result):
    """The walker's swing: redundancy coordinates, nacelle path and objective.

    Attributes:
        branch: Swinging branch.
        joints: The redundant coordinates' joints (``branch{i}_qL``, ``branch{i}_qR``).
        t: Times (N,) [s].
        r: Lengths ``(q_L, q_R)`` of the swinging branch (N, 2) [m].
        r_d: Their rates (N, 2) [m/s].
        r_dd: Their accelerations (N, 2) [m/s^2].
        nacelle_R: Nacelle orientations (N, 3, 3).
        nacelle_p: Nacelle origins (N, 3) [m].
        baseline: Clearances of the baseline (every sample).
        clearances: Clearances of the chosen path (every sample).
        objective_baseline: ``Phi`` of the baseline [m] (its smallest leg distance when its
            stroke margins are comfortable).
        objective: ``Phi`` of the chosen path (>= the baseline's) [m].
        optimised: Whether the optimised path was kept (else the baseline).
        iterations: SLSQP iterations.
        coefficients: ``(c, delta)`` of the chosen path (zeros for the baseline).
        scale: Fraction of the optimised departure from the baseline kept (1, or less when a
            force limit required it).
        settings: The settings used.

    """

    branch: int
    joints: tuple[str, str]
    t: np.ndarray
    r: np.ndarray
    r_d: np.ndarray
    r_dd: np.ndarray
    nacelle_R: np.ndarray
    nacelle_p: np.ndarray
    baseline: Clearances
    clearances: Clearances
    objective_baseline: float
    objective: float
    optimised: bool
    iterations: int
    coefficients: np.ndarray
    scale: float = 1.0
    settings: RedundancySettings = field(default_factory=RedundancySettings)
    _swing: Any = field(default=None, repr=False, compare=False)

    def rescaled(self, fraction: float) -> SwingSolution:
        """The same swing keeping ``fraction`` of the optimised departure from the baseline.

        Used when the full departure asks an actuator for too much force.

        Args:
            fraction: 0 gives the baseline, 1 this path.

        Returns:
            The new path, its clearances and objective.

        """
        if not 0.0 <= fraction <= 1.0:
            raise InvalidInputError("fraction", f"must be in [0, 1], got {fraction!r}")
        sw = self._swing
        z = fraction * self.coefficients
        c, _, R, P = sw.evaluate(z)
        r, rd, rdd = sw.coordinates(z)
        return dataclasses.replace(
            self,
            r=r,
            r_d=rd,
            r_dd=rdd,
            nacelle_R=R,
            nacelle_p=P,
            clearances=c,
            objective=self.settings.objective(c),
            optimised=bool(fraction > 0.0 and self.optimised),
            coefficients=z,
            scale=fraction * self.scale,
        )

    def end(self) -> pin.SE3:
        """Nacelle placement at the end of the swing."""
        return pin.SE3(self.nacelle_R[-1], self.nacelle_p[-1])

    as_json = deprecated_alias("as_json", "to_json")

    def table(self) -> str:
        """The objective, baseline against chosen path, and both paths' clearances."""
        how = "optimised" if self.optimised else "baseline kept"
        return (
            f"branch {self.branch} swing: objective {quantity(self.objective_baseline, 'm')} -> "
            f"{quantity(self.objective, 'm')} ({how}, {self.iterations} iterations, scale "
            f"{self.scale:.3g})\n  baseline: {self.baseline.table()}\n  chosen:   "
            f"{self.clearances.table()}"
        )

    def to_json(self) -> dict[str, Any]:
        """The objective's values, baseline and chosen path (the CLI's ``redundancy`` entry)."""
        return {
            "objective": self.objective,
            "objective_baseline": self.objective_baseline,
            "optimised": self.optimised,
            "scale": self.scale,
            "iterations": self.iterations,
            "baseline": self.baseline.to_json(),
            "chosen": self.clearances.to_json(),
            "stroke_keep": self.settings.stroke_keep,
            "singularity_keep": self.settings.singularity_keep,
        }


class _Swing:
    """Closed-form evaluation of a swing for given ``(c, delta)``."""

    def __init__(
        self,
        p: Any,
        stance: Stance,
        locked: LockedBranch,
        task: TaskTrajectory,
        r1: np.ndarray,
        settings: RedundancySettings,
    ) -> None:
        self.p, self.locked, self.settings = p, locked, settings
        self.branch = locked.branch
        self.t = np.array(task.t)
        T = float(self.t[-1] - self.t[0])
        self.s, self.sd, self.sdd = motion_law("quintic", T)(self.t - self.t[0])
        self.phi, phid, phidd = bumps((self.t - self.t[0]) / T, settings.bumps)
        self.phid, self.phidd = phid / T, phidd / T**2
        self.R_F, self.p_F = foot_frames(task)
        A = np.array([f.translation for f in stance.footholds])
        self.A = np.repeat(A[None], self.t.size, axis=0)
        self.A[:, self.branch - 1] = self.p_F
        self.r0, self.r1 = locked.r0, np.asarray(r1, dtype=float)
        self.velocity = p.velocity
        self.K = settings.bumps

    def coordinates(
        self, z: np.ndarray, idx: np.ndarray | slice = slice(None)
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``r``, ``r_d``, ``r_dd`` (N, 2) for ``z = (c (K, 2) flattened, delta (2))``.

        ``z`` may be a batch (B, nz): the results are then (B, N, 2).
        """
        Z = np.atleast_2d(z)
        K = self.K
        c = Z[:, : 2 * K].reshape(-1, K, 2)
        d = self.r1 + Z[:, 2 * K : 2 * K + 2] - self.r0  # (B, 2)
        out = []
        for law, phi in (
            (self.s, self.phi),
            (self.sd, self.phid),
            (self.sdd, self.phidd),
        ):
            out.append(
                law[idx][None, :, None] * d[:, None, :] + np.einsum("nk,bkj->bnj", phi[idx], c)
            )
        out[0] = out[0] + self.r0
        if np.ndim(z) == 1:
            return out[0][0], out[1][0], out[2][0]
        return out[0], out[1], out[2]

    def evaluate(
        self, z: np.ndarray, idx: np.ndarray | slice = slice(None)
    ) -> tuple[Clearances, np.ndarray, np.ndarray, np.ndarray]:
        """Clearances, speed ratios, nacelle orientations and origins at the samples.

        ``z`` may be a batch (B, nz): the B paths' samples are then stacked (B N rows).
        """
        r, rd, _ = self.coordinates(np.atleast_2d(z), idx)
        B, n_s = r.shape[:2]
        R_F = np.tile(self.R_F[idx], (B, 1, 1))
        p_F = np.tile(self.p_F[idx], (B, 1))
        R, P = self.locked.nacelle(R_F, p_F, r[..., 0].reshape(-1), r[..., 1].reshape(-1))
        c = clearances(self.p, R, P, np.tile(self.A[idx], (B, 1, 1)), self.branch)
        # lengths the triangle cannot take (|q_L - q_R| >= e): the nacelle formula clips them;
        # count them as singular so that no accepted path uses them
        flat = np.abs(r[..., 0] - r[..., 1]).reshape(-1) >= self.locked.edge
        if flat.any():
            c.singularity[flat] = 0.0
        t = self.t[idx]
        L = c.lengths.reshape(B, n_s, -1)
        speed = np.abs(np.gradient(L, t, axis=1)) if t.size > 2 else np.zeros_like(L)
        i = 2 * (self.branch - 1)
        speed[..., i : i + 2] = np.abs(rd)
        return c, speed.max(axis=-1).reshape(-1) / self.velocity, R, P


def plan_swing(
    p: Any,
    stance: Stance,
    branch: int,
    nacelle: pin.SE3,
    task: TaskTrajectory,
    target: pin.SE3,
    settings: RedundancySettings | None = None,
) -> SwingSolution:
    """Choose the walker's nacelle path while branch ``i`` swings (see the module docstring).

    Args:
        p: Walker parameters (``branches=4``).
        stance: Footholds when the swing starts (the swinging foot's included).
        branch: Swinging branch ``i``.
        nacelle: Nacelle placement when the locks engage.
        task: The swinging foot's trajectory (foot link frame,
            :func:`pkdyn.tripod.scenario.swing_task`).
        target: Nacelle placement wanted at the end (the station home above the landed feet).
        settings: Objective and solver settings.

    Returns:
        The chosen path (optimised, or the baseline when the optimisation does not improve).

    """
    settings = RedundancySettings() if settings is None else settings
    R_F, p_F = foot_frames(task)
    locked = LockedBranch.engage(p, nacelle, pin.SE3(R_F[0], p_F[0]), branch)
    r1 = locked.lengths_near(p, pin.SE3(R_F[-1], p_F[-1]), target)
    sw = _Swing(p, stance, locked, task, r1, settings)
    N = sw.t.size
    idx = np.unique(np.linspace(0, N - 1, min(N, settings.samples)).round().astype(int))
    nz = 2 * settings.bumps + 2
    z0 = np.zeros(nz)
    base, base_speed, R0, P0 = sw.evaluate(z0)
    phi0 = settings.objective(base)
    keep = (
        settings.stroke_keep,
        min(settings.singularity_keep, float(base.singularity.min())),
        max(settings.speed_margin, float(base_speed.max())),
    )
    best: tuple[np.ndarray, Clearances, np.ndarray, np.ndarray, float, int] = (
        z0,
        base,
        R0,
        P0,
        phi0,
        0,
    )
    if settings.optimise and nz:
        # the subsampled optimisation keeps a little more, so that every sample keeps enough
        # (but no more than the baseline has on those samples: it must remain feasible)
        sub, sub_speed, _, _ = sw.evaluate(z0, idx)
        strict = (
            keep[0] + _SAFETY[0],
            min(keep[1] + _SAFETY[1], float(sub.singularity.min())),
            max(keep[2] - _SAFETY[2], float(sub_speed.max())),
        )
        z_opt, iterations = _optimise(sw, idx, settings, strict)
        for fraction in (1.0, 0.9, 0.75, 0.5, 0.25):  # back towards the baseline if need be
            c, speed, R, P = sw.evaluate(fraction * z_opt)
            phi = settings.objective(c)
            ok = phi >= phi0 and c.singularity.min() >= keep[1] and speed.max() <= keep[2]
            if ok:
                best = (fraction * z_opt, c, R, P, phi, iterations)
                break
    z, chosen, R, P, phi, iterations = best
    r, rd, rdd = sw.coordinates(z)
    return SwingSolution(
        branch=branch,
        joints=(f"branch{branch}_qL", f"branch{branch}_qR"),
        t=sw.t,
        r=r,
        r_d=rd,
        r_dd=rdd,
        nacelle_R=R,
        nacelle_p=P,
        baseline=base,
        clearances=chosen,
        objective_baseline=phi0,
        objective=phi,
        optimised=bool(np.any(z != 0.0)),
        iterations=iterations,
        coefficients=z,
        settings=settings,
        _swing=sw,
    )


def _optimise(
    sw: _Swing,
    idx: np.ndarray,
    settings: RedundancySettings,
    keep: tuple[float, float, float],
) -> tuple[np.ndarray, int]:
    """SLSQP in epigraph form over ``x = (z, t, s)`` (see the module docstring).

    ``t`` bounds the leg distances from below, ``s <= 0`` the stroke margins' shortfall:
    ``m_k >= stroke_keep + s``; the objective is ``t + stroke_weight s`` plus the bonuses.

    Values and forward-difference gradients come from batched evaluations: the point and its
    ``nz`` perturbations in one vectorised pass.
    """
    nz = 2 * settings.bumps + 2
    h = 1e-6
    cache: dict[tuple[bytes, bool], tuple[np.ndarray, np.ndarray]] = {}

    def values(c: Clearances, speed: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Objective without ``t`` (B,) and constraints without ``t`` (B, 4 n) of a batch."""
        B = z.shape[0]
        d = c.distance.reshape(B, -1)
        sing = c.singularity.reshape(B, -1)
        mean = np.mean(np.minimum(d, settings.distance_cap), axis=1)
        bonus = settings.mean_weight * mean + settings.singularity_weight * sing.min(axis=1)
        f = -bonus + 1e-3 * np.einsum("bi,bi->b", z, z)
        g = np.concatenate(
            [
                c.leg_to_leg.reshape(B, -1),
                c.per_leg_to_nacelle.reshape(B, -1),
                c.stroke_margin.reshape(B, -1).min(axis=1, keepdims=True) - keep[0],
                sing - keep[1],
                keep[2] - speed.reshape(B, -1),
            ],
            axis=1,
        )
        return f, g

    def terms(x: np.ndarray, grad: bool) -> tuple[np.ndarray, np.ndarray]:
        key = (x[:nz].tobytes(), grad)
        if key not in cache:
            if len(cache) > 64:
                cache.clear()
            z = x[:nz]
            Z = np.vstack([z, z + h * np.eye(nz)]) if grad else z[None]
            c, speed, _, _ = sw.evaluate(Z, idx)
            f, g = values(c, speed, Z)
            if grad:
                cache[key] = ((f[1:] - f[0]) / h, (g[1:] - g[0]).T / h)
            else:
                cache[key] = (f, g[0])
        return cache[key]

    n_s = idx.size * (1 + 4 * len(sw.A[0]))  # leg-to-leg, then every leg to the nacelle
    W = settings.stroke_weight

    def objective(x: np.ndarray) -> float:
        return float(terms(x, False)[0][0]) - float(x[nz]) - W * float(x[nz + 1])

    def objective_grad(x: np.ndarray) -> np.ndarray:
        return np.concatenate([terms(x, True)[0], [-1.0, -W]])

    def constraints(x: np.ndarray) -> np.ndarray:
        g = terms(x, False)[1].copy()
        g[:n_s] -= x[nz]
        g[n_s] -= x[nz + 1]
        return g

    def constraints_jac(x: np.ndarray) -> np.ndarray:
        J = terms(x, True)[1]
        cols = np.zeros((J.shape[0], 2))
        cols[:n_s, 0] = -1.0
        cols[n_s, 1] = -1.0
        return np.hstack([J, cols])

    c0, _, _, _ = sw.evaluate(np.zeros(nz), idx)
    t0 = float(c0.distance.min())
    s0 = min(0.0, float(c0.stroke_margin.min()) - keep[0])
    x0 = np.concatenate([np.zeros(nz), [t0, s0]])
    span = 0.5 * (sw.p.stroke_max - sw.p.stroke_min)
    bounds = [(-span, span)] * nz + [(None, None), (None, 0.0)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = minimize(
            objective,
            x0,
            jac=objective_grad,
            method="SLSQP",
            bounds=bounds,
            constraints=[{"type": "ineq", "fun": constraints, "jac": constraints_jac}],
            options={"maxiter": settings.max_iter, "ftol": 1e-7},
        )
    x = np.asarray(res.x, dtype=float)
    if not np.all(np.isfinite(x)):
        return np.zeros(nz), int(res.nit)
    return x[:nz], int(res.nit)
