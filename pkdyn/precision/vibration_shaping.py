r"""Input shaping of a commanded motion from the modes along its path.

An input shaper convolves the command with a few impulses whose amplitudes sum to one and whose
delays are set by a mode's damped period ``T_d = 2 pi / omega_d``
(``omega_d = omega sqrt(1 - zeta^2)``), so that the vibrations the impulses excite cancel (Singer
and Seering, 1990). With ``K = exp(-zeta pi / sqrt(1 - zeta^2))``:

- ``zv``: amplitudes ``[1, K] / (1 + K)`` at ``[0, T_d / 2]`` (zero residual vibration at the
  design frequency);
- ``zvd``: ``[1, 2K, K^2] / (1 + K)^2`` at ``[0, T_d / 2, T_d]`` (zero residual vibration and
  zero derivative with respect to the frequency: robust to a frequency error).

Several modes: the shapers of the lowest ``modes`` modes convolved (every combination of their
impulses). The frequency is **tracked along the path**: each delay is a function of time,
``tau_j(t) = n_j pi / omega_d(t)`` with ``omega_d(t)`` the mode's damped frequency at the pose the
command reaches at ``t`` (a cubic spline through the frequencies at poses along the path, held
at the end pose after the motion), and the shaped platform trajectory is

.. math::

    x_s(t) = \sum_j A_j\, x(t - \tau_j(t)), \quad
    \dot x_s = \sum_j A_j \dot x(t - \tau_j) (1 - \dot\tau_j), \quad
    \ddot x_s = \sum_j A_j [\ddot x(t - \tau_j) (1 - \dot\tau_j)^2 - \dot x(t - \tau_j) \ddot\tau_j]

(``x`` held at rest before the start and after the end; the pose vector convolved component by
component). The shaped motion lasts longer by the largest delay at the end pose. It is mapped to
the joints like any command: the shaped platform stays within the convex hull of nearby poses of
the path (corners of the path are rounded by a fraction of a millimetre).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from pkdyn.dynamics.trajectory import TaskTrajectory
from pkdyn.exceptions import InvalidInputError
from pkdyn.precision.vibration_command import Hermite5

__all__ = ["SHAPERS", "Shaper", "impulses", "shape"]

SHAPERS = ("zv", "zvd")
"""The input shapers."""


def impulses(kind: str, zeta: float) -> tuple[np.ndarray, np.ndarray]:
    """Amplitudes and delays in half damped periods of one mode's shaper.

    Args:
        kind: ``zv`` or ``zvd``.
        zeta: The mode's damping ratio, in ``[0, 1)``.

    Returns:
        ``(A, n)``: amplitudes (summing to 1) and delays in units of ``T_d / 2``.

    Raises:
        InvalidInputError: An unknown shaper, or a mode damped critically or more.

    """
    if kind not in SHAPERS:
        raise InvalidInputError("shaper", f"unknown {kind!r} (one of {', '.join(SHAPERS)})")
    if not 0.0 <= zeta < 1.0:
        raise InvalidInputError(
            "shaper",
            f"the targeted mode has a damping ratio of {zeta:.3g}: it does not oscillate, "
            "there is nothing to shape",
        )
    K = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta * zeta))
    if kind == "zv":
        return np.array([1.0, K]) / (1.0 + K), np.array([0.0, 1.0])
    return np.array([1.0, 2.0 * K, K * K]) / (1.0 + K) ** 2, np.array([0.0, 1.0, 2.0])


@dataclass(frozen=True, eq=False)  # numpy fields
class Shaper:
    """A shaper tracking the frequencies of some modes along a path.

    Attributes:
        kind: ``zv`` or ``zvd``.
        times: Times along the unshaped command where the frequencies are known (P,) [s].
        frequencies: Undamped frequency of each targeted mode there (P, n_modes) [Hz].
        damping: Damping ratio of each targeted mode there (P, n_modes).

    """

    kind: str
    times: np.ndarray
    frequencies: np.ndarray
    damping: np.ndarray

    @property
    def modes(self) -> int:
        """Number of modes targeted."""
        return int(self.frequencies.shape[1])

    def _half_periods(self) -> list[CubicSpline]:
        """``T_d / 2`` of each mode as a function of time (clamped: held outside)."""
        out = []
        w = 2.0 * np.pi * self.frequencies
        half = np.pi / (w * np.sqrt(1.0 - self.damping**2))
        for i in range(self.modes):
            if self.times.size >= 2:
                out.append(CubicSpline(self.times, half[:, i], bc_type="clamped"))
            else:
                out.append(CubicSpline([0.0, 1.0], [half[0, i]] * 2, bc_type="clamped"))
        return out

    def delays_end(self) -> np.ndarray:
        """Delays of the convolved impulses at the end pose (n_impulses,) [s]."""
        _, n = self._combined()
        half = np.pi / (2.0 * np.pi * self.frequencies[-1] * np.sqrt(1.0 - self.damping[-1] ** 2))
        return np.asarray(n @ half)

    def _combined(self) -> tuple[np.ndarray, np.ndarray]:
        """Amplitudes (J,) and delays in half periods per mode (J, n_modes) of the cascade."""
        per = [impulses(self.kind, float(np.mean(self.damping[:, i]))) for i in range(self.modes)]
        amps, counts = [], []
        for combo in itertools.product(*[range(a.size) for a, _ in per]):
            amps.append(math.prod(float(per[i][0][j]) for i, j in enumerate(combo)))
            counts.append([float(per[i][1][j]) for i, j in enumerate(combo)])
        return np.array(amps), np.array(counts)

    def describe(self) -> dict[str, Any]:
        """JSON-ready description."""
        A, _ = self._combined()
        return {
            "kind": self.kind,
            "modes": list(range(1, self.modes + 1)),
            "frequencies_start": [float(f) for f in self.frequencies[0]],
            "frequencies_end": [float(f) for f in self.frequencies[-1]],
            "damping_ratio": [float(z) for z in self.damping[-1]],
            "amplitudes": [float(a) for a in A],
            "delays_end": [float(d) for d in self.delays_end()],
            "duration_added": float(np.max(self.delays_end())),
        }


def shape(task: TaskTrajectory, shaper: Shaper) -> TaskTrajectory:
    """The shaped platform trajectory (see the module docstring).

    Args:
        task: The unshaped command (uniform samples from ``t = 0``).
        shaper: The shaper (its ``times`` along ``task``).

    Returns:
        The shaped command on the same sample step, longer by the largest delay at the end.

    """
    A, n = shaper._combined()
    # each amplitude's damping ratio: the per-mode shapers use one ratio along the path (their
    # mean); the delays track the frequency
    halves = shaper._half_periods()
    T = float(task.t[-1])
    h = float(task.t[1] - task.t[0])
    extra = float(np.max(shaper.delays_end()))
    steps = int(math.ceil((T + extra) / h - 1e-9))
    t = h * np.arange(steps + 1)
    tq = np.minimum(t, T)
    tau = np.zeros((A.size, t.size))
    tau_d = np.zeros_like(tau)
    tau_dd = np.zeros_like(tau)
    for i, hp in enumerate(halves):
        val, d1, d2 = hp(tq), hp(tq, 1), hp(tq, 2)
        d1 = np.where(t > T, 0.0, d1)
        d2 = np.where(t > T, 0.0, d2)
        tau += n[:, i : i + 1] * val[None, :]
        tau_d += n[:, i : i + 1] * d1[None, :]
        tau_dd += n[:, i : i + 1] * d2[None, :]
    base = Hermite5(task.t, task.pose, task.pose_d, task.pose_dd)
    pose = np.zeros((t.size, 6))
    pd = np.zeros((t.size, 6))
    pdd = np.zeros((t.size, 6))
    for j, a in enumerate(A):
        x, xd, xdd = base(t - tau[j])
        g = (1.0 - tau_d[j])[:, None]
        pose += a * x
        pd += a * xd * g
        pdd += a * (xdd * g * g - xd * tau_dd[j][:, None])
    return TaskTrajectory(t, pose, pd, pdd, name=f"{task.name}, {shaper.kind.upper()}-shaped")


def shaper_modes(value: Any, available: int) -> int:
    """Number of modes a shaper targets, checked against the modes available."""
    from pkdyn.inputs import count

    n = count("shaper_modes", value, 1, 4)
    if n > available:
        raise InvalidInputError(
            "shaper_modes", f"{n} modes targeted but the model has {available} elastic modes"
        )
    return n


def tracked(
    kind: str, times: Sequence[float] | np.ndarray, frequencies: np.ndarray, damping: np.ndarray
) -> Shaper:
    """A :class:`Shaper` (arguments checked)."""
    if not isinstance(kind, str) or kind not in SHAPERS:
        raise InvalidInputError("shaper", f"unknown {kind!r} (one of {', '.join(SHAPERS)})")
    for z in np.ravel(damping):
        impulses(kind, float(z))
    return Shaper(
        kind, np.asarray(times, dtype=float), np.asarray(frequencies), np.asarray(damping)
    )
