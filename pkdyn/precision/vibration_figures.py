"""The figures of a vibration: peak deviation, residual amplitude, settling time.

Both methods return the platform deviation ``d`` and its rate at output steps of at most a
sixteenth of the shortest period they resolve; between two steps the deviation is the cubic
Hermite polynomial matching ``d`` and ``d'`` at both ends (the integrators' dense output, error
below 1e-4 of the amplitude at that resolution), and the figures are read from it, not from the
rows:

- ``peak_deviation``: the largest norm of the reference point's deviation (translation) over
  the motion ``[0, T]``;
- ``residual_amplitude``: the largest norm of the deviation from the static equilibrium of the
  end pose over ``[T, T + 0.2 s]`` (:data:`RESIDUAL_WINDOW`);
- ``settling_time``: counted from ``T``, the first time after which the norm of the deviation
  from that equilibrium stays below the band until the end of the window observed after the
  motion, which lasts the dwell (at least the residual window) and two periods of the first
  mode more: a momentary dip of the norm at the end of the dwell (two modes beating, or one
  mode's vibration in two directions) is not taken for settling. The tool **settles within the
  dwell** when that time is at most the dwell. ``None`` when the norm is still outside the band
  at the end of the window; 0 when it never leaves it after the motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = ["RESIDUAL_WINDOW", "Dense", "Figures", "figures"]

RESIDUAL_WINDOW = 0.2
"""Length of the window after the motion over which the residual amplitude is taken [s]."""

_SAMPLES = 5
"""Points per step where the dense output is scanned before a peak is refined (a step is at
most a sixteenth of the shortest period resolved: the norm's largest value in a step is within
1e-3 of the largest of these points, well within the candidates' 2 % margin)."""

_REFINE = 33
"""Points of the grid on which a candidate step is refined (then a parabola through its top)."""


@dataclass(eq=False)  # numpy fields
class Dense:
    """A piecewise cubic Hermite vector signal (the dense output of an integration).

    Attributes:
        t: Times (M,) [s], increasing.
        y: Values (M, n).
        yd: Rates (M, n).

    """

    t: np.ndarray
    y: np.ndarray
    yd: np.ndarray

    def at(self, k: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Values at fractions ``s`` (..., ) of steps ``k`` (...,), shape (..., n)."""
        h = (self.t[k + 1] - self.t[k])[..., None]
        s = s[..., None]
        s2, s3 = s * s, s * s * s
        return (
            (2 * s3 - 3 * s2 + 1) * self.y[k]
            + (s3 - 2 * s2 + s) * h * self.yd[k]
            + (-2 * s3 + 3 * s2) * self.y[k + 1]
            + (s3 - s2) * h * self.yd[k + 1]
        )

    def norm(self, k: int, s: float) -> float:
        """Norm of the value at fraction ``s`` of step ``k``."""
        return float(np.linalg.norm(self.at(np.array(k), np.array(s))))

    def time(self, k: int, s: float) -> float:
        """Time at fraction ``s`` of step ``k`` [s]."""
        return float(self.t[k] + s * (self.t[k + 1] - self.t[k]))


def _window(dense: Dense, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Steps overlapping ``[lo, hi]`` and the fraction bounds of each within it."""
    t = dense.t
    ks = np.flatnonzero((t[1:] > lo) & (t[:-1] < hi))
    h = t[ks + 1] - t[ks]
    s0 = np.clip((lo - t[ks]) / h, 0.0, 1.0)
    s1 = np.clip((hi - t[ks]) / h, 0.0, 1.0)
    return ks, s0, s1


def _scan(dense: Dense, ks: np.ndarray, s0: np.ndarray, s1: np.ndarray) -> np.ndarray:
    """Largest norm of each step on a grid of :data:`_SAMPLES` points (len(ks),)."""
    t = dense.t
    h = (t[ks + 1] - t[ks])[:, None]
    y0, y1 = dense.y[ks], dense.y[ks + 1]
    m0, m1 = h * dense.yd[ks], h * dense.yd[ks + 1]
    # the cubic's power-basis coefficients per step (K, n)
    c2 = 3.0 * (y1 - y0) - 2.0 * m0 - m1
    c3 = 2.0 * (y0 - y1) + m0 + m1
    frac = np.linspace(0.0, 1.0, _SAMPLES)
    S = (s0[:, None] + (s1 - s0)[:, None] * frac[None, :])[:, :, None]  # (K, samples, 1)
    v = y0[:, None, :] + S * (m0[:, None, :] + S * (c2[:, None, :] + S * c3[:, None, :]))
    return np.asarray(np.sqrt(np.einsum("ksc,ksc->ks", v, v)).max(axis=1))


def _refine(dense: Dense, k: int, a: float, b: float, points: int = _REFINE) -> tuple[float, float]:
    """Largest norm on ``[a, b]`` of step ``k`` (a fine grid, then a parabola through its top)."""
    s = np.linspace(a, b, points)
    vals = np.linalg.norm(dense.at(np.full(points, k), s), axis=-1)
    j = int(np.argmax(vals))
    best, where = float(vals[j]), float(s[j])
    if 0 < j < points - 1:
        y0, y1, y2 = vals[j - 1], vals[j], vals[j + 1]
        den = y0 - 2.0 * y1 + y2
        if den < 0.0:
            off = 0.5 * (y0 - y2) / den
            where = float(s[j] + off * (s[1] - s[0]))
            best = max(best, dense.norm(k, where))
    return best, where


def largest(dense: Dense, lo: float, hi: float) -> tuple[float, float]:
    """Largest norm of the dense signal over ``[lo, hi]`` and its time (refined)."""
    ks, s0, s1 = _window(dense, lo, hi)
    if ks.size == 0:
        return float("nan"), float("nan")
    scanned = _scan(dense, ks, s0, s1)
    top = float(scanned.max())
    best, when = -1.0, float("nan")
    for i in np.argsort(scanned)[::-1][:8]:
        if scanned[i] < 0.98 * top:
            break
        k = int(ks[i])
        val, s = _refine(dense, k, float(s0[i]), float(s1[i]))
        if val > best:
            best, when = val, dense.time(k, s)
    return best, when


def settling(dense: Dense, lo: float, hi: float, band: float) -> float | None:
    """First time after ``lo`` from which the norm stays below ``band`` until ``hi``.

    Returns:
        The settling time counted from ``lo``; ``0.0`` when the norm never reaches the band;
        ``None`` when it is still at or beyond the band at ``hi``.

    """
    ks, s0, s1 = _window(dense, lo, hi)
    if ks.size == 0:
        return None
    k_end = int(ks[-1])
    if dense.norm(k_end, float(s1[-1])) >= band:
        return None
    scanned = _scan(dense, ks, s0, s1)
    for i in np.flatnonzero(scanned >= 0.9 * band)[::-1]:
        k = int(ks[i])
        a, b = float(s0[i]), float(s1[i])
        grid = np.linspace(a, b, _REFINE)
        vals = np.linalg.norm(dense.at(np.full(grid.size, k), grid), axis=-1)
        peak, peak_s = _refine(dense, k, a, b)
        if peak < band:
            continue
        # the last crossing: after the last grid point at or above the band (and the peak)
        above = np.flatnonzero(vals >= band)
        start = max(float(grid[above[-1]]) if above.size else peak_s, peak_s)
        ends = grid[grid > start]
        stop = float(ends[0]) if ends.size else b
        if dense.norm(k, stop) >= band:  # still above at the step's end: crossing in the next
            return dense.time(k, stop) - lo
        s_cross = brentq(lambda s, k=k: dense.norm(k, s) - band, start, stop, xtol=1e-14)
        return dense.time(k, float(s_cross)) - lo
    return 0.0


@dataclass(frozen=True)
class Figures:
    """Peak, residual and settling figures of a deviation (see the module docstring).

    Attributes:
        peak_deviation: Largest deviation norm over the motion [m].
        peak_time: When it happens [s].
        residual_amplitude: Largest norm of the deviation from the end equilibrium over the
            residual window [m].
        settling_time: Settling time after the end of the motion [s], or ``None``.
        settled: Whether it is at most the dwell.

    """

    peak_deviation: float
    peak_time: float
    residual_amplitude: float
    settling_time: float | None
    settled: bool


def figures(
    t: np.ndarray,
    d: np.ndarray,
    d_dot: np.ndarray,
    static_end: np.ndarray,
    T: float,
    dwell: float,
    band: float,
    window: float,
) -> Figures:
    """The figures of a deviation (translation components only: the norms are in m).

    Args:
        t: Output times (M,) [s].
        d: Translation deviation (M, k) [m].
        d_dot: Its rate (M, k) [m/s].
        static_end: Static deflection at the end pose (k,) [m].
        T: End of the motion [s].
        dwell: Time after the motion within which the tool must settle [s].
        band: Settling band on the norm [m].
        window: Time observed after the motion [s] (at least the dwell).

    Returns:
        The figures.

    """
    motion = Dense(t, d, d_dot)
    peak, when = largest(motion, 0.0, T)
    about = Dense(t, d - static_end, d_dot)
    residual, _ = largest(about, T, T + RESIDUAL_WINDOW)
    settle = settling(about, T, T + window, band)
    ok = settle is not None and settle <= dwell
    return Figures(peak, when, residual, settle, ok)
