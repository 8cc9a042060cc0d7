"""How many poses, how accurate a measurement: planning a calibration by simulation.

:func:`plan_calibration` answers "with which number of poses and which measurement noise does
the calibrated robot reach a target accuracy?" from simulated calibrations of perturbed robots:

1. candidate poses inside the workspace (:func:`~pkdyn.calibration.selection.candidate_poses`)
   are ordered by the greedy D-optimal choice (:func:`~pkdyn.calibration.selection.
   select_poses`): the first ``N`` of them are the ``N`` poses measured; other candidates are the
   validation poses;
2. each trial draws the parameter errors within their tolerances, builds that robot
   (:func:`~pkdyn.precision.perturbation.perturbed`) and solves its forward geometry at the
   readings of every pose (the truth);
3. for each pose count ``N`` and noise ``sigma``, the truth at the ``N`` poses plus Gaussian
   noise is the measurement, and :func:`~pkdyn.calibration.calibrate` itself estimates the
   errors from it (the estimator a calibration uses: robust weights, the prior, iterations to
   convergence; stated noise ``sigma``, no hold-out, the trust rules not applied); the
   estimated robot's position error at the validation poses (RMS and largest) is recorded (a
   calibration that fails counts as an infinite error).

The result (:class:`CalibrationPlan`) tabulates the mean errors over the trials and, per noise,
the smallest pose count that meets the target.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.calibration.identifiability import identifiability
from pkdyn.calibration.measurements import Measurements
from pkdyn.calibration.selection import candidate_poses, design_matrix, select_poses
from pkdyn.calibration.solve import calibrate
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel, parameter_model
from pkdyn.precision.perturbation import perturbed
from pkdyn.progress import progress as progress_bar
from pkdyn.results import Result, deprecated, renamed_keyword
from pkdyn.threads import one_blas_thread
from pkdyn.units import quantity

__all__ = ["CalibrationPlan", "plan_calibration"]

MAX_RUNS = 2_000
"""Most simulated calibrations of one plan (trials x noise levels x pose counts): each is a
whole calibration (0.1 to 1 s), so that a plan stays under about half an hour."""


@dataclass
class CalibrationPlan(Result):
    """Simulated calibration accuracy per pose count and measurement noise.

    Attributes:
        poses: Pose counts (n_N,).
        noise: Measurement noise standard deviations [m] (n_s,).
        rms: Mean over the trials of the RMS position error at the validation poses after
            calibration (n_N, n_s) [m].
        worst: Mean over the trials of the largest position error (n_N, n_s) [m].
        before: Mean RMS position error of the uncalibrated robots [m].
        target: The target [m].
        statistic: ``rms`` or ``max``: which error the target bounds.
        identifiable: Number of identifiable parameters.
        trials: Number of simulated robots.

    """

    poses: np.ndarray
    noise: np.ndarray
    rms: np.ndarray
    worst: np.ndarray
    before: float
    target: float
    statistic: str
    identifiable: int
    trials: int

    def meets(self) -> np.ndarray:
        """(n_N, n_s) True where the target is met."""
        err = self.rms if self.statistic == "rms" else self.worst
        return err <= self.target

    def recommendation(self) -> dict[float, int | None]:
        """Per noise: the smallest pose count meeting the target (``None``: none does)."""
        ok = self.meets()
        out: dict[float, int | None] = {}
        for j, s in enumerate(self.noise):
            rows = np.flatnonzero(ok[:, j])
            out[float(s)] = int(self.poses[rows[0]]) if rows.size else None
        return out

    def summary(self) -> str:
        """One sentence: what reaches the target."""
        rec = {s: n for s, n in self.recommendation().items() if n is not None}
        what = "RMS" if self.statistic == "rms" else "largest"
        if not rec:
            return (
                f"no tested pose count and noise reaches a {what} position error of "
                f"{quantity(self.target, 'm')} (best: {quantity(float(np.min(self.rms)), 'm')} "
                "RMS)"
            )
        s_max = max(rec)
        return (
            f"a {what} position error <= {quantity(self.target, 'm')} needs a measurement "
            f"noise <= {quantity(s_max, 'm')} with >= {rec[s_max]} poses"
            + "".join(
                f"; noise {quantity(s, 'm')}: {n} poses"
                for s, n in sorted(rec.items())
                if s != s_max
            )
        )

    def table(self) -> str:
        """The mean errors after calibration per pose count (rows) and noise (columns)."""
        head = f"{'poses':>6} " + " ".join(f"{quantity(s, 'm'):>22}" for s in self.noise)
        lines = [
            f"{self.trials} simulated robots, {self.identifiable} identifiable parameters; "
            f"uncalibrated: {quantity(self.before, 'm')} RMS at the validation poses",
            "position error after calibration, RMS / largest, per measurement noise:",
            head,
        ]
        for i, n in enumerate(self.poses):
            cells = [
                f"{quantity(self.rms[i, j], 'm')} / {quantity(self.worst[i, j], 'm')}"
                for j in range(self.noise.size)
            ]
            lines.append(f"{int(n):>6} " + " ".join(f"{c:>22}" for c in cells))
        lines.append(self.summary())
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        """Deprecated: :meth:`to_json`."""
        deprecated("CalibrationPlan.as_dict", "to_json()")
        return self.to_json()

    def to_json(self) -> dict[str, Any]:
        """The plan as JSON values (errors and noise [m])."""
        return {
            "poses": [int(n) for n in self.poses],
            "noise": [float(s) for s in self.noise],
            "rms": self.rms.tolist(),
            "worst": self.worst.tolist(),
            "before": self.before,
            "target": self.target,
            "statistic": self.statistic,
            "identifiable": self.identifiable,
            "trials": self.trials,
            "recommendation": {str(k): v for k, v in self.recommendation().items()},
            "summary": self.summary(),
        }


def _positions(
    robot: Robot, gains: np.ndarray, readings: np.ndarray, qs: list[np.ndarray]
) -> np.ndarray:
    out = np.empty((len(readings), 3))
    for i, (r, q) in enumerate(zip(readings, qs, strict=True)):
        res = forward_geometry(robot, (1.0 + gains) * r, q_init=q, check_limits=False)
        assert res.placement is not None
        out[i] = res.placement.translation
    return out


@one_blas_thread
@renamed_keyword("progress_bar", "progress")
def plan_calibration(
    robot: Robot,
    target: float,
    model: ParameterModel | str = "auto",
    tolerance: Sequence[float] | np.ndarray | tuple[float, float] = (2e-3, 0.0087),
    poses: Sequence[int] | None = None,
    noise: Sequence[float] = (1e-6, 1e-5, 1e-4),
    statistic: str = "rms",
    trials: int = 3,
    candidates: int = 150,
    validation: int = 40,
    seed: int = 0,
    progress: bool | None = None,
) -> CalibrationPlan:
    """Simulate calibrations to find the pose count and measurement noise a target needs.

    Position measurements (the common case; module docstring).

    Args:
        robot: The nominal robot.
        target: Position accuracy to reach after calibration [m].
        model: Parameter model or its name (:func:`pkdyn.precision.parameters.parameter_model`).
        tolerance: ``(length [m], angle [rad])`` tolerances of the parameters (default +-2 mm,
            +-0.5 deg), or one per parameter; errors are drawn uniformly within them.
        poses: Pose counts to try (default: from the identifiable count, times 1, 1.5, 2, 4).
        noise: Measurement noise standard deviations to try [m].
        statistic: The target bounds the ``rms`` or the ``max`` position error.
        trials: Simulated robots per setting.
        candidates: Candidate poses drawn in the workspace.
        validation: Candidates kept apart to validate (not measured).
        seed: Random seed.
        progress: Force the progress bar on or off (``progress_bar``: its former name, kept
            for one release).

    Returns:
        The plan.

    Raises:
        InvalidInputError: Bad target, statistic or counts.

    """
    from pkdyn import inputs

    inputs.instance("robot", robot, Robot, "a Robot (pkdyn.load)")
    try:
        target = inputs.positive("target", target, "m", bound=robot.length_scale)
    except InvalidInputError:
        raise InvalidInputError(
            "target", f"{target}: give a position accuracy > 0 m (at most the robot's size)"
        ) from None
    if statistic not in ("rms", "max"):
        raise InvalidInputError("statistic", f"'{statistic}': use rms or max")
    try:
        trials = inputs.count("trials", trials, 1, 1000)
    except InvalidInputError:
        raise InvalidInputError("trials", f"{trials}: give 1 to 1,000") from None
    candidates = inputs.count("candidates", candidates, 4, 5000)
    validation = inputs.count("validation", validation, 1, 5000)
    seed = inputs.seed("seed", seed)
    noise_arr = inputs.vector("noise", noise, None, "m", bound=robot.length_scale)
    if noise_arr.size == 0 or np.any(noise_arr <= 0.0):
        raise InvalidInputError("noise", f"{list(noise_arr)}: give noise levels > 0 m")
    noise = [float(s) for s in noise_arr]
    if poses is not None:
        poses = [inputs.count("poses", n, 1, 5000) for n in inputs.vector("poses", poses)]
    runs = trials * len(noise) * (4 if poses is None else len(poses))
    if runs > MAX_RUNS:
        raise InvalidInputError(
            "trials",
            f"{trials} trials x {len(noise)} noise levels x the pose counts = {runs} simulated "
            f"calibrations, more than {MAX_RUNS}: fewer trials or settings",
        )
    pm = parameter_model(robot, model) if isinstance(model, str) else model
    tol = inputs.vector("tolerance", tolerance, None, "m, rad", bound=1e3)
    t = pm.tolerances(float(tol[0]), float(tol[1])) if tol.size == 2 and pm.size != 2 else tol
    if t.shape != (pm.size,):
        raise InvalidInputError("tolerance", f"give (length, angle) or {pm.size} values")
    qs = candidate_poses(robot, candidates + validation, seed=seed, progress=progress)
    if len(qs) < validation + 4:
        raise InvalidInputError(
            "candidates", f"only {len(qs)} poses found inside the workspace; lower validation"
        )
    qv, qc = qs[:validation], qs[validation:]
    blocks = design_matrix(robot, qc, pm)  # (zero columns: errors the loops cannot absorb)
    t = np.where(np.all(blocks == 0.0, axis=(0, 1)), 0.0, t)  # those are not drawn
    ident = identifiability(blocks.reshape(-1, pm.size), list(pm.names), len(qc))
    cols = np.sort(ident.identifiable)
    r = cols.size
    if poses is None:
        base = int(np.ceil((r + 1) / 3))
        counts = sorted({min(len(qc), max(base, int(f * base))) for f in (1.0, 1.5, 2.0, 4.0)})
    else:
        counts = sorted(int(n) for n in poses)
    if counts[0] * 3 <= r or counts[-1] > len(qc):
        raise InvalidInputError(
            "poses",
            f"pose counts must give more than {r} values (> {r // 3} poses) and at most the "
            f"{len(qc)} candidates",
        )
    order = select_poses(blocks, counts[-1]).order
    qa_c = np.array([q[robot.actuated_q] for q in qc])  # joint coordinates
    readings_v = np.array([q[robot.actuated_q] for q in qv])
    rng = np.random.default_rng(seed + 1)
    rms = np.zeros((len(counts), len(noise)))
    worst = np.zeros_like(rms)
    before = []
    done = 0
    for _ in progress_bar(range(trials), "calibration plan", "robot", progress):
        p_true = rng.uniform(-1.0, 1.0, pm.size) * t
        try:
            truth = perturbed(robot, pm, p_true)
            x_c = _positions(truth.robot, truth.gains, qa_c, qc)
            x_v = _positions(truth.robot, truth.gains, readings_v, qv)
        except PkdynError:
            continue
        done += 1
        f0_v = np.array([robot.platform_placement(q).translation for q in qv])
        before.append(float(np.sqrt(np.mean(np.sum((x_v - f0_v) ** 2, axis=1)))))
        for a, n in enumerate(counts):
            sel = order[:n]
            for b, s in enumerate(noise):
                measured = x_c[sel] + rng.normal(0.0, s, (n, 3))
                m = Measurements("position", robot.readings(qa_c[sel]), measured)
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        est = calibrate(robot, m, pm, noise=s, holdout=0.0, accept=True)
                    xv_est = _positions(est.robot, est.gains, readings_v, qv)
                except PkdynError:
                    rms[a, b] += np.inf
                    worst[a, b] += np.inf
                    continue
                e = np.linalg.norm(xv_est - x_v, axis=1)
                rms[a, b] += float(np.sqrt(np.mean(e**2)))
                worst[a, b] += float(np.max(e))
    if done == 0:
        raise InvalidInputError(
            "tolerance", "no simulated robot could be assembled: smaller tolerances"
        )
    return CalibrationPlan(
        np.array(counts),
        np.asarray(noise, dtype=float),
        rms / done,
        worst / done,
        float(np.mean(before)),
        float(target),
        statistic,
        r,
        done,
    )
