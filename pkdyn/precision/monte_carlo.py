"""Monte Carlo of exactly solved robots: the check of the first-order error budgets.

:func:`monte_carlo` draws geometric errors within their tolerances, rebuilds the robot with them
(family parameters: the family builder run with them; other models: the placements moved
exactly, :func:`pkdyn.precision.perturbation.perturbed`) and solves its forward geometry at the
same actuator readings; the pose errors' spread is then compared with the first order of
:func:`pkdyn.precision.budgets.geometric_errors`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.arguments import public
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.precision.budgets import _GAP_TOL, _std, _tolerances, pose_error
from pkdyn.precision.parameters import (
    ParameterModel,
    built_placements,
    family_values,
    placements,
)
from pkdyn.precision.perturbation import perturbed, with_placements
from pkdyn.precision.sensitivity import pose_sensitivity
from pkdyn.progress import progress as progress_bar
from pkdyn.results import Result, jsonable, renamed_keyword
from pkdyn.threads import one_blas_thread
from pkdyn.units import quantity

__all__ = ["MonteCarlo", "monte_carlo"]


@dataclass
class MonteCarlo(Result):
    """Pose errors of robots drawn with random errors, solved exactly.

    Attributes:
        errors: Pose error of each sample (N, 6) [m, rad].
        failed: Samples that could not be assembled at the actuator readings.
        first_order_rms: The first-order position RMS of the same tolerances [m], when known
            (:func:`pkdyn.precision.budgets.geometric_errors`), to compare with.
        distribution: ``uniform`` or ``normal``.
        seed: The random seed.

    """

    errors: np.ndarray
    failed: int = 0
    first_order_rms: float | None = None
    distribution: str = "uniform"
    seed: int = 0

    @property
    def rms(self) -> np.ndarray:
        """RMS per pose component (6,) [m, rad]."""
        if not len(self.errors):
            return np.full(6, np.nan)
        return np.sqrt(np.mean(self.errors**2, axis=0))

    @property
    def position_rms(self) -> float:
        """RMS of the position error's norm [m]."""
        if not len(self.errors):
            return float("nan")
        return float(np.sqrt(np.mean(np.sum(self.errors[:, :3] ** 2, axis=1))))

    @property
    def position_max(self) -> float:
        """Largest position error norm among the samples [m]."""
        return float(np.max(np.linalg.norm(self.errors[:, :3], axis=1), initial=0.0))

    @property
    def orientation_rms(self) -> float:
        """RMS of the rotation error's norm [rad]."""
        if not len(self.errors):
            return float("nan")
        return float(np.sqrt(np.mean(np.sum(self.errors[:, 3:] ** 2, axis=1))))

    def to_json(self) -> dict[str, Any]:
        """Sample counts, RMS per component and of the norms, the largest position error."""
        return {
            "samples": int(len(self.errors)),
            "failed": self.failed,
            "distribution": self.distribution,
            "seed": self.seed,
            "rms": jsonable(self.rms),
            "position_rms": jsonable(self.position_rms),
            "position_max": self.position_max,
            "orientation_rms": jsonable(self.orientation_rms),
            "first_order_position_rms": jsonable(self.first_order_rms),
        }

    def table(self) -> str:
        """One line: the sampled RMS (against the first order) and the largest error."""
        n = len(self.errors)
        if n == 0:
            return f"Monte Carlo: none of the {self.failed} robots assembled at the readings"
        text = f"Monte Carlo ({n} robots): position RMS {quantity(self.position_rms, 'm')}"
        if self.first_order_rms is not None:
            text += f" (first order {quantity(self.first_order_rms, 'm')})"
        text += f", largest {quantity(self.position_max, 'm')}"
        if self.failed:
            text += f"; {self.failed} robots did not assemble at the readings"
        return text


def _draw(rng: np.random.Generator, t: np.ndarray, distribution: str) -> np.ndarray:
    if distribution == "uniform":
        return rng.uniform(-1.0, 1.0, t.size) * t
    return rng.normal(0.0, 1.0, t.size) * (t / 3.0)


@renamed_keyword("progress_bar", "progress")
@public
@one_blas_thread
def monte_carlo(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    model: ParameterModel,
    tolerance: float | Sequence[float] | np.ndarray,
    samples: int = 200,
    distribution: str = "uniform",
    seed: int = 0,
    progress: bool | None = None,
    *,
    workers: int | None = 1,
    scheduler: str | None = None,
    client: Any = None,
    timeout: float = 10.0,
) -> MonteCarlo:
    """Pose errors of ``samples`` robots with random geometric errors, solved exactly.

    Each sample draws the parameters, rebuilds the robot (family parameters: the family builder
    run with them; other models: :func:`~pkdyn.precision.perturbation.perturbed`) and solves its
    forward geometry at the actuator readings of ``q`` (gains applied). Parameters the mechanism
    cannot absorb (:attr:`GeometricAccuracy.not_assembling`) are left at zero.

    Args:
        robot: The nominal robot.
        q: Assembled configuration (nq,): the actuator readings and the nominal pose.
        model: The parameter model.
        tolerance: One per parameter (or one for all).
        samples: Number of robots (at most 100,000).
        distribution: ``uniform`` or ``normal``.
        seed: Random seed.
        progress: Force the progress bar on or off (default: on a terminal;
            ``progress_bar``, its former name, is kept for one release).
        workers: Local worker processes (1: this process; ``None``: as many as the machine
            justifies); the samples are drawn here, so the robots do not depend on it.
        scheduler: A Dask scheduler address (``tcp://host:8786``) to run the robots on.
        client: A connected ``distributed.Client`` instead of ``scheduler``.
        timeout: How long to wait for the scheduler or for a worker [s].

    Returns:
        The sampled pose errors.

    Raises:
        InvalidInputError: Malformed tolerances, distribution, sample count or workers.
        StudyError: A worker died, the scheduler cannot be reached, or the robot cannot be
            rebuilt in the workers (:mod:`pkdyn.precision.parallel`).

    """
    from pkdyn.inputs import count
    from pkdyn.inputs import seed as _seed

    qq = as_finite("q", q, robot.nq)
    t = _tolerances(model, tolerance)
    _std(t, distribution)
    try:
        samples = count("samples", samples, 1, 100_000)
    except InvalidInputError:
        raise InvalidInputError("samples", f"{samples}: give 1 to 100,000") from None
    seed = _seed("seed", seed)
    gap = pose_sensitivity(robot, qq, model).gap
    if gap.size:
        t = np.where(np.max(np.abs(gap), axis=0) > _GAP_TOL, 0.0, t)
    nominal = robot.platform_placement(qq)
    readings = qq[robot.actuated_q]
    rng = np.random.default_rng(seed)
    family = model.kind == "family parameters"
    if family and _delta_closed_form(robot, model):
        # every sample at once: the same draws (one stream, sample after sample)
        dp_all = _draw_all(rng, t, distribution, int(samples))
        errors_all, ok = _delta_family_errors(robot, model, dp_all, readings, nominal)
        return MonteCarlo(errors_all[ok], int(np.sum(~ok)), distribution=distribution, seed=seed)
    if family and _gough_stewart_closed_form(robot, model):
        dp_all = _draw_all(rng, t, distribution, int(samples))
        errors_all, solved, refused = _gough_stewart_family_errors(
            robot, model, dp_all, qq, nominal
        )
        ok = solved.copy()
        for k in np.flatnonzero(~solved & ~refused):  # the few the batch leaves: general path
            e = _sample_error(robot, model, dp_all[k], qq, True, nominal)
            if e is not None:
                errors_all[k], ok[k] = e, True
        return MonteCarlo(errors_all[ok], int(np.sum(~ok)), distribution=distribution, seed=seed)
    if workers != 1 or scheduler or client is not None:
        from pkdyn.precision.parallel import fingerprint, recipe, run_chunks

        dp_all = _draw_all(rng, t, distribution, int(samples))
        payload = (recipe(robot), fingerprint(robot), model, qq, family)
        found = run_chunks(
            _chunk, payload, list(dp_all), workers, scheduler, client, timeout, chunk=64
        )
        kept_rows = [e for e in found if e is not None]
        return MonteCarlo(
            np.array(kept_rows).reshape(-1, 6),
            sum(e is None for e in found),
            distribution=distribution,
            seed=seed,
        )
    errors, failed = [], 0
    for _ in progress_bar(range(int(samples)), "Monte Carlo", "robot", progress, min_items=50):
        e = _sample_error(robot, model, _draw(rng, t, distribution), qq, family, nominal)
        if e is None:
            failed += 1
        else:
            errors.append(e)
    return MonteCarlo(np.array(errors).reshape(-1, 6), failed, distribution=distribution, seed=seed)


def _sample_error(
    robot: Robot,
    model: ParameterModel,
    dp: np.ndarray,
    q: np.ndarray,
    family: bool,
    nominal: pin.SE3,
) -> np.ndarray | None:
    """The pose error (6,) of one robot drawn with parameters ``dp``, or ``None`` (no assembly)."""
    readings = q[robot.actuated_q]
    try:
        if family:
            sample = _family_sample(robot, model, dp)
            qa = readings * (1.0 + model.gains(dp))
        else:
            pert = perturbed(robot, model, dp, assemble=False, shared=True)
            sample, qa = pert.robot, pert.joint_coordinates(readings)
        res = _solve_forward(sample, qa, q_init=q, check_limits=False)
    except PkdynError:
        return None
    assert res.placement is not None
    return pose_error(nominal, res.placement)


_solve_forward = forward_geometry.__wrapped__  # type: ignore[attr-defined]
""":func:`~pkdyn.model.assembly.forward_geometry` without its public argument checks: the Monte
Carlo checked ``q`` once, and the robots and readings it passes are its own (the checks cost a
tenth of a sample)."""


def _chunk(payload: Any, chunk: list[np.ndarray]) -> list[np.ndarray | None]:
    """Pose errors of a chunk of draws, in a worker (:mod:`pkdyn.precision.parallel`)."""
    from pkdyn.precision.parallel import worker_robot

    how, digest, model, q, family = payload
    robot = worker_robot(how, digest, geometry=False)
    nominal = robot.platform_placement(q)
    return [_sample_error(robot, model, dp, q, family, nominal) for dp in chunk]


def _draw_all(rng: np.random.Generator, t: np.ndarray, distribution: str, n: int) -> np.ndarray:
    """``n`` draws of :func:`_draw` at once (n, len(t)): the same numbers, in the same order."""
    if distribution == "uniform":
        return rng.uniform(-1.0, 1.0, (n, t.size)) * t
    return rng.normal(0.0, 1.0, (n, t.size)) * (t / 3.0)


_DELTA_GEOMETRY = ("ra", "rb", "la", "lb")
"""The library Delta's parameters its platform position depends on (Clavel's closed form)."""


def _delta_closed_form(robot: Robot, model: ParameterModel) -> bool:
    """Whether the samples of a family model of the Delta have Clavel's closed form.

    A library Delta with three ball-jointed arms and its platform frame at the nacelle's
    centre: every sample is a Delta of the family whose nacelle keeps its orientation and sits
    where Clavel's direct model puts it (the other parameters of the model, the bars' spacing,
    move no nacelle position).
    """
    from pkdyn.dynamics.delta import has_delta_dynamics

    if robot.family != "delta" or not has_delta_dynamics(robot):
        return False
    assert robot.platform_frame is not None
    offset = robot.model.frames[robot.platform_frame].placement.translation
    return bool(np.all(np.asarray(offset) == 0.0))


def _family_sample(robot: Robot, model: ParameterModel, dp: np.ndarray) -> Robot:
    """The robot its family builder gives with the model's parameters moved by ``dp``."""
    params = family_values(robot, model, model.nominal + dp)
    return with_placements(
        robot, placements(robot), built_placements(robot, params), assemble=False
    )


class _Arrays:
    """Clavel's four lengths as (n, 1) arrays: :func:`pkdyn.closed_form.delta.forward` on all."""

    def __init__(self, values: dict[str, np.ndarray]) -> None:
        for k, v in values.items():
            setattr(self, k, v[:, None])


def _delta_family_errors(
    robot: Robot,
    model: ParameterModel,
    dp: np.ndarray,
    readings: np.ndarray,
    nominal: pin.SE3,
) -> tuple[np.ndarray, np.ndarray]:
    """Pose errors (n, 6) and which samples assemble (n,) of family samples of the Delta.

    Per sample, the lengths ``ra, rb, la, lb`` of the family's parameters moved by ``dp`` and
    the actuators at the readings with the samples' gains, Clavel's direct model; the nacelle
    keeps the nominal orientation (a zero rotation error).
    """
    from pkdyn.closed_form.delta import forward
    from pkdyn.precision.family_parameters import _resolved

    p0 = _resolved(robot)
    values = model.nominal[None, :] + dp
    names = list(model.names)
    lengths = {
        k: values[:, names.index(k)] if k in names else np.full(len(dp), float(getattr(p0, k)))
        for k in _DELTA_GEOMETRY
    }
    gains = np.array([model.gains(d) for d in dp]) if model.G.size else np.zeros((len(dp), 3))
    qa = readings[None, :3] * (1.0 + gains[:, :3])
    geometry: Any = _Arrays(lengths)
    P, ok = forward(geometry, qa)
    errors = np.zeros((len(dp), 6))
    errors[:, :3] = P - np.asarray(nominal.translation)[None, :]
    return errors, ok


def _gough_stewart_closed_form(robot: Robot, model: ParameterModel) -> bool:
    """Whether the samples of a family model of the Gough-Stewart have its batched direct model.

    A library Gough-Stewart (either base joint) built as its family builds it (its placements
    are those of its parameters: no other mounting, no moved joint), with its platform frame
    at the platform's origin, and a model whose parameters are joint centres ``A``, ``B`` or
    actuator gains: every sample is then a platform whose legs join ``A_i`` to ``B_i`` with
    the length its prismatic joint reads (:func:`pkdyn.closed_form.gough_stewart.forward`).
    """
    from pkdyn.library.gough_stewart import Params
    from pkdyn.precision.family_parameters import _resolved
    from pkdyn.precision.placements import local_placement

    if robot.family != "gough_stewart" or not isinstance(robot.params, Params):
        return False
    if robot.platform_frame is None or len(robot.actuators) != 6:
        return False
    frame = robot.model.frames[robot.platform_frame]
    if not frame.placement.isIdentity(0.0):
        return False
    if _gough_stewart_columns(robot, model) is None:
        return False
    where = placements(robot)
    ours = [local_placement(robot, pl) for pl in where]
    built = built_placements(robot, _resolved(robot))
    scale = robot.length_scale
    return all(
        np.allclose(a.homogeneous, b.homogeneous, rtol=0.0, atol=1e-12 * scale)
        for a, b in zip(ours, built, strict=True)
    )


def _gough_stewart_columns(
    robot: Robot, model: ParameterModel
) -> tuple[np.ndarray, np.ndarray] | None:
    """Where each of the model's joint-centre parameters sits in ``[A; B]`` (12, 3), or ``None``.

    Returns:
        The model's column (k,) and the flat index into the (12, 3) array ``[A; B]`` (k,) of
        each joint-centre parameter; ``None`` if a parameter is neither a joint centre nor a
        gain.

    """
    from pkdyn.precision.family_parameters import _param_name, _resolved, _scalar_fields

    p0 = _resolved(robot)
    flat = {
        _param_name(f, idx, p0): (0 if f == "A" else 18) + 3 * idx[0] + idx[1]
        for f, idx, _ in _scalar_fields(p0)
        if f in ("A", "B")
    }
    gains = np.any(model.G != 0.0, axis=0) if model.G.size else np.zeros(len(model.names), bool)
    cols, where = [], []
    for k, name in enumerate(model.names):
        if name in flat:
            cols.append(k)
            where.append(flat[name])
        elif not gains[k]:
            return None
    return np.array(cols, dtype=int), np.array(where, dtype=int)


_GS_TOL = 1e-13
"""Leg-length residual of a converged sample of the batched direct model, in robot sizes."""

_GS_MARGIN = 1e-2
"""Smallest singular value of a sample's leg rows, relative to its largest, of a sample the
batched direct model keeps; nearer a singularity, the general path solves it."""

_GS_MOVED = 0.5
"""Farthest a sample the batched direct model keeps may move from the nominal pose: in robot
sizes and in rad (farther, the general path solves it)."""


def _gough_stewart_family_errors(
    robot: Robot,
    model: ParameterModel,
    dp: np.ndarray,
    q: np.ndarray,
    nominal: pin.SE3,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pose errors (n, 6) of family samples of the Gough-Stewart, which were solved, refused.

    Per sample, the joint centres ``A``, ``B`` of the family's parameters moved by ``dp``, the
    legs at the readings with the samples' gains, and the direct geometric model solved by
    Newton's method from the nominal pose, every sample at once
    (:func:`pkdyn.closed_form.gough_stewart.forward`). A sample is left to the caller (``False``)
    where the general path would do something else than one solve from ``q`` (an actuator
    moving farther than a continuation step), where Newton's method does not converge, or
    near a singularity (:data:`_GS_MARGIN`) or far from the start (:data:`_GS_MOVED`): the
    general path then decides.

    Returns:
        The pose errors (n, 6) [m, rad] (of the solved samples), which samples were solved
        (n,), and which the family refuses (n,): joint centres that put a leg off its stroke
        at the home pose (``Params``' own test; on the general path, a failed sample).

    """
    from pkdyn.closed_form.gough_stewart import forward, leg_lengths, leg_rows, rotation_log
    from pkdyn.model.assembly import CONTINUATION_STEP
    from pkdyn.precision.family_parameters import _resolved

    p0 = _resolved(robot)
    n = len(dp)
    columns = _gough_stewart_columns(robot, model)
    assert columns is not None
    cols, where = columns
    values = model.nominal[None, :] + dp
    AB = np.broadcast_to(np.concatenate([p0.a, p0.b]).ravel(), (n, 36)).copy()
    AB[:, where] = values[:, cols]
    AB = AB.reshape(n, 12, 3)
    A, B = AB[:, :6], AB[:, 6:]
    readings = q[robot.actuated_q]
    gains = dp @ model.G.T if model.G.size else np.zeros((n, 6))
    rho = readings[None, :] * (1.0 + gains)
    near = np.max(np.abs(rho - readings) / robot.actuator_scale, axis=1) <= CONTINUATION_STEP
    R0 = np.asarray(nominal.rotation)
    p_start = np.asarray(nominal.translation)
    P, R, solved = forward(A, B, rho, p_start, R0, _GS_TOL * robot.length_scale)
    solved &= near
    # the family refuses joint centres that put a leg off its stroke at the home pose
    # (Params.__post_init__): those samples fail on the general path; at the stroke's ends
    # to rounding, the general path decides
    home = np.broadcast_to(np.array([0.0, 0.0, p0.home_height()]), (n, 3))
    at_home = leg_lengths(A, B, home, np.broadcast_to(np.eye(3), (n, 3, 3)))
    lo, hi = np.asarray(p0.rho_min, dtype=float), np.asarray(p0.rho_max, dtype=float)
    margin = _GS_TOL * robot.length_scale
    refused = np.any((at_home < lo - margin) | (at_home > hi + margin), axis=1)
    accepted = np.all((at_home > lo + margin) & (at_home < hi - margin), axis=1)
    solved &= accepted
    rows = leg_rows(A[solved], B[solved], P[solved], R[solved])
    s = np.linalg.svd(rows, compute_uv=False)
    solved[solved] = s[:, -1] > _GS_MARGIN * s[:, 0]
    errors = np.zeros((n, 6))
    errors[:, :3] = P - p_start[None, :]
    errors[:, 3:] = rotation_log(np.matmul(R0.T[None], R))
    # a platform moved far from the start: the general path's (damped) solve may end in
    # another assembly mode, or nowhere
    moved = np.maximum(
        np.sqrt(np.sum(errors[:, :3] ** 2, axis=1)) / robot.length_scale,
        np.sqrt(np.sum(errors[:, 3:] ** 2, axis=1)),
    )
    solved &= moved <= _GS_MOVED
    return errors, np.where(refused, False, solved), refused
