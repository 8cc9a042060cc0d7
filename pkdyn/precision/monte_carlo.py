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
from pkdyn.progress import progress
from pkdyn.results import Result, jsonable
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
    progress_bar: bool | None = None,
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
        progress_bar: Force the progress bar on or off (default: on a terminal).

    Returns:
        The sampled pose errors.

    Raises:
        InvalidInputError: Malformed tolerances, distribution or sample count.

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
    errors, failed = [], 0
    family = model.kind == "family parameters"
    for _ in progress(range(int(samples)), "Monte Carlo", "robot", progress_bar, min_items=50):
        dp = _draw(rng, t, distribution)
        try:
            if family:
                sample = _family_sample(robot, model, dp)
                qa = readings * (1.0 + model.gains(dp))
            else:
                pert = perturbed(robot, model, dp)
                sample, qa = pert.robot, pert.joint_coordinates(readings)
            res = forward_geometry(sample, qa, q_init=qq, check_limits=False)
        except PkdynError:
            failed += 1
            continue
        assert res.placement is not None
        errors.append(pose_error(nominal, res.placement))
    return MonteCarlo(np.array(errors).reshape(-1, 6), failed, distribution=distribution, seed=seed)


def _family_sample(robot: Robot, model: ParameterModel, dp: np.ndarray) -> Robot:
    """The robot its family builder gives with the model's parameters moved by ``dp``."""
    params = family_values(robot, model, model.nominal + dp)
    return with_placements(robot, placements(robot), built_placements(robot, params))
