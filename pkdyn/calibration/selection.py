"""Choosing where to measure: candidate poses inside the workspace, greedy observability design.

:func:`candidate_poses` draws platform poses around the home pose (translations within
``spread`` times the robot's size, rotations of the controlled components within
``rotation`` [rad]) and keeps those the inverse geometric model reaches within the actuator
strokes and passive-joint limits, away from singularities. :func:`select_poses` picks ``count``
of them that maximise an observability index (:mod:`pkdyn.calibration.identifiability`) of the
identifiable parameters:

- ``O1`` (default, D-optimal): greedy by the exact increase of ``log det(W^T W)`` (rank-one
  block updates, all candidates at once), then exchange passes (a selected pose is swapped for a
  candidate while that increases the index);
- ``O2`` ... ``O5``: greedy by the index itself, computed from the eigenvalues of ``W^T W``
  with each candidate added.

A small ridge (1e-9 of the mean diagonal) keeps the first steps defined while fewer values than
parameters are selected.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.calibration.identifiability import INDICES, identifiability, observability
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.inputs import is_complex
from pkdyn.model.assembly import inverse_geometry
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel
from pkdyn.precision.sensitivity import pose_sensitivity
from pkdyn.progress import progress as progress_bar
from pkdyn.results import renamed_keyword
from pkdyn.threads import one_blas_thread
from pkdyn.workspace.limits import REACHABLE
from pkdyn.workspace.numeric import configuration_violation

__all__ = ["Selection", "candidate_poses", "design_matrix", "select_poses"]


@renamed_keyword("progress_bar", "progress")
def candidate_poses(
    robot: Robot,
    count: int = 200,
    spread: float = 0.25,
    rotation: float = 0.2,
    seed: int = 0,
    progress: bool | None = None,
) -> list[np.ndarray]:
    """Assembled configurations at random platform poses inside the workspace.

    Args:
        robot: The robot.
        count: Number of configurations wanted (1..5,000).
        spread: Half-width of the translation box, times the robot's size
            (:attr:`pkdyn.Robot.length_scale`).
        rotation: Half-width of each controlled rotation [rad].
        seed: Random seed.
        progress: Force the progress bar on or off (``progress_bar``: its former name, kept
            for one release).

    Returns:
        Configurations (nq,) each; fewer than ``count`` when 20 draws per wanted pose did not
        find enough (a small workspace: reduce ``spread``).

    Raises:
        InvalidInputError: A count outside 1..5,000, or a robot without a platform.

    """
    from pkdyn import inputs

    inputs.instance("robot", robot, Robot, "a Robot (pkdyn.load)")
    try:
        count = inputs.count("count", count, 1, 5000)
    except InvalidInputError:
        raise InvalidInputError("count", f"{count}: give 1 to 5,000 candidate poses") from None
    spread = inputs.positive("spread", spread, "x the robot's size", bound=10.0)
    rotation = inputs.non_negative("rotation", rotation, "rad", bound=math.pi)
    seed = inputs.seed("seed", seed)
    if robot.platform_frame is None:
        raise InvalidInputError("robot", f"{robot.name} declares no platform frame")
    rng = np.random.default_rng(seed)
    M0 = robot.platform_placement(robot.q_home)
    rows = set(int(r) for r in robot.task_rows)
    half = spread * robot.length_scale
    out: list[np.ndarray] = []
    q_prev = robot.q_home
    for _ in progress_bar(
        range(20 * int(count)), "candidate poses", "draw", progress, min_items=500
    ):
        if len(out) >= count:
            break
        t = np.array([rng.uniform(-half, half) if k in rows else 0.0 for k in range(3)])
        w = np.array([rng.uniform(-rotation, rotation) if k + 3 in rows else 0.0 for k in range(3)])
        target = pin.SE3(M0.rotation @ pin.exp3(w), M0.translation + t)
        q = None
        starts = (None, q_prev) if robot.family is not None else (q_prev, robot.q_home)
        for q0 in starts:  # (a family's closed form first: its working mode)
            try:
                q = inverse_geometry(robot, target, q_init=q0).q
                break
            except PkdynError:
                continue
        if q is None or configuration_violation(robot, q, ("stroke", "joint"), 0.0) != REACHABLE:
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                pose_sensitivity(robot, q)
        except PkdynError:
            continue
        out.append(q)
        q_prev = q
    return out


def design_matrix(
    robot: Robot,
    qs: Sequence[np.ndarray],
    model: ParameterModel,
    kind: str = "position",
    sigma: tuple[float, float] = (1.0, 1.0),
) -> np.ndarray:
    """Weighted identification Jacobian blocks (M, rows, n_par) of configurations ``qs``.

    ``pose``: position and rotation rows (divided by ``sigma``); ``position`` (and the implicit
    kinds, for design purposes): position rows. The columns of parameters the mechanism cannot
    absorb (:attr:`pkdyn.precision.sensitivity.PoseSensitivity.gap`) are zero: they are
    not identified.
    """
    d = 6 if kind == "pose" else 3
    w = np.array([sigma[0]] * 3 + [sigma[1]] * 3)[:d]
    out = np.empty((len(qs), d, model.size))
    gap = np.zeros(model.size)
    for i, q in enumerate(qs):
        s = pose_sensitivity(robot, q, model)
        out[i] = s.K[:d] / w[:, None]
        if s.gap.size:
            gap = np.maximum(gap, np.max(np.abs(s.gap), axis=0))
    out[:, :, gap > 1e-9] = 0.0
    return out


@dataclass
class Selection:
    """Poses chosen by :func:`select_poses`.

    Attributes:
        order: Indices of the chosen candidates, in the order they were chosen.
        index: The observability index maximised.
        values: The five indices of the chosen set.
        identifiable: Indices of the parameters identifiable on all candidates.

    """

    order: np.ndarray
    index: str
    values: dict[str, float]
    identifiable: np.ndarray


def _logdet_gain(Ainv: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """``log det(I + B A^-1 B^T)`` for each candidate block ``B`` (M, d, n)."""
    S = np.einsum("mij,jk,mlk->mil", blocks, Ainv, blocks)
    S = S + np.eye(blocks.shape[1])[None]
    sign, logdet = np.linalg.slogdet(S)
    return np.where(sign > 0, logdet, -np.inf)


def _index_of(A: np.ndarray, index: str, poses: int) -> float:
    ev = np.linalg.eigvalsh(A)
    s = np.sqrt(np.clip(ev, 0.0, None))[::-1]
    return observability(s, poses)[index]


@one_blas_thread
def select_poses(
    blocks: np.ndarray,
    count: int,
    index: str = "O1",
    exchange: bool = True,
) -> Selection:
    """Choose ``count`` candidates maximising an observability index (module docstring).

    Args:
        blocks: Weighted Jacobian blocks of the candidates (M, rows, n_par)
            (:func:`design_matrix`).
        count: Number of poses to choose (<= M).
        index: ``O1`` ... ``O5``.
        exchange: Run exchange passes after the greedy choice (``O1`` only).

    Returns:
        The selection.

    Raises:
        InvalidInputError: Unknown index, or more poses asked than candidates.

    """
    from pkdyn import inputs

    if index not in INDICES:
        raise InvalidInputError("index", f"'{index}': use one of {', '.join(INDICES)}")
    if isinstance(blocks, str | bytes | dict) or is_complex(blocks):
        raise InvalidInputError("blocks", "expected an array (M, rows, n_par) (design_matrix)")
    try:
        blocks = np.asarray(blocks, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(
            "blocks", "expected an array (M, rows, n_par) (design_matrix)"
        ) from None
    if blocks.ndim != 3 or not np.all(np.isfinite(blocks)):
        raise InvalidInputError(
            "blocks", f"expected finite (M, rows, n_par) Jacobian blocks, got shape {blocks.shape}"
        )
    M, d, _ = blocks.shape
    count = inputs.count("count", count, 1, max(M, 1))
    if not 1 <= count <= M:
        raise InvalidInputError("count", f"{count} poses asked from {M} candidates")
    ident = identifiability(blocks.reshape(M * d, -1), [str(k) for k in range(blocks.shape[2])], M)
    cols = np.sort(ident.identifiable)
    B = blocks[:, :, cols]
    n = cols.size
    ridge = 1e-9 * float(np.mean(np.einsum("mij,mij->j", B, B))) + 1e-300
    A = ridge * np.eye(n)
    chosen: list[int] = []
    free = np.ones(M, dtype=bool)
    for k in range(count):
        if index == "O1":
            gain = _logdet_gain(np.linalg.inv(A), B)
        else:
            gain = np.array(
                [
                    _index_of(A + B[i].T @ B[i], index, k + 1) if free[i] else -np.inf
                    for i in range(M)
                ]
            )
        gain[~free] = -np.inf
        i = int(np.argmax(gain))
        chosen.append(i)
        free[i] = False
        A = A + B[i].T @ B[i]
    if exchange and index == "O1":
        improved = True
        passes = 0
        while improved and passes < 5:
            improved, passes = False, passes + 1
            for slot in range(len(chosen)):
                i = chosen[slot]
                A_minus = A - B[i].T @ B[i]
                gain = _logdet_gain(np.linalg.inv(A_minus), B)
                gain[~free] = -np.inf
                j = int(np.argmax(gain))
                current = _logdet_gain(np.linalg.inv(A_minus), B[i : i + 1])[0]
                if gain[j] > current + 1e-9:
                    chosen[slot] = j
                    free[i], free[j] = True, False
                    A = A_minus + B[j].T @ B[j]
                    improved = True
    s = np.linalg.svd(B[chosen].reshape(-1, n), compute_uv=False)
    return Selection(np.array(chosen, dtype=int), index, observability(s, count), cols)
