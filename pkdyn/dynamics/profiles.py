"""Rest-to-rest motion laws on a normalised path parameter ``s`` from 0 to 1.

Each law maps a time ``t`` in ``[0, T]`` to ``s(t)``, ``s'(t)`` [1/s] and ``s''(t)`` [1/s^2], with
zero velocity and acceleration at both ends:

- ``quintic``: the fifth-degree polynomial ``s = 10 u^3 - 15 u^4 + 6 u^5`` (``u = t / T``), the
  smoothest polynomial law with zero end accelerations (peak ``s'' = 5.77 / T^2``, jerk jumps
  at the ends);
- ``jerk``: the jerk-limited "double S" law: piecewise-constant jerk ``+j, 0, -j`` during the
  acceleration phase, a constant-velocity phase, then the mirror image; the time fractions are
  ``accel_fraction`` (acceleration phase / T, default 1/3) and ``jerk_fraction`` (jerk ramp /
  acceleration phase, default 1/3). The accelerations are continuous, the jerk is bounded.

Both laws are exact piecewise polynomials (no numerical integration).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = ["PROFILES", "MotionLaw", "motion_law"]

PROFILES = ("quintic", "jerk")
"""Names of the motion laws :func:`motion_law` knows."""


@dataclass(frozen=True)
class MotionLaw:
    """A rest-to-rest law ``s(t)`` from 0 to 1 over ``duration``.

    Attributes:
        name: ``quintic`` or ``jerk``.
        duration: Duration ``T`` [s].
        accel_fraction: Jerk law: acceleration phase as a fraction of ``T`` (0 < f <= 1/2).
        jerk_fraction: Jerk law: jerk ramp as a fraction of the acceleration phase
            (0 < f <= 1/2).

    """

    name: str
    duration: float
    accel_fraction: float = 1.0 / 3.0
    jerk_fraction: float = 1.0 / 3.0

    def __call__(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``s``, ``s'`` [1/s] and ``s''`` [1/s^2] at times ``t`` [s] (clipped to [0, T]).

        Scalars give one-element arrays.
        """
        T = self.duration
        u = np.clip(np.atleast_1d(np.asarray(t, dtype=float)) / T, 0.0, 1.0)
        if self.name == "quintic":
            s = u**3 * (10.0 - 15.0 * u + 6.0 * u**2)
            sd = 30.0 * u**2 * (1.0 - u) ** 2 / T
            sdd = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / T**2
            return s, sd, sdd
        s, sd, sdd = _double_s(u, self.accel_fraction, self.jerk_fraction)
        return s, sd / T, sdd / T**2


def motion_law(
    name: str,
    duration: float,
    accel_fraction: float = 1.0 / 3.0,
    jerk_fraction: float = 1.0 / 3.0,
) -> MotionLaw:
    """A validated motion law.

    Args:
        name: ``quintic`` or ``jerk``.
        duration: Duration [s] (> 0).
        accel_fraction: Jerk law: acceleration phase / duration, in (0, 1/2].
        jerk_fraction: Jerk law: jerk ramp / acceleration phase, in (0, 1/2].

    Returns:
        The law.

    Raises:
        InvalidInputError: Unknown name or out-of-range values.

    """
    if name not in PROFILES:
        raise InvalidInputError(
            "profile", f"unknown profile {name!r} (one of {', '.join(PROFILES)})"
        )
    if not np.isfinite(duration) or duration <= 0.0:
        raise InvalidInputError("duration", f"duration must be > 0 s, got {duration}")
    if not 0.0 < accel_fraction <= 0.5:
        raise InvalidInputError("accel_fraction", f"must be in (0, 0.5], got {accel_fraction}")
    if not 0.0 < jerk_fraction <= 0.5:
        raise InvalidInputError("jerk_fraction", f"must be in (0, 0.5], got {jerk_fraction}")
    return MotionLaw(name, float(duration), float(accel_fraction), float(jerk_fraction))


def _double_s(u: np.ndarray, fa: float, fj: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Double-S law on ``u`` in [0, 1] for unit duration and unit distance."""
    ta, tj = fa, fa * fj  # acceleration phase, jerk ramp (unit duration)
    # unit jerk: breakpoints of the acceleration phase, then normalise to s(1) = 1
    knots = np.array([0.0, tj, ta - tj, ta])
    jerks = np.array([1.0, 0.0, -1.0])
    # integrate the acceleration phase exactly, segment by segment
    a0, v0, p0 = [0.0], [0.0], [0.0]
    for k, j in enumerate(jerks):
        h = knots[k + 1] - knots[k]
        a0.append(a0[-1] + j * h)
        v0.append(v0[-1] + a0[-2] * h + 0.5 * j * h**2)
        p0.append(p0[-1] + v0[-2] * h + 0.5 * a0[-2] * h**2 + j * h**3 / 6.0)
    vmax, pa = v0[-1], p0[-1]
    total = 2.0 * pa + vmax * (1.0 - 2.0 * ta)
    s = np.empty_like(u)
    sd = np.empty_like(u)
    sdd = np.empty_like(u)

    def accel_phase(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        seg = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, 2)
        h = x - knots[seg]
        j = jerks[seg]
        a = np.asarray(a0)[seg] + j * h
        v = np.asarray(v0)[seg] + np.asarray(a0)[seg] * h + 0.5 * j * h**2
        p = (
            np.asarray(p0)[seg]
            + np.asarray(v0)[seg] * h
            + 0.5 * np.asarray(a0)[seg] * h**2
            + j * h**3 / 6.0
        )
        return p, v, a

    first = u <= ta
    last = u >= 1.0 - ta
    mid = ~(first | last)
    p, v, a = accel_phase(u[first])
    s[first], sd[first], sdd[first] = p, v, a
    s[mid] = pa + vmax * (u[mid] - ta)
    sd[mid] = vmax
    sdd[mid] = 0.0
    p, v, a = accel_phase(1.0 - u[last])
    s[last], sd[last], sdd[last] = total - p, v, -a
    return s / total, sd / total, sdd / total
