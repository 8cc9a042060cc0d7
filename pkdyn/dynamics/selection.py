"""Motor x gearbox selection per actuator from catalogs, along a trajectory.

For each actuator and each pair (motor, gearbox) of the catalogs (or each motor on the robot's
own transmission when no gearbox is given), the drive model of :mod:`pkdyn.dynamics.actuation`
gives the motor torque along the trajectory with that pair's reduction ``N``, efficiency and
reflected inertia ``N^2 (J_motor + J_gearbox)``:

    tau_j = tau_load + N^2 J qa_ddot,    tau_m = f(N qa_dot) + tau_j / (N kappa)

with ``tau_load`` the joint-side efforts of the mechanism alone (the robot's own rotor inertia
removed: ``tau - armature qa_ddot``). The pair is feasible when

- every (speed, torque) sample lies inside the motor's peak envelope
  (:meth:`~pkdyn.dynamics.motors.Motor.peak_torque_at`) and below its maximum speed;
- the RMS torque (thermal: over the trajectory, or the worst window of one thermal time
  constant when the trajectory is longer) lies inside the continuous envelope at the mean
  speed (:meth:`~pkdyn.dynamics.motors.Motor.continuous_torque_at`);
- the gearbox's output torque peak stays below its peak torque, its speed-weighted mean cubic
  output torque (the figure gearbox ratings use) below its rated torque, and the motor speed
  below its maximum input speed.

Feasible pairs are ranked by a criterion (the motor's rated torque, the pair's mass or price);
rejected pairs carry the checks they fail, with the figures. Also reported: the load inertia
seen by each actuator (the largest diagonal term of the actuator-space inertia matrix along the
trajectory, :func:`actuator_inertia`), each pair's inertia ratio ``(J_load / N^2 + J_gearbox) /
J_motor``, and each motor's optimal gear ratio ``(mean(tau_load^2) / (J_motor^2
mean(qa_ddot^2)))^(1/4)``, which minimises the RMS motor torque of a lossless gearbox (inertia
matching for a purely inertial load), with the largest ratio its maximum speed allows.

With redundant actuation, ``tau_load`` is the least-norm sharing of the inverse dynamics and
each motor accelerates its own rotor (a valid sharing, not re-optimised per pair). A prismatic
actuator keeps its screw (its reduction in rad/m and efficiency), and the gearbox, in front of
it, multiplies the reduction; the motor on the screw alone is a candidate too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.dynamics.actuation import drives
from pkdyn.dynamics.inverse import EffortTrajectory, inverse_dynamics
from pkdyn.dynamics.motors import Catalog, Gearbox, Motor
from pkdyn.dynamics.payload import with_payload
from pkdyn.dynamics.trajectory import JointTrajectory
from pkdyn.exceptions import InvalidInputError, NoFeasibleDriveError
from pkdyn.model.robot import Robot
from pkdyn.results import Result, deprecated_alias, renamed_keyword
from pkdyn.units import quantity
from solvers import Drives
from solvers.numerics import lstsq, null_space

__all__ = [
    "CRITERIA",
    "MAX_PAIR_SAMPLES",
    "ActuatorSelection",
    "Candidate",
    "Check",
    "MotorRatio",
    "Selection",
    "actuator_inertia",
    "select_drives",
]

MAX_PAIR_SAMPLES = 50_000_000
"""Most (motor x gearbox pairs) x actuators x trajectory samples one selection checks (about
5 us each: a few minutes)."""

CRITERIA = ("rated_torque", "mass", "price")
"""Ranking criteria of the feasible pairs (smallest first)."""

_RPM = 60.0 / (2.0 * math.pi)


def actuator_inertia(robot: Robot, q: np.ndarray, armature: bool = False) -> np.ndarray:
    """Inertia matrix of the mechanism in actuator coordinates at ``q``.

    ``M_a = (S Z H^-1 Z^T S^T)^-1`` with ``Z`` a basis of the motions the closures allow and
    ``H = Z^T M Z``: the kinetic energy is ``0.5 qa_dot^T M_a qa_dot`` for the motion of least
    energy (internal mobilities such as the Delta's bar spins at rest). With redundant actuation
    (dependent actuator rates) ``M_a`` is the pseudo-inverse, exact on the feasible rates.

    Args:
        robot: The robot (a payload included if any).
        q: Assembled configuration (nq,).
        armature: Include the reflected rotor inertias (default: the mechanism alone).

    Returns:
        ``M_a`` (n_a, n_a) [kg m^2 or kg].

    """
    model = robot.model
    data = model.createData()
    M = np.array(pin.crba(model, data, q))
    M = np.triu(M) + np.triu(M, 1).T
    if not armature:
        M -= np.diag(np.asarray(model.armature))
    if robot.constraints.n:
        _, J = robot.constraints.residual_and_jacobian(data, q)
        Z = null_space(J)
    else:
        Z = np.eye(model.nv)
    H = Z.T @ M @ Z
    SZ = Z[robot.actuated_v]
    K = SZ @ lstsq(H, SZ.T)  # the actuators' inverse inertia
    return lstsq(K, np.eye(K.shape[0]))  # redundant actuation: the pseudo-inverse


@dataclass(frozen=True)
class Check(Result):
    """One requirement of a pair against one limit.

    Attributes:
        name: What is checked (``peak torque``, ``RMS torque``, ``speed``, ``gearbox peak
            torque``, ``gearbox rated torque``, ``gearbox input speed``).
        demand: What the trajectory needs (SI).
        capacity: What the motor or gearbox offers there (SI).
        unit: Unit of both.
        time: Time of the worst sample [s] (``None`` for a mean figure).
        speed: Motor speed there [rad/s] (``None`` when irrelevant).

    """

    name: str
    demand: float
    capacity: float
    unit: str
    time: float | None = None
    speed: float | None = None

    @property
    def utilisation(self) -> float:
        """``demand / capacity`` (> 1: fails)."""
        if self.capacity <= 0.0:
            return math.inf if self.demand > 0.0 else 0.0
        return self.demand / self.capacity

    @property
    def ok(self) -> bool:
        """Within the limit."""
        return self.utilisation <= 1.0

    def describe(self) -> str:
        """One line: what is needed, what is available, by how much it fails."""
        at = "" if self.speed is None else f" at {abs(self.speed) * _RPM:.0f} rpm"
        when = "" if self.time is None else f", t = {self.time:.4g} s"
        over = self.utilisation - 1.0
        excess = f" (+{100 * over:.0f} %)" if math.isfinite(over) else ""
        return (
            f"{self.name} {_fmt(self.demand, self.unit)}{at} > "
            f"{_fmt(self.capacity, self.unit)}{excess}{when}"
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {
            "name": self.name,
            "demand": self.demand,
            "capacity": self.capacity,
            "unit": self.unit,
            "utilisation": self.utilisation if math.isfinite(self.utilisation) else None,
            "ok": self.ok,
            "time": self.time,
            "speed": self.speed,
        }

    as_json = deprecated_alias("as_json", "to_json")

    def table(self) -> str:
        """Demand against capacity, with the unit, and whether it passes."""
        state = "ok" if self.ok else "FAILS"
        return (
            f"{self.name}: {_fmt(self.demand, self.unit)} needed, "
            f"{_fmt(self.capacity, self.unit)} available ({state})"
        )


def _fmt(x: float, unit: str) -> str:
    if unit == "rad/s":
        return f"{x * _RPM:.0f} rpm"
    return f"{x:.3g} {unit}"


@dataclass(frozen=True)
class Candidate(Result):
    """A motor (x gearbox) on one actuator along the trajectory.

    Attributes:
        actuator: Actuator name.
        motor: The motor.
        gearbox: The gearbox (``None``: the robot's own transmission).
        reduction: Total reduction ``N`` (motor speed / joint speed).
        checks: Every requirement with its figures.
        motor_peak: Peak ``|motor torque|`` [N m].
        motor_rms: RMS motor torque (thermal figure) [N m].
        mean_speed: Time mean of ``|motor speed|`` [rad/s] (the RMS point's speed).
        peak_speed: Peak ``|motor speed|`` [rad/s].
        inertia_ratio: ``(J_load / N^2 + J_gearbox) / J_motor``.
        reflected_inertia: ``N^2 (J_motor + J_gearbox)`` seen by the joint [kg m^2 or kg].
        copper_loss: Mean copper loss ``R (tau_rms / k_t)^2`` [W] (``None`` without ``k_t``
            and ``R``).
        score: Value of the ranking criterion (``nan`` when the catalog lacks it).
        speed: Motor speeds (N,) [rad/s] (for the operating-point plot).
        torque: Motor torques (N,) [N m].

    """

    actuator: str
    motor: Motor
    gearbox: Gearbox | None
    reduction: float
    checks: tuple[Check, ...]
    motor_peak: float
    motor_rms: float
    mean_speed: float
    peak_speed: float
    inertia_ratio: float
    reflected_inertia: float
    copper_loss: float | None
    score: float
    speed: np.ndarray = field(repr=False, compare=False)
    torque: np.ndarray = field(repr=False, compare=False)

    @property
    def name(self) -> str:
        """``motor + gearbox`` (or the motor alone)."""
        return self.motor.name + ("" if self.gearbox is None else f" + {self.gearbox.name}")

    @property
    def feasible(self) -> bool:
        """Every check passes."""
        return all(c.ok for c in self.checks)

    @property
    def failures(self) -> list[Check]:
        """The failing checks, worst first."""
        return sorted((c for c in self.checks if not c.ok), key=lambda c: -c.utilisation)

    @property
    def utilisation(self) -> float:
        """The largest utilisation over the checks (> 1: rejected)."""
        return max(c.utilisation for c in self.checks)

    @property
    def mass(self) -> float:
        """Motor plus gearbox mass [kg] (a missing gearbox mass counts 0)."""
        g = 0.0 if self.gearbox is None or self.gearbox.mass is None else self.gearbox.mass
        return self.motor.mass + g

    def why(self) -> str:
        """Why it is rejected (the failing checks), or ``feasible``."""
        bad = self.failures
        return "; ".join(c.describe() for c in bad) if bad else "feasible"

    def table(self) -> str:
        """The pair, its reduction, torques and speed, and why it is rejected (if it is)."""
        return (
            f"{self.actuator}: {self.name}, reduction {quantity(self.reduction, '', 4)}, motor "
            f"peak {quantity(self.motor_peak, 'N m')}, RMS {quantity(self.motor_rms, 'N m')}, "
            f"peak speed {self.peak_speed * _RPM:.0f} rpm; {self.why()}"
        )

    as_json = deprecated_alias("as_json", "to_json")

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict (no time series)."""
        return {
            "motor": self.motor.name,
            "gearbox": None if self.gearbox is None else self.gearbox.name,
            "reduction": self.reduction,
            "feasible": self.feasible,
            "motor_peak": self.motor_peak,
            "motor_rms": self.motor_rms,
            "mean_speed": self.mean_speed,
            "peak_speed": self.peak_speed,
            "inertia_ratio": self.inertia_ratio,
            "reflected_inertia": self.reflected_inertia,
            "copper_loss": self.copper_loss,
            "mass": self.mass,
            "score": self.score if math.isfinite(self.score) else None,
            "checks": [c.to_json() for c in self.checks],
            "why": self.why(),
        }


@dataclass(frozen=True)
class MotorRatio:
    """A motor's optimal gear ratio on one actuator.

    Attributes:
        motor: Motor name.
        optimal: Ratio minimising its RMS torque (lossless gearbox) (``inf`` without
            acceleration).
        rms_at_optimal: Its RMS torque at that ratio [N m].
        speed_limited: Largest ratio its maximum speed allows along the trajectory.

    """

    motor: str
    optimal: float
    rms_at_optimal: float
    speed_limited: float

    @property
    def usable(self) -> float:
        """The optimal ratio, capped by the speed limit."""
        return min(self.optimal, self.speed_limited)


@dataclass(frozen=True)
class ActuatorSelection:
    """Every candidate of one actuator.

    Attributes:
        actuator: Actuator name.
        load_inertia: Largest mechanism inertia seen by the joint along the trajectory
            [kg m^2 or kg] (rotor excluded).
        feasible: Feasible pairs, best first.
        rejected: Rejected pairs, closest to feasible first.
        ratios: Each motor's optimal gear ratio.

    """

    actuator: str
    load_inertia: float
    feasible: list[Candidate]
    rejected: list[Candidate]
    ratios: list[MotorRatio]

    @property
    def best(self) -> Candidate | None:
        """The first-ranked feasible pair."""
        return self.feasible[0] if self.feasible else None

    def closest(self, n: int = 3) -> list[str]:
        """The ``n`` closest rejected pairs and what each lacks."""
        return [f"{c.name}: {c.why()}" for c in self.rejected[:n]]


@dataclass(frozen=True)
class Selection(Result):
    """Motor (x gearbox) selection of every actuator.

    Attributes:
        robot: Robot name.
        trajectory: Trajectory name.
        payload: Payload [kg].
        duration: Trajectory duration [s].
        criterion: Ranking criterion (:data:`CRITERIA`).
        catalog: Catalog source(s).
        actuators: Per-actuator candidates.

    """

    robot: str
    trajectory: str
    payload: float
    duration: float
    criterion: str
    catalog: str
    actuators: list[ActuatorSelection]

    @property
    def feasible(self) -> bool:
        """Every actuator has a feasible pair."""
        return all(a.feasible for a in self.actuators)

    def choice(self) -> list[Candidate]:
        """The best pair of each actuator.

        Raises:
            NoFeasibleDriveError: An actuator has no feasible pair (with the closest ones and
                what each lacks).

        """
        out = []
        for a in self.actuators:
            if a.best is None:
                raise NoFeasibleDriveError(a.actuator, a.closest())
            out.append(a.best)
        return out

    as_json = deprecated_alias("as_json", "to_json")

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict: every candidate, with its checks and the reasons of rejection."""
        return {
            "robot": self.robot,
            "trajectory": self.trajectory,
            "payload": self.payload,
            "duration": self.duration,
            "criterion": self.criterion,
            "catalog": self.catalog,
            "feasible": self.feasible,
            "actuators": [
                {
                    "actuator": a.actuator,
                    "load_inertia": a.load_inertia,
                    "best": None if a.best is None else a.best.name,
                    "feasible": [c.to_json() for c in a.feasible],
                    "rejected": [c.to_json() for c in a.rejected],
                    "optimal_ratios": [
                        {
                            "motor": r.motor,
                            "optimal": r.optimal if math.isfinite(r.optimal) else None,
                            "rms_at_optimal": r.rms_at_optimal,
                            "speed_limited": r.speed_limited
                            if math.isfinite(r.speed_limited)
                            else None,
                        }
                        for r in a.ratios
                    ],
                }
                for a in self.actuators
            ],
        }

    @renamed_keyword("show", "top")
    def table(self, top: int = 5) -> str:
        """A readable report: the best pairs, the closest rejected ones, the optimal ratios.

        Args:
            top: Pairs listed per actuator in each group (``show``: its former name, kept for
                one release).

        Returns:
            The text.

        """
        lines = [
            f"motor selection from {self.catalog} (ranked by {self.criterion.replace('_', ' ')}; "
            "torques motor side)"
        ]
        for a in self.actuators:
            n = len(a.feasible) + len(a.rejected)
            lines.append(
                f"{a.actuator}: load inertia {quantity(a.load_inertia, 'kg m^2')}, "
                f"{len(a.feasible)} feasible of {n} pairs"
            )
            if a.feasible:
                lines.append(
                    f"  {'#':>2} {'motor + gearbox':<24} {'N':>5} {'peak/avail':>12} "
                    f"{'rms/rated':>11} {'rpm/max':>11} {'J ratio':>7} {'kg':>5}"
                )
            for k, c in enumerate(a.feasible[:top], start=1):
                pk = next(x for x in c.checks if x.name == "peak torque")
                rm = next(x for x in c.checks if x.name == "RMS torque")
                lines.append(
                    f"  {k:>2} {c.name:<24} {c.reduction:5.3g} "
                    f"{c.motor_peak:5.2f}/{pk.capacity:<6.2f} "
                    f"{c.motor_rms:5.2f}/{rm.capacity:<5.2f} "
                    f"{c.peak_speed * _RPM:5.0f}/{c.motor.max_speed * _RPM:<5.0f} "
                    f"{c.inertia_ratio:7.2f} {c.mass:5.2f}"
                )
            if len(a.feasible) > top:
                lines.append(f"     ... {len(a.feasible) - top} more feasible")
            if a.rejected:
                head = "closest rejected" if a.feasible else "NO FEASIBLE PAIR; closest"
                lines.append(f"  {head} ({len(a.rejected)} rejected):")
                for c in a.rejected[:top]:
                    lines.append(f"    {c.name}: {c.why()}")
            opt = ", ".join(
                f"{r.motor} {r.optimal:.3g}"
                + (f" (speed limit {r.speed_limited:.3g})" if r.speed_limited < r.optimal else "")
                for r in a.ratios
            )
            lines.append(f"  optimal ratio per motor (RMS torque): {opt}")
        return "\n".join(lines)


def _mean(t: np.ndarray, x: np.ndarray) -> float:
    T = float(t[-1] - t[0])
    return float(np.sum(0.5 * (x[1:] + x[:-1]) * np.diff(t)) / T)


def _rms(t: np.ndarray, x: np.ndarray, window: float | None) -> float:
    """RMS over the trajectory, or the worst window of ``window`` seconds if it is shorter."""
    T = float(t[-1] - t[0])
    if window is None or window >= T:
        return math.sqrt(_mean(t, x**2))
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (x[1:] ** 2 + x[:-1] ** 2) * np.diff(t))])
    ends = np.searchsorted(t, t + window)
    ok = ends < t.size
    starts = np.flatnonzero(ok)
    span = t[ends[ok]] - t[starts]
    return math.sqrt(float(np.max((cum[ends[ok]] - cum[starts]) / span)))


def _criterion(c: Motor, g: Gearbox | None, criterion: str) -> float:
    if criterion == "rated_torque":
        return c.rated_torque
    if criterion == "mass":
        return c.mass + (0.0 if g is None or g.mass is None else g.mass)
    prices = [c.price] + ([] if g is None else [g.price])
    return math.nan if any(p is None for p in prices) else float(sum(p or 0.0 for p in prices))


def _evaluate(
    act: str,
    m: Motor,
    g: Gearbox | None,
    base: tuple[float, float, float],
    t: np.ndarray,
    tau_load: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    load_inertia: float,
    criterion: str,
) -> Candidate:
    """One actuator with one motor (x gearbox); ``base``: fixed stage (ratio, eta, eta_b)."""
    b, eta_s, eta_bs = base
    if g is None:  # the motor on the fixed stage alone (the robot's transmission, or a screw)
        N, J, eta, eta_b = b, m.rotor_inertia, eta_s, eta_bs
    else:
        N = g.ratio * b
        J = m.rotor_inertia + g.inertia
        eta = g.efficiency * eta_s
        eta_b = (
            g.efficiency if g.backdrive_efficiency is None else g.backdrive_efficiency
        ) * eta_bs
    d = Drives([N], J, eta, eta_b, m.viscous, m.coulomb)
    tau_j = tau_load + d.armature[0] * qdd
    tau_m = d.motor_effort(tau_j[:, None], qd[:, None])[:, 0]
    omega = d.motor_speed(qd[:, None])[:, 0]
    # the torque envelopes at speeds clipped to the maximum (the speed check judges the speed)
    env = m.peak_torque_at(np.clip(omega, -m.max_speed, m.max_speed))
    with np.errstate(divide="ignore", invalid="ignore"):
        util = np.where(env > 0.0, np.abs(tau_m) / env, np.where(tau_m == 0.0, 0.0, np.inf))
    k = int(np.argmax(util))
    rms = _rms(t, tau_m, m.thermal_time_constant)
    mean_speed = _mean(t, np.abs(omega))
    kw = int(np.argmax(np.abs(omega)))
    checks = [
        Check("peak torque", float(abs(tau_m[k])), float(env[k]), "N m", float(t[k]), omega[k]),
        Check(
            "RMS torque",
            rms,
            float(m.continuous_torque_at(min(mean_speed, m.max_speed))),
            "N m",
            None,
            mean_speed,
        ),
        Check("speed", float(abs(omega[kw])), m.max_speed, "rad/s", float(t[kw])),
    ]
    if g is not None:
        out = np.abs(tau_load) / b  # the gearbox output torque (its rotor inertia is upstream)
        ko = int(np.argmax(out))
        w = np.abs(omega)
        if _mean(t, w) > 0.0:
            cubic = (_mean(t, w * out**3) / _mean(t, w)) ** (1.0 / 3.0)
        else:
            cubic = float(np.max(out))
        checks += [
            Check("gearbox peak torque", float(out[ko]), g.peak_torque, "N m", float(t[ko])),
            Check("gearbox rated torque", cubic, g.rated_torque, "N m"),
            Check("gearbox input speed", float(w[kw]), g.max_input_speed, "rad/s", float(t[kw])),
        ]
    copper = None
    if m.torque_constant is not None and m.resistance is not None:
        copper = m.resistance * (rms / m.torque_constant) ** 2
    g_J = 0.0 if g is None else g.inertia
    return Candidate(
        actuator=act,
        motor=m,
        gearbox=g,
        reduction=N,
        checks=tuple(checks),
        motor_peak=float(np.max(np.abs(tau_m))),
        motor_rms=rms,
        mean_speed=mean_speed,
        peak_speed=float(np.max(np.abs(omega))),
        inertia_ratio=(load_inertia / N**2 + g_J) / m.rotor_inertia,
        reflected_inertia=float(d.armature[0]),
        copper_loss=copper,
        score=_criterion(m, g, criterion),
        speed=omega,
        torque=tau_m,
    )


def _ratio(m: Motor, t: np.ndarray, tau_load: np.ndarray, qd: np.ndarray, qdd: np.ndarray):
    A = _mean(t, tau_load**2)
    B = _mean(t, tau_load * qdd) * m.rotor_inertia
    C = _mean(t, qdd**2) * m.rotor_inertia**2
    opt = (A / C) ** 0.25 if C > 0.0 else math.inf
    rms = math.sqrt(max(A / opt**2 + 2.0 * B + C * opt**2, 0.0)) if math.isfinite(opt) else 0.0
    vmax = float(np.max(np.abs(qd)))
    return MotorRatio(m.name, opt, rms, m.max_speed / vmax if vmax > 0.0 else math.inf)


def select_drives(
    robot: Robot,
    trajectory: JointTrajectory,
    catalog: Catalog,
    payload: float = 0.0,
    criterion: str = "rated_torque",
    efforts: EffortTrajectory | None = None,
    wrench: Any = None,
    inertia_samples: int = 40,
    progress: bool | None = None,
) -> Selection:
    """Feasible motor x gearbox pairs per actuator, ranked, with the reasons of each rejection.

    Args:
        robot: The robot (its own rotor inertia is replaced by each candidate's).
        trajectory: Joint trajectory (closure-consistent).
        catalog: Motors, and gearboxes (none: each motor on the robot's own transmission).
        payload: Payload mass at the platform [kg].
        criterion: Ranking of the feasible pairs: ``rated_torque`` (smallest motor), ``mass``
            (lightest pair) or ``price`` (cheapest pair).
        efforts: Inverse dynamics of the loaded robot along ``trajectory`` if already computed
            (e.g. :attr:`SizingResult.efforts <pkdyn.dynamics.sizing.SizingResult.efforts>`).
        wrench: Platform wrench for the inverse dynamics (see
            :func:`pkdyn.dynamics.inverse_dynamics`).
        inertia_samples: Samples of the trajectory where the load inertia is evaluated.
        progress: Progress bar of the inverse dynamics.

    Returns:
        The selection (``.feasible``, ``.choice()``, ``.table()``, ``.as_json()``).

    Raises:
        InvalidInputError: Unknown criterion, a catalog without motors, prices missing for the
            ``price`` criterion, or more pairs x samples than :data:`MAX_PAIR_SAMPLES`.

    """
    if criterion not in CRITERIA:
        raise InvalidInputError(
            "criterion", f"unknown {criterion!r} (one of {', '.join(CRITERIA)})"
        )
    if not catalog.motors:
        raise InvalidInputError("catalog", f"{catalog.source or 'the catalog'} lists no motors")
    n_pairs = len(catalog.motors) * max(1, len(catalog.gearboxes) + 1)
    work = n_pairs * len(robot.actuators) * int(trajectory.t.size)
    if work > MAX_PAIR_SAMPLES:
        raise InvalidInputError(
            "catalog",
            f"{len(catalog.motors)} motors x {len(catalog.gearboxes)} gearboxes on "
            f"{len(robot.actuators)} actuators along {trajectory.t.size} samples is {work:.3g} "
            f"pair-samples, more than {MAX_PAIR_SAMPLES:.0e} (about {work * 5e-6 / 60:.0f} min): "
            "split the catalog, or sample the trajectory more coarsely (--dt)",
        )
    if criterion == "price":
        missing = [m.name for m in catalog.motors if m.price is None] + [
            g.name for g in catalog.gearboxes if g.price is None
        ]
        if missing:
            raise InvalidInputError(
                "criterion", f"price missing for {', '.join(missing[:5])} (rank by rated_torque)"
            )
    loaded = with_payload(robot, payload) if payload else robot
    if efforts is None:
        efforts = inverse_dynamics(loaded, trajectory, wrench=wrench, progress=progress)
    t = trajectory.t
    qd, qdd = trajectory.qa_dot, trajectory.qa_ddot
    own = drives(robot)
    tau_load = efforts.tau - own.armature * qdd
    idx = np.unique(np.linspace(0, t.size - 1, max(2, inertia_samples)).astype(int))
    Ma = np.array([np.diag(actuator_inertia(loaded, trajectory.q[k])) for k in idx])
    J_load = np.max(Ma, axis=0)
    out = []
    for i, act in enumerate(robot.actuators):
        jm = robot.model.joints[int(robot.actuated_joints[i])]
        prismatic = jm.shortname().startswith("JointModelP")
        eta_b = act.efficiency if act.backdrive_efficiency is None else act.backdrive_efficiency
        if catalog.gearboxes and prismatic:
            base = (act.reduction, act.efficiency, eta_b)
        elif catalog.gearboxes:
            base = (1.0, 1.0, 1.0)
        else:
            base = (act.reduction, act.efficiency, eta_b)
        # a screw may also be driven directly: its motor alone is a candidate too
        gears: tuple[Gearbox | None, ...] = catalog.gearboxes or (None,)
        if catalog.gearboxes and prismatic:
            gears = (None, *catalog.gearboxes)
        pairs = [
            _evaluate(
                act.name, m, g, base, t, tau_load[:, i], qd[:, i], qdd[:, i], J_load[i], criterion
            )
            for m in catalog.motors
            for g in gears
        ]
        ok = sorted(
            (c for c in pairs if c.feasible), key=lambda c: (c.score, c.mass, c.utilisation)
        )
        bad = sorted((c for c in pairs if not c.feasible), key=lambda c: c.utilisation)
        ratios = [_ratio(m, t, tau_load[:, i], qd[:, i], qdd[:, i]) for m in catalog.motors]
        out.append(ActuatorSelection(act.name, float(J_load[i]), ok, bad, ratios))
    return Selection(
        robot=robot.name,
        trajectory=trajectory.name,
        payload=float(payload),
        duration=float(t[-1] - t[0]),
        criterion=criterion,
        catalog=catalog.source,
        actuators=out,
    )
