"""What any motion can identify: the robot's conditions, and its base parameters.

- :func:`check_identifiable`: the robot must be non-redundantly actuated and its actuators must
  determine its motion (internal mobilities such as a Delta's bar spin are allowed: no sensor
  sees them);
- :func:`structural_base`: the base parameters (:mod:`~pkdyn.identification.base`) from the
  regressor of random joint motions near home, consistent with the closures (so that the
  dependencies found hold for every motion).
"""

from __future__ import annotations

import numpy as np

from pkdyn.dynamics.actuation import actuation
from pkdyn.exceptions import InvalidInputError
from pkdyn.identifiability import Identifiability
from pkdyn.identification.base import base_parameters
from pkdyn.identification.motion import BATCH, SINGULAR_RTOL, MotionBatch, MotionSampler
from pkdyn.identification.parameters import ParameterSet
from pkdyn.identification.regressor import ClosedLoopRegressor
from pkdyn.model.robot import Robot
from solvers import numerics

__all__ = ["SEED", "check_identifiable", "structural_base"]

SEED = 20240527
"""Seed of the random motions of :func:`structural_base`."""


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
    if robot.constraints.n:
        J = robot.constraints.jacobian(robot.model.createData(), robot.q_home)
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
        J = np.zeros((m, robot.constraints.n, robot.nv))
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
    robot: Robot, ps: ParameterSet, seed: int = SEED
) -> tuple[Identifiability, np.ndarray]:
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
    sel = np.flatnonzero(ps.identified)
    base = base_parameters(Y, [ps.names[i] for i in sel], [ps.units[i] for i in sel])
    return base, np.linalg.norm(Y, axis=0) / np.sqrt(Y.shape[0])
