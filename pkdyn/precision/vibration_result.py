"""The result of a vibration analysis: time series, figures, table, JSON, CSV and plot."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.vibration_damping import Damping
from pkdyn.precision.vibration_figures import RESIDUAL_WINDOW
from pkdyn.results import Result, jsonable
from pkdyn.tables import write_table
from pkdyn.units import quantity, vector

__all__ = ["Display", "DominantMode", "VibrationResult"]

Display = tuple[np.ndarray, np.ndarray, np.ndarray]
"""``(t_coarse, command, deformation)`` of a result, for displays."""


@dataclass(frozen=True)
class DominantMode:
    """A mode's share of the residual vibration (its free vibration when the motion ends).

    Attributes:
        mode: Mode number at the end pose, 1 = lowest.
        frequency: Its undamped natural frequency at the end pose [Hz].
        damping_ratio: Its damping ratio.
        amplitude: Amplitude of the reference point's motion in this mode [m].
        share: Its fraction of the sum of the amplitudes.

    """

    mode: int
    frequency: float
    damping_ratio: float
    amplitude: float
    share: float


@dataclass(eq=False)  # numpy fields
class VibrationResult(Result):
    """How a robot vibrates along a motion (see :func:`pkdyn.precision.vibration.vibration`).

    Attributes:
        robot: The robot's name.
        trajectory: The motion's name.
        method: ``modal`` or ``multibody``.
        task: Task component names (the columns of ``deviation``).
        t: Output times (M,) [s], from the start of the motion to the end of the window after it.
        deviation: Reference point's actual minus commanded pose (M, task size) [m, rad], world
            axes (rotation vector for the rotations).
        deviation_rate: Its rate (M, task size) [m/s, rad/s].
        duration: Duration of the motion ``T`` [s] (the commanded motion, shaped if it is).
        dwell: Time after the motion within which the tool must settle [s].
        band: Settling band on the norm of the position deviation [m].
        payload: Payload, a point mass at the reference point [kg].
        point: Reference point, platform frame [m].
        peak_deviation: Largest norm of the position deviation over ``[0, T]`` [m].
        peak_time: When it happens [s].
        residual_amplitude: Largest norm of the position deviation from the end pose's static
            equilibrium over ``[T, T + 0.2 s]`` [m].
        settling_time: Time after ``T`` from which that norm stays within the band (until the
            end of the window observed: the dwell, at least the residual window, and two
            periods of the first mode) [s]; ``None``: still outside at the end of the window.
        settled: The tool settles within the dwell (``settling_time <= dwell``).
        static_deflection: Deviation in the static equilibrium of the end pose (task size)
            [m, rad] (gravity, payload, feedforward).
        frequencies_start: Natural frequencies at the start pose [Hz] (the modes integrated).
        frequencies_end: The same at the end pose [Hz].
        dominant_modes: The modes of the residual vibration, largest first.
        feedforward: ``none``, ``gravity`` or ``rigid``.
        damping: The damping (servos and links).
        actuator_stiffness: Joint-side stiffness per actuator [N m/rad or N/m].
        links: Names of the compliant links.
        internal: Internal mobilities without stiffness (not modes).
        modes: Modes integrated (modal method; the others quasi-static) or resolved.
        poses: Poses along the motion where the modes were computed (modal method).
        shaper: The input shaper applied to the command (its description), or ``None``.
        energy_drift: Relative violation of the energy balance (multibody method), or ``None``.
        elastic: The elastic model (for displays; not serialised).
        animate: What computes ``t_coarse``, ``command`` and ``deformation`` when they are
            first asked for (:meth:`animation`; a closed-form analysis maps the joints for a
            display only).
        t_coarse: Times of ``deformation`` (K,) [s].
        command: Commanded extended configurations at ``t_coarse`` (K, nq_ext).
        deformation: Deformation from the command at ``t_coarse`` (K, nv_ext).
        prismatic: Whether each actuator is prismatic (units of the servo figures).

    """

    robot: str
    trajectory: str
    method: str
    task: tuple[str, ...]
    t: np.ndarray
    deviation: np.ndarray
    deviation_rate: np.ndarray
    duration: float
    dwell: float
    band: float
    payload: float
    point: np.ndarray
    peak_deviation: float
    peak_time: float
    residual_amplitude: float
    settling_time: float | None
    settled: bool
    static_deflection: np.ndarray
    frequencies_start: np.ndarray
    frequencies_end: np.ndarray
    dominant_modes: list[DominantMode]
    feedforward: str
    damping: Damping
    actuator_stiffness: np.ndarray
    links: tuple[str, ...]
    internal: int
    modes: int
    poses: int | None
    shaper: dict[str, Any] | None = None
    energy_drift: float | None = None
    elastic: ElasticModel | None = field(default=None, repr=False)
    animate: Callable[[], Display] | None = field(default=None, repr=False)
    t_coarse: np.ndarray | None = field(default=None, repr=False)
    command: np.ndarray | None = field(default=None, repr=False)
    deformation: np.ndarray | None = field(default=None, repr=False)
    prismatic: tuple[bool, ...] = ()

    def animation(self) -> Display | None:
        """``(t_coarse, command, deformation)`` for displays, ``None`` when not kept.

        Times (K,) [s], commanded configurations of the elastic model's robot (K, nq_ext) and
        the deformation from them (K, nv_ext); computed on first use when the analysis did
        not need them (``animate``).
        """
        if self.deformation is None and self.animate is not None:
            self.t_coarse, self.command, self.deformation = self.animate()
            self.animate = None
        if self.t_coarse is None or self.command is None or self.deformation is None:
            return None
        return self.t_coarse, self.command, self.deformation

    @property
    def translation(self) -> np.ndarray:
        """Column indices of the translation components in ``deviation``."""
        return np.array([i for i, n in enumerate(self.task) if n in ("x", "y", "z")], dtype=int)

    @property
    def deviation_norm(self) -> np.ndarray:
        """Norm of the position deviation (M,) [m]."""
        return np.asarray(np.linalg.norm(self.deviation[:, self.translation], axis=1))

    @property
    def deviation_from_rest(self) -> np.ndarray:
        """Norm of the position deviation from the end pose's static equilibrium (M,) [m]."""
        tr = self.translation
        return np.asarray(
            np.linalg.norm(self.deviation[:, tr] - self.static_deflection[tr], axis=1)
        )

    @property
    def cycle_time(self) -> float | None:
        """Motion plus settling time [s] (``None`` when it does not settle)."""
        return None if self.settling_time is None else self.duration + self.settling_time

    def to_json(self) -> dict[str, Any]:
        """JSON values, SI units (m, s, Hz, kg): the figures, the model, no time series."""
        tr = self.translation
        return jsonable(
            {
                "robot": self.robot,
                "trajectory": self.trajectory,
                "method": self.method,
                "duration": self.duration,
                "dwell": self.dwell,
                "band": self.band,
                "payload": self.payload,
                "point": self.point,
                "peak_deviation": self.peak_deviation,
                "peak_time": self.peak_time,
                "residual_amplitude": self.residual_amplitude,
                "residual_window": RESIDUAL_WINDOW,
                "settling_time": self.settling_time,
                "settled": self.settled,
                "static_deflection": self.static_deflection,
                "static_deflection_norm": float(np.linalg.norm(self.static_deflection[tr])),
                "task": list(self.task),
                "frequencies": {"start": self.frequencies_start, "end": self.frequencies_end},
                "dominant_modes": [vars(m) for m in self.dominant_modes],
                "feedforward": self.feedforward,
                "damping": self.damping.to_json(),
                "actuator_stiffness": self.actuator_stiffness,
                "links": list(self.links),
                "internal_mobilities": self.internal,
                "modes": self.modes,
                "poses": self.poses,
                "shaper": self.shaper,
                "energy_drift": self.energy_drift,
                "convention": "deviation: reference point's actual minus commanded position "
                "[m] (rotation vector [rad]), world axes; peak over the motion; residual and "
                "settling about the end pose's static equilibrium; settling_time from the end "
                "of the motion (null: not within the dwell)",
            }
        )

    def table(self) -> str:
        """The figures as text, units on every figure."""
        tr = self.translation
        static = float(np.linalg.norm(self.static_deflection[tr]))
        shown = np.where(
            np.abs(self.static_deflection[tr]) > 1e-9 * static, self.static_deflection[tr], 0.0
        )
        if self.settling_time is None:
            settle = f"longer than the {quantity(self.t[-1] - self.duration, 's')} observed"
        else:
            settle = (
                f"{quantity(self.settling_time, 's')} (motion and settling "
                f"{quantity(self.duration + self.settling_time, 's')}; "
                + ("within" if self.settled else "beyond")
                + f" the {quantity(self.dwell, 's')} dwell)"
            )
        lines = [
            f"{self.robot}: {self.trajectory}, {quantity(self.duration, 's')}, payload "
            f"{quantity(1e3 * self.payload, 'g')}, {self.method} method"
            + (f", {self.shaper['kind'].upper()} shaping" if self.shaper else ""),
            f"peak deviation:      {quantity(self.peak_deviation, 'm')} at "
            f"{quantity(self.peak_time, 's')}",
            f"residual amplitude:  {quantity(self.residual_amplitude, 'm')} (over "
            f"{quantity(RESIDUAL_WINDOW, 's')} after the motion)",
            f"settling time:       {settle} to a {quantity(self.band, 'm')} band",
            f"static deflection:   {quantity(static, 'm')} at the end pose, "
            f"{vector(shown * 1e6, 'um')}",
            "frequencies:         "
            + _freqs(self.frequencies_start)
            + " at the start, "
            + _freqs(self.frequencies_end)
            + " at the end",
        ]
        if self.dominant_modes:
            dom = ", ".join(
                f"mode {m.mode} ({quantity(m.frequency, 'Hz')}, {100 * m.share:.0f} %)"
                for m in self.dominant_modes[:3]
            )
            lines.append(f"dominant modes:      {dom}")
        d = self.damping
        lines.append(
            f"damping:             ratio {d.ratio:g} of mode 1 at the middle pose "
            f"({quantity(d.f1, 'Hz')}); servos "
            + ", ".join(
                quantity(c, "N s/m" if pr else "N m s/rad")
                for c, pr in zip(
                    d.actuator, self.prismatic or (False,) * d.actuator.size, strict=True
                )
            )
            + f"; feedforward {self.feedforward}"
        )
        if self.energy_drift is not None:
            lines.append(f"energy balance:      {self.energy_drift:.2g} (relative drift)")
        return "\n".join(lines)

    def write_csv(self, path: str | Path) -> None:
        """Time series: ``t``, the deviation's components, its norm and its norm from rest.

        Columns ``t`` [s], ``deviation_<c>`` per task component [m, rad], ``deviation_norm``
        [m] and ``deviation_from_rest`` [m] (the norm about the end pose's equilibrium).

        Args:
            path: Output file.

        Raises:
            OutputError: The file cannot be written (an existing file is left intact).

        """
        header = (
            ["t"]
            + [f"deviation_{c}" for c in self.task]
            + ["deviation_norm", "deviation_from_rest"]
        )
        table = np.column_stack(
            [self.t, self.deviation, self.deviation_norm, self.deviation_from_rest]
        )
        write_table(path, header, table, digits=10)


def _freqs(f: np.ndarray, count: int = 4) -> str:
    shown = ", ".join(f"{x:.4g}" for x in f[:count])
    more = f" (+{f.size - count})" if f.size > count else ""
    return f"[{shown}]{more} Hz"
