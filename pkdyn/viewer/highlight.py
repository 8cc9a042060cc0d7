"""What the viewer highlights: singular configurations and the pair of legs closest to collision.

The analyses come from the core (:mod:`pkdyn.analysis.singularity`,
:mod:`pkdyn.analysis.collisions`); this module only turns their answers into per-configuration
labels the scene can colour.
"""

from __future__ import annotations

import warnings

import numpy as np

from pkdyn.analysis.collisions import CollisionChecker, distance_report
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as bar

__all__ = [
    "CLOSEST_COLOR",
    "NEAR_COLOR",
    "REGULAR",
    "SINGULAR",
    "SINGULAR_COLOR",
    "NEAR",
    "closest_pair",
    "closest_pairs",
    "singularity_labels",
]

REGULAR, NEAR, SINGULAR = 0, 1, 2
"""Singularity labels: regular, near-singular (warning zone), singular (any kind)."""

SINGULAR_COLOR = (0.90, 0.05, 0.05)
"""Colour of the moving parts in a singular configuration."""

NEAR_COLOR = (1.00, 0.55, 0.60)
"""Colour of the moving parts in a near-singular configuration."""

CLOSEST_COLOR = (0.85, 0.00, 0.85)
"""Colour of the two geometry objects closest to collision."""


@public
def singularity_labels(
    robot: Robot, Q: np.ndarray, progress: bool | None = None
) -> tuple[np.ndarray, list[str]]:
    """Classify each configuration of a trajectory (:func:`pkdyn.analysis.singularity.classify`).

    Args:
        robot: Robot with a platform.
        Q: Assembled configurations (N, nq).
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default) shows
            it when stderr is a terminal and there are at least 200 samples.

    Returns:
        Labels (N,) in ``REGULAR, NEAR, SINGULAR`` and the kind of each configuration
        (``regular``, ``serial``, ``parallel``, ``both``).

    """
    from pkdyn.analysis.singularity import classify
    from pkdyn.inputs import matrix

    Q = matrix("Q", Q, None, robot.nq, "rad or m")
    labels = np.zeros(len(Q), dtype=int)
    kinds: list[str] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # near-singular warnings: reported as labels instead
        for i, q in enumerate(bar(Q, "singularities", "sample", progress, min_items=200)):
            rep = classify(robot, q)
            kinds.append(rep.kind)
            labels[i] = SINGULAR if rep.kind != "regular" else (NEAR if rep.near else REGULAR)
    return labels, kinds


@public
def closest_pair(robot: Robot, q: np.ndarray) -> tuple[str, str, float]:
    """The two collision objects closest to each other (coal, via ``distance_report``).

    Args:
        robot: Robot loaded with its geometry.
        q: Assembled configuration (nq,).

    Returns:
        ``(a, b, distance)``: geometry object names and their signed distance [m] (negative
        when they penetrate).

    Raises:
        PkdynError: No collision pair to check.

    """
    best = distance_report(robot, q).pairs[0]  # sorted closest first
    return str(best.a), str(best.b), float(best.distance)


def closest_pairs(
    robot: Robot, Q: np.ndarray, progress: bool | None = None
) -> list[tuple[str, str, float]]:
    """:func:`closest_pair` at each configuration of a trajectory.

    Args:
        robot: The robot, loaded with geometry.
        Q: Configurations (N, nq).
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default) shows
            it when stderr is a terminal and there are at least 200 samples.

    Returns:
        ``(body_a, body_b, distance [m])`` per configuration.

    """
    checker = CollisionChecker(robot)
    out = []
    for q in bar(Q, "distances", "sample", progress, min_items=200):
        d = checker.distances(q)
        k = int(np.argmin(d))
        a, b = checker.names[k]
        out.append((str(a), str(b), float(d[k])))
    return out
