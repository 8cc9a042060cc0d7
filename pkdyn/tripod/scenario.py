"""The machining-and-walking scenario of seed 003 (section 3.2), planned with PP and BE modes.

One cycle of the walk, from a station where the nacelle is level above the centroid of the
footholds (its *home*):

1. **machining** (PP): the cycle of :mod:`pkdyn.tripod.machining` on the skin under the nacelle;
2. for each branch ``i = 1, 2, 3`` in turn:

   - **reconfiguration** (PP): the nacelle moves to the pose ``x_re`` at which the lockable
     joints reach the values ``b_i`` wanted for the swing, then the locks engage;
   - **swing** (BE, branch ``i``): foot ``i`` is released and carried by the six actuators to
     its new foothold (moved by ``step`` on the support, lifted ``lift`` halfway), the
     locks holding; it is clamped there;

3. **reconfiguration** (PP): the nacelle returns level above the new centroid, the next station.

Never more than one branch is detached. The wanted locked values come from the pose the nacelle
should have when the swing ends, ``x_end``: above the new centroid, tilted by ``tilt`` about the
horizontal axis normal to branch ``i``: ``b_i = B_iIKMX(x_end, new footholds)``. Then
``x_re = XFKMB_i(b_i, old footholds)`` (the paper's two geometric models). The tilt matters: with
a level nacelle every support edge ``P_L P_R`` is parallel to the support, so the locked ``q1``
of the supports do not react to a nacelle translation and the nacelle can slide along the
swinging branch's rod ``L`` with the foot at rest — a serial singularity of mode BE (the tests
show it); a tilt of 0.1 rad keeps ``cond(B)`` below about 10 (on the plane). When that axis
leaves less than :data:`SEARCH_MARGIN` of stroke at ``x_re`` or ``x_end``, the best of twelve
horizontal tilt axes is used instead.

The support is the plane ``z = 0`` or, as an option (``surface_radius``), a cylinder of axis
``y`` cresting at the origin: walking along ``x`` across its curvature, each foot lands with a
new sole attitude, and the swing turns the foot evenly from the old attitude to the new one.
With the swinging foot rigid to rod ``L`` (locks), a turn of the foot needs a large motion of
the nacelle (its sensitivity is the conditioning of mode BE), so the tilt axis matters there.

Each phase is mapped to joint space by :func:`pkdyn.dynamics.trajectory.map_task_trajectory` on the
mode's robot (:func:`pkdyn.tripod.modes.mode_robot`): the spindle tip is the platform in PP, the
swinging foot in BE, and the locks are constraints of that robot, so ``(q, v, a)`` satisfy the
closures, the clamps and the locks to second order.

**The four-branch walker** (``pkdyn.load("tripod", branches=4)``) walks by the same plan, one
branch after the other (four swings per cycle). Its locks leave the nacelle two degrees of
freedom while a foot swings, so it needs no special pose for them: each reconfiguration brings the
nacelle level above the centroid of the feet (the station home; ``tilt`` is the tripod's only), the
locks engage there, and the swing's nacelle path is chosen by
:func:`pkdyn.tripod.redundancy.plan_swing`, which keeps the legs apart (the phase's
``redundancy``), then mapped with the swinging branch's two actuator lengths prescribed
(:func:`pkdyn.dynamics.redundant.map_redundant_trajectory`). Should the chosen path ask an actuator
for more than its force limit (inverse dynamics), its departure from the baseline is halved until
it does not (down to the baseline). Its PP phases are mapped by the same function with nothing
prescribed: eight actuators drive a 6-DOF nacelle, a redundant actuation that
:func:`~pkdyn.dynamics.trajectory.map_task_trajectory`'s square kinematic models do not describe.
A plan the walker cannot do stops with an error naming the phase, the branch and the limit: a new
foothold out of reach (an actuator beyond its stroke at the landing), a swing whose legs would
interfere whatever the nacelle does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.dynamics.inverse import inverse_dynamics
from pkdyn.dynamics.profiles import motion_law
from pkdyn.dynamics.redundant import map_redundant_trajectory
from pkdyn.dynamics.trajectory import (
    JointTrajectory,
    TaskTrajectory,
    map_task_trajectory,
    point_to_point,
)
from pkdyn.exceptions import InvalidInputError, PkdynError, TrajectoryError, UnreachablePoseError
from pkdyn.inputs import count, non_negative, positive, real
from pkdyn.library import tripod
from pkdyn.model.assembly import inverse_geometry
from pkdyn.model.pose import pose_to_vector
from pkdyn.model.robot import Robot
from pkdyn.progress import progress_steps
from pkdyn.tripod.machining import MachiningPlan, machining_task
from pkdyn.tripod.modes import (
    Mode,
    Stance,
    be_mode,
    branch_numbers,
    foot_frame,
    mode_robot,
    pp_mode,
)
from pkdyn.tripod.redundancy import RedundancySettings, SwingSolution, plan_swing
from pkdyn.tripod.xfkmb import actuator_lengths, bikmx, xfkmb

__all__ = [
    "MAX_SCENARIO_SAMPLES",
    "WALKER_TOL",
    "Phase",
    "WalkPlan",
    "foothold",
    "plan_scenario",
    "station_home",
    "swing_task",
    "tool_pose",
]


@dataclass(frozen=True)
class WalkPlan:
    """Parameters of the scenario (SI units).

    Attributes:
        step: Displacement of every foot per cycle on the support ``(dx, dy)`` [m].
        cycles: Number of cycles (machining + three swings + return to level).
        lift: Height of the swinging foot's arc above the straight path [m].
        tilt: Nacelle tilt at the end of each swing [rad] (keeps mode BE away from its
            serial singularity, see the module docstring).
        swing_time: Duration of a swing [s].
        reconfiguration_time: Duration of a reconfiguration move [s].
        dt: Sample period [s].
        machining: Machining cycle at each station (``None``: walk only).
        surface_radius: Radius [m] of the support: ``inf`` for the plane ``z = 0``; otherwise
            the cylinder of axis ``y`` cresting at ``z = 0`` above the origin (a surface of
            moderate curvature crossed by a walk along ``x``: every step changes the feet's
            attitude).
        redundancy: The walker's redundancy resolution while swinging
            (:class:`pkdyn.tripod.redundancy.RedundancySettings`; unused by the tripod).

    """

    step: tuple[float, float] = (0.10, 0.0)
    cycles: int = 2
    lift: float = 0.03
    tilt: float = 0.10
    swing_time: float = 2.5
    reconfiguration_time: float = 1.5
    dt: float = 0.05
    machining: MachiningPlan | None = field(default_factory=MachiningPlan)
    surface_radius: float = math.inf
    redundancy: RedundancySettings = field(default_factory=RedundancySettings)

    def __post_init__(self) -> None:
        radius = self.surface_radius
        if not (isinstance(radius, int | float) and not isinstance(radius, bool) and radius > 1.0):
            raise InvalidInputError(
                "surface_radius", f"must be > 1 m (inf: a plane), got {radius!r}"
            )
        if not isinstance(self.step, tuple | list | np.ndarray) or len(self.step) != 2:
            raise InvalidInputError("step", f"expected two numbers (dx, dy) [m], got {self.step!r}")
        for k, x in zip(("dx", "dy"), self.step, strict=True):
            real(f"step {k}", x, "m", bound=MAX_STEP)
        n = count("cycles", self.cycles, maximum=MAX_CYCLES)
        times = [positive(k, getattr(self, k), "s") for k in ("swing_time", "reconfiguration_time")]
        dt = positive("dt", self.dt, "s")
        if min(times) < 2.0 * dt:
            raise InvalidInputError(
                "dt",
                f"{dt:g} s samples the {min(times):g} s move fewer than 2 times: the motion "
                f"would be missed; use dt <= {min(times) / 10:.3g} s",
            )
        non_negative("lift", self.lift, "m", bound=MAX_STEP)
        non_negative("tilt", self.tilt, "rad", bound=math.pi / 2)
        samples = n * PHASES_PER_CYCLE * max(times) / dt
        if samples > MAX_SAMPLES:
            raise InvalidInputError(
                "dt",
                f"{n} cycles of phases up to {max(times):g} s sampled every {dt:g} s are up to "
                f"{samples:.3g} samples (each an inverse geometry and dynamics, ~1 ms); at most "
                f"{MAX_SAMPLES:.0e}: fewer cycles, shorter phases or a longer dt",
            )


MAX_STEP = 1.0
"""Largest foot displacement per cycle and foot lift [m]: beyond the walker's size."""

MAX_CYCLES = 1000
"""Most walking cycles of one scenario."""

PHASES_PER_CYCLE = 10
"""Most phases of one cycle (the walker: a reconfiguration and a swing per branch, machining
and the return to level)."""

MAX_SAMPLES = 200_000
"""Most samples of one scenario (the default plan has 800): larger plans are refused up front."""


@dataclass
class Phase:
    """One phase of the scenario, mapped to joint space.

    Attributes:
        name: ``machining``, ``reconfiguration`` or ``swing``.
        mode: Mode (PP, or BE with its locks).
        stance: Footholds during the phase (the swinging foot's is its start).
        robot: The mode's robot (constraints and platform of the phase).
        trajectory: Joint trajectory (times from 0).
        t0: Start time of the phase in the scenario [s].
        wrench: Machining wrench on the platform per sample (N, 6), or ``None``.
        planned_locks: Lock values ``b_i`` from ``B_iIKMX`` (swings), in the order of
            :func:`pkdyn.tripod.modes.be_mode`.
        planned_end: Planned nacelle placement at the end of the phase (swings: ``x_end``;
            reconfigurations: ``x_re`` or the station home), or ``None``.
        landing: New foothold of the swinging foot (swings), or ``None``.
        redundancy: The walker's swings: the chosen nacelle path and its objective, or ``None``.

    """

    name: str
    mode: Mode
    stance: Stance
    robot: Robot
    trajectory: JointTrajectory
    t0: float
    wrench: np.ndarray | None = None
    planned_locks: np.ndarray | None = None
    planned_end: pin.SE3 | None = None
    landing: pin.SE3 | None = None
    redundancy: SwingSolution | None = None

    @property
    def branch(self) -> int | None:
        """Swinging branch (BE), ``None`` in PP."""
        return self.mode.branch


def _params(robot: Robot) -> tripod.Params:
    if robot.family != "tripod":
        raise PkdynError(
            f"{robot.name}: the scenario needs the library tripod (pkdyn.load('tripod'))"
        )
    return robot.params


def station_home(p: tripod.Params, stance: Stance) -> pin.SE3:
    """Level nacelle placement above the centroid of the footholds.

    ``P_O`` is ``nacelle_height - foot_height`` above the centroid of the foot-frame origins
    (``nacelle_height`` above the support on a plane).
    """
    c = stance.centroid()
    return pin.SE3(np.eye(3), np.array([c[0], c[1], c[2] + p.nacelle_height - p.foot_height]))


def foothold(p: tripod.Params, x: float, y: float, heading: float, radius: float) -> pin.SE3:
    """Foot frame ``R_A`` of a foot clamped at ``(x, y)`` on the support, sole normal ``w_a``.

    Args:
        p: Tripod parameters.
        x: Position of the foothold along ``x`` [m].
        y: Position along ``y`` [m].
        heading: Angle of ``u_a`` about the normal [rad] (``phi_i``: radial at home).
        radius: Support radius [m] (``inf``: the plane ``z = 0``; else the cylinder of axis
            ``y`` through ``(0, 0, -radius)``, ``x`` measured along its surface).

    Returns:
        The frame: origin ``foot_height`` above the surface along its normal.

    """
    if math.isinf(radius):
        R, point = np.eye(3), np.array([x, y, 0.0])
    else:
        alpha = x / radius  # arc length along the crest
        R = pin.exp3(np.array([0.0, alpha, 0.0]))
        point = np.array([radius * math.sin(alpha), y, radius * (math.cos(alpha) - 1.0)])
    R = R @ pin.exp3(np.array([0.0, 0.0, heading]))
    return pin.SE3(R, point + p.foot_height * R[:, 2])


def _stance(p: tripod.Params, xy: np.ndarray, radius: float) -> Stance:
    angles = tripod_cf.branch_angles(p)
    return Stance(tuple(foothold(p, xy[i, 0], xy[i, 1], a, radius) for i, a in enumerate(angles)))


def tool_pose(p: tripod.Params, nacelle: pin.SE3) -> np.ndarray:
    """Spindle-tip pose ``[x, y, z, roll, pitch, yaw]`` of a nacelle placement [m, rad]."""
    M = nacelle * pin.SE3(np.eye(3), np.array([0.0, 0.0, -p.tool_offset]))
    pos, rpy = pose_to_vector(M)
    return np.concatenate([pos, rpy])


def _pose(M: pin.SE3) -> np.ndarray:
    pos, rpy = pose_to_vector(M)
    return np.concatenate([pos, rpy])


def swing_task(start: pin.SE3, end: pin.SE3, lift: float, T: float, dt: float) -> TaskTrajectory:
    """Swinging-foot trajectory: straight from ``start`` to ``end`` plus a lift, turning evenly.

    With the quintic rest-to-rest law ``s(t)``, the foot frame's origin ``A`` follows
    ``A0 + s (A1 - A0) + 4 lift s (1 - s) w`` (``w`` the mean of the two sole normals) and its
    orientation ``R0 exp(s omega)`` with ``omega = log3(R0^T R1)`` (constant axis in the foot
    frame), so the foot turns from the old sole attitude to the new one.

    Args:
        start: Foot frame ``R_A`` at the old foothold.
        end: Foot frame ``R_A`` at the new foothold.
        lift: Height of the arc [m].
        T: Duration [s].
        dt: Sample period [s].

    Returns:
        The trajectory of the foot link frame (the BE platform), in the pose-vector form of
        :class:`pkdyn.dynamics.trajectory.TaskTrajectory` (roll-pitch-yaw rates from the angular
        velocity).

    """
    n = max(2, int(round(T / dt)) + 1)
    t = np.linspace(0.0, T, n)
    s, sd, sdd = motion_law("quintic", T)(t)
    F0, F1 = foot_frame(start), foot_frame(end)
    A0, A1 = np.array(start.translation), np.array(end.translation)
    w = np.array(start.rotation[:, 2] + end.rotation[:, 2])
    w /= np.linalg.norm(w)
    d = A1 - A0
    omega = pin.log3(F0.rotation.T @ F1.rotation)  # foot-frame axis, constant
    pose = np.zeros((n, 6))
    pose[:, :3] = A0 + np.outer(s, d) + np.outer(4.0 * lift * s * (1.0 - s), w)
    dp = d + np.outer(4.0 * lift * (1.0 - 2.0 * s), w)  # dA/ds
    pd = np.zeros((n, 6))
    pd[:, :3] = dp * sd[:, None]
    pdd = np.zeros((n, 6))
    pdd[:, :3] = dp * sdd[:, None] + np.outer(-8.0 * lift * sd**2, w)
    local = pin.ReferenceFrame.LOCAL
    for k in range(n):
        rpy = pin.rpy.matrixToRpy(F0.rotation @ pin.exp3(s[k] * omega))
        E = pin.rpy.computeRpyJacobian(rpy, local)  # omega_local = E rpy_dot
        rpy_d = np.linalg.solve(E, omega * sd[k])
        Ed = pin.rpy.computeRpyJacobianTimeDerivative(rpy, rpy_d, local)
        pose[k, 3:] = rpy
        pd[k, 3:] = rpy_d
        pdd[k, 3:] = np.linalg.solve(E, omega * sdd[k] - Ed @ rpy_d)
    return TaskTrajectory(t, pose, pd, pdd, name="swing")


SEARCH_MARGIN = 0.05
"""Stroke margin [m] below which the tilt axis of ``x_end`` is searched (see
:func:`_swing_poses`)."""


def _tilted(p: tripod.Params, stance: Stance, psi: float, tilt: float) -> pin.SE3:
    """Station home turned by ``tilt`` about the horizontal axis at angle ``psi``."""
    axis = np.array([math.cos(psi), math.sin(psi), 0.0])
    return pin.SE3(pin.exp3(tilt * axis), station_home(p, stance).translation)


def _stroke_margin(p: tripod.Params, lengths: np.ndarray) -> float:
    return float(min(lengths.min() - p.stroke_min, p.stroke_max - lengths.max()))


def _swing_poses(
    p: tripod.Params, stance: Stance, landed: Stance, branch: int, tilt: float
) -> tuple[pin.SE3, np.ndarray, pin.SE3]:
    """``x_end``, ``b_i = B_iIKMX(x_end, landed)`` and ``x_re = XFKMB_i(b_i, stance)``.

    ``x_end`` is the station home above ``landed`` tilted by ``tilt`` about the horizontal axis
    normal to branch ``i``; if this leaves less than :data:`SEARCH_MARGIN` of stroke at
    ``x_re`` or ``x_end`` (it happens on curved supports, where the swing turns the foot), the
    best of twelve horizontal axes is taken (largest smallest stroke margin).
    """
    default = tripod_cf.PHI[branch - 1] + 0.5 * math.pi
    best: tuple[float, pin.SE3, np.ndarray, pin.SE3] | None = None
    error: Exception | None = None
    for psi in [default] + [default + k * math.pi / 6.0 for k in range(1, 12)]:
        x_end = _tilted(p, landed, psi, tilt)
        b_i = bikmx(p, x_end, landed, branch)
        try:
            res = xfkmb(p, b_i, stance, branch, x_end, check_limits=False)
        except UnreachablePoseError as err:
            error = err
            continue
        m = min(
            _stroke_margin(p, res.lengths), _stroke_margin(p, actuator_lengths(p, x_end, landed))
        )
        if best is None or m > best[0]:
            best = (m, x_end, b_i, res.placement)
        if best[0] >= SEARCH_MARGIN:
            break
    if best is None or best[0] < 0.0:
        why = (
            f"the best leaves its stroke by {-best[0]:.4g} m"
            if best is not None
            else f"XFKMB_{branch} failed: {error}"
        )
        raise TrajectoryError(
            f"swing of branch {branch}: no reconfiguration pose keeps the locks the swing needs "
            f"within the strokes ({why}); shorten the step or change the tilt"
        )
    return best[1], best[2], best[3]


def _nacelle(robot: Robot, q: np.ndarray) -> pin.SE3:
    pin.forwardKinematics(robot.model, robot.data, q)
    return pin.SE3(robot.data.oMi[robot.model.getJointId("nacelle")])


WALKER_TOL = 1e-13
"""Closure, clamp, lock and task residual [m or rad] to which the walker's phases are mapped (its
clamped feet then stay within 1e-12 m of their footholds)."""


def _map(robot: Robot, task: TaskTrajectory, q: np.ndarray, redundant: bool) -> JointTrajectory:
    """A PP phase to joint space (the walker's redundant actuation: nothing prescribed)."""
    if not redundant:
        return map_task_trajectory(robot, task, q_init=q, check_limits=False, progress=False)
    none = np.zeros((task.t.size, 0))
    return map_redundant_trajectory(robot, task, (), none, none, none, q, tol=WALKER_TOL)


def _actuator_name(k: int) -> str:
    return f"branch{k // 2 + 1}_q{'LR'[k % 2]}"


def _check_swing(p: tripod.Params, sol: SwingSolution, where: str, landing: bool = True) -> None:
    """Stop a walker's swing that leaves a stroke or makes its legs interfere."""
    c = sol.clearances
    L = c.lengths
    over = np.maximum(p.stroke_min - L, L - p.stroke_max)
    k, i = np.unravel_index(int(np.argmax(over)), over.shape)
    if over[k, i] > 0.0:
        if k == L.shape[0] - 1:
            what, at, fix = "the new foothold is out of reach", "at the landing", "shorten the step"
        else:
            what, fix = "the foot's path leaves the workspace", "lower the lift or shorten the step"
            at = f"at t = {sol.t[k] - sol.t[0]:.3g} s of the swing"
        raise TrajectoryError(
            f"{where}: {what}: actuator '{_actuator_name(int(i))}' would need {L[k, i]:.4g} m "
            f"{at}, beyond its stroke [{p.stroke_min}, {p.stroke_max}] m whatever the nacelle "
            f"does; {fix}"
        )
    j = int(np.argmin(c.distance))
    if c.distance[j] < 0.0:
        a, b = c.closest[j]
        raise TrajectoryError(
            f"{where}: {a} and {b} would interfere (clearance {1e3 * c.distance[j]:.3g} mm < 0 "
            f"at t = {sol.t[j] - sol.t[0]:.3g} s) even with the nacelle path optimised; change "
            "the step, the lift or the dimensions"
        )


def _walker_swing(
    robot: Robot,
    plan: WalkPlan,
    stance: Stance,
    q: np.ndarray,
    branch: int,
    old: pin.SE3,
    new_foot: pin.SE3,
    target: pin.SE3,
    where: str,
) -> tuple[Mode, Robot, JointTrajectory, SwingSolution]:
    """The walker's swing: locks engaged at ``q``, nacelle path chosen, mapped, forces checked."""
    p = _params(robot)
    mode = be_mode(robot, q, branch)  # the locks engage where the joints stand
    r = mode_robot(robot, stance, mode, q)
    task = swing_task(old, new_foot, plan.lift, plan.swing_time, plan.dt)
    sol = plan_swing(p, stance, branch, _nacelle(robot, q), task, target, plan.redundancy)
    _check_swing(p, sol, where)
    effort = np.array([a.effort for a in robot.actuators])
    while True:
        jt = map_redundant_trajectory(
            r, task, sol.joints, sol.r, sol.r_d, sol.r_dd, q, tol=WALKER_TOL
        )
        if not sol.optimised:
            break
        tau = inverse_dynamics(r, jt, progress=False).tau
        if np.all(np.abs(tau) <= effort):
            break
        sol = sol.rescaled(0.5 if sol.scale > 0.2 else 0.0)
    return mode, r, jt, sol


MAX_SCENARIO_SAMPLES = 200_000
"""Most samples of a scenario (each is mapped to joint space and checked: a few ms)."""


def _check_work(p: tripod.Params, plan: WalkPlan, branches: int) -> None:
    """Refuse a plan whose samples exceed :data:`MAX_SCENARIO_SAMPLES` or whose lift is absurd.

    Raises:
        InvalidInputError: Too many samples (the estimate given), or a lift longer than the
            actuators.

    """
    if plan.lift > p.stroke_max:
        raise InvalidInputError(
            "lift",
            f"{plan.lift:g} m is more than the longest actuator ({p.stroke_max:g} m): no foot "
            "can be lifted that high",
        )
    swing = plan.swing_time / plan.dt
    moves = plan.reconfiguration_time / plan.dt
    per_cycle = branches * (swing + moves) + moves
    if plan.machining is not None:
        per_cycle += _machining_duration(plan.machining) / plan.dt
    total = plan.cycles * per_cycle
    if total > MAX_SCENARIO_SAMPLES:
        raise InvalidInputError(
            "scenario",
            f"{plan.cycles:g} cycles of about {per_cycle:.3g} samples (dt = {plan.dt:g} s) is "
            f"{total:.3g} samples, more than {MAX_SCENARIO_SAMPLES:,} (each is mapped and "
            f"checked, a few ms: about {total * 3e-3 / 3600:.2g} h); fewer cycles, shorter "
            "phases or a longer dt",
        )


def _machining_duration(m: MachiningPlan) -> float:
    """Upper bound of a machining cycle's duration [s] (every move, plunge and retract)."""
    holes = len(m.holes_y)
    return (holes + 3) * m.move_time + 2 * (holes + 1) * m.plunge_time + m.contour_time


def plan_scenario(
    robot: Robot, plan: WalkPlan | None = None, progress: bool | None = None
) -> list[Phase]:
    """Plan the scenario and map every phase to joint space.

    Args:
        robot: The library tripod at its home configuration (``pkdyn.load("tripod")``), or the
            walker (``pkdyn.load("tripod", branches=4)``).
        plan: Scenario parameters (default :class:`WalkPlan`).
        progress: Progress bar over the phases: ``True`` / ``False`` force it on / off, ``None``
            (default) shows it when stderr is a terminal.

    Returns:
        The phases in order; each ends where the next starts, at rest.

    Raises:
        PkdynError: Not the library tripod.
        InvalidInputError: More samples than :data:`MAX_SCENARIO_SAMPLES`, or a lift longer
            than the actuators (refused before any work).
        TrajectoryError: ``XFKMB_i`` finds no reconfiguration pose within the strokes (step
            too long), or a phase leaves the workspace or meets a parallel singularity; the
            walker: a new foothold out of reach or legs that would interfere (the message names
            the phase, the branch and the limit).

    """
    plan = WalkPlan() if plan is None else plan
    p = _params(robot)
    branches = branch_numbers(p)
    walker = len(branches) != 3
    radius = plan.surface_radius
    xy = np.array([np.array(f.translation[:2]) for f in tripod_cf.foothold_frames(p)])
    angles = tripod_cf.branch_angles(p)
    stance = _stance(p, xy, radius)
    q = np.array(robot.q_home)
    if not math.isinf(radius):  # stand on the surface first: assemble the clamped robot there
        r = mode_robot(robot, stance, pp_mode(), q)
        q = inverse_geometry(r, tool_pose(p, station_home(p, stance)), q, check_limits=False).q
    phases: list[Phase] = []
    t0 = 0.0
    step = np.array(plan.step, dtype=float)
    per_cycle = 2 * len(branches) + (2 if plan.machining is not None else 1)
    n_phases = plan.cycles * per_cycle
    _check_work(p, plan, len(branches))

    def add(phase: Phase) -> np.ndarray:
        nonlocal t0
        phases.append(phase)
        t0 += float(phase.trajectory.t[-1])
        advance()
        return np.array(phase.trajectory.q[-1])

    def move_nacelle(target: pin.SE3, q: np.ndarray) -> np.ndarray:
        r = mode_robot(robot, stance, pp_mode(), q)
        task = point_to_point(
            tool_pose(p, _nacelle(robot, q)),
            tool_pose(p, target),
            plan.reconfiguration_time,
            dt=plan.dt,
        )
        jt = _map(r, task, q, walker)
        return add(Phase("reconfiguration", pp_mode(), stance, r, jt, t0, planned_end=target))

    with progress_steps(n_phases, "tripod scenario", "phase", progress) as advance:
        for cycle in range(plan.cycles):
            if plan.machining is not None:
                r = mode_robot(robot, stance, pp_mode(), q)
                task, W = machining_task(
                    plan.machining, tool_pose(p, station_home(p, stance)), dt=plan.dt
                )
                jt = _map(r, task, q, walker)
                q = add(Phase("machining", pp_mode(), stance, r, jt, t0, wrench=W))
            for b in branches:
                old = stance.footholds[b - 1]
                xy[b - 1] += step
                new_foot = foothold(p, xy[b - 1, 0], xy[b - 1, 1], angles[b - 1], radius)
                landed = stance.moved(b, new_foot)
                if walker:
                    home = station_home(p, stance)
                    q = move_nacelle(home, q)
                    where = f"phase {len(phases)} (cycle {cycle + 1}, swing of branch {b})"
                    mode, r, jt, sol = _walker_swing(
                        robot, plan, stance, q, b, old, new_foot, station_home(p, landed), where
                    )
                    planned: tuple[np.ndarray, pin.SE3, SwingSolution | None] = (
                        bikmx(p, home, stance, b),
                        sol.end(),
                        sol,
                    )
                else:
                    x_end, b_i, x_re = _swing_poses(p, stance, landed, b, plan.tilt)
                    q = move_nacelle(x_re, q)
                    mode = be_mode(robot, q, b)  # the locks engage where the joints stand
                    r = mode_robot(robot, stance, mode, q)
                    task = swing_task(old, new_foot, plan.lift, plan.swing_time, plan.dt)
                    jt = map_task_trajectory(r, task, q_init=q, check_limits=False, progress=False)
                    planned = (b_i, x_end, None)
                phase = Phase(
                    "swing",
                    mode,
                    stance,
                    r,
                    jt,
                    t0,
                    planned_locks=planned[0],
                    planned_end=planned[1],
                    landing=new_foot,
                    redundancy=planned[2],
                )
                q = add(phase)
                stance = landed
            q = move_nacelle(station_home(p, stance), q)
    return phases
