"""Clavel's chart recomputed: his Tableau 21 as a design study over ``(r, b)`` (seed 000).

Clavel tabulates the workspace dimensions of the Delta against its normalised parameters
``r = (ra - rb) / la`` and ``b = lb / la`` for ``gamma_max = 40 deg`` and ``(alpha + beta)_min =
30 deg``: ``d = D/la``, ``s = S/la^2``, ``h = H/la``, ``hmax``, ``v = s h`` and ``z_h`` (the copy
in seed 000 withholds the numbers; they follow from his formulas). :func:`clavel_chart_study`
is that table as a grid study of the library Delta through the ``clavel`` parametrisation,
with the complete prism's height also measured on the mechanism (``clavel_h_numeric``) beside
the closed form; :func:`clavel_chart_text` prints it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pkdyn.design.result import StudyResult
from pkdyn.design.study import Study
from pkdyn.workspace.clavel import AB_MIN, GAMMA_MAX

__all__ = ["clavel_chart_study", "clavel_chart_text"]


def clavel_chart_study(
    r: tuple[float, float] = (0.4, 1.0),
    b: tuple[float, float] = (1.5, 3.0),
    grid: int = 4,
    gamma_max: float = GAMMA_MAX,
    ab_min: float = AB_MIN,
    rays: int = 24,
    **fixed: Any,
) -> Study:
    """The grid study of Clavel's chart.

    Args:
        r: Range of ``r = (ra - rb) / la``.
        b: Range of ``b = lb / la``.
        grid: Values per parameter (``grid^2`` designs).
        gamma_max: Clavel's limit 1 [rad].
        ab_min: Clavel's limit 2 [rad].
        rays: Directions of the numeric measurement.
        **fixed: Other Delta parameters (default: the DELTA 580's ``la``, ``rb``); ``z_home``
            defaults to the middle of each design's prism.

    Returns:
        The study (run it with :func:`pkdyn.design.run_study`).

    """
    return Study(
        "delta",
        {"r": r, "b": b},
        fixed=fixed,
        parametrisation="clavel",
        metrics=["clavel_chart"],
        sampler="grid",
        n=grid,
        settings={"gamma_max": gamma_max, "ab_min": ab_min, "clavel_rays": rays},
        name="Clavel's chart (Tableau 21)",
    )


def clavel_chart_text(result: StudyResult) -> str:
    """Clavel's table: ``d, s, h`` (closed form and numeric), ``hmax, v, z_h`` per ``(r, b)``."""
    t = result.designs
    s = result.study
    gm = math.degrees(float(s.settings.get("gamma_max", GAMMA_MAX)))
    ab = math.degrees(float(s.settings.get("ab_min", AB_MIN)))
    cols = [
        ("r", "clavel_r"),
        ("b", "clavel_b"),
        ("d", "clavel_d"),
        ("s", "clavel_s"),
        ("h", "clavel_h"),
        ("h numeric", "clavel_h_numeric"),
        ("hmax", "clavel_hmax"),
        ("v", "clavel_v"),
        ("z_h", "clavel_z_h"),
    ]
    lines = [
        f"Clavel's chart (seed 000, Tableau 21): gamma_max = {gm:g} deg, "
        f"(alpha+beta)_min = {ab:g} deg; lengths / la",
        "".join(f"{h:>11s}" for h, _ in cols) + f"{'numeric-cf':>12s}",
    ]
    for i, row in enumerate(t.rows):
        rec = t.record(i)
        if all(np.isfinite(row.values)):
            diff = rec["clavel_h_numeric"] - rec["clavel_h"]
            lines.append("".join(f"{rec[c]:11.4f}" for _, c in cols) + f"{diff:12.1e}")
        else:
            r_, b_ = row.x
            lines.append(f"{r_:11.4f}{b_:11.4f}  {row.reason}")
    return "\n".join(lines)
