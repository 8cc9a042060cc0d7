"""The outcome of an identification: estimates, what is not identifiable, predictions, output.

:class:`IdentificationResult` follows the result protocol (:mod:`pkdyn.results`): ``table()``
(what ``pkdyn identify`` prints, units on every figure), ``to_json()`` (``--json``), ``plot()``
(the fit per actuator: measured and predicted efforts and the residual) and
:meth:`IdentificationResult.write_urdf` (the identified description,
:mod:`pkdyn.identification.writer`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.identifiability import Identifiability
from pkdyn.identification.estimation import Estimate
from pkdyn.identification.parameters import ParameterSet
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.results import Result, deprecated
from pkdyn.units import quantity

__all__ = ["Fit", "IdentificationResult", "predict_efforts"]


@public
def predict_efforts(
    robot: Robot,
    ps: ParameterSet,
    theta: np.ndarray,
    t: np.ndarray,
    qa: np.ndarray,
    qa_dot: np.ndarray,
    qa_ddot: np.ndarray,
) -> np.ndarray:
    """Actuator efforts of a motion for standard parameters ``theta`` (p,).

    Args:
        robot: The robot (nominal: the held parameters are its values).
        ps: Its parameter set.
        theta: Standard parameters (p,).
        t: Times (N,) [s].
        qa: Actuated joint coordinates (N, n_a) [rad or m] (the joint coordinates of
            readings: :meth:`pkdyn.Robot.joint_coordinates`).
        qa_dot: Their rates (N, n_a).
        qa_ddot: Their accelerations (N, n_a).

    Returns:
        Joint-side efforts (N, n_a) [N m or N] (reduction x motor torque).

    Raises:
        TrajectoryError: A sample cannot be assembled.

    """
    from pkdyn.identification.motion import BATCH, MotionSampler
    from pkdyn.identification.regressor import ClosedLoopRegressor
    from pkdyn.inputs import instance, matrix, vector

    instance("ps", ps, ParameterSet, "a ParameterSet (pkdyn.identification.parameter_set)")
    theta = vector("theta", theta, ps.p)
    t = vector("t", t, unit="s")
    n_a = len(robot.actuators)
    qa, qa_dot, qa_ddot = (
        matrix(name, x, t.size, n_a, "rad or m")
        for name, x in (("qa", qa), ("qa_dot", qa_dot), ("qa_ddot", qa_ddot))
    )
    reg = ClosedLoopRegressor(robot, ps)
    sampler = MotionSampler(robot)
    N = t.size
    out = np.empty((N, len(robot.actuators)))
    for s in range(0, N, BATCH):
        e = min(N, s + BATCH)
        b = sampler.batch(t[s:e], qa[s:e], qa_dot[s:e], qa_ddot[s:e], s)
        out[s:e] = reg.efforts(b, theta)
    return out


@dataclass(frozen=True, eq=False)  # numpy fields
class Fit:
    """Measured and predicted efforts at samples of the identification motion (evenly spaced).

    Attributes:
        t: Times (k,) [s].
        measured: Measured efforts (k, n_a) [N m or N].
        estimate: Efforts of the estimated base parameters (k, n_a).
        physical: Efforts of the physically consistent parameters (k, n_a) (what the written
            description gives).

    """

    t: np.ndarray
    measured: np.ndarray
    estimate: np.ndarray
    physical: np.ndarray


def _value(v: float, unit: str) -> str:
    """A parameter value with its unit, plain (``kg m^2`` takes no SI prefix)."""
    text = f"{v:.4g}"
    return f"{'0' if text == '-0' else text} {unit}".rstrip()


@dataclass(frozen=True, eq=False)  # numpy fields
class IdentificationResult(Result):
    """An identification (see :func:`pkdyn.identification.identify`).

    Attributes:
        robot: The nominal robot.
        parameters: Its standard parameters and which were identified.
        base: The base parameters of the identified ones (an
            :class:`~pkdyn.identifiability.Identifiability`).
        estimate: Weighted least-squares estimate of the base parameters, with how well the
            motion excites each (:attr:`Estimate.excited`, :attr:`Estimate.excitation`).
        theta: Physically consistent standard parameters (p,) (held ones: nominal).
        filtered: The rates and accelerations came from filtered positions.
        seconds: Wall time of the identification [s].
        fit: Measured and predicted efforts at samples of the motion (``None``: not kept).

    """

    robot: Robot
    parameters: ParameterSet
    base: Identifiability
    estimate: Estimate
    theta: np.ndarray
    filtered: bool = False
    seconds: float = 0.0
    fit: Fit | None = None

    @property
    def theta_base(self) -> np.ndarray:
        """Base parameters of the physical set :attr:`theta` (p_b,)."""
        sel = self.parameters.identified
        return self.base.K @ self.theta[sel]

    @property
    def misfit(self) -> np.ndarray:
        """Shift of each base parameter from the estimate to the physical set, in std (p_b,)."""
        e = self.estimate
        ok = (e.std > 0.0) & np.isfinite(e.std)
        return np.where(ok, (self.theta_base - e.theta) / np.where(ok, e.std, 1.0), 0.0)

    @property
    def relative_std(self) -> np.ndarray:
        """Standard deviation of each base parameter relative to its plausible magnitude (p_b,).

        The magnitude (:attr:`Estimate.reference`: the nominal value of the combination, or a
        typical one of its kind), not the estimate: a wild estimate would make any standard
        deviation look small. ``1 / excitation``.
        """
        e = self.estimate
        ref = e.reference if e.reference.size else np.abs(e.theta)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(ref != 0.0, e.std / np.abs(ref), np.inf)

    @property
    def excited(self) -> np.ndarray:
        """Whether the motion excites each base parameter (p_b,) bool."""
        return self.estimate.excited

    @property
    def unexcited(self) -> list[str]:
        """Formulas of the base parameters the motion does not excite (held at nominal)."""
        f = self.base.formulas()
        return [f[k] for k in np.flatnonzero(~self.estimate.excited)]

    def robot_identified(self) -> Robot:
        """The robot with the identified parameters (unit gearbox efficiency)."""
        from pkdyn.identification.writer import identified_robot

        return identified_robot(self.robot, self.parameters, self.theta)

    def predict(
        self, t: np.ndarray, qa: np.ndarray, qa_dot: np.ndarray, qa_ddot: np.ndarray
    ) -> np.ndarray:
        """Efforts (N, n_a) [N m or N] the identified model gives for a motion.

        Args:
            t: Times (N,) [s].
            qa: Actuator readings (N, n_a) [rad or m] (the robot's readings rule applies, as in
                :func:`~pkdyn.identification.identify`).
            qa_dot: Their rates (N, n_a).
            qa_ddot: Their accelerations (N, n_a).

        """
        from pkdyn.inputs import matrix, vector

        r = self.robot
        t = vector("t", t, unit="s")
        n_a = len(r.actuators)
        qa, qa_dot, qa_ddot = (
            matrix(name, x, t.size, n_a, "rad or m")
            for name, x in (("qa", qa), ("qa_dot", qa_dot), ("qa_ddot", qa_ddot))
        )
        return predict_efforts(
            r,
            self.parameters,
            self.theta,
            t,
            r.joint_coordinates(qa),
            r.joint_coordinates(qa_dot, rates=True),
            r.joint_coordinates(qa_ddot, rates=True),
        )

    def urdf(self) -> str:
        """The identified description (:func:`pkdyn.identification.writer.identified_urdf`)."""
        from pkdyn.identification.writer import identified_urdf

        return identified_urdf(self.robot, self.parameters, self.theta)

    def write_urdf(self, path: str | os.PathLike[str]) -> str:
        """Write the identified description atomically; returns the text written."""
        from pkdyn.identification.writer import write_urdf

        return write_urdf(path, self.robot, self.parameters, self.theta)

    def payload(self) -> dict[str, Any] | None:
        """The identified payload, or ``None`` when the payload is not identified.

        Returns:
            Mass [kg], centre of mass [m] and inertia about it [kg m^2], platform frame.

        """
        ps = self.parameters
        s = ps.payload_slice
        if not ps.identified[s.start]:
            return None
        import pinocchio as pin

        I = pin.Inertia.FromDynamicParameters(np.asarray(self.theta[s], dtype=float))
        return {
            "mass": float(I.mass),
            "com": [float(x) for x in I.lever],
            "inertia": np.asarray(I.inertia).tolist(),
        }

    def drives(self) -> dict[str, dict[str, float]]:
        """Per actuator: viscous [N m s/rad], Coulomb [N m] friction, rotor inertia [kg m^2]."""
        ps = self.parameters
        return {
            a.name: {
                f: float(self.theta[ps.drive_column(i, f)])
                for f in ("viscous", "coulomb", "rotor_inertia")
            }
            for i, a in enumerate(self.robot.actuators)
        }

    def _units(self) -> list[str]:
        b = self.base
        return [b.units[int(i)] if b.units else "" for i in b.identifiable]

    def _effort_unit(self) -> list[str]:
        return ["N" if p else "N m" for p in self.robot.actuator_prismatic]

    def to_json(self) -> dict[str, Any]:
        """The identification as JSON values (SI units; the units of each parameter given)."""
        e = self.estimate
        names = self.robot.actuator_names
        shift = self.misfit
        excited = e.excited if e.excited.size else np.ones(e.theta.size, dtype=bool)
        return {
            "robot": self.robot.name,
            "samples": int(e.samples),
            "groups": list(self.parameters.chosen),
            "filtered": self.filtered,
            "seconds": self.seconds,
            "condition_number": e.condition,
            "noise_std": dict(zip(names, e.sigma.tolist(), strict=True)),
            "residual_rms": dict(zip(names, e.rms.tolist(), strict=True)),
            "base_parameters": [
                {
                    "formula": f,
                    "unit": u,
                    "value": float(v),
                    "std": float(s) if np.isfinite(s) else None,
                    "excited": bool(x),
                    "excitation": float(r) if e.excitation.size and np.isfinite(r) else None,
                    "physical": float(pv),
                    "shift_std": float(m),
                }
                for f, u, v, s, x, r, pv, m in zip(
                    self.base.formulas(),
                    self._units(),
                    e.theta,
                    e.std,
                    excited,
                    e.excitation if e.excitation.size else np.full(e.theta.size, np.nan),
                    self.theta_base,
                    shift,
                    strict=True,
                )
            ],
            "unexcited": self.unexcited,
            "unidentifiable": self.base.no_effect,
            "grouped": self.base.grouped,
            "max_physical_shift_std": float(np.max(np.abs(shift), initial=0.0)),
            "drives": self.drives(),
            "payload": self.payload(),
        }

    def table(self, limit: int = 40) -> str:
        """A text report: fit, base parameters with their deviations and excitation, the rest."""
        from pkdyn.inputs import count

        limit = count("limit", limit, 1)
        e = self.estimate
        names = self.robot.actuator_names
        eu = self._effort_unit()
        lines = [
            f"{self.robot.name}: {e.samples} samples, {self.base.size} base parameters "
            f"({', '.join(self.parameters.chosen)}), condition number {e.condition:.3g}"
            + (", rates from filtered positions" if self.filtered else ""),
            "noise std / residual RMS per actuator: "
            + ", ".join(
                f"{n} {quantity(s, u)} / {quantity(r, u)}"
                for n, s, r, u in zip(names, e.sigma, e.rms, eu, strict=True)
            ),
            f"{'value':>18} {'std':>12} {'rel':>7}  base parameter",
        ]
        rel = self.relative_std
        units = self._units()
        excited = e.excited if e.excited.size else np.ones(e.theta.size, dtype=bool)
        for k, f in enumerate(self.base.formulas()[:limit]):
            if not excited[k]:
                r = "not excited, held"
            else:
                r = f"{100 * rel[k]:6.1f}%" if np.isfinite(rel[k]) else "      -"
            std = _value(e.std[k], units[k]) if np.isfinite(e.std[k]) else "inf"
            lines.append(f"{_value(e.theta[k], units[k]):>18} {std:>12} {r}  {f}")
        if self.base.size > limit:
            lines.append(f"... and {self.base.size - limit} more (--json lists them all)")
        held = self.unexcited
        if held:
            lines.append(
                f"not excited by this motion (held at nominal, flagged): {len(held)}: "
                + "; ".join(held[:4])
                + (" ..." if len(held) > 4 else "")
                + " (use a richer excitation: pkdyn.identification.excitation)"
            )
        un = self.base.no_effect
        if un:
            lines.append(
                f"not identifiable (no effect on the efforts, kept nominal): {len(un)}: "
                + ", ".join(un[:8])
                + (" ..." if len(un) > 8 else "")
            )
        shift = float(np.max(np.abs(self.misfit), initial=0.0))
        lines.append(
            f"physically consistent parameters: largest base-parameter shift {shift:.3g} std"
        )
        for name, d in self.drives().items():
            lines.append(
                f"{name}: viscous {_value(d['viscous'], 'N m s/rad')}, Coulomb "
                f"{_value(d['coulomb'], 'N m')}, rotor inertia "
                f"{_value(d['rotor_inertia'], 'kg m^2')} (motor side)"
            )
        pay = self.payload()
        if pay is not None:
            c = pay["com"]
            lines.append(
                f"payload: {_value(pay['mass'], 'kg')} at ({c[0]:.4g}, {c[1]:.4g}, {c[2]:.4g}) m "
                "(platform frame)"
            )
        return "\n".join(lines)

    def as_json(self) -> dict[str, Any]:
        """Deprecated: :meth:`to_json`."""
        deprecated("IdentificationResult.as_json", "to_json()")
        return self.to_json()
