"""Excitation trajectories: periodic actuator motions that make the regressor well conditioned.

Each actuator follows a finite Fourier series of period ``T`` (Swevers et al., 1997), written so
that it starts at the home position, at rest and without acceleration:

    ``qa_i(t) = qa_i(0) + sum_l  a_il / (w l) sin(w l t) - b_il / (w l) (cos(w l t) - 1)``,
    ``w = 2 pi / T``,   ``sum_l a_il = 0``,   ``sum_l l b_il = 0``.

The coefficients minimise the condition number of the base regressor (columns scaled to unit
norm) over one period, sampled at ``samples`` instants, subject to the position limits (the
joint limits, or ``amplitude`` about home when there are none), the speed limits and the effort
limits (efforts of the nominal model) at those instants, each with a 5 % margin so that they
also hold between them: ``scipy.optimize.minimize`` (SLSQP,
finite-difference gradients) from a seeded random start. Each evaluation assembles the samples
and evaluates the regressor, so the search costs seconds to minutes; keep ``samples`` and
``harmonics`` small and sample the result densely afterwards.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pkdyn.exceptions import PkdynError
from pkdyn.identification.motion import BATCH, MotionSampler
from pkdyn.identification.parameters import parameter_set
from pkdyn.identification.regressor import ClosedLoopRegressor
from pkdyn.model.robot import Robot

__all__ = ["FourierTrajectory", "excitation_trajectory"]

_MARGIN = 0.05  # fraction of each range kept free at the design samples


@dataclass(frozen=True, eq=False)  # numpy fields
class FourierTrajectory:
    """A periodic actuator motion (module doc).

    Attributes:
        period: Period ``T`` [s].
        start: Actuator positions at ``t = 0`` (n_a,) [rad or m].
        a: Cosine coefficients of the rates (n_a, L) [rad/s or m/s].
        b: Sine coefficients of the rates (n_a, L) [rad/s or m/s].
        condition: Condition number of the base regressor over the design samples.

    """

    period: float
    start: np.ndarray
    a: np.ndarray
    b: np.ndarray
    condition: float = float("nan")

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, rates and accelerations (N, n_a) at times ``t`` (N,) [s]."""
        t = np.asarray(t, dtype=float).reshape(-1, 1, 1)
        L = self.a.shape[1]
        wl = 2.0 * np.pi / self.period * np.arange(1, L + 1)  # (L,)
        s, c = np.sin(wl * t), np.cos(wl * t)  # (N, 1, L)
        a, b = self.a[None], self.b[None]
        q = self.start + np.sum(a / wl * s - b / wl * (c - 1.0), axis=2)
        qd = np.sum(a * c + b * s, axis=2)
        qdd = np.sum(wl * (-a * s + b * c), axis=2)
        return q, qd, qdd

    def sample(self, rate: float, periods: int = 1) -> tuple[np.ndarray, ...]:
        """``(t, qa, qa_dot, qa_ddot)`` sampled at ``rate`` [Hz] over ``periods`` periods."""
        t = np.arange(0.0, periods * self.period, 1.0 / rate)
        return (t, *self.evaluate(t))


def _unpack(x: np.ndarray, n: int, L: int) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients from free variables: the last harmonic closes the rest conditions."""
    a = np.zeros((n, L))
    b = np.zeros((n, L))
    k = n * (L - 1)
    a[:, :-1] = x[:k].reshape(n, L - 1)
    b[:, :-1] = x[k:].reshape(n, L - 1)
    a[:, -1] = -a[:, :-1].sum(axis=1)  # sum_l a_l = 0: at rest at t = 0
    b[:, -1] = -(b[:, :-1] * np.arange(1, L)).sum(axis=1) / L  # sum_l l b_l = 0
    return a, b


def excitation_trajectory(
    robot: Robot,
    period: float = 10.0,
    harmonics: int = 5,
    samples: int = 60,
    parameters: Sequence[str] | str | None = None,
    amplitude: float | None = None,
    max_iter: int = 30,
    seed: int = 0,
) -> FourierTrajectory:
    """The Fourier excitation of least regressor condition number within the limits.

    Args:
        robot: The robot (nominal model: efforts for the effort limits).
        period: Period [s].
        harmonics: Number of harmonics ``L`` (>= 2).
        samples: Instants per period where the condition and the limits are evaluated.
        parameters: Groups to be identified (they define the base regressor).
        amplitude: Largest excursion from home where a joint has no position limits
            [rad, or m for prismatic actuators] (default 0.3 rad, 5 % of the robot's size).
        max_iter: Iterations of the optimiser.
        seed: Seed of the random start.

    Returns:
        The trajectory and its condition number.

    Raises:
        InvalidInputError: Bad period, harmonics or samples.
        PkdynError: No admissible start was found (limits too tight).

    """
    from scipy.optimize import minimize

    from pkdyn import inputs
    from pkdyn.identification.structure import check_identifiable, structural_base

    period = inputs.positive("period", period, "s", bound=1e6)
    harmonics = inputs.count("harmonics", harmonics, 2, 50)
    samples = inputs.count("samples", samples, 4, 10_000)
    max_iter = inputs.count("max_iter", max_iter, 0, 10_000)
    seed = inputs.seed("seed", seed)
    if amplitude is not None:
        amplitude = inputs.positive("amplitude", amplitude, "rad or m", bound=1e3)
    check_identifiable(robot)
    n = len(robot.actuators)
    ps = parameter_set(robot, parameters)
    base, _ = structural_base(robot, ps)
    reg = ClosedLoopRegressor(robot, ps)
    start = robot.q_home[robot.actuated_q].copy()
    lo = robot.model.lowerPositionLimit[robot.actuated_q]
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    span = (
        np.where(robot.actuator_prismatic, 0.05 * robot.length_scale, 0.3)
        if amplitude is None
        else np.full(n, float(amplitude))
    )
    lo = np.where(np.isfinite(lo), lo, start - span)
    hi = np.where(np.isfinite(hi), hi, start + span)
    pad = _MARGIN * (hi - lo)  # the limits hold at the design samples: keep off them between
    lo, hi = lo + pad, hi - pad
    vmax = np.array([a.velocity for a in robot.actuators])
    emax = np.array([a.effort for a in robot.actuators])
    t = np.linspace(0.0, period, samples, endpoint=False)
    w = 2.0 * np.pi / period
    ind = base.identifiable
    cache: dict[bytes, tuple[float, np.ndarray]] = {}

    def evaluate(x: np.ndarray) -> tuple[float, np.ndarray]:
        key = x.tobytes()
        if key in cache:
            return cache[key]
        a, b = _unpack(x, n, harmonics)
        traj = FourierTrajectory(period, start, a, b)
        q, qd, qdd = traj.evaluate(t)
        margins = [
            ((q - lo) / (hi - lo)).ravel(),
            ((hi - q) / (hi - lo)).ravel(),
        ]
        if np.all(np.isfinite(vmax)):
            margins.append((1.0 - _MARGIN - np.abs(qd) / vmax).ravel())
        cond = 1e12
        try:
            sampler = MotionSampler(robot)
            rows, efforts = [], []
            for s in range(0, samples, BATCH):
                e = min(samples, s + BATCH)
                bt = sampler.batch(t[s:e], q[s:e], qd[s:e], qdd[s:e], s)
                W, known = reg.full(bt)
                rows.append(W[:, :, ps.identified][:, :, ind].reshape(-1, ind.size))
                efforts.append(W @ ps.nominal + known)
            Y = np.vstack(rows)
            Y = Y / np.maximum(np.linalg.norm(Y, axis=0), 1e-300)
            sv = np.linalg.svd(Y, compute_uv=False)
            cond = float(sv[0] / max(sv[-1], sv[0] * 1e-12))
            if np.all(np.isfinite(emax)):
                margins.append((1.0 - _MARGIN - np.abs(np.vstack(efforts)) / emax).ravel())
        except PkdynError:  # out of reach: no admissible point
            margins.append(-np.ones(1))
        out = (float(np.log(cond)), np.concatenate(margins))
        cache[key] = out
        return out

    rng = np.random.default_rng(seed)
    k = 2 * n * (harmonics - 1)
    scale = 0.25 * w * (hi - lo)  # rates whose excursion stays well inside the range
    x0 = None
    for shrink in (1.0, 0.5, 0.25, 0.1):
        trial = shrink * rng.uniform(-1.0, 1.0, k) * np.tile(np.repeat(scale, harmonics - 1), 2)
        if np.min(evaluate(trial)[1]) >= 0.0:
            x0 = trial
            break
    if x0 is None:
        raise PkdynError(f"{robot.name}: no admissible excitation found within the limits")
    sol = minimize(
        lambda x: evaluate(x)[0],
        x0,
        method="SLSQP",
        constraints=[{"type": "ineq", "fun": lambda x: evaluate(x)[1]}],
        options={"maxiter": max_iter},
    )
    best = sol.x if np.min(evaluate(sol.x)[1]) >= -1e-6 else x0
    a, b = _unpack(best, n, harmonics)
    return FourierTrajectory(period, start, a, b, float(np.exp(evaluate(best)[0])))
