"""The fastest cycle whose tool settles within a band during a dwell, with and without shaping.

The torque- and speed-limited fastest motion along the path
(:func:`pkdyn.dynamics.fastest.fastest_trajectory`, a rigid robot) is the starting point. Its
uniform slow-downs by ``scale >= 1`` (times ``scale t``, efforts
``C + (tau - C) / scale^2``: within the limits) are searched for the smallest whose tool,
after the motion, settles within the band before the end of the dwell
(:mod:`pkdyn.precision.vibration_figures`): a scan in steps of :data:`SCAN_STEP` from
``scale = 1`` up to ``max_scale``, then bisection between the last failing and the first
settling scale (the settling time is not monotonic in the speed: the scan keeps the first
settling one). The motion time reported is the slowed motion's; the cycle is the motion plus
the dwell.

- **Without shaping**, the modal method (:mod:`pkdyn.precision.vibration_modal`) runs on the
  path itself: the modes at poses along it are computed once; the unbalanced force is
  ``F0 + F1 / scale + F2 / scale^2`` (gravity and feedforward at rest; the dampers; the
  inertial part, quadratic in the speeds), with toppra's accelerations constant over each path
  interval (the forcing jumps at the samples, as the command's acceleration does).
- **With shaping** (``zv``, ``zvd``: :mod:`pkdyn.precision.vibration_shaping`), each slowed
  motion is shaped, its frequencies tracked along the path, then mapped and analysed as any
  command (:func:`pkdyn.precision.vibration.analyse`); the shaped motion lasts longer by the
  shaper's delay, counted in its motion time.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.dynamics.fastest import FastestResult, fastest_trajectory
from pkdyn.dynamics.trajectory import TaskTrajectory
from pkdyn.exceptions import InvalidInputError
from pkdyn.model.robot import PLATFORM_HINT, Robot
from pkdyn.precision.condensation import RANK_TOL, constraint_rows
from pkdyn.precision.elastic import elastic_model
from pkdyn.precision.material import Material
from pkdyn.precision.vibration import (
    DEFAULT_BAND,
    DEFAULT_DWELL,
    MAX_DWELL,
    Setup,
    _dominant,
    analyse,
    check_compliant,
    prepare,
    result,
    static_deflection,
)
from pkdyn.precision.vibration_command import Command, command, extended_motion, uniform
from pkdyn.precision.vibration_modal import (
    DEFAULT_POSES,
    DEFAULT_POSES_LINKS,
    modal_response,
    path_modes,
    pose_samples,
)
from pkdyn.precision.vibration_result import VibrationResult
from pkdyn.precision.vibration_shaping import SHAPERS, Shaper, shape, tracked
from pkdyn.results import Result, jsonable
from pkdyn.threads import one_blas_thread
from pkdyn.units import quantity
from solvers import numerics

__all__ = ["MAX_SCALE", "SCAN_STEP", "Settled", "SettledFastest", "fastest_settling"]

SCAN_STEP = 1.02
"""Ratio of two successive slow-downs of the scan (2 %)."""

MAX_SCALE = 4.0
"""Default largest slow-down searched."""

_BISECTIONS = 8


@dataclass(frozen=True, eq=False)
class Settled:
    """The fastest settling motion of one kind (unshaped or shaped).

    Attributes:
        shaper: ``None`` (unshaped), ``zv`` or ``zvd``.
        scale: Slow-down of the torque-limited fastest motion, or ``None``: none up to the
            largest searched settles.
        motion_time: Duration of the (slowed, shaped) motion [s], or ``None``.
        settling_time: Settling time after it [s], or ``None``.
        cycle_time: Motion plus dwell [s], or ``None``.
        evaluations: Motions analysed by the search.
        vibration: The analysis of the motion found (or of the slowest searched).

    """

    shaper: str | None
    scale: float | None
    motion_time: float | None
    settling_time: float | None
    cycle_time: float | None
    evaluations: int
    vibration: VibrationResult

    def to_json(self) -> dict[str, Any]:
        """JSON values (SI units)."""
        v = self.vibration
        return jsonable(
            {
                "shaper": self.shaper,
                "scale": self.scale,
                "motion_time": self.motion_time,
                "settling_time": self.settling_time,
                "cycle_time": self.cycle_time,
                "peak_deviation": v.peak_deviation,
                "residual_amplitude": v.residual_amplitude,
                "evaluations": self.evaluations,
            }
        )


@dataclass(eq=False)
class SettledFastest(Result):
    """The fastest cycles that settle, with and without shaping (module docstring).

    Attributes:
        robot: The robot's name.
        fastest: The torque- and speed-limited fastest motion (rigid robot).
        band: Settling band [m].
        dwell: Dwell within which the tool must settle [s].
        max_scale: Largest slow-down searched.
        unshaped: The fastest settling motion without shaping.
        shaped: The same with shaping, or ``None``.

    """

    robot: str
    fastest: FastestResult
    band: float
    dwell: float
    max_scale: float
    unshaped: Settled
    shaped: Settled | None

    def to_json(self) -> dict[str, Any]:
        """JSON values (SI units): the rigid fastest time and both settling motions."""
        v = self.unshaped.vibration
        return jsonable(
            {
                "robot": self.robot,
                "band": self.band,
                "dwell": self.dwell,
                "max_scale": self.max_scale,
                "fastest_motion_time": self.fastest.cycle_time,
                "unshaped": self.unshaped.to_json(),
                "shaped": None if self.shaped is None else self.shaped.to_json(),
                "frequencies": {"start": v.frequencies_start, "end": v.frequencies_end},
                "damping": v.damping.to_json(),
                "feedforward": v.feedforward,
                "method": "modal",
            }
        )

    def table(self) -> str:
        """The comparison as text, units on every figure."""
        lines = [
            f"settling within {quantity(self.band, 'm')} during a "
            f"{quantity(self.dwell, 's')} dwell (torque-limited motion: "
            f"{quantity(self.fastest.cycle_time, 's')}):"
        ]
        for s in (self.unshaped, self.shaped):
            if s is None:
                continue
            what = "unshaped" if s.shaper is None else f"{s.shaper.upper()}-shaped"
            if s.scale is None:
                lines.append(
                    f"  {what:<12} none settles up to {self.max_scale:g} times slower "
                    f"(residual {quantity(s.vibration.residual_amplitude, 'm')} at the "
                    "slowest): widen the band, lengthen the dwell or stiffen the robot"
                )
                continue
            assert s.motion_time is not None and s.settling_time is not None
            assert s.cycle_time is not None
            lines.append(
                f"  {what:<12} motion {quantity(s.motion_time, 's')} (x{s.scale:.4g}), settles "
                f"{quantity(s.settling_time, 's')} after it; cycle with the dwell "
                f"{quantity(s.cycle_time, 's')}"
            )
        if self.shaped is not None and self.shaped.cycle_time and self.unshaped.cycle_time:
            gain = 1.0 - self.shaped.cycle_time / self.unshaped.cycle_time
            lines.append(f"  shaping shortens the cycle by {100 * gain:.1f} %")
        return "\n".join(lines)


class _PathForcing:
    """The unbalanced force along the fastest motion as ``F0 + F1 / s + F2 / s^2``.

    Per path interval, its left and right values (toppra's acceleration is constant over an
    interval and jumps at the samples).
    """

    def __init__(self, st: Setup, fast: FastestResult) -> None:
        em = st.elastic
        r = em.robot
        traj = fast.trajectory
        Q, V, _ = extended_motion(st.em, traj)
        path = fast.path
        _, Vp, Ap = extended_motion(st.em, path)  # q'(s), q''(s)
        model, data = r.model, r.model.createData()
        iv = np.asarray(r.actuated_v)
        n, nv = Q.shape[0], r.nv
        zero = np.zeros(nv)
        P = r.passive
        tau_c = fast.C if st.feedforward != "none" else np.zeros_like(fast.C)
        rigid = st.feedforward == "rigid"
        self.t = traj.t
        # along each interval: s'' constant (u_i), s'^2 linear in s between the samples
        u = fast.segment_s_ddot
        x = fast.s_dot**2
        self.F0 = np.empty((n, nv))
        self.F1 = np.zeros((n, nv))
        A_l = np.empty((n, nv))  # inertial force per unit s'' (-M q')
        B_l = np.empty((n, nv))  # per unit s'^2 (-(M q'' + C(q') q'))
        self._N = []
        for k in range(n):
            g = pin.rnea(model, data, Q[k], zero, zero)
            f0 = -g
            if P is not None:
                f0 = f0 + P.force(Q[k], zero)
                self.F1[k] = P.force(Q[k], V[k]) - P.force(Q[k], zero)
            f0[iv] += tau_c[k]
            A_l[k] = -(pin.rnea(model, data, Q[k], zero, Vp[k]) - g)
            B_l[k] = -(pin.rnea(model, data, Q[k], Vp[k], Ap[k]) - g)
            rows = constraint_rows(em, Q[k])
            N = numerics.null_space(rows, RANK_TOL, scale=1.0) if rows.shape[0] else None
            self._N.append(N)
            self.F0[k] = f0
        if rigid:  # the rigid inverse dynamics' inertial part: C + (A u + B x) per interval
            A_l[:, iv] += fast.A
            B_l[:, iv] += fast.B
        self.A, self.B, self.u, self.x = A_l, B_l, u, x
        self.F0 = self._project(self.F0)
        self.F1 = self._project(self.F1)
        self.A = self._project(A_l)
        self.B = self._project(B_l)

    def _project(self, F: np.ndarray) -> np.ndarray:
        out = np.empty_like(F)
        for k, N in enumerate(self._N):
            out[k] = F[k] if N is None else N @ (N.T @ F[k])
        return out

    def ends(self, scale: float) -> tuple[np.ndarray, ...]:
        """``(t, F_left, F_right, F_left', F_right')`` of the motion slowed by ``scale``."""
        t = self.t * scale
        h = np.diff(t)[:, None]
        u = (self.u / scale**2)[:, None]
        x = self.x / scale**2
        F1 = self.F1 / scale
        base = self.F0 + F1
        FL = base[:-1] + self.A[:-1] * u + self.B[:-1] * x[:-1, None]
        FR = base[1:] + self.A[1:] * u + self.B[1:] * x[1:, None]
        slope = (FR - FL) / h
        return t, FL, FR, slope, slope

    def at_rest_end(self) -> np.ndarray:
        """The force at the end of the motion, at rest (nv,)."""
        return np.asarray(self.F0[-1])


def _search(
    evaluate: Callable[[float], VibrationResult], max_scale: float, step: float
) -> tuple[float | None, VibrationResult, int]:
    """The smallest slow-down that settles: scan by ``step`` ratios, then bisection."""
    count = 0
    lo = None
    scale = 1.0
    while True:
        res = evaluate(scale)
        count += 1
        if res.settled:
            break
        lo = scale
        if scale >= max_scale:
            return None, res, count
        scale = min(scale * step, max_scale)
    if lo is None:
        return 1.0, res, count
    hi, best = scale, res
    for _ in range(_BISECTIONS):
        mid = math.sqrt(lo * hi)
        trial = evaluate(mid)
        count += 1
        if trial.settled:
            hi, best = mid, trial
        else:
            lo = mid
    return hi, best, count


def _settled(kind: str | None, scale: float | None, v: VibrationResult, count: int) -> Settled:
    if scale is None or v.settling_time is None or not v.settled:
        return Settled(kind, None, None, None, None, count, v)
    return Settled(kind, scale, v.duration, v.settling_time, v.duration + v.dwell, count, v)


@one_blas_thread
def fastest_settling(
    robot: Robot,
    path: TaskTrajectory,
    band: float = DEFAULT_BAND,
    dwell: float = DEFAULT_DWELL,
    *,
    payload: float = 0.0,
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    material: str | Material | None = None,
    links: bool = True,
    damping_ratio: float | None = None,
    actuator_damping: float | Sequence[float] | np.ndarray | None = None,
    feedforward: str = "none",
    shaper: str | None = "zv",
    shaper_modes: int = 1,
    modes: int | None = None,
    poses: int | None = None,
    effort: float | np.ndarray | None = None,
    velocity: float | np.ndarray | None = None,
    max_scale: float = MAX_SCALE,
    fast: FastestResult | None = None,
    progress: bool | None = None,
) -> SettledFastest:
    """The fastest cycle along ``path`` whose tool settles within ``band`` during ``dwell``.

    Args:
        robot: The robot (with its geometry when links are beams).
        path: The path (a task trajectory whose time is the path parameter, e.g.
            :func:`~pkdyn.dynamics.trajectory.named_task` ``(robot, "adept")``).
        band: Settling band on the norm of the tool's deviation [m].
        dwell: Time after the motion within which the tool must settle [s].
        payload: Payload, a point mass at the platform [kg].
        actuator_stiffness: Servo stiffness [N m/rad or N/m] (``None``: described).
        material: Material of the slender links.
        links: Model the links' compliance.
        damping_ratio: Damping ratio of the first mode at the middle pose (default 0.02).
        actuator_damping: Servo damping [N m s/rad or N s/m].
        feedforward: ``none``, ``gravity`` or ``rigid``.
        shaper: ``zv`` or ``zvd`` (also searched with shaping), or ``None``.
        shaper_modes: Modes the shaper targets.
        modes: Modes integrated (default: up to 8 times the first frequency).
        poses: Poses along the path for the modes (default 33, 65 with compliant links).
        effort: Effort limits (default: the robot's).
        velocity: Speed limits (default: the robot's).
        max_scale: Largest slow-down searched.
        fast: The fastest motion along ``path`` already computed (with this payload).
        progress: Progress bars.

    Returns:
        The torque-limited fastest motion and the fastest settling ones.

    Raises:
        InvalidInputError: A bad option (named).
        InfeasibleEffortError, TrajectoryError: As :func:`fastest_trajectory`.

    """
    from pkdyn.inputs import count, flag, instance, non_negative, positive

    instance("robot", robot, Robot, "a Robot (pkdyn.load)")
    instance("path", path, TaskTrajectory, "a TaskTrajectory (pkdyn.dynamics.trajectory)")
    if robot.platform_frame is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    band = positive("band", band, "m", bound=max(10.0 * robot.length_scale, 1.0))
    dwell = positive("dwell", dwell, "s", bound=MAX_DWELL)
    payload = non_negative("payload", payload, "kg")
    max_scale = positive("max_scale", max_scale, bound=100.0)
    if max_scale < 1.0:
        raise InvalidInputError("max_scale", f"must be >= 1, got {max_scale:g}")
    if shaper is not None and (not isinstance(shaper, str) or shaper not in SHAPERS):
        raise InvalidInputError("shaper", f"unknown {shaper!r} (one of {', '.join(SHAPERS)})")
    shaper_n = count("shaper_modes", shaper_modes, 1, 4)
    if modes is not None:
        modes = count("modes", modes, 1)
    if poses is not None:
        poses = count("poses", poses, 2, 100_000)
    links = flag("links", links)
    em = elastic_model(robot, actuator_stiffness, material, links)
    check_compliant(em)
    if poses is None:
        poses = DEFAULT_POSES_LINKS if em.links else DEFAULT_POSES
    if fast is None:
        fast = fastest_trajectory(
            robot, path, payload=payload, effort=effort, velocity=velocity, progress=progress
        )
    p = np.zeros(3)
    joint1, task1 = fast.scaled(1.0)
    cmd1 = Command(task1, np.asarray(fast.efforts.tau), feedforward, robot, em, mapped=joint1)
    st = prepare(
        robot, em, cmd1, p, payload, feedforward, damping_ratio, actuator_damping, band, dwell,
        modes, poses, progress,
    )  # fmt: skip
    samples = pose_samples(joint1.t.size, poses)
    pm = path_modes(st.elastic, joint1.q, samples, p, progress)
    forcing = _PathForcing(st, fast)
    rest_end = forcing.at_rest_end()[None, :]
    static = static_deflection(pm, rest_end[0])
    n = st.kept
    w = 2.0 * np.pi * pm.frequencies[:, :n]

    def unshaped(scale: float) -> VibrationResult:
        t, FL, FR, dL, dR = forcing.ends(scale)
        h = float(np.max(np.diff(t)))
        sub = st.sub(h, float(t[-1]))
        r = modal_response(
            pm, t[samples], t, np.vstack([FL, rest_end]), st.c, n, sub, st.rest, (FL, FR, dL, dR)
        )
        dominant = _dominant(
            pm.frequencies[-1, :n], r.zeta_end, pm.platform[-1, :n], r.eta_end,
            r.eta_dot_end, r.eta_static_end,
        )  # fmt: skip
        return result(
            st, f"{task1.name} x{scale:.4g}", "modal", float(t[-1]), r.t, r.d, r.d_dot, static,
            pm.frequencies[0, :n], pm.frequencies[-1, :n], dominant, pm.internal,
            int(samples.size), None, None, None,
        )  # fmt: skip

    scale_u, best_u, count_u = _search(unshaped, max_scale, SCAN_STEP)
    settled_u = _settled(None, scale_u, best_u, count_u)
    settled_s = None
    if shaper is not None:
        U = pm.shapes[:, :shaper_n]
        z = np.einsum("pmv,v,pmv->pm", U, st.c, U) / (2.0 * w[:, :shaper_n])
        f = pm.frequencies[:, :shaper_n]

        def shaped(scale: float) -> VibrationResult:
            _, task = fast.scaled(scale)
            task = uniform(task)
            sh: Shaper = tracked(shaper, joint1.t[samples] * scale, f, z)
            cmd = command(em, shape(task, sh), payload, p, feedforward, progress)
            return analyse(st, cmd, "modal", sh)

        # (shaping removes most of the residual: the scan is coarser, the mapping dearer)
        scale_s, best_s, count_s = _search(shaped, max_scale, SCAN_STEP**3)
        settled_s = _settled(shaper, scale_s, best_s, count_s)
    return SettledFastest(robot.name, fast, band, dwell, max_scale, settled_u, settled_s)
