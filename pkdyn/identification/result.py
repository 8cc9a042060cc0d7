"""The outcome of an identification: estimates, what is not identifiable, predictions, output."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.identification.base import BaseParameters
from pkdyn.identification.estimation import Estimate
from pkdyn.identification.parameters import ParameterSet
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot

__all__ = ["IdentificationResult", "predict_efforts"]


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
        qa: Actuator positions (N, n_a) [rad or m].
        qa_dot: Rates (N, n_a).
        qa_ddot: Accelerations (N, n_a).

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
class IdentificationResult:
    """An identification (see :func:`pkdyn.identification.identify`).

    Attributes:
        robot: The nominal robot.
        parameters: Its standard parameters and which were identified.
        base: The base parameters of the identified ones.
        estimate: Weighted least-squares estimate of the base parameters.
        theta: Physically consistent standard parameters (p,) (held ones: nominal).
        filtered: The rates and accelerations came from filtered positions.
        seconds: Wall time of the identification [s].

    """

    robot: Robot
    parameters: ParameterSet
    base: BaseParameters
    estimate: Estimate
    theta: np.ndarray
    filtered: bool = False
    seconds: float = 0.0

    @property
    def theta_base(self) -> np.ndarray:
        """Base parameters of the physical set :attr:`theta` (p_b,)."""
        sel = self.parameters.identified
        return self.base.K @ self.theta[sel]

    @property
    def misfit(self) -> np.ndarray:
        """Shift of each base parameter from the estimate to the physical set, in std (p_b,)."""
        e = self.estimate
        return (self.theta_base - e.theta) / np.where(e.std > 0.0, e.std, 1.0)

    @property
    def relative_std(self) -> np.ndarray:
        """Relative standard deviation of each base parameter (p_b,) (``inf`` at zero)."""
        e = self.estimate
        with np.errstate(divide="ignore"):
            return np.where(e.theta != 0.0, e.std / np.abs(e.theta), np.inf)

    def robot_identified(self) -> Robot:
        """The robot with the identified parameters (unit gearbox efficiency)."""
        from pkdyn.identification.writer import identified_robot

        return identified_robot(self.robot, self.parameters, self.theta)

    def predict(
        self, t: np.ndarray, qa: np.ndarray, qa_dot: np.ndarray, qa_ddot: np.ndarray
    ) -> np.ndarray:
        """Efforts (N, n_a) [N m or N] the identified model gives for a motion."""
        return predict_efforts(self.robot, self.parameters, self.theta, t, qa, qa_dot, qa_ddot)

    def urdf(self) -> str:
        """The identified description (:func:`pkdyn.identification.writer.identified_urdf`)."""
        from pkdyn.identification.writer import identified_urdf

        return identified_urdf(self.robot, self.parameters, self.theta)

    def write_urdf(self, path: str | os.PathLike[str]) -> None:
        """Write the identified description atomically."""
        from pkdyn.identification.writer import write_urdf

        write_urdf(path, self.robot, self.parameters, self.theta)

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

    def as_json(self) -> dict[str, Any]:
        """A JSON-ready summary."""
        e = self.estimate
        return {
            "robot": self.robot.name,
            "samples": int(e.samples),
            "groups": list(self.parameters.chosen),
            "filtered": self.filtered,
            "seconds": self.seconds,
            "condition_number": e.condition,
            "noise_std": dict(zip(self.robot.actuator_names, e.sigma.tolist(), strict=True)),
            "residual_rms": dict(zip(self.robot.actuator_names, e.rms.tolist(), strict=True)),
            "base_parameters": [
                {
                    "formula": f,
                    "value": float(v),
                    "std": float(s),
                    "physical": float(pv),
                }
                for f, v, s, pv in zip(
                    self.base.formulas(), e.theta, e.std, self.theta_base, strict=True
                )
            ],
            "unidentifiable": self.base.unidentifiable,
            "grouped": self.base.grouped,
            "max_physical_shift_std": float(np.max(np.abs(self.misfit), initial=0.0)),
            "drives": self.drives(),
            "payload": self.payload(),
        }

    def table(self, limit: int = 40) -> str:
        """A text report: fit, base parameters with their relative deviations, what is left."""
        from pkdyn.inputs import count

        limit = count("limit", limit, 1)
        e = self.estimate
        lines = [
            f"{self.robot.name}: {e.samples} samples, {self.base.size} base parameters "
            f"({', '.join(self.parameters.chosen)}), condition number {e.condition:.3g}"
            + (", rates from filtered positions" if self.filtered else ""),
            "noise std / residual RMS per actuator: "
            + ", ".join(
                f"{n} {s:.3g} / {r:.3g}"
                for n, s, r in zip(self.robot.actuator_names, e.sigma, e.rms, strict=True)
            ),
            f"{'value':>13} {'std':>10} {'rel':>7}  base parameter",
        ]
        rel = self.relative_std
        for k, f in enumerate(self.base.formulas()[:limit]):
            r = f"{100 * rel[k]:6.1f}%" if np.isfinite(rel[k]) else "      -"
            lines.append(f"{e.theta[k]:13.6g} {e.std[k]:10.3g} {r}  {f}")
        if self.base.size > limit:
            lines.append(f"... and {self.base.size - limit} more (--json lists them all)")
        un = self.base.unidentifiable
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
                f"{name}: viscous {d['viscous']:.4g} N m s/rad, Coulomb {d['coulomb']:.4g} N m, "
                f"rotor inertia {d['rotor_inertia']:.4g} kg m^2 (motor side)"
            )
        pay = self.payload()
        if pay is not None:
            c = pay["com"]
            lines.append(
                f"payload: {pay['mass']:.4g} kg at ({c[0]:.4g}, {c[1]:.4g}, {c[2]:.4g}) m "
                "(platform frame)"
            )
        return "\n".join(lines)
