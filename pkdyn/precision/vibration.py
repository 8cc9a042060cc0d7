"""How a robot vibrates along a motion and how long its tool takes to settle: :func:`vibration`.

The elastic model of the precision layer (:mod:`pkdyn.precision.elastic`: actuator servo
stiffness, compliant links, the robot's own springs) moves under the loads of a commanded
motion: its inertial and gravity loads and a payload (a point mass at the reference point). The
tool deviates from its rigid motion during the move and rings after it. Conventions (stated so
that the figures compare with other tools):

- **Servo**: each actuator is a spring-damper at the joint side between the commanded and the
  actual joint coordinate, ``tau = k (q_cmd - q) + c (q_cmd' - q') + tau_ff``; the feedforward
  ``tau_ff`` is ``none`` (a motor that follows the command exactly behind an elastic
  transmission; the default), ``gravity`` (the static load of the commanded pose held) or
  ``rigid`` (the rigid inverse dynamics of the command: with rigid links this cancels the
  vibration exactly, so it only matters with compliant links).
- **Damping** (:mod:`pkdyn.precision.vibration_damping`): ``actuator_damping`` ``c`` on the
  error rate, or ``damping_ratio`` ``Z`` (default 0.02) with ``c = 2 Z k / omega_1``,
  ``omega_1`` the first undamped frequency at the motion's middle pose (the commanded pose at
  half its duration); the links' virtual springs get ``beta k``, ``beta = 2 Z / omega_1``.
- **Start**: at rest in the static equilibrium of the start pose (gravity, payload, feedforward).
- **Deviation**: the reference point's actual minus commanded position (world axes; for
  rotations in the task, the rotation vector of actual times commanded transposed); its norm for
  the band. ``peak_deviation`` over the motion ``[0, T]``; ``residual_amplitude`` the largest
  norm over ``[T, T + 0.2 s]``, and ``settling_time`` (counted from ``T``: the first time after
  which the norm stays below the band until the end of the dwell), both measured about the
  static equilibrium of the end pose (whose deflection is reported apart as
  ``static_deflection``); peaks and crossings from the dense output
  (:mod:`pkdyn.precision.vibration_figures`).

Two methods: ``modal`` (:mod:`pkdyn.precision.vibration_modal`: the pose-dependent modes along
the path, superposed; fast; in closed form on the library Delta with rigid links,
:mod:`pkdyn.precision.vibration_closed_form`, where no pose is solved) and ``multibody``
(:mod:`pkdyn.precision.vibration_multibody`: the elastic model simulated, nothing linearised;
the reference). An input shaper
(:mod:`pkdyn.precision.vibration_shaping`, ``zv`` or ``zvd``) can be applied to the command.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.dynamics.delta import DeltaDynamics
from pkdyn.dynamics.payload import with_payload
from pkdyn.dynamics.trajectory import TRAJECTORIES, TaskTrajectory, named_task
from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.robot import PLATFORM_HINT, Robot
from pkdyn.precision.elastic import ElasticModel, elastic_model
from pkdyn.precision.material import Material
from pkdyn.precision.modes import Modes
from pkdyn.precision.modes import modes as modes_at
from pkdyn.precision.stiffness import nothing_compliant
from pkdyn.precision.vibration_closed_form import (
    DeltaModes,
    DeltaPoses,
    applies,
    joint_deformation,
)
from pkdyn.precision.vibration_command import FEEDFORWARDS, Command, command
from pkdyn.precision.vibration_damping import Damping, actuator_damping_values, damping
from pkdyn.precision.vibration_damping import damping_ratio as check_ratio
from pkdyn.precision.vibration_figures import RESIDUAL_WINDOW, figures
from pkdyn.precision.vibration_modal import (
    DEFAULT_POSES,
    DEFAULT_POSES_LINKS,
    PathModes,
    loads,
    modal_response,
    path_modes,
    pose_samples,
)
from pkdyn.precision.vibration_multibody import multibody_response
from pkdyn.precision.vibration_result import Display, DominantMode, VibrationResult
from pkdyn.precision.vibration_shaping import SHAPERS, Shaper, shape, shaper_modes, tracked
from pkdyn.threads import one_blas_thread

__all__ = [
    "DEFAULT_BAND",
    "DEFAULT_DWELL",
    "METHODS",
    "MAX_OUTPUT_POINTS",
    "MODE_CUTOFF",
    "STEPS_PER_PERIOD",
    "Setup",
    "VibrationResult",
    "analyse",
    "prepare",
    "vibration",
]

METHODS = ("modal", "multibody")
"""The methods of :func:`vibration`."""

DEFAULT_BAND = 1e-4
"""Settling band when none is given [m] (a 0.1 mm placing tolerance)."""

DEFAULT_DWELL = 0.5
"""Time after the motion within which the tool must settle when none is given [s]."""

MODE_CUTOFF = 8.0
"""Without a mode count, the modal method integrates the modes up to this multiple of the first
frequency at the middle pose (the others respond quasi-statically)."""

STEPS_PER_PERIOD = 16
"""Output steps per period of the highest mode resolved (the dense output's resolution)."""

MAX_OUTPUT_POINTS = 2_000_000
"""Most output times of one analysis (a long motion at a fine step resolving fast modes)."""

MAX_DWELL = 60.0
"""Longest dwell accepted [s]."""


def _task(
    robot: Robot,
    trajectory: str | Path | TaskTrajectory,
    cycle_time: float | None,
    dt: float,
    profile: str,
) -> TaskTrajectory:
    """The commanded platform trajectory named, read or given."""
    from pkdyn.inputs import positive

    if isinstance(trajectory, TaskTrajectory):
        if cycle_time is not None:
            raise InvalidInputError("cycle_time", "does not apply to a trajectory given as samples")
        return trajectory
    if isinstance(trajectory, Path) or (
        isinstance(trajectory, str) and trajectory.lower().endswith(".csv")
    ):
        if cycle_time is not None:
            raise InvalidInputError("cycle_time", "does not apply to a trajectory read from a file")
        from pkdyn.dynamics.trajectory_file import read_task_csv

        return read_task_csv(robot, trajectory)
    if not isinstance(trajectory, str) or trajectory not in TRAJECTORIES:
        from pkdyn.exceptions import close_match

        raise InvalidInputError(
            "trajectory",
            f"{trajectory!r:.60}: one of {', '.join(TRAJECTORIES)}, a .csv file or a "
            "TaskTrajectory"
            + (close_match(trajectory, list(TRAJECTORIES)) if isinstance(trajectory, str) else ""),
        )
    opts: dict[str, Any] = {"dt": positive("dt", dt, "s")}
    if trajectory == "adept":
        opts["profile"] = profile
        if cycle_time is not None:
            opts["cycle_time"] = positive("cycle_time", cycle_time, "s")
    elif trajectory == "p2p":
        opts["profile"] = profile
        if cycle_time is not None:
            opts["duration"] = positive("cycle_time", cycle_time, "s")
    elif cycle_time is not None:
        c = positive("cycle_time", cycle_time, "s")
        opts.update(frequency=1.0 / c, duration=c)
    return named_task(robot, trajectory, **opts)


def check_compliant(em: ElasticModel) -> None:
    """Refuse a rigid model (every actuator ``inf``, no spring, rigid links): nothing vibrates.

    Raises:
        InvalidInputError: The robot is rigid.

    """
    if nothing_compliant(em):
        raise InvalidInputError(
            "actuator_stiffness",
            f"{em.base.name}: every actuator is rigid (inf) and nothing else is compliant: the "
            "robot is rigid and does not vibrate; give finite actuator stiffnesses or a "
            "material for the links",
        )


def _with_payload(em: ElasticModel, payload: float, point: np.ndarray) -> ElasticModel:
    if payload <= 0.0:
        return em
    return dataclasses.replace(em, robot=with_payload(em.robot, payload, offset=tuple(point)))


def _carries(cmd: Command, payload: float, point: np.ndarray) -> bool:
    """Whether the command's loaded robot carries this payload at this point."""
    return cmd.payload == payload and (
        payload == 0.0 or (cmd.point is not None and np.array_equal(cmd.point, point))
    )


def _damping_c(em: ElasticModel, dmp: Damping) -> np.ndarray:
    """All the viscous coefficients per extended coordinate: servos, links, the robot's own."""
    c = dmp.coefficients(em)
    if em.robot.passive is not None:
        c = c + np.asarray(em.robot.passive.damping)
    return c


def _shaper(kind: str, count: int, st: Setup, cmd: Command) -> Shaper:
    """The shaper of the lowest ``count`` modes, their frequencies tracked along ``cmd``."""
    pm, c, _ = _path_modes(st, cmd, 17)
    n = shaper_modes(count, pm.count)
    w = 2.0 * np.pi * pm.frequencies[:, :n]
    U = pm.shapes[:, :n]
    if c.ndim == 1:
        z = np.einsum("pmv,v,pmv->pm", U, c, U) / (2.0 * w)
    else:
        z = np.einsum("pmv,pvw,pmw->pm", U, c, U) / (2.0 * w)
    return tracked(kind, cmd.t[pm.samples], pm.frequencies[:, :n], z)


def _path_modes(
    st: Setup, cmd: Command, most: int | None = None
) -> tuple[PathModes, np.ndarray, DeltaPoses | None]:
    """The modes along ``cmd`` (at most ``most`` poses) and the damping in their coordinates.

    In closed form (:mod:`pkdyn.precision.vibration_closed_form`: the nacelle's coordinates)
    at every sample (or ``st.poses``) when it applies, with the arm geometry at every sample;
    else at ``st.poses`` poses (default :data:`~pkdyn.precision.vibration_modal.DEFAULT_POSES`,
    :data:`~pkdyn.precision.vibration_modal.DEFAULT_POSES_LINKS` with compliant links), with
    the damping per extended coordinate.
    """
    n = cmd.t.size
    if st.arms is not None:
        count = n if st.poses is None else st.poses
        samples = pose_samples(n, count if most is None else min(count, most))
        poses = st.arms.poses(cmd.task.pose[:, :3])
        at = poses.take(samples)
        c_a = st.c[np.asarray(st.elastic.robot.actuated_v)]
        return st.arms.path_modes(at, samples), st.arms.damping(at, c_a), poses
    default = DEFAULT_POSES_LINKS if st.em.links else DEFAULT_POSES
    count = default if st.poses is None else st.poses
    samples = pose_samples(n, count if most is None else min(count, most))
    return path_modes(st.elastic, cmd.joint.q, samples, st.point, st.progress), st.c, None


def _dominant(
    f_end: np.ndarray,
    zeta: np.ndarray,
    platform: np.ndarray,
    eta: np.ndarray,
    eta_dot: np.ndarray,
    eta_static: np.ndarray,
) -> list[DominantMode]:
    """Modes ranked by the amplitude of their free vibration when the motion ends."""
    w = 2.0 * np.pi * f_end
    e = eta - eta_static
    wd = w * np.sqrt(np.maximum(1.0 - zeta**2, 1e-12))
    amp = np.sqrt(e**2 + ((eta_dot + zeta * w * e) / wd) ** 2) * np.linalg.norm(
        platform[:, :3], axis=1
    )
    total = float(np.sum(amp))
    order = np.argsort(amp)[::-1][:5]
    return [
        DominantMode(
            mode=int(i) + 1,
            frequency=float(f_end[i]),
            damping_ratio=float(zeta[i]),
            amplitude=float(amp[i]),
            share=float(amp[i] / total) if total > 0.0 else 0.0,
        )
        for i in order
    ]


@one_blas_thread
@public
def vibration(
    robot: Robot,
    trajectory: str | Path | TaskTrajectory = "adept",
    *,
    cycle_time: float | None = None,
    payload: float = 0.0,
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    material: str | Material | None = None,
    links: bool = True,
    damping_ratio: float | None = None,
    actuator_damping: float | Sequence[float] | np.ndarray | None = None,
    feedforward: str = "none",
    band: float = DEFAULT_BAND,
    dwell: float = DEFAULT_DWELL,
    method: str = "modal",
    shaper: str | None = None,
    shaper_modes: int = 1,
    modes: int | None = None,
    poses: int | None = None,
    point: Sequence[float] | np.ndarray | None = None,
    dt: float = 1e-3,
    profile: str = "quintic",
    progress: bool | None = None,
) -> VibrationResult:
    """How the robot's tool deviates from its rigid motion along a motion, and settles after it.

    Args:
        robot: The robot (loaded with its geometry when links are modelled as beams).
        trajectory: ``adept`` or ``p2p`` (:func:`pkdyn.dynamics.trajectory.named_task`), a CSV
            file (:func:`pkdyn.dynamics.trajectory_file.read_task_csv`) or a
            :class:`~pkdyn.dynamics.trajectory.TaskTrajectory`; from rest to rest.
        cycle_time: Duration of a named trajectory [s] (adept: the cycle, there and back,
            default 0.5 s; p2p: the move).
        payload: Payload, a point mass at the reference point [kg].
        actuator_stiffness: Joint-side servo stiffness, one or one per actuator [N m/rad or
            N/m]; ``None``: the description's ``<pkdyn:stiffness>``.
        material: Material of the slender links (beams); ``None``: the description's.
        links: Model the links' compliance (``False``: rigid links).
        damping_ratio: Damping ratio of the first mode at the middle pose (default 0.02).
        actuator_damping: Servo damping on the error rate, one or one per actuator
            [N m s/rad or N s/m] (default: ``2 Z k / omega_1``).
        feedforward: ``none``, ``gravity`` or ``rigid`` (module docstring).
        band: Settling band on the norm of the position deviation [m] (default 0.1 mm).
        dwell: Time after the motion within which the tool must settle [s] (default 0.5 s).
        method: ``modal`` (fast) or ``multibody`` (the reference).
        shaper: ``zv`` or ``zvd`` to shape the command from the modes along the path.
        shaper_modes: Number of (lowest) modes the shaper targets.
        modes: Modes integrated by the modal method, and resolved by the output step of both
            methods (the lowest; the others respond quasi-statically in the modal method);
            ``None``: those up to 8 times the first frequency at the middle pose.
        poses: Poses along the motion where the modes are computed (modal method; default 33
            with rigid links, 65 with compliant ones; every sample where the closed form
            applies: :mod:`pkdyn.precision.vibration_closed_form`).
        point: Reference point (tool), platform frame [m] (default: the platform origin).
        dt: Sample period of a named trajectory [s].
        profile: Motion law of a named trajectory (``quintic`` or ``jerk``).
        progress: Progress bars (mapping, modes).

    Returns:
        The deviation's time series and figures.

    Raises:
        InvalidInputError: A bad option (named), a motion that does not start and end at rest,
            a rigid actuator with the multibody method, too much work.
        TrajectoryError: The motion leaves the workspace or meets a singularity.
        SingularConfigurationError: A pose where the platform moves without stiffness.
        SimulationError: The multibody simulation fails.

    """
    from pkdyn.inputs import count, flag, instance, non_negative, positive, vector

    instance("robot", robot, Robot, "a Robot (pkdyn.load)")
    if robot.platform_frame is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    if not isinstance(method, str) or method not in METHODS:
        raise InvalidInputError("method", f"unknown {method!r} (one of {', '.join(METHODS)})")
    if not isinstance(feedforward, str) or feedforward not in FEEDFORWARDS:
        raise InvalidInputError(
            "feedforward", f"unknown {feedforward!r} (one of {', '.join(FEEDFORWARDS)})"
        )
    if shaper is not None and (not isinstance(shaper, str) or shaper not in SHAPERS):
        raise InvalidInputError("shaper", f"unknown {shaper!r} (one of {', '.join(SHAPERS)})")
    links = flag("links", links)
    payload = non_negative("payload", payload, "kg")
    L = robot.length_scale
    band = positive("band", band, "m", bound=max(10.0 * L, 1.0))
    dwell = positive("dwell", dwell, "s", bound=MAX_DWELL)
    if modes is not None:
        modes = count("modes", modes, 1)
    if poses is not None:
        poses = count("poses", poses, 2, 100_000)
    shaper_n = count("shaper_modes", shaper_modes, 1, 4)
    p = np.zeros(3) if point is None else vector("point", point, 3, "m", bound=max(100.0 * L, 10.0))
    task = _task(robot, trajectory, cycle_time, dt, profile)
    em = elastic_model(robot, actuator_stiffness, material, links)
    check_compliant(em)
    if damping_ratio is not None:
        damping_ratio = check_ratio(damping_ratio)
    if actuator_damping is not None:
        actuator_damping = actuator_damping_values(em, actuator_damping)
    if method == "multibody" and not np.all(np.isfinite(em.actuator_stiffness)):
        raise InvalidInputError(
            "actuator_stiffness",
            "the multibody method simulates each actuator as a servo of finite stiffness; "
            "give finite stiffnesses (or use the modal method)",
        )
    cmd = command(em, task, payload, p, feedforward, progress)
    if any(lc.sliding for lc in em.links):
        em = em.at(cmd.joint.q[0])  # (a compliant prismatic rod: its length at the start)
    setup = prepare(
        robot, em, cmd, p, payload, feedforward, damping_ratio, actuator_damping, band, dwell,
        modes, poses, progress,
    )  # fmt: skip
    shaped: Shaper | None = None
    if shaper is not None:
        shaped = _shaper(shaper, shaper_n, setup, cmd)
        cmd = command(em, shape(cmd.task, shaped), payload, p, feedforward, progress)
    return analyse(setup, cmd, method, shaped)


@dataclass(eq=False)  # numpy fields
class Setup:
    """What every analysis of one robot, model and load shares (:func:`prepare`).

    Attributes:
        robot: The robot as loaded.
        em: Its elastic model.
        elastic: The elastic model carrying the payload.
        point: Reference point, platform frame [m].
        payload: Payload [kg].
        feedforward: The servos' feedforward.
        damping: The damping.
        c: Viscous coefficient per extended velocity coordinate (servos, links, own dampers).
        kept: Modes integrated and resolved.
        f1: Lowest frequency at the middle pose [Hz].
        f_top: Highest of their frequencies at the middle pose [Hz].
        band: Settling band [m].
        dwell: Settling dwell [s].
        poses: Poses along a motion for the modal method (``None``: its default).
        progress: Progress bars.
        arms: The closed-form modes of the arms, when they apply
            (:mod:`pkdyn.precision.vibration_closed_form`).

    """

    robot: Robot
    em: ElasticModel
    elastic: ElasticModel
    point: np.ndarray
    payload: float
    feedforward: str
    damping: Damping
    c: np.ndarray
    kept: int
    f1: float
    f_top: float
    band: float
    dwell: float
    poses: int | None
    progress: bool | None
    arms: DeltaModes | None = None

    @property
    def rest(self) -> float:
        """Time observed after a motion [s].

        The dwell (at least the residual window) and two periods of the first mode (see
        :mod:`pkdyn.precision.vibration_figures`).
        """
        return max(self.dwell, RESIDUAL_WINDOW) + 2.0 / self.f1

    def sub(self, h: float, T: float) -> int:
        """Output steps per sample interval ``h`` resolving the kept modes; the work checked.

        Raises:
            InvalidInputError: More than :data:`MAX_OUTPUT_POINTS` output points.

        """
        sub = max(1, int(math.ceil(h * self.f_top * STEPS_PER_PERIOD * 1.25)))
        points = (T + self.rest) / h * sub
        if points > MAX_OUTPUT_POINTS:
            raise InvalidInputError(
                "dt",
                f"{T + self.rest:.3g} s resolved at {STEPS_PER_PERIOD} steps per period of "
                f"{self.f_top:.4g} Hz is {points:.3g} output points (at most "
                f"{MAX_OUTPUT_POINTS:.0e}): a shorter motion or dwell, fewer modes, or a "
                "stiffer model",
            )
        return sub


@one_blas_thread
def prepare(
    robot: Robot,
    em: ElasticModel,
    cmd: Command,
    point: np.ndarray,
    payload: float,
    feedforward: str,
    damping_ratio: float | None,
    actuator_damping: float | Sequence[float] | np.ndarray | None,
    band: float,
    dwell: float,
    modes: int | None,
    poses: int | None,
    progress: bool | None = None,
) -> Setup:
    """The shared part of the analyses of ``cmd``'s path: damping from its middle pose, modes kept.

    Arguments as :func:`vibration` (checked already), the command built.
    """
    mid = (cmd.t.size - 1) // 2
    arms = None
    if applies(em):
        if cmd.delta is not None and _carries(cmd, payload, point):  # (its closed forms read)
            emL = dataclasses.replace(em, robot=cmd.loaded)
            arms = DeltaModes(cmd.delta, em.actuator_stiffness)
        else:
            emL = _with_payload(em, payload, point)
            arms = DeltaModes(DeltaDynamics(emL.robot), em.actuator_stiffness)
    else:
        emL = _with_payload(em, payload, point)
    if arms is not None:
        at = arms.poses(cmd.task.pose[mid : mid + 1, :3])
        f_mid = arms.path_modes(at, np.array([mid])).frequencies[0]
    else:
        f_mid = modes_at(emL, cmd.joint.q[mid], point=point).frequencies
    dmp = damping(emL, float(f_mid[0]), float(cmd.t[mid]), damping_ratio, actuator_damping)
    if modes is None:
        kept = int(np.searchsorted(f_mid, MODE_CUTOFF * f_mid[0], side="right"))
    else:
        kept = min(modes, f_mid.size)
    return Setup(
        robot, em, emL, point, payload, feedforward, dmp, _damping_c(emL, dmp), kept,
        float(f_mid[0]), float(f_mid[kept - 1]), band, dwell, poses, progress, arms,
    )  # fmt: skip


@one_blas_thread
def analyse(st: Setup, cmd: Command, method: str, shaped: Shaper | None = None) -> VibrationResult:
    """The analysis of one command by one method (see :func:`vibration`)."""
    emL, p = st.elastic, st.point
    T, h = cmd.duration, cmd.step
    sub = st.sub(h, T)
    n_kept = st.kept
    pm: PathModes | None = None
    poses: DeltaPoses | None = None
    if method == "modal":
        pm, c, poses = _path_modes(st, cmd)
        if poses is not None:  # the arms' unbalanced efforts seen by the nacelle
            assert cmd.arms is not None
            F = np.einsum("nki,nk->ni", poses.Jinv, cmd.tau_ff - cmd.arms.tau)
        else:
            F = loads(emL, cmd.q, cmd.v, cmd.a, cmd.tau_ff)
        r = modal_response(pm, cmd.t[pm.samples], cmd.t, F, c, n_kept, sub, st.rest)
        static = static_deflection(pm, F[-1])
        f_start, f_end = pm.frequencies[0, :n_kept], pm.frequencies[-1, :n_kept]
        dominant = _dominant(
            f_end, r.zeta_end, pm.platform[-1, :n_kept], r.eta_end, r.eta_dot_end, r.eta_static_end
        )
        t_out, d, dd = r.t, r.d, r.d_dot
        t_c, u = r.t_coarse, r.u
        drift = None
        internal = pm.internal
    else:
        link_c = st.c.copy()
        link_c[np.asarray(emL.robot.actuated_v)] = 0.0
        if emL.robot.passive is not None:
            link_c -= np.asarray(emL.robot.passive.damping)  # (the simulation adds its own)
        mb = multibody_response(emL, cmd, link_c, st.damping.actuator, p, sub, st.rest)
        m0 = modes_at(emL, cmd.joint.q[0], point=p)
        mE = modes_at(emL, cmd.joint.q[-1], point=p)
        f_start, f_end = m0.frequencies[:n_kept], mE.frequencies[:n_kept]
        dominant = _dominant_multibody(emL, mE, n_kept, mb.u_end, mb.u_dot_end, cmd, st.c)
        static = mb.static_end
        t_out, d, dd = mb.t, mb.d, mb.d_dot
        t_c, u = mb.t_coarse, mb.u
        drift = mb.energy_drift
        internal = mE.internal
    n_c = min(t_c.size, u.shape[0])

    def shown() -> Display:
        Qc = np.vstack([cmd.q, np.tile(cmd.q[-1], (max(n_c - cmd.q.shape[0], 0), 1))])[:n_c]
        if poses is not None:  # (the nacelle's deviations: the arms' through J_inv)
            Jinv = poses.Jinv[np.minimum(np.arange(n_c), poses.Jinv.shape[0] - 1)]
            E = np.einsum("nki,ni->nk", Jinv, u[:n_c])
            return t_c[:n_c], Qc, joint_deformation(emL, Qc, E)
        return t_c[:n_c], Qc, u[:n_c]

    closed = poses is not None
    return result(
        st,
        cmd.task.name,
        method,
        T,
        t_out,
        d,
        dd,
        static,
        np.asarray(f_start),
        np.asarray(f_end),
        dominant,
        internal,
        None if pm is None else int(pm.samples.size),
        None if shaped is None else shaped.describe(),
        drift,
        shown if closed else shown(),  # (closed form: the joints mapped for a display only)
    )


def static_deflection(pm: PathModes, F_end: np.ndarray) -> np.ndarray:
    """Platform deviation (6,) in the linear static equilibrium of the end pose under ``F_end``."""
    w = 2.0 * np.pi * pm.frequencies[-1]
    return np.asarray(pm.platform[-1].T @ ((pm.shapes[-1] @ F_end) / w**2))


def result(
    st: Setup,
    name: str,
    method: str,
    T: float,
    t_out: np.ndarray,
    d: np.ndarray,
    dd: np.ndarray,
    static: np.ndarray,
    f_start: np.ndarray,
    f_end: np.ndarray,
    dominant: list[DominantMode],
    internal: int,
    poses: int | None,
    shaper: dict[str, Any] | None,
    drift: float | None,
    display: Display | Callable[[], Display] | None,
) -> VibrationResult:
    """The figures of a deviation and the result holding them.

    ``display``: the commanded configurations and the deformation for displays
    (:meth:`VibrationResult.animation`), or what computes them when first asked for.
    """
    from pkdyn.analysis.kinematics import TASK_NAMES

    rows = np.asarray(st.robot.task_rows, dtype=int)
    tr = [i for i, r_ in enumerate(rows) if r_ < 3]
    fig = figures(
        t_out, d[:, rows][:, tr], dd[:, rows][:, tr], static[rows][tr], T, st.dwell, st.band,
        st.rest,
    )  # fmt: skip
    t_c, Qc, u = display if isinstance(display, tuple) else (None, None, None)
    return VibrationResult(
        robot=st.robot.name,
        trajectory=name,
        method=method,
        task=tuple(TASK_NAMES[i] for i in rows),
        t=t_out,
        deviation=d[:, rows],
        deviation_rate=dd[:, rows],
        duration=T,
        dwell=st.dwell,
        band=st.band,
        payload=st.payload,
        point=st.point,
        peak_deviation=fig.peak_deviation,
        peak_time=fig.peak_time,
        residual_amplitude=fig.residual_amplitude,
        settling_time=fig.settling_time,
        settled=fig.settled,
        static_deflection=static[rows],
        frequencies_start=f_start,
        frequencies_end=f_end,
        dominant_modes=dominant,
        feedforward=st.feedforward,
        damping=st.damping,
        actuator_stiffness=np.asarray(st.em.actuator_stiffness),
        links=tuple(lc.link for lc in st.em.links),
        internal=internal,
        modes=st.kept,
        poses=poses,
        shaper=shaper,
        energy_drift=drift,
        elastic=st.elastic,
        animate=display if callable(display) else None,
        t_coarse=t_c,
        command=Qc,
        deformation=u,
        prismatic=tuple(bool(x) for x in st.robot.actuator_prismatic),
    )


def _dominant_multibody(
    em: ElasticModel,
    m_end: Modes,
    n: int,
    u_end: np.ndarray,
    u_dot_end: np.ndarray,
    cmd: Command,
    c: np.ndarray,
) -> list[DominantMode]:
    """Dominant modes of a simulated end state: its deformation projected on the end modes."""
    from pkdyn.precision.modes import mass_matrix

    M = mass_matrix(em.robot, m_end.q_elastic)
    U = m_end.shapes[:n]
    eta = U @ M @ u_end
    eta_dot = U @ M @ u_dot_end
    F_end = loads(em, cmd.q[-1:], cmd.v[-1:], cmd.a[-1:], cmd.tau_ff[-1:])[0]
    w = 2.0 * np.pi * m_end.frequencies[:n]
    eta_s = (U @ F_end) / w**2
    zeta = np.einsum("mv,v,mv->m", U, c, U) / (2.0 * w)
    return _dominant(m_end.frequencies[:n], zeta, m_end.platform[:n], eta, eta_dot, eta_s)
