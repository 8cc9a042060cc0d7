"""Checks of the tripod scenario, phase by phase (seed 003).

For every sample of every phase of :func:`pkdyn.tripod.scenario.plan_scenario`:

- **actuator forces** from the inverse dynamics (:func:`pkdyn.dynamics.inverse_dynamics`, i.e.
  :class:`solvers.InverseDynamics` with the phase's constraints: closures, clamps, locks), with
  gravity and, while machining, the machining wrench at the tool (``f_ext = J_tool^T F``);
- **stroke margins**: distance of each actuator length to its nearer stroke limit [m];
- **distances** with coal between the legs (actuator bodies and rods) of different branches and
  between each leg and the nacelle (plate and spindle) [m];
- **singularity margin**: ``distance`` of :func:`pkdyn.analysis.singularity.classify` on the phase's
  robot (``1 / cond`` of ``A`` and ``B``; 0 at a singularity); for the walker in mode PP (eight
  actuators, 6 DOF: redundant actuation, whose eight relations ``A x_dot = B q_dot_a`` the square
  models of :mod:`pkdyn.analysis.kinematics` truncate to six) the same measure on all eight
  relations (:func:`redundant_singularity_distance`);
- **closure residuals** of the hinges and of the clamped feet (constraint residuals);
- **locked joints**: largest departure of a locked coordinate from its locked value (read from
  the joint coordinates, not from the lock constraints);
- **support feet**: largest departure of a clamped foot frame (forward kinematics) from its
  foothold;
- the walker's swings: the values of the redundancy resolution's objective
  (:mod:`pkdyn.tripod.redundancy`), baseline and chosen path.

The same checks run on the tripod and on the four-branch walker (``branches=4``); the effort
distribution of the walker's redundant actuation in mode PP is the least weighted norm or, with
``allocation="max"``, the least largest force (:func:`pkdyn.dynamics.inverse_dynamics`), within
the force limits (the QP's bounds) when such a distribution exists.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.analysis.collisions import CollisionChecker
from pkdyn.analysis.kinematics import SINGULAR_TOL, _cond, _relations, platform_jacobian
from pkdyn.analysis.singularity import classify
from pkdyn.dynamics import inverse_dynamics
from pkdyn.dynamics.inverse import EffortTrajectory
from pkdyn.exceptions import InfeasibleEffortError
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.tripod.modes import branch_numbers, foot_placement
from pkdyn.tripod.scenario import Phase, WalkPlan, plan_scenario
from pkdyn.units import columns, quantity
from solvers import numerics

__all__ = [
    "LEGS",
    "PhaseReport",
    "ScenarioReport",
    "analyse",
    "leg_pairs",
    "redundant_singularity_distance",
    "run_scenario",
]

LEGS = ("cylL", "rodL", "cylR", "rodR")
"""Links of a branch that make its legs (actuator bodies and rods)."""


def leg_pairs(branches: int = 3) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
    """Link pairs checked for interference: leg-to-leg (different branches), leg-to-nacelle.

    Args:
        branches: Number of branches (3: the tripod, 4: the walker).

    Returns:
        ``(leg_to_leg, leg_to_nacelle)`` lists of link-name pairs.

    """
    legs = [(b, f"branch{b}_{n}") for b in branch_numbers(branches) for n in LEGS]
    leg_leg = [(a, c) for (ba, a) in legs for (bc, c) in legs if ba < bc]
    leg_nacelle = [(a, "nacelle") for _, a in legs]
    return leg_leg, leg_nacelle


@dataclass
class PhaseReport(Result):
    """Checks of one phase (worst values over its samples).

    Attributes:
        name: ``machining``, ``reconfiguration`` or ``swing``.
        mode: ``PP`` or ``BE``.
        branch: Swinging branch (BE) or ``None``.
        locked: The paper's names of the locked joints.
        t0: Start time [s].
        duration: Duration [s].
        samples: Number of samples.
        max_closure_residual: Largest residual of the hinges and clamps [m or rad].
        max_lock_drift: Largest departure of a locked coordinate from its value [rad]
            (0 without locks).
        max_support_drift: Largest departure of a clamped foot frame from its foothold
            (position [m] or rotation angle [rad], the larger).
        max_actuator_force: Largest ``|tau|`` [N].
        max_actuator_speed: Largest actuator speed [m/s].
        min_stroke_margin: Smallest distance of an actuator to its stroke limits [m]
            (negative: out of stroke).
        min_leg_distance: Smallest leg-to-leg or leg-to-nacelle distance [m] (negative:
            penetration).
        min_leg_to_leg: Smallest leg-to-leg distance [m].
        min_leg_to_nacelle: Smallest leg-to-nacelle distance [m].
        closest_pair: The two geometries at ``min_leg_distance``.
        min_singularity_distance: Smallest ``1 / cond`` of the kinematic models (0: singular).
        max_dynamics_residual: Largest residual of the inverse-dynamics equation [N].
        end_error: Distance of the nacelle at the phase's end from its planned placement
            (swings: ``x_end`` of ``B_iIKMX``; reconfigurations: ``x_re`` or the station home)
            [m or rad, the larger], or ``None``.
        lock_plan_error: Swings: largest difference between the engaged locks and ``b_i`` of
            ``B_iIKMX`` [rad], or ``None``.
        redundancy: The walker's swings: the objective's values
            (:meth:`pkdyn.tripod.redundancy.SwingSolution.as_json`), else ``None``.

    """

    name: str
    mode: str
    branch: int | None
    locked: list[str]
    t0: float
    duration: float
    samples: int
    max_closure_residual: float
    max_lock_drift: float
    max_support_drift: float
    max_actuator_force: float
    max_actuator_speed: float
    min_stroke_margin: float
    min_leg_distance: float
    min_leg_to_leg: float
    min_leg_to_nacelle: float
    closest_pair: tuple[str, str]
    min_singularity_distance: float
    max_dynamics_residual: float
    end_error: float | None
    lock_plan_error: float | None
    redundancy: dict[str, Any] | None = None

    as_json = deprecated_alias("as_json", "to_json")

    def table(self) -> str:
        """The phase's worst figures on one line, in units."""
        return (
            f"{self.name} ({self.mode}{'' if self.branch is None else f', branch {self.branch}'}"
            f", {quantity(self.duration, 's')}): closure {self.max_closure_residual:.1e} m or "
            f"rad, force {quantity(self.max_actuator_force, 'N')}, legs "
            f"{quantity(self.min_leg_distance, 'm')} apart, stroke left "
            f"{quantity(self.min_stroke_margin, 'm')}, 1/cond "
            f"{quantity(self.min_singularity_distance, '', 3)}"
        )

    def to_json(self) -> dict[str, Any]:
        """Plain-JSON form (the CLI's ``phases`` entries)."""
        return jsonable(
            {
                "name": self.name,
                "mode": self.mode,
                "branch": self.branch,
                "locked": list(self.locked),
                "t0": self.t0,
                "duration": self.duration,
                "samples": self.samples,
                "max_closure_residual": self.max_closure_residual,
                "max_lock_drift": self.max_lock_drift,
                "max_support_drift": self.max_support_drift,
                "max_actuator_force": self.max_actuator_force,
                "max_actuator_speed": self.max_actuator_speed,
                "min_stroke_margin": self.min_stroke_margin,
                "min_leg_distance": self.min_leg_distance,
                "min_leg_to_leg": self.min_leg_to_leg,
                "min_leg_to_nacelle": self.min_leg_to_nacelle,
                "closest_pair": list(self.closest_pair),
                "min_singularity_distance": self.min_singularity_distance,
                "max_dynamics_residual": self.max_dynamics_residual,
                "end_error": self.end_error,
                "lock_plan_error": self.lock_plan_error,
                "redundancy": self.redundancy,
            }
        )


@dataclass
class ScenarioReport(Result):
    """The scenario, its checks and the sampled series (samples of all phases in order).

    Attributes:
        phases: The planned phases.
        reports: One :class:`PhaseReport` per phase.
        t: Time of each sample (N,) [s] (phase boundaries appear twice).
        phase: Phase index of each sample (N,).
        q: Configurations (N, nq).
        tau: Actuator forces (N, n_a) [N] (6 for the tripod, 8 for the walker).
        stroke_margin: Smallest stroke margin per sample (N,) [m].
        leg_distance: Smallest leg distance per sample (N,) [m].
        singularity_distance: ``1 / cond`` per sample (N,) (NaN where not evaluated).
        nacelle: Position of ``P_O`` per sample (N, 3) [m].
        feet: Foot-frame origins ``A_i`` per sample (N, n, 3) [m] (branch, xyz).
        actuators: Actuator names.
        effort_limit: Actuator force limit [N].
        speed_limit: Actuator speed limit [m/s].

    """

    phases: list[Phase]
    reports: list[PhaseReport]
    t: np.ndarray
    phase: np.ndarray
    q: np.ndarray
    tau: np.ndarray
    stroke_margin: np.ndarray
    leg_distance: np.ndarray
    singularity_distance: np.ndarray
    nacelle: np.ndarray
    feet: np.ndarray
    actuators: list[str]
    effort_limit: float
    speed_limit: float = float("inf")

    def violations(self) -> list[str]:
        """What the scenario breaks: strokes, interference, effort limit (empty: none).

        The actuator speeds are reported (``max_actuator_speed``, ``speed_limit``), not counted:
        the scenario's timing is the plan's, a slower plan fixes them.
        """
        out = []
        for k, r in enumerate(self.reports):
            where = f"phase {k} ({r.name}{'' if r.branch is None else f' {r.branch}'})"
            if r.min_stroke_margin < 0.0:
                out.append(
                    f"{where}: an actuator leaves its stroke by {-r.min_stroke_margin:.4g} m"
                )
            if r.min_leg_distance < 0.0:
                out.append(f"{where}: {r.closest_pair[0]} and {r.closest_pair[1]} interfere")
            if r.max_actuator_force > self.effort_limit:
                out.append(
                    f"{where}: actuator force {r.max_actuator_force:.4g} N beyond the limit "
                    f"{self.effort_limit:.4g} N"
                )
        return out

    as_json = deprecated_alias("as_json", "to_json")

    def table(self) -> str:
        """One line per phase (worst values), then the whole run and its violations."""
        out = self.to_json()
        walker = out["summary"].get("branches", 3) != 3
        rows = [
            ["#", "phase", "mode", "br", "closure", "force", "legs apart", "stroke left", "1/cond"]
            + (["objective: baseline -> chosen"] if walker else [])
        ]
        for k, ph in enumerate(out["phases"]):
            red = ph.get("redundancy")
            rows.append(
                [
                    str(k),
                    ph["name"],
                    ph["mode"],
                    str(ph["branch"] or "-"),
                    f"{ph['max_closure_residual']:.1e}",
                    quantity(ph["max_actuator_force"], "N"),
                    quantity(ph["min_leg_distance"], "m"),
                    quantity(ph["min_stroke_margin"], "m"),
                    quantity(ph["min_singularity_distance"], "", 3),
                ]
                + (
                    [
                        f"{quantity(red['objective_baseline'], 'm')} -> "
                        f"{quantity(red['objective'], 'm')}"
                    ]
                    if walker and red is not None
                    else []
                )
            )
        s = out["summary"]
        return (
            columns(rows)
            + "\n(closure: largest hinge or clamp residual, m or rad)\n"
            + f"{quantity(s['duration'], 's')}, {s['samples']} samples; locks held to "
            f"{s['max_lock_drift']:.1e} rad, feet to {s['max_support_drift']:.1e} m; "
            + ("no violation" if not s["violations"] else "; ".join(s["violations"]))
        )

    def to_json(self) -> dict[str, Any]:
        """``{"phases": [...], "summary": {...}}`` (see :class:`PhaseReport`)."""
        reps = self.reports
        return {
            "phases": [r.to_json() for r in reps],
            "summary": {
                "duration": float(self.t[-1]),
                "samples": int(self.t.size),
                "max_closure_residual": max(r.max_closure_residual for r in reps),
                "max_lock_drift": max(r.max_lock_drift for r in reps),
                "max_support_drift": max(r.max_support_drift for r in reps),
                "max_actuator_force": max(r.max_actuator_force for r in reps),
                "min_stroke_margin": min(r.min_stroke_margin for r in reps),
                "min_leg_distance": min(r.min_leg_distance for r in reps),
                "min_singularity_distance": min(r.min_singularity_distance for r in reps),
                "effort_limit": self.effort_limit,
                "speed_limit": self.speed_limit,
                "branches": int(self.feet.shape[1]),
                "violations": self.violations(),
            },
        }


def _nacelle(robot: Robot, q: np.ndarray) -> pin.SE3:
    pin.forwardKinematics(robot.model, robot.data, q)
    return pin.SE3(robot.data.oMi[robot.model.getJointId("nacelle")])


def _se3_error(a: pin.SE3, b: pin.SE3) -> float:
    return max(
        float(np.linalg.norm(a.translation - b.translation)),
        float(np.linalg.norm(pin.log3(a.rotation.T @ b.rotation))),
    )


def redundant_singularity_distance(robot: Robot, q: np.ndarray) -> float:
    """``1 / cond`` of ``A`` and ``B`` from all the relations ``A x_dot = B q_dot_a``.

    For a redundantly actuated robot (more actuators than degrees of freedom, e.g. the walker in
    mode PP) every actuator rate is tied to the platform twist: ``n_a`` relations, which
    :func:`pkdyn.analysis.kinematics.kinematic_models` truncates to ``m``. Here the orthonormal
    basis of all of them gives ``A`` (n_a, m) and ``B`` (n_a, n_a); the measure is the smaller of
    ``1 / cond(A)`` (over its ``m`` singular values: 0 when the platform can move with the
    actuators locked) and ``1 / cond(B)``. For a robot with as many relations as task components
    it is :func:`pkdyn.analysis.singularity.classify`'s ``distance``.

    Args:
        robot: The robot (a mode robot of the walker).
        q: Assembled configuration (nq,).

    Returns:
        The distance in ``[0, 1]``.

    """
    Jc = robot.constraints.jacobian(robot.data, q)
    rows = np.asarray(robot.task_rows, dtype=int)
    Jx = platform_jacobian(robot, q)[rows]
    a, p = np.asarray(robot.actuated_v), np.asarray(robot.passive_v)
    rel = _relations(Jc, Jx, a, p)
    _, s, Vt = np.linalg.svd(rel.R, full_matrices=False)
    k = numerics.rank_of(s, SINGULAR_TOL)
    n_a, m = a.size, rows.size
    B, A = Vt[:k, :n_a], -Vt[:k, n_a:]
    cond_A = _cond(np.linalg.svd(A, compute_uv=False), m)
    cond_B = _cond(np.linalg.svd(B, compute_uv=False), min(k, n_a))
    return float(min(1.0 / cond_A, 1.0 / cond_B))


def _efforts(r: Robot, phase: Phase, allocation: str, redundant: bool) -> EffortTrajectory:
    """Inverse dynamics of a phase; redundant actuation distributes within the force limits.

    Where no distribution within the limits exists, the unbounded one is reported (its largest
    force then exceeds the limit: a violation).
    """
    jt, W = phase.trajectory, phase.wrench
    if redundant:
        try:
            return inverse_dynamics(
                r, jt, wrench=W, limits=True, progress=False, allocation=allocation
            )
        except InfeasibleEffortError:
            pass
    return inverse_dynamics(r, jt, wrench=W, progress=False, allocation=allocation)


def _analyse_phase(
    robot: Robot,
    phase: Phase,
    checkers: tuple[CollisionChecker, CollisionChecker],
    stride: int,
    allocation: str,
) -> tuple[PhaseReport, dict[str, np.ndarray]]:
    r = phase.robot
    jt = phase.trajectory
    N = jt.t.size
    lock_names = {lk.name for lk in phase.mode.locks}
    closures = r.constraints.rebuilt(
        closures=[c for c in r.constraints.closure_specs if c.name not in lock_names]
    )
    data = r.model.createData()
    lo = r.model.lowerPositionLimit[r.actuated_q]
    hi = r.model.upperPositionLimit[r.actuated_q]
    branches = branch_numbers(robot)
    clamped = [b for b in branches if b != phase.branch]
    targets = phase.mode.lock_targets()
    redundant = len(r.actuators) > r.mobility(jt.q[0])
    effort = _efforts(r, phase, allocation, redundant)
    res = np.empty(N)
    lock = np.zeros(N)
    support = np.empty(N)
    margin = np.empty(N)
    d_ll = np.empty(N)
    d_ln = np.empty(N)
    sing = np.full(N, np.nan)
    nacelle = np.empty((N, 3))
    foot_xyz = np.empty((N, len(branches), 3))
    nacelle_id = robot.model.getJointId("nacelle")
    closest = ("", "")
    best = np.inf
    for k in range(N):
        q = jt.q[k]
        res[k] = float(np.max(np.abs(closures.residual(data, q))))
        if targets.size:
            d = phase.mode.lock_vector(robot, q) - targets
            lock[k] = float(np.max(np.abs(np.arctan2(np.sin(d), np.cos(d)))))
        feet = [foot_placement(robot, q, b) for b in branches]  # runs the kinematics
        nacelle[k] = robot.data.oMi[nacelle_id].translation
        foot_xyz[k] = [f.translation for f in feet]
        support[k] = max(_se3_error(feet[b - 1], phase.stance.footholds[b - 1]) for b in clamped)
        qa = q[r.actuated_q]
        margin[k] = float(np.min(np.minimum(qa - lo, hi - qa)))
        dist = [c.distances(q) for c in checkers]
        d_ll[k], d_ln[k] = float(dist[0].min()), float(dist[1].min())
        for c, dd in zip(checkers, dist, strict=True):
            i = int(np.argmin(dd))
            if dd[i] < best:
                best, closest = float(dd[i]), c.names[i]
        if k % stride == 0 or k == N - 1:
            if redundant:
                sing[k] = redundant_singularity_distance(r, q)
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sing[k] = classify(r, q).distance
    end_error = None
    if phase.planned_end is not None:
        end_error = _se3_error(_nacelle(robot, jt.q[-1]), phase.planned_end)
    lock_plan_error = None
    if phase.planned_locks is not None:
        b = phase.planned_locks  # [q1, q2, q3, q6, (q1_j, q1_k)]; locks: [q2, q1], q3, q6, ...
        planned = np.concatenate([[b[1], b[0], b[2], b[3]], b[4:]])
        lock_plan_error = float(np.max(np.abs(targets - planned)))
    report = PhaseReport(
        name=phase.name,
        mode=phase.mode.kind,
        branch=phase.branch,
        locked=list(phase.mode.locked),
        t0=phase.t0,
        duration=float(jt.t[-1]),
        samples=N,
        max_closure_residual=float(res.max()),
        max_lock_drift=float(lock.max()),
        max_support_drift=float(support.max()),
        max_actuator_force=float(np.max(np.abs(effort.tau))),
        max_actuator_speed=float(np.max(np.abs(jt.qa_dot))),
        min_stroke_margin=float(margin.min()),
        min_leg_distance=float(min(d_ll.min(), d_ln.min())),
        min_leg_to_leg=float(d_ll.min()),
        min_leg_to_nacelle=float(d_ln.min()),
        closest_pair=closest,
        min_singularity_distance=float(np.nanmin(sing)),
        max_dynamics_residual=float(np.max(effort.residual)),
        end_error=end_error,
        lock_plan_error=lock_plan_error,
        redundancy=None if phase.redundancy is None else phase.redundancy.to_json(),
    )
    series = {
        "tau": effort.tau,
        "margin": margin,
        "distance": np.minimum(d_ll, d_ln),
        "singularity": sing,
        "nacelle": nacelle,
        "feet": foot_xyz,
    }
    return report, series


def analyse(
    robot: Robot,
    phases: list[Phase],
    stride: int = 1,
    progress: bool | None = None,
    allocation: str = "norm",
) -> ScenarioReport:
    """Run every check on every phase.

    Args:
        robot: The library tripod (or walker), loaded with its collision geometry.
        phases: From :func:`pkdyn.tripod.scenario.plan_scenario`.
        stride: Evaluate the singularity margin every ``stride`` samples (and at each phase's
            last sample).
        progress: Progress bar over the phases: ``True`` / ``False`` force it on / off, ``None``
            (default) shows it when stderr is a terminal.
        allocation: Effort distribution of redundant actuation (the walker in PP): ``"norm"``
            or ``"max"`` (see :func:`pkdyn.dynamics.inverse_dynamics`).

    Returns:
        The report.

    """
    leg_leg, leg_nacelle = leg_pairs(len(branch_numbers(robot)))
    checkers = (CollisionChecker(robot, leg_leg), CollisionChecker(robot, leg_nacelle))
    iterator = progress_bar(phases, "checks", "phase", progress)
    reports: list[PhaseReport] = []
    series: dict[str, list[np.ndarray]] = {
        k: [] for k in ("tau", "margin", "distance", "singularity", "nacelle", "feet")
    }
    t, idx, Q = [], [], []
    for k, phase in enumerate(iterator):
        rep, s = _analyse_phase(robot, phase, checkers, max(1, int(stride)), allocation)
        reports.append(rep)
        for key, val in s.items():
            series[key].append(val)
        t.append(phase.t0 + phase.trajectory.t)
        idx.append(np.full(phase.trajectory.t.size, k))
        Q.append(phase.trajectory.q)
    return ScenarioReport(
        phases=phases,
        reports=reports,
        t=np.concatenate(t),
        phase=np.concatenate(idx),
        q=np.vstack(Q),
        tau=np.vstack(series["tau"]),
        stroke_margin=np.concatenate(series["margin"]),
        leg_distance=np.concatenate(series["distance"]),
        singularity_distance=np.concatenate(series["singularity"]),
        nacelle=np.vstack(series["nacelle"]),
        feet=np.concatenate(series["feet"]),
        actuators=list(robot.actuator_names),
        effort_limit=float(min(a.effort for a in robot.actuators)),
        speed_limit=float(min(a.velocity for a in robot.actuators)),
    )


def run_scenario(
    robot: Robot,
    plan: WalkPlan | None = None,
    stride: int = 1,
    progress: bool | None = None,
    allocation: str = "norm",
) -> ScenarioReport:
    """Plan the scenario (:func:`pkdyn.tripod.scenario.plan_scenario`) and check it.

    Args:
        robot: The library tripod (or walker), loaded with its collision geometry.
        plan: Scenario parameters.
        stride: Singularity-margin sampling stride (see :func:`analyse`).
        progress: Progress bars: ``True`` / ``False`` force them on / off, ``None`` (default)
            shows them when stderr is a terminal.
        allocation: Effort distribution of the walker's redundant actuation (see
            :func:`analyse`).

    Returns:
        The report.

    """
    phases = plan_scenario(robot, plan, progress=progress)
    return analyse(robot, phases, stride, progress, allocation)
