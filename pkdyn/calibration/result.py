"""The outcome of a calibration: the identified errors, what was not identified, the errors left.

:class:`CalibrationResult` follows the result protocol (:mod:`pkdyn.results`): ``table()`` (what
``pkdyn calibrate`` prints, units on every figure), ``to_json()`` (``--json``), ``plot()`` (the
residuals per pose and axis before and after) and :meth:`CalibrationResult.write_urdf` (the
calibrated description, :mod:`pkdyn.calibration.writer`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkdyn.calibration.writer import calibrated_urdf
from pkdyn.identifiability import Identifiability
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel
from pkdyn.precision.perturbation import Perturbed
from pkdyn.results import Result, deprecated
from pkdyn.units import quantity

__all__ = ["CalibrationResult", "ErrorStats", "error_stats"]


@dataclass
class ErrorStats(Result):
    """Errors of a model against measurements.

    Attributes:
        position_rms: RMS of the position error norm [m] (implicit kinds: of the distance to
            the group's point or plane).
        position_max: Largest position error norm [m].
        orientation_rms: RMS of the rotation error norm [rad] (``pose`` only, else 0).
        orientation_max: Largest rotation error norm [rad].
        count: Number of measurements.
        joint_rms: RMS of the measured joints' coordinate errors [rad or m] (``joints``).
        joint_max: Largest of them [rad or m].

    """

    position_rms: float
    position_max: float
    orientation_rms: float = 0.0
    orientation_max: float = 0.0
    count: int = 0
    joint_rms: float = 0.0
    joint_max: float = 0.0

    @property
    def rms(self) -> float:
        """The RMS error of the kind measured: joints' when measured, else positions'."""
        return self.joint_rms if self.joint_rms or self.joint_max else self.position_rms

    def to_json(self) -> dict[str, Any]:
        """The statistics [m, rad] as JSON values."""
        return {
            "position_rms": self.position_rms,
            "position_max": self.position_max,
            "orientation_rms": self.orientation_rms,
            "orientation_max": self.orientation_max,
            "count": self.count,
            "joint_rms": self.joint_rms,
            "joint_max": self.joint_max,
        }

    def table(self) -> str:
        """One line: RMS and largest errors with their units."""
        if self.joint_rms or self.joint_max:
            return (
                f"joints {quantity(self.joint_rms, 'rad')} RMS, {quantity(self.joint_max, 'rad')}"
                f" max ({self.count} measurements)"
            )
        text = f"{quantity(self.position_rms, 'm')} RMS, {quantity(self.position_max, 'm')} max"
        if self.orientation_rms or self.orientation_max:
            text += (
                f"; orientation {quantity(self.orientation_rms, 'rad')} RMS, "
                f"{quantity(self.orientation_max, 'rad')} max"
            )
        return text + f" ({self.count} measurements)"

    def as_dict(self) -> dict[str, Any]:
        """Deprecated: :meth:`to_json`."""
        deprecated("ErrorStats.as_dict", "to_json()")
        return self.to_json()


def error_stats(kind: str, res: np.ndarray) -> ErrorStats:
    """Error statistics of a measurement kind from unweighted residuals (N, rows) [m, rad]."""
    n = len(res)
    if n == 0:
        return ErrorStats(0.0, 0.0)
    if kind == "joints":
        e = np.abs(res)
        return ErrorStats(
            0.0, 0.0, count=n, joint_rms=float(np.sqrt(np.mean(e**2))), joint_max=float(e.max())
        )
    pos = np.linalg.norm(res[:, :3] if kind != "plane" else res[:, :1], axis=1)
    rot = np.linalg.norm(res[:, 3:6], axis=1) if kind == "pose" else np.zeros(n)
    return ErrorStats(
        float(np.sqrt(np.mean(pos**2))),
        float(np.max(pos)),
        float(np.sqrt(np.mean(rot**2))),
        float(np.max(rot)),
        n,
    )


@dataclass(eq=False)
class CalibrationResult(Result):
    """The outcome of :func:`pkdyn.calibration.calibrate`.

    Attributes:
        robot: The calibrated robot (the nominal one with the identified errors).
        gains: Identified relative actuator gains (n_a,): joint coordinate ``(1 + gain)`` times
            the nominal robot's joint coordinate of a reading.
        nominal: The nominal robot.
        model: The parameter model.
        p: Identified parameter errors (n_par,) [m, rad, -]; zero for the parameters not
            estimated.
        std: Their standard deviations (n_par,); NaN for the parameters not estimated.
        identifiability: Identifiable parameters, unidentifiable combinations and observability
            indices of the calibration poses (nominal robot).
        not_assembling: Parameters the mechanism cannot absorb (held at zero).
        nuisance: Identified unknowns of implicit measurements: ``{"points": (G, 3)}`` or
            ``{"planes": (G, 4)}`` (unit normal, offset [m]).
        sigma: Measurement standard deviations used as weights (position [m], orientation
            [rad]).
        scale: A-posteriori residual scale (RMS weighted residual in units of ``sigma``): near 1
            when ``sigma`` is the true noise.
        before: Errors of the nominal model on the calibration set.
        after: Errors of the calibrated model on the calibration set.
        validation_before: Nominal model on the validation set (``None``: no validation).
        validation_after: Calibrated model on the validation set.
        weights: Final robust weight of each calibration measurement.
        calibration_rows: Indices (in the input) of the calibration measurements.
        validation_rows: Indices of the validation measurements (in the input, or in the
            separate validation measurements).
        iterations: Levenberg-Marquardt iterations.
        converged: Whether the iterations converged.
        kind: The kind of measurements (``position``, ``pose``...).
        noise_known: The noise was stated (``sigma`` is it), else estimated.
        tolerance: Tolerance of each parameter the corrections are judged against (n_par,).
        residuals_before: Residuals of the nominal model (N, rows) [m, rad], calibration set.
        residuals_after: Residuals of the calibrated model (N, rows).
        validation_residuals: ``(before, after)`` residuals on the validation set, or ``None``.
        reasons: Why not to trust the calibration (empty: trusted; :mod:`~.trust`).
        cause: The likely cause (:mod:`~.diagnosis`) when not trusted, else ``""``.
        lines: Line (or row) of each calibration measurement in its file, for messages, or
            ``None``.

    """

    robot: Robot
    gains: np.ndarray
    nominal: Robot
    model: ParameterModel
    p: np.ndarray
    std: np.ndarray
    identifiability: Identifiability
    not_assembling: tuple[str, ...]
    nuisance: dict[str, np.ndarray]
    sigma: tuple[float, float]
    scale: float
    before: ErrorStats
    after: ErrorStats
    validation_before: ErrorStats | None
    validation_after: ErrorStats | None
    weights: np.ndarray
    calibration_rows: np.ndarray
    validation_rows: np.ndarray
    iterations: int
    converged: bool
    kind: str = "position"
    noise_known: bool = True
    tolerance: np.ndarray = field(default_factory=lambda: np.zeros(0))
    residuals_before: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    residuals_after: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    validation_residuals: tuple[np.ndarray, np.ndarray] | None = None
    reasons: tuple[str, ...] = ()
    cause: str = ""
    lines: np.ndarray | None = None

    @property
    def trusted(self) -> bool:
        """No reason not to trust it (:mod:`pkdyn.calibration.trust`)."""
        return not self.reasons

    @property
    def estimated(self) -> np.ndarray:
        """Indices of the estimated (identifiable) parameters, ascending."""
        n = self.model.size
        ident = np.asarray(self.identifiability.identifiable, dtype=int)
        return np.sort(ident[ident < n])

    @property
    def outliers(self) -> np.ndarray:
        """Calibration measurements (input indices) the robust weights reduced below 1/2."""
        return self.calibration_rows[self.weights < 0.5]

    def perturbed(self) -> Perturbed:
        """The calibrated robot and its gains."""
        return Perturbed(self.robot, self.gains)

    # -- output --------------------------------------------------------------------------

    def provenance(self) -> str:
        """One line: the calibration the calibrated description comes from (its comment)."""
        return (
            f"calibrated by pkdyn from {self.calibration_rows.size} poses: {self.model.kind} "
            f"model, {self.estimated.size} parameters identified; RMS error "
            + (
                f"{self.before.position_rms:.3g} m -> {self.after.position_rms:.3g} m"
                if self.before.joint_rms == 0.0
                else f"(passive joints) {self.before.joint_rms:.3g} -> {self.after.joint_rms:.3g}"
            )
        )

    def urdf(self, xml: str | None = None) -> str:
        """The calibrated description (:func:`pkdyn.calibration.writer.calibrated_urdf`)."""
        return calibrated_urdf(self, xml)

    def write_urdf(self, path: str | os.PathLike[str], xml: str | None = None) -> str:
        """Write the calibrated description to ``path`` atomically.

        Args:
            path: Output file.
            xml: The nominal robot's URDF text (default: the description it was loaded from).

        Returns:
            The text written.

        Raises:
            OutputError: The file cannot be written (an existing file is left intact).
            InvalidInputError: The nominal description is not a URDF at hand.

        """
        from pkdyn.files import atomic_write

        text = self.urdf(xml)
        with atomic_write(path) as fh:
            fh.write(text)
        return text

    def _figure(self, stats: ErrorStats) -> str:
        if self.kind == "joints":
            return f"{stats.rms:.4g} rad or m"
        return quantity(stats.rms, "m")

    def to_json(self) -> dict[str, Any]:
        """Parameters, identifiability, errors and trust as JSON values (SI units)."""
        ident = self.identifiability.to_json()
        n = self.model.size
        tol = self.tolerance if self.tolerance.size == n else np.full(n, np.nan)
        return {
            "model": self.model.kind,
            "kind": self.kind,
            "parameters": [
                {
                    "name": self.model.names[k],
                    "unit": self.model.units[k],
                    "value": float(self.p[k]),
                    "std": float(self.std[k]),
                    "tolerance": float(tol[k]) if np.isfinite(tol[k]) else None,
                }
                for k in self.estimated
            ],
            "unidentifiable": ident["unidentifiable"],
            "not_assembling": list(self.not_assembling),
            "observability": ident["observability"],
            "noise_amplification": ident["noise_amplification"],
            "sigma": list(self.sigma),
            "noise_known": self.noise_known,
            "scale": self.scale,
            "before": self.before.to_json(),
            "after": self.after.to_json(),
            "validation_before": None
            if self.validation_before is None
            else self.validation_before.to_json(),
            "validation_after": None
            if self.validation_after is None
            else self.validation_after.to_json(),
            "outliers": [int(i) for i in self.outliers],
            "poses": {
                "calibration": int(self.calibration_rows.size),
                "validation": int(self.validation_rows.size),
            },
            "iterations": self.iterations,
            "converged": self.converged,
            "trusted": self.trusted,
            "reasons": list(self.reasons),
            "likely_cause": self.cause or None,
        }

    def table(self) -> str:
        """What ``pkdyn calibrate`` prints: errors, corrections, what is not identified, trust."""
        m, ident = self.model, self.identifiability
        what = "passive joint error RMS" if self.kind == "joints" else "position error RMS"
        noise = (
            f"noise {quantity(self.sigma[0], 'm')} stated"
            if self.noise_known
            else f"noise not stated: {quantity(self.scale * self.sigma[0], 'm')} estimated"
        )
        lines = [
            f"{self.nominal.name} ({m.kind} model): {self.estimated.size} of {m.size} parameters "
            f"identified from {self.calibration_rows.size} poses ({self.kind} measurements)",
            f"{what}: {self._figure(self.before)} before, {self._figure(self.after)} after "
            f"(calibration poses; {noise})",
        ]
        if self.validation_after is not None and self.validation_before is not None:
            lines.append(
                f"held-out poses ({self.validation_rows.size}): "
                f"{self._figure(self.validation_before)} before, "
                f"{self._figure(self.validation_after)} after"
            )
        tol = self.tolerance if self.tolerance.size == m.size else np.full(m.size, np.nan)
        lines.append(f"{'parameter':>16} {'correction':>12} {'std':>10} {'tolerance':>10}")
        for k in self.estimated:
            u = m.units[k]
            unit = "" if u == "-" else u
            lines.append(
                f"{m.names[k]:>16} {quantity(self.p[k], unit):>12} "
                f"{quantity(self.std[k], unit):>10} {quantity(tol[k], unit):>10}"
            )
        unid = [j for j in ident.unidentifiable if j < m.size]
        if unid:
            parts = []
            for j in unid[:8]:
                combo = ident.combination(int(j), top=2)
                parts.append(
                    m.names[int(j)]
                    + (
                        " (acts as " + ", ".join(f"{c:+.3g} {n}" for n, c in combo) + ")"
                        if combo
                        else " (no effect)"
                    )
                )
            more = f" and {len(unid) - 8} more" if len(unid) > 8 else ""
            lines.append(f"not identifiable (held at nominal): {'; '.join(parts)}{more}")
        if len(self.outliers):
            where = (
                [f"line {int(self.lines[i])}" for i in np.flatnonzero(self.weights < 0.5)]
                if self.lines is not None
                else [f"row {int(i) + 1}" for i in self.outliers]
            )
            shown = ", ".join(where[:8]) + (" ..." if len(where) > 8 else "")
            lines.append(f"outliers (down-weighted by the robust weights): {shown}")
        if self.not_assembling:
            lines.append(f"not assembling (held at nominal): {len(self.not_assembling)} parameters")
        if ident.indices:
            lines.append(ident.indices_line())
        if not self.converged:
            lines.append(f"the fit did not converge in {self.iterations} iterations")
        if self.reasons:
            lines.append(
                "NOT TRUSTED: "
                + "; ".join(self.reasons)
                + (f"; likely cause: {self.cause}" if self.cause else "")
            )
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        """Deprecated: :meth:`to_json`."""
        deprecated("CalibrationResult.as_dict", "to_json()")
        return self.to_json()
