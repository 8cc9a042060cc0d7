"""The result of :func:`pkdyn.dynamics.simulate`: the solver's time series, with the robot's names.

:class:`SimulationResult` is :class:`solvers.ForwardResult` (every series, ``energy_drift``) plus
what a table, a plot or a CSV needs of the robot (actuator names, their coordinates' indices and
units) and the settings of the run, and the result protocol (:class:`pkdyn.results.Result`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from types import SimpleNamespace
from typing import Any

import numpy as np

from pkdyn.model.robot import Robot
from pkdyn.results import Result, jsonable
from pkdyn.units import columns, quantity
from solvers import ForwardResult

__all__ = ["SimulationResult"]


@dataclass
class SimulationResult(ForwardResult, Result):
    """A simulation's time series (:class:`solvers.ForwardResult`) and what names them.

    Attributes:
        robot: Robot name.
        actuators: Actuator names, in order.
        actuated_q: Configuration indices of the actuated coordinates (n_a,).
        actuated_v: Velocity indices of the actuated coordinates (n_a,).
        units: Unit of each actuator coordinate (``rad`` or ``m``).
        integrator: ``dopri5``, ``rk4`` or ``euler``.
        dt: Output time step [s].

    """

    robot: str = ""
    actuators: tuple[str, ...] = ()
    actuated_q: np.ndarray | None = None
    actuated_v: np.ndarray | None = None
    units: tuple[str, ...] = ()
    integrator: str = ""
    dt: float = 0.0
    couplings: tuple[str, ...] = ()

    @classmethod
    def of(
        cls, robot: Robot, result: ForwardResult, integrator: str, dt: float
    ) -> SimulationResult:
        """The solver's result with the robot's names and the run's settings."""
        base = {f.name: getattr(result, f.name) for f in fields(ForwardResult)}
        return cls(
            **base,
            robot=robot.name,
            actuators=tuple(robot.actuator_names),
            actuated_q=np.asarray(robot.actuated_q),
            actuated_v=np.asarray(robot.actuated_v),
            units=tuple("m" if p else "rad" for p in robot.actuator_prismatic),
            integrator=integrator,
            dt=dt,
            couplings=tuple(robot.constraints.couplings.names),
        )

    @property
    def qa(self) -> np.ndarray:
        """Actuator coordinates (N, n_a) [rad or m]."""
        return self.q[:, self._index(self.actuated_q)]

    @property
    def qa_dot(self) -> np.ndarray:
        """Actuator rates (N, n_a) [rad/s or m/s]."""
        return self.v[:, self._index(self.actuated_v)]

    def _index(self, idx: np.ndarray | None) -> np.ndarray:
        return np.zeros(0, dtype=int) if idx is None else np.asarray(idx, dtype=int)

    @property
    def layout(self) -> Any:
        """What :func:`pkdyn.dynamics.simulation_output.simulation_columns` reads of a robot."""
        return SimpleNamespace(
            name=self.robot,
            actuator_names=list(self.actuators),
            actuated_q=self._index(self.actuated_q),
            actuated_v=self._index(self.actuated_v),
        )

    def to_json(self) -> dict[str, Any]:
        """The run's figures and the motion of each actuator (start, end, peak rate).

        Returns:
            ``robot, duration`` [s], ``dt`` [s], ``integrator``, ``steps``, ``substeps``,
            ``max_closure_residual`` [m or rad] (and ``max_coupling_residual`` [rad or m] when
            the robot has couplings), ``energy_drift_rel``, ``max_kinetic_energy``
            [J], ``work`` [J] (of the actuator efforts), ``projections``, ``actuators``:
            per actuator ``name``, ``start``, ``end`` [rad or m], ``peak_rate`` [rad/s or m/s];
            ``singular_passages`` (:meth:`solvers.conditioning.SingularityEvent.to_json`),
            ``valid_until`` [s] (the start of the first passage through a singularity, or the
            end) and ``energy_drift_rel_valid`` (the energy drift up to it).

        """
        qa, qd = self.qa, self.qa_dot
        coupled = {}
        if self.couplings and self.coupling_residual is not None:
            coupled = {"max_coupling_residual": float(np.max(self.coupling_residual))}
        return jsonable(
            {
                **coupled,
                "robot": self.robot,
                "duration": float(self.t[-1] - self.t[0]),
                "dt": self.dt,
                "integrator": self.integrator,
                "steps": int(self.t.size - 1),
                "substeps": int(self.extras.get("substeps", self.t.size - 1)),
                "max_closure_residual": float(np.max(self.closure_residual)),
                "energy_drift_rel": self.energy_drift(),
                "max_kinetic_energy": float(np.max(self.kinetic)),
                "work": float(self.work[-1]),
                "projections": int(self.projections),
                "actuators": [
                    {
                        "name": name,
                        "start": float(qa[0, k]),
                        "end": float(qa[-1, k]),
                        "peak_rate": float(np.max(np.abs(qd[:, k]))),
                    }
                    for k, name in enumerate(self.actuators)
                ],
                "singular_passages": [ev.to_json() for ev in self.events],
                "valid_until": float(self.valid_until),
                "energy_drift_rel_valid": self.energy_drift(self.valid_until),
            }
        )

    def table(self) -> str:
        """The run, how each actuator moved, the closures kept and the energy balance."""
        duration = float(self.t[-1] - self.t[0])
        lines = [
            f"{self.robot}: {quantity(duration, 's')} simulated, {self.t.size - 1} steps of "
            f"{quantity(self.dt, 's')} ({self.integrator}, "
            f"{int(self.extras.get('substeps', self.t.size - 1))} substeps)"
        ]
        qa, qd = self.qa, self.qa_dot
        if qa.shape[1]:
            rows = [["  actuator", "start", "end", "peak rate"]]
            for k, name in enumerate(self.actuators):
                u = self.units[k] if k < len(self.units) else ""
                rows.append(
                    [
                        f"  {name}",
                        quantity(qa[0, k], u),
                        quantity(qa[-1, k], u),
                        quantity(float(np.max(np.abs(qd[:, k]))), f"{u}/s" if u else ""),
                    ]
                )
            lines.append(columns(rows))
        lines += [
            f"max closure residual: {float(np.max(self.closure_residual)):.2g} m or rad",
            *(
                [f"max coupling residual: {float(np.max(self.coupling_residual)):.2g} rad or m"]
                if self.couplings and self.coupling_residual is not None
                else []
            ),
            f"kinetic energy: {quantity(float(self.kinetic[0]), 'J')} at the start, "
            f"{quantity(float(np.max(self.kinetic)), 'J')} at most; work of the efforts "
            f"{quantity(float(self.work[-1]), 'J')}",
            f"energy drift: {quantity(100 * self.energy_drift(), '%', 3)} of the energy exchanged",
        ]
        lines += [f"singular passage: {ev.describe()}" for ev in self.events]
        if self.valid_until < float(self.t[-1]):
            drift = self.energy_drift(self.valid_until)
            lines.append(
                f"exact rigid motion up to t = {quantity(self.valid_until, 's')} (the first "
                "passage through a singularity); energy drift up to there: "
                f"{quantity(100 * drift, '%', 3)}"
            )
        return "\n".join(lines)
