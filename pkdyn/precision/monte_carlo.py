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
        res = forward_geometry(sample, qa, q_init=q, check_limits=False)
    except PkdynError:
        return None
    assert res.placement is not None
    return pose_error(nominal, res.placement)


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
