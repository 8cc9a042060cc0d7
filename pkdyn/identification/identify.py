"""Identify a robot's dynamic parameters from one measured motion: the whole procedure.

1. The standard parameters and the groups to identify (:mod:`~.parameters`); the robot must be
   non-redundantly actuated and its actuators must determine its motion (internal mobilities
   such as a Delta's bar spin are allowed: no sensor sees them).
2. The base parameters, from the regressor of random motions (:mod:`~.base`).
3. Rates and accelerations by zero-phase filtering when only positions are given
   (:mod:`~.filtering`).
4. Batch after batch: joint motions (:mod:`~.motion`), regressor rows (:mod:`~.regressor`),
   folded into the weighted least squares (:mod:`~.estimation`).
5. Physically consistent standard parameters reproducing the estimate (:mod:`~.physical`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from pkdyn.dynamics.actuation import actuation
from pkdyn.exceptions import InvalidInputError
from pkdyn.identification.base import BaseParameters, base_parameters
from pkdyn.identification.data import Measurements
from pkdyn.identification.estimation import Accumulator
from pkdyn.identification.filtering import derivatives
from pkdyn.identification.motion import BATCH, SINGULAR_RTOL, MotionBatch, MotionSampler
from pkdyn.identification.parameters import ParameterSet, parameter_set
from pkdyn.identification.physical import consistent_parameters
from pkdyn.identification.regressor import ClosedLoopRegressor
from pkdyn.identification.result import IdentificationResult
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.threads import single_blas_thread
from solvers import numerics

__all__ = ["MAX_SAMPLES", "check_identifiable", "identify", "structural_base"]

MAX_SAMPLES = 2_000_000
"""Largest number of samples accepted (about 3 minutes for a Delta on one core)."""

PARALLEL_SAMPLES = 20_000
"""From this many samples on, two worker processes share the samples by default."""

SPLIT_STEP = 0.05
"""Actuator travel [rad, or a tenth of the actuator scale] between the samples of the coarse
pass that finds where the worker processes start."""

_WORK: dict[str, Any] = {}  # the job of the worker processes (inherited by fork)

_SEED = 20240527


def check_identifiable(robot: Robot) -> None:
    """Refuse robots whose efforts the measured actuator motion does not determine.

    Raises:
        InvalidInputError: No actuator, redundant actuation, or actuators that do not
            determine the motion (an underactuated or floating mechanism).

    """
    n_a = len(robot.actuators)
    if n_a == 0:
        raise InvalidInputError("robot", f"{robot.name} has no actuator: nothing to identify")
    dof, _ = robot.mobility_split()
    if dof != n_a:
        what = "redundantly actuated" if dof < n_a else "underactuated"
        raise InvalidInputError(
            "robot",
            f"{robot.name} is {what} ({n_a} actuators for {dof} degrees of freedom): its "
            "efforts are not a function of the actuator motion; identification needs "
            "exactly one actuator per degree of freedom",
        )
    if robot.closure_set.nc:
        J = robot.closure_set.jacobian(robot.model.createData(), robot.q_home)
        Z = numerics.null_space(J, numerics.RTOL, 1.0)
        G = Z.T @ actuation(robot).matrix(robot.nv).T
        if numerics.rank(G, numerics.RTOL, 1.0) < n_a:
            raise InvalidInputError(
                "robot",
                f"{robot.name}: the actuators are not independent at home (singular or "
                "redundant actuation); identification needs independent actuators",
            )


def _random_batches(robot: Robot, n: int, seed: int) -> list[MotionBatch]:
    """Joint motions of ``n`` random samples near home, closure-consistent (structural rows).

    The samples of a draw are solved together (batched Newton from home); the few that do not
    converge, or are singular, are replaced by the next draw, and after four draws by samples
    solved one at a time.
    """
    rng = np.random.default_rng(seed)
    n_a = len(robot.actuators)
    lo = robot.model.lowerPositionLimit[robot.actuated_q]
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    qa0 = robot.q_home[robot.actuated_q]
    spread = 0.2 * robot.actuator_scale * np.where(robot.actuator_prismatic, 0.1, 1.0)
    finite = np.isfinite(lo) & np.isfinite(hi)
    spread = np.where(finite, np.minimum(spread, 0.2 * (hi - lo)), spread)
    sampler = MotionSampler(robot)
    out: list[MotionBatch] = []
    got, draws = 0, 0
    while got < n and draws < 4:
        draws += 1
        m = min(BATCH, n - got)
        qa = qa0 + spread * rng.uniform(-1.0, 1.0, (m, n_a))
        if finite.any():
            qa = np.where(finite, np.clip(qa, lo, hi), qa)
        qd = robot.actuator_scale * rng.standard_normal((m, n_a))
        qdd = robot.actuator_scale * rng.standard_normal((m, n_a)) * 10.0
        Q = np.tile(robot.q_home, (m, 1))
        Q[:, robot.actuated_q] = qa
        J = np.zeros((m, robot.closure_set.nc, robot.nv))
        failed = sampler.newton_batch(Q, np.arange(m), J)
        keep = np.setdiff1d(np.arange(m), failed)
        if failed.size:  # the buffers of the kept samples moved to rows 0..k-1
            for k, i in enumerate(keep):
                sampler.kin.capture_configuration(k, Q[i])
        b, err = sampler.rates(Q[keep], J[keep], qd[keep], qdd[keep])
        ok = np.flatnonzero(err <= SINGULAR_RTOL)
        if ok.size < keep.size:
            P = None if b.passive_map is None else b.passive_map[ok]
            b = MotionBatch(b.q[ok], b.v[ok], b.a[ok], b.J[ok], 0, P)
        out.append(b)
        got += ok.size
    tries = 0
    while got < n and tries < 4 * n:  # sample by sample (Levenberg-Marquardt where needed)
        tries += 1
        qa1 = qa0 + spread * rng.uniform(-1.0, 1.0, n_a)
        if finite.any():
            qa1 = np.where(finite, np.clip(qa1, lo, hi), qa1)
        qd1 = robot.actuator_scale * rng.standard_normal(n_a)
        qdd1 = robot.actuator_scale * rng.standard_normal(n_a) * 10.0
        sampler.restart(robot.q_home)
        try:
            out.append(sampler.batch(np.zeros(1), qa1[None], qd1[None], qdd1[None]))
        except Exception:  # noqa: BLE001 - a random sample out of reach: draw another
            continue
        got += 1
    if got < n:
        raise InvalidInputError(
            "robot", f"{robot.name}: random motions near home could not be assembled"
        )
    return out


def structural_base(
    robot: Robot, ps: ParameterSet, seed: int = _SEED
) -> tuple[BaseParameters, np.ndarray]:
    """Base parameters of the identified columns, from random closure-consistent motions.

    Args:
        robot: The robot.
        ps: Its parameter set.
        seed: Seed of the random motions.

    Returns:
        The base parameters and the column norms (p_id,) of the random regressor.

    """
    reg = ClosedLoopRegressor(robot, ps)
    p_id = int(ps.identified.sum())
    n_a = len(robot.actuators)
    n = int(np.ceil(3 * p_id / n_a)) + 20
    rows = []
    for b in _random_batches(robot, n, seed):
        Y, _ = reg.rows(b)
        rows.append(Y.reshape(-1, p_id))
    Y = np.vstack(rows)
    names = [ps.names[i] for i in np.flatnonzero(ps.identified)]
    return base_parameters(Y, names), np.linalg.norm(Y, axis=0) / np.sqrt(Y.shape[0])


def _accumulate(
    first: int, stop: int, q0: np.ndarray | None, progress: bool | None
) -> tuple[list[np.ndarray], int, np.ndarray]:
    """Regressor rows of samples ``first:stop`` folded into triangular factors (``_WORK``)."""
    w = _WORK
    robot, ps, base = w["robot"], w["ps"], w["base"]
    t, qa, qd, qdd, tau = w["t"], w["qa"], w["qd"], w["qdd"], w["tau"]
    reg = ClosedLoopRegressor(robot, ps)
    sampler = MotionSampler(robot, q0)
    acc = Accumulator(len(robot.actuators), base.size)
    colsq = np.zeros(int(ps.identified.sum()))
    ind = base.independent
    starts = range(first, stop, BATCH)
    for s in progress_bar(starts, "identification", "batch", progress, min_items=20):
        e = min(stop, s + BATCH)
        b = sampler.batch(t[s:e], qa[s:e], qd[s:e], qdd[s:e], s)
        Y, known = reg.rows(b)
        colsq += np.einsum("nip,nip->p", Y, Y)
        acc.add(Y[:, :, ind], tau[s:e] - known)
    return acc.factors(), acc.samples, colsq


def _worker(
    job: tuple[int, int, np.ndarray | None],
) -> tuple[list[np.ndarray], int, np.ndarray]:
    return _accumulate(job[0], job[1], job[2], False)


def _split_configurations(robot: Robot, splits: list[int]) -> list[np.ndarray]:
    """Assembled configurations at the split samples, followed from home on a coarse grid.

    The grid keeps the samples where the actuators have moved :data:`SPLIT_STEP` (in units of
    a tenth of their scale for prismatic ones) since the last kept sample: its cost follows the
    length of the motion, not the number of samples, and a fast motion is followed as closely
    as a slow one.
    """
    w = _WORK
    t, qa = w["t"], w["qa"]
    last = splits[-1]
    unit = robot.actuator_scale * np.where(robot.actuator_prismatic, 0.1, 1.0)
    step = np.abs(np.diff(qa[: last + 1], axis=0) / unit).max(axis=1, initial=0.0)
    travel = np.concatenate([[0.0], np.cumsum(step)])
    cells = np.floor(travel / SPLIT_STEP)
    kept = np.flatnonzero(np.diff(cells, prepend=-1.0) > 0)
    idx = np.union1d(kept, splits)
    sampler = MotionSampler(robot)
    Q, _ = sampler.configurations(qa[idx], t[idx])
    return [Q[int(np.searchsorted(idx, k))] for k in splits]


def _parallel(robot: Robot, N: int, workers: int) -> list[tuple[list[np.ndarray], int, np.ndarray]]:
    import multiprocessing

    bounds = [round(k * N / workers) for k in range(workers + 1)]
    starts = _split_configurations(robot, bounds[1:-1])
    jobs: list[tuple[int, int, np.ndarray | None]] = [(bounds[0], bounds[1], None)] + [
        (bounds[k], bounds[k + 1], q) for k, q in zip(range(1, workers), starts, strict=True)
    ]
    from pkdyn.workers import worker_init

    # workers deaf to Ctrl-C and tied to this process: an interruption is reported once, here
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(workers, initializer=worker_init, initargs=(os.getpid(),)) as pool:
        return pool.map(_worker, jobs)


def prior_weights(effect: np.ndarray, nominal: np.ndarray, base: BaseParameters) -> np.ndarray:
    """Metric ``D`` of the pull to the nominal values (:mod:`~.physical`), per parameter.

    A parameter the efforts see weighs its effect on them (its column norm in noise units). One
    without any effect (unidentifiable) would weigh nothing and could drift anywhere when its
    body needs a change to be physical; it weighs instead what a change of the same relative
    size costs a typical seen parameter: it moves no more than its body's consistency needs,
    and the data still decide everything they can see.

    Args:
        effect: Column norms (p,) of the identified parameters, in noise units.
        nominal: Their nominal values (p,).
        base: Their base parameters.

    Returns:
        Weights (p,), > 0.

    """
    out = effect.copy()
    unseen = np.zeros(effect.size, dtype=bool)
    names = list(base.names)
    for n in base.unidentifiable:
        unseen[names.index(n)] = True
    seen = ~unseen & (effect > 0.0) & (nominal != 0.0)
    typical = float(np.median(effect[seen] * np.abs(nominal[seen]))) if seen.any() else 1.0
    # the size of a parameter: its nominal value, at least a hundredth of the largest of its
    # kind (a first moment or product of inertia of 1e-19 from rounding is zero, not a scale
    # that would freeze it)
    kind = np.array([n.rsplit(".", 1)[-1] for n in base.names])
    mag = np.abs(nominal)
    floor = np.array([mag[kind == k].max() for k in kind])
    floor = np.where(floor > 0.0, 1e-2 * floor, mag.max(initial=1.0) or 1.0)
    scale = np.maximum(mag, floor)
    out[unseen] = typical / scale[unseen]
    tiny = out <= 0.0
    out[tiny] = 1e-12 * max(float(out.max(initial=0.0)), 1.0)
    return out


@public
def identify(
    robot: Robot,
    data: Measurements,
    parameters: Sequence[str] | str | None = None,
    cutoff: float | None = None,
    progress: bool | None = None,
    workers: int | None = None,
) -> IdentificationResult:
    """Identify the dynamic parameters of a robot from one measured motion.

    Args:
        robot: The robot (its values are the nominal ones, and the ones held).
        data: The measured motion, with efforts.
        parameters: Groups to identify (:data:`~pkdyn.identification.parameters.GROUPS`;
            default inertia, friction, rotor).
        cutoff: Cut-off frequency [Hz] of the position filter when the rates are not given.
        progress: Progress bar (``None``: on a terminal, for more than 20 batches; one
            process only).
        workers: Processes sharing the samples (default: 2 from :data:`PARALLEL_SAMPLES`
            samples on where processes can be forked, else 1); each follows its share from an
            assembled configuration found on a coarse pass, and their factors are merged.

    Returns:
        The identification (base parameters with their standard deviations, physical
        parameters, what is not identifiable).

    Raises:
        InvalidInputError: A robot that cannot be identified, measurements without efforts or
            of the wrong width, too few samples, or a motion that does not excite every base
            parameter.
        TrajectoryError: A sample that cannot be assembled.

    """
    with single_blas_thread():
        return _identify(robot, data, parameters, cutoff, progress, workers)


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

    instance("robot", robot, Robot, "a Robot (pkdyn.load)")
    instance("data", data, Measurements, "Measurements (pkdyn.identification.read_measurements)")
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
    if not np.any(data.tau):
        raise InvalidInputError(
            data.source,
            "every tau_* value is 0: the efforts carry nothing to identify from (check the "
            "tau_* columns: joint-side efforts [N m or N])",
        )
    if data.qa.shape[1] != n_a:
        raise InvalidInputError(data.source, f"{data.qa.shape[1]} actuators for {n_a}")
    N = data.t.size
    if N > MAX_SAMPLES:
        raise InvalidInputError(
            data.source,
            f"{N} samples: more than {MAX_SAMPLES} (about {N * 1e-4 / 60:.0f} min); decimate "
            "the recording",
        )
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
    qa, qd, qdd = data.qa, data.qa_dot, data.qa_ddot
    if qd is None or qdd is None:
        qa, qd, qdd = derivatives(data.t, data.qa, cutoff)
    import multiprocessing

    if workers is None:
        forkable = "fork" in multiprocessing.get_all_start_methods()
        workers = min(2, os.cpu_count() or 1) if forkable and N >= PARALLEL_SAMPLES else 1
    workers = max(1, min(int(workers), N // (4 * BATCH) or 1))
    _WORK.update(robot=robot, ps=ps, base=base, t=data.t, qa=qa, qd=qd, qdd=qdd, tau=data.tau)
    try:
        if workers > 1:
            parts = _parallel(robot, N, workers)
        else:
            parts = [_accumulate(0, N, None, progress)]
    finally:
        _WORK.clear()
    acc = Accumulator(n_a, base.size)
    colsq = np.zeros(int(ps.identified.sum()))
    for R, n, cs in parts:
        acc.merge(R, n)
        colsq += cs
    est = acc.estimate(formulas)
    sel = np.flatnonzero(ps.identified)
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
    effect = prior_weights(np.sqrt(colsq) / sigma, ps.nominal[sel], base)
    theta_id = consistent_parameters(
        base.K, est.R, est.theta, ps.nominal[sel], bodies, nonneg, effect
    )
    theta = ps.nominal.copy()
    theta[sel] = theta_id
    return IdentificationResult(
        robot=robot,
        parameters=ps,
        base=base,
        estimate=est,
        theta=theta,
        filtered=data.qa_dot is None,
        seconds=time.perf_counter() - start,
    )
