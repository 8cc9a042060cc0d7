"""Precision work spread over worker processes or a Dask cluster (Monte Carlo, maps).

The robot travels to the workers as the recipe that builds it, not as Pinocchio objects (its
constraint models cannot be pickled): a library robot as its family and parameters (built by
:class:`pkdyn.model.candidate.CandidateBuilder`, bit for bit what ``pkdyn.load`` gives), a
description file as its path (loaded with the default options). Each worker builds it once per
recipe and checks its fingerprint (every number of its model, closures and home) against the
robot of the caller: a robot the recipe does not rebuild exactly (a file loaded with options, a
robot changed after loading) is refused with one :class:`~pkdyn.exceptions.StudyError` rather
than evaluated as another. The executors are :mod:`pkdyn.executors` (the design studies').
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError, PkdynError, StudyError
from pkdyn.executors import Executor, make_executor, ordered
from pkdyn.model.robot import Robot

__all__ = ["fingerprint", "recipe", "run_chunks", "worker_robot"]

Recipe = tuple[str, str, Any]


def recipe(robot: Robot) -> Recipe:
    """How a worker rebuilds ``robot``: ``("family", name, params)`` or ``("file", path, None)``."""
    if robot.family is not None and robot.params is not None:
        return ("family", str(robot.family), robot.params)
    return ("file", str(robot.source), None)


def fingerprint(robot: Robot) -> str:
    """A digest of the numbers a computation reads: placements, inertias, limits, closures, home."""
    m = robot.model
    h = hashlib.sha256()
    for j in range(m.njoints):
        h.update(np.asarray(m.jointPlacements[j].homogeneous).tobytes())
        h.update(np.asarray(m.inertias[j].toDynamicParameters()).tobytes())
    for f in m.frames:
        h.update(np.asarray(f.placement.homogeneous).tobytes())
    for attr in ("lowerPositionLimit", "upperPositionLimit", "armature"):
        h.update(np.asarray(getattr(m, attr)).tobytes())
    for cm in robot.constraint_models:
        h.update(np.asarray(cm.joint1_placement.homogeneous).tobytes())
        h.update(np.asarray(cm.joint2_placement.homogeneous).tobytes())
    h.update(np.asarray(robot.q_home).tobytes())
    h.update(np.asarray(robot.actuated_q).tobytes())
    return h.hexdigest()


@lru_cache(maxsize=4)
def _built(kind: str, name: str, params: Any, geometry: bool) -> Robot:
    if kind == "family":
        from pkdyn.model.candidate import CandidateBuilder

        return CandidateBuilder(name, collision=geometry).robot(params)
    from pkdyn.model.loader import load

    return load(name, geometry=geometry)


def worker_robot(how: Recipe, digest: str, geometry: bool) -> Robot:
    """The robot of a recipe, built once per worker process, checked against ``digest``.

    Raises:
        StudyError: The recipe does not rebuild the caller's robot.

    """
    kind, name, params = how
    try:
        robot = _built(kind, name, params, geometry)
    except PkdynError as err:
        raise StudyError(
            "workers",
            f"the robot cannot be rebuilt in the worker processes ({err}): run with one worker "
            "(workers=1, --workers 1)",
        ) from None
    if fingerprint(robot) != digest:
        raise StudyError(
            "workers",
            f"{robot.name} cannot be rebuilt in the worker processes as it was loaded (a file "
            "loaded with options, or a robot changed after loading): run with one worker "
            "(workers=1, --workers 1)",
        )
    return robot


def run_chunks(
    fn: Callable[[Any, list[Any]], list[Any]],
    payload: Any,
    items: Sequence[Any],
    workers: int | None,
    scheduler: str | None,
    client: Any,
    timeout: float,
    chunk: int,
) -> list[Any]:
    """``fn(payload, chunk)`` over chunks of ``items`` on the executor asked for, in order.

    Args:
        fn: The chunk function (module level: pickled by reference).
        payload: What every chunk needs (the robot's recipe and digest, the options).
        items: The pieces of work.
        workers: Local worker processes (``None``: as many as the machine justifies).
        scheduler: A Dask scheduler address (``tcp://host:8786``), or ``None``.
        client: A connected ``distributed.Client``, or ``None``.
        timeout: How long to wait for the scheduler or a worker [s].
        chunk: Pieces per chunk.

    Returns:
        The results of the pieces, in their order.

    Raises:
        InvalidInputError: Bad ``workers`` or ``timeout``.
        StudyError: A worker died, the scheduler cannot be reached, or the robot cannot be
            rebuilt in the workers.

    """
    if chunk < 1:
        raise InvalidInputError("chunk", f"must be >= 1, got {chunk}")
    chunks = [list(items[k : k + chunk]) for k in range(0, len(items), chunk)]
    ex: Executor = make_executor(workers, client, scheduler, timeout, designs=len(chunks))
    with ex:
        parts = ordered(ex, fn, payload, chunks)
    return [x for part in parts for x in part]
