"""The general path's stiffness over many configurations at once (the maps' lean path, batched).

:func:`pkdyn.precision.maps.translational` condenses the virtual-joint model at one
configuration (:mod:`pkdyn.precision.condensation`): the constraint rows and the platform
Jacobian (Pinocchio, per configuration), then a null space, ``K_z = N^T K_u N``, its
eigen-decomposition, the compliance and the rule of :mod:`pkdyn.precision.validity`, a dozen
small dense problems whose cost is numpy's per-call overhead. :func:`translational_batch` takes
the Jacobians of every configuration first, then solves each of those problems for all
configurations in one call (LAPACK on each matrix of the stack): the same arithmetic, the
figures of the per-configuration path to round-off (``tests/test_precision_speed.py``).

It covers the common case: links whose elastic model does not change with the configuration
(no sliding leg's rod), springs whose stiffness is their diagonal, every actuator compliant
(:func:`batchable`); the callers keep the per-configuration path for the others.
"""

from __future__ import annotations

import numpy as np

from pkdyn.precision.condensation import (
    _MOVES_TOL,
    FREE_TOL,
    RANK_TOL,
    _needs_hessian,
    _scale,
    constraint_rows,
    platform_rows,
)
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.validity import NEAR_COMPLIANCE, UNBOUNDED_COMPLIANCE, freed

__all__ = ["batchable", "translational_batch"]


def batchable(em: ElasticModel) -> bool:
    """Whether :func:`translational_batch` covers this elastic model (module docstring)."""
    return (
        not any(lc.sliding for lc in em.links)
        and not _needs_hessian(em)
        and bool(np.all(np.isfinite(em.actuator_stiffness)))
    )


def _rank(s: np.ndarray, rtol: float, scale: float) -> np.ndarray:
    """:func:`solvers.numerics.rank_of` of each row of decreasing values ``s`` (N, k)."""
    if s.shape[1] == 0:
        return np.zeros(s.shape[0], dtype=int)
    cut = rtol * np.maximum(s[:, 0], scale)
    return np.count_nonzero(s > cut[:, None], axis=1)


def translational_batch(
    em: ElasticModel, Q: np.ndarray, point: np.ndarray, w: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`pkdyn.precision.maps.translational` at configurations ``Q``, batched.

    Args:
        em: The elastic model (:func:`batchable`).
        Q: Configurations of the robot (N, nq), assembled.
        point: Reference point in the platform frame [m].
        w: Tool wrench (6,) for the deflection, or ``None``.

    Returns:
        ``(kmin, deflection, near, ok)``: the smallest translational stiffness [N/m]
        (``inf``: rigid), the deflection [m] (``nan`` without ``w``), the near-singularity flag
        and whether the figure is defined (``False`` where the per-configuration path raises a
        :class:`~pkdyn.exceptions.SingularConfigurationError`), each (N,).

    """
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    n = Q.shape[0]
    rows_task = [int(i) for i in em.base.task_rows]
    t = [i for i in rows_task if i < 3]
    kmin = np.full(n, np.nan)
    defl = np.full(n, np.nan)
    near = np.zeros(n, dtype=bool)
    ok = np.zeros(n, dtype=bool)
    if n == 0:
        return kmin, defl, near, ok
    # the Jacobians, configuration by configuration (Pinocchio)
    R, Jp = [], []
    for q in Q:
        R.append(constraint_rows(em, em.embed(q)))
        Jp.append(platform_rows(em, point)[0])
    Rs, Jps = np.array(R), np.array(Jp)
    nv = Jps.shape[2]
    if Rs.shape[1]:
        _, s, Vt = np.linalg.svd(Rs)  # (each matrix: the null space of numerics.null_space)
        rank = _rank(s, RANK_TOL, 1.0)  # (numerics.null_space(rows, RANK_TOL, scale=1))
    else:
        Vt = np.broadcast_to(np.eye(nv), (n, nv, nv))
        rank = np.zeros(n, dtype=int)
    k_u = em.spring_stiffness()
    scale = _scale(em)
    L = em.robot.length_scale
    _, k_ref = freed(em)
    S = np.array([1.0 / L if i < 3 else 1.0 for i in rows_task])
    for r in np.unique(rank):
        idx = np.flatnonzero(rank == r)
        N = np.swapaxes(Vt[idx, r:, :], 1, 2)  # (g, nv, nz)
        nz = N.shape[2]
        if nz == 0:
            C = np.zeros((idx.size, 6, 6))
            good = np.ones(idx.size, dtype=bool)
        else:
            Kz = np.matmul(np.swapaxes(N, 1, 2), k_u[None, :, None] * N)
            Kz = 0.5 * (Kz + np.swapaxes(Kz, 1, 2))
            wz, V = np.linalg.eigh(Kz)
            aw = np.abs(wz)
            srt = -np.sort(-aw, axis=1)
            keep = _rank(srt, FREE_TOL, 0.0)  # how many count (condensation.negligible)
            thresh = np.take_along_axis(srt, np.maximum(keep - 1, 0)[:, None], axis=1)[:, 0]
            zero = (aw < thresh[:, None]) | (keep[:, None] == 0)
            Jz = np.matmul(Jps[idx], N)  # (g, 6, nz)
            sJz = scale[None, :, None] * Jz
            moving = np.matmul(sJz, V) * zero[:, None, :]
            reach = np.max(np.abs(sJz), axis=(1, 2))
            singular = np.max(np.abs(moving), axis=(1, 2)) > _MOVES_TOL * np.maximum(reach, 1.0)
            negative = np.any((wz < 0.0) & ~zero, axis=1)
            JV = np.matmul(Jz, V)
            inv = np.where(zero, 0.0, 1.0 / np.where(zero, 1.0, wz))
            C = np.matmul(JV * inv[:, None, :], np.swapaxes(JV, 1, 2))
            good = ~(singular | negative)
        # the stiffness rule on the task rows (validity.check_stiffness, all actuators finite)
        Ct = C[:, rows_task][:, :, rows_task]
        Cs = k_ref * (S[None, :, None] * Ct * S[None, None, :])
        Cs = 0.5 * (Cs + np.swapaxes(Cs, 1, 2))
        wc = np.linalg.eigvalsh(Cs)
        unbounded = wc[:, 0] <= UNBOUNDED_COMPLIANCE * np.maximum(wc[:, -1], 1.0)
        good &= ~unbounded
        ok[idx] = good
        near[idx] = good & (wc[:, 0] <= NEAR_COMPLIANCE)
        if t:
            top = np.linalg.eigvalsh(C[:, t][:, :, t])[:, -1]
            with np.errstate(divide="ignore"):
                k = np.where(top > 0.0, 1.0 / np.where(top > 0.0, top, 1.0), np.inf)
            kmin[idx] = np.where(good, k, np.nan)
        if w is not None:
            d = np.linalg.norm(np.matmul(C, np.asarray(w, dtype=float))[:, :3], axis=1)
            defl[idx] = np.where(good, d, np.nan)
    return kmin, defl, near, ok
