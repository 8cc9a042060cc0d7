"""Identify a robot's dynamic parameters from one measured motion: the whole procedure.

1. The robot must be identifiable (:func:`~.structure.check_identifiable`); its standard
   parameters and the groups to identify (:mod:`~.parameters`); the base parameters, from the
   regressor of random motions (:func:`~.structure.structural_base`).
2. The readings become joint coordinates (:meth:`pkdyn.Robot.joint_coordinates`: a calibrated
   description's encoder gains and offsets); they are checked against the joints' limits and
   the motion must move (:mod:`~.checks`); rates and accelerations come from zero-phase
   filtering when only positions are given (:mod:`~.filtering`).
3. A coarse pass along the motion (a sample every :data:`SPLIT_STEP` of actuator travel)
   assembles it: readings the robot cannot be assembled at are refused, naming their line; its
   configurations also start the worker processes.
4. Batch after batch: joint motions (:mod:`~.motion`), regressor rows (:mod:`~.regressor`),
   folded into the weighted least squares (:mod:`~.estimation`); from
   :data:`PARALLEL_SAMPLES` samples on, two worker processes (:func:`pkdyn.workers.fork_map`)
   share them, each from its start configuration, and their factors are merged.
5. The estimate: which base parameters the motion excites (each judged against its plausible
   magnitude, :mod:`~.magnitudes`); the others held at their nominal values and flagged.
6. Physically consistent standard parameters reproducing the estimate (:mod:`~.physical`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pkdyn.exceptions import InvalidInputError, TrajectoryError
from pkdyn.identifiability import Identifiability
from pkdyn.identification.checks import check_limits, check_moves, readings_hint
from pkdyn.identification.data import MAX_SAMPLES, Measurements
from pkdyn.identification.estimation import Accumulator
from pkdyn.identification.filtering import derivatives
from pkdyn.identification.magnitudes import base_references, drive_scales, prior_weights
from pkdyn.identification.motion import BATCH, MotionSampler
from pkdyn.identification.parameters import ParameterSet, parameter_set
from pkdyn.identification.physical import consistent_parameters
from pkdyn.identification.regressor import ClosedLoopRegressor
from pkdyn.identification.result import Fit, IdentificationResult
from pkdyn.identification.structure import check_identifiable, structural_base
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.results import renamed_keyword
from pkdyn.threads import single_blas_thread
from pkdyn.units import vector

__all__ = [
    "FIT_SAMPLES",
    "MAX_SAMPLES",
    "PARALLEL_SAMPLES",
    "SPLIT_STEP",
    "check_identifiable",
    "identify",
    "structural_base",
]

PARALLEL_SAMPLES = 20_000
"""From this many samples on, two worker processes share the samples by default."""

SPLIT_STEP = 0.05
"""Actuator travel [rad, or a tenth of the actuator scale] between the samples of the coarse
pass that checks the closures and finds where the worker processes start."""

FIT_SAMPLES = 2_000
"""Most samples kept to show the fit (measured and predicted efforts): evenly spaced."""


@dataclass(frozen=True, eq=False)  # numpy fields
class _Work:
    """What every share of the samples reads (passed to the worker processes by fork)."""

    robot: Robot
    ps: ParameterSet
    base: Identifiability
    t: np.ndarray
    qa: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    every: int  # a sample in every ``every`` is kept to show the fit


@dataclass(eq=False)  # numpy fields
class _Share:
    """The folded rows of a share of the samples."""

    factors: list[np.ndarray]
    samples: int
    colsq: np.ndarray
    kept: np.ndarray  # indices of the samples kept to show the fit
    Y: np.ndarray  # their base regressor rows (k, n_a, p_b)
    known: np.ndarray  # their known efforts (k, n_a)


def _accumulate(
    work: _Work, job: tuple[int, int, np.ndarray | None], progress: bool | None = False
) -> _Share:
    """Regressor rows of samples ``first:stop`` folded into triangular factors."""
    first, stop, q0 = job
    robot, ps, base = work.robot, work.ps, work.base
    reg = ClosedLoopRegressor(robot, ps)
    sampler = MotionSampler(robot, q0)
    acc = Accumulator(len(robot.actuators), base.size)
    colsq = np.zeros(int(ps.identified.sum()))
    ind = base.identifiable
    kept, Ys, knowns = [], [], []
    starts = range(first, stop, BATCH)
    for s in progress_bar(starts, "identification", "batch", progress, min_items=20):
        e = min(stop, s + BATCH)
        b = sampler.batch(work.t[s:e], work.qa[s:e], work.qd[s:e], work.qdd[s:e], s)
        Y, known = reg.rows(b)
        colsq += np.einsum("nip,nip->p", Y, Y)
        Yb = Y[:, :, ind]
        acc.add(Yb, work.tau[s:e] - known)
        pick = np.flatnonzero((np.arange(s, e) % work.every) == 0)
        kept.append(s + pick)
        Ys.append(Yb[pick])
        knowns.append(known[pick])
    return _Share(
        acc.factors(),
        acc.samples,
        colsq,
        np.concatenate(kept) if kept else np.zeros(0, dtype=int),
        np.concatenate(Ys) if Ys else np.zeros((0, len(robot.actuators), base.size)),
        np.concatenate(knowns) if knowns else np.zeros((0, len(robot.actuators))),
    )


def _worker(work: _Work, job: tuple[int, int, np.ndarray | None]) -> _Share:
    return _accumulate(work, job, False)


def _coarse_pass(
    robot: Robot, data: Measurements, t: np.ndarray, qa: np.ndarray, splits: list[int]
) -> list[np.ndarray]:
    """Assemble the motion on a coarse grid; the configurations at the ``splits`` samples.

    The grid keeps the samples where the actuators have moved :data:`SPLIT_STEP` (in units of
    a tenth of their scale for prismatic ones) since the last kept sample: its cost follows the
    length of the motion, not the number of samples, and a fast motion is followed as closely
    as a slow one.

    Raises:
        InvalidInputError: Readings the robot cannot be assembled at (their line named).

    """
    unit = robot.actuator_scale * np.where(robot.actuator_prismatic, 0.1, 1.0)
    step = np.abs(np.diff(qa, axis=0) / unit).max(axis=1, initial=0.0)
    travel = np.concatenate([[0.0], np.cumsum(step)])
    cells = np.floor(travel / SPLIT_STEP)
    kept = np.flatnonzero(np.diff(cells, prepend=-1.0) > 0)
    idx = np.union1d(kept, np.asarray(splits, dtype=int))
    try:
        Q, _ = MotionSampler(robot).configurations(qa[idx], t[idx])
    except TrajectoryError as err:
        k = int(idx[err.sample]) if err.sample is not None and err.sample < idx.size else 0
        detail = str(err).split(": ", 1)[-1]
        raise InvalidInputError(
            data.source,
            f"{data.where(k)} (t = {t[k]:.6g} s): the readings {vector(data.qa[k])} cannot be "
            f"assembled ({detail}; the robot's size is {robot.length_scale:.3g} m)"
            + readings_hint(robot, qa[idx[: max(err.sample or 0, 0) + 1]]),
        ) from None
    return [Q[int(np.searchsorted(idx, k))] for k in splits]


@renamed_keyword("data", "measurements")
@public
def identify(
    robot: Robot,
    measurements: Measurements,
    parameters: Sequence[str] | str | None = None,
    cutoff: float | None = None,
    progress: bool | None = None,
    workers: int | None = None,
) -> IdentificationResult:
    """Identify the dynamic parameters of a robot from one measured motion.

    Args:
        robot: The robot (its values are the nominal ones, and the ones held).
        measurements: The measured motion, with efforts; its ``qa`` are actuator readings (the
            robot's readings rule applies, :meth:`pkdyn.Robot.joint_coordinates`; ``data``: its
            former name, kept for one release).
        parameters: Groups to identify (:data:`~pkdyn.identification.parameters.GROUPS`;
            default inertia, friction, rotor).
        cutoff: Cut-off frequency [Hz] of the position filter when the rates are not given.
        progress: Progress bar (``None``: on a terminal, for more than 20 batches; one
            process only).
        workers: Processes sharing the samples (default: 2 from :data:`PARALLEL_SAMPLES`
            samples on where processes can be forked, else 1); each follows its share from an
            assembled configuration found on the coarse pass, and their factors are merged.

    Returns:
        The identification (base parameters with their standard deviations and how well the
        motion excites each, physical parameters, what is not identifiable).

    Raises:
        InvalidInputError: A robot that cannot be identified, measurements without efforts or
            of the wrong width, too few samples, readings beyond the joints' limits or that
            cannot be assembled (their line named), or a motion that excites nothing.
        TrajectoryError: A sample that cannot be assembled.

    """
    with single_blas_thread():
        return _identify(robot, measurements, parameters, cutoff, progress, workers)


def _identify(
    robot: Robot,
    data: Measurements,
    parameters: Sequence[str] | str | None,
    cutoff: float | None,
    progress: bool | None,
    workers: int | None,
) -> IdentificationResult:
    start = time.perf_counter()
    from pkdyn.inputs import count, flag, instance, positive
    from pkdyn.workers import can_fork, fork_map

    instance("robot", robot, Robot, "a Robot (pkdyn.load)")
    what = "Measurements (pkdyn.identification.read_measurements)"
    instance("measurements", data, Measurements, what)
    if cutoff is not None:
        cutoff = positive("cutoff", cutoff, "Hz")
    if workers is not None:
        workers = count("workers", workers, 1, 1024)
    if progress is not None:
        progress = flag("progress", progress)
    check_identifiable(robot)
    n_a = len(robot.actuators)
    if data.tau is None:
        raise InvalidInputError(data.source, "no tau_* columns: the efforts to identify from")
    if data.qa.shape[1] != n_a:
        raise InvalidInputError(data.source, f"{data.qa.shape[1]} actuators for {n_a}")
    N = data.t.size
    if N > MAX_SAMPLES:
        raise InvalidInputError(
            data.source,
            f"{N} samples: more than {MAX_SAMPLES} (about {N * 1e-4 / 60:.0f} min); decimate "
            "the recording",
        )
    # the readings rule, then what the readings can be
    qa = robot.joint_coordinates(data.qa)
    check_limits(robot, qa, data.source, data.where)
    check_moves(robot, qa, data.source)
    ps = parameter_set(robot, parameters)
    base, _ = structural_base(robot, ps)
    if base.size == 0:
        raise InvalidInputError("parameters", "no chosen parameter has an effect on the efforts")
    formulas = base.formulas()
    if N * n_a < base.size:
        raise InvalidInputError(
            data.source,
            f"{N} samples x {n_a} actuators = {N * n_a} equations for {base.size} base "
            f"parameters; record at least {int(np.ceil(base.size / n_a)) + 1} samples",
        )
    if data.qa_dot is None or data.qa_ddot is None:
        qa, qd, qdd = derivatives(data.t, qa, cutoff)
    else:
        qd = robot.joint_coordinates(data.qa_dot, rates=True)
        qdd = robot.joint_coordinates(data.qa_ddot, rates=True)
    if workers is None:
        workers = min(2, os.cpu_count() or 1) if can_fork() and N >= PARALLEL_SAMPLES else 1
    workers = count("workers", workers, 1, 64) if can_fork() else 1
    workers = max(1, min(workers, N // (4 * BATCH) or 1))
    bounds = [round(k * N / workers) for k in range(workers + 1)]
    starts = _coarse_pass(robot, data, data.t, qa, bounds[1:-1])
    work = _Work(robot, ps, base, data.t, qa, qd, qdd, data.tau, max(1, -(-N // FIT_SAMPLES)))
    jobs: list[tuple[int, int, np.ndarray | None]] = [(bounds[0], bounds[1], None)] + [
        (bounds[k], bounds[k + 1], q) for k, q in zip(range(1, workers), starts, strict=True)
    ]
    if workers > 1:
        shares = fork_map(_worker, work, jobs)
    else:
        shares = [_accumulate(work, jobs[0], progress)]
    if not np.any(data.tau):
        raise InvalidInputError(
            data.source,
            "every tau_* value is 0: the efforts carry nothing to identify from (check the "
            "tau_* columns: joint-side efforts [N m or N])",
        )
    acc = Accumulator(n_a, base.size)
    colsq = np.zeros(int(ps.identified.sum()))
    for share in shares:
        acc.merge(share.factors, share.samples)
        colsq += share.colsq
    sel = np.flatnonzero(ps.identified)
    nominal = ps.nominal[sel]
    scales = drive_scales(robot)
    est = acc.estimate(formulas, base_references(base, nominal, scales), base.K @ nominal)
    pos = {int(c): k for k, c in enumerate(sel)}
    bodies = [
        slice(pos[ps.body_slice(k).start], pos[ps.body_slice(k).start] + 10)
        for k in range(len(ps.bodies))
        if ps.identified[ps.body_slice(k).start]
    ]
    if ps.identified[ps.payload_slice.start]:
        s0 = pos[ps.payload_slice.start]
        bodies.append(slice(s0, s0 + 10))
    nonneg = np.array([ps.groups[c] in ("friction", "rotor") for c in sel])
    sigma = float(np.sqrt(np.mean(est.sigma**2))) or 1.0
    K = base.K
    unseen = ~np.any(K[est.excited] != 0.0, axis=0)  # only in base parameters not excited
    effect = prior_weights(np.sqrt(colsq) / sigma, nominal, base, unseen, scales)
    theta_id = consistent_parameters(K, est.R, est.theta, nominal, bodies, nonneg, effect)
    theta = ps.nominal.copy()
    theta[sel] = theta_id
    kept = np.concatenate([s.kept for s in shares])
    Yk = np.concatenate([s.Y for s in shares])
    known = np.concatenate([s.known for s in shares])
    fit = Fit(
        data.t[kept],
        data.tau[kept],
        np.einsum("nip,p->ni", Yk, est.theta) + known,
        np.einsum("nip,p->ni", Yk, K @ theta_id) + known,
    )
    return IdentificationResult(
        robot=robot,
        parameters=ps,
        base=base,
        estimate=est,
        theta=theta,
        filtered=data.qa_dot is None,
        seconds=time.perf_counter() - start,
        fit=fit,
    )
