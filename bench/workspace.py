"""Workspace and collision benchmarks (issue 6).

- Gough-Stewart translation workspace on a grid, poses/s: strokes and base-joint pyramids
  (separable closed form), then with interference (on the positions that pass the first
  limits), and the interference check alone on every pose.
- Interference (the one definition: coal on the collision geometry, pairs of
  ``interference_checker``) from leg vectors, vectorised lower bounds then coal near contact,
  against coal on every pair of every pose: the same verdicts.
- For context: the general numeric path (inverse model + coal per pose), the Delta closed form,
  Clavel's numeric figures and Merlet's MEL study.

Run ``python bench/workspace.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

import pkdyn
from pkdyn.workspace.clavel import clavel_numeric
from pkdyn.workspace.legs import HexapodEvaluator, leg_placements
from pkdyn.workspace.numeric import NumericEvaluator
from pkdyn.workspace.orientation import mel_study
from pkdyn.workspace.translation import translation_workspace

Row = tuple[str, str, str]


def _median_s(fn: Callable[[], object], repeats: int = 5) -> float:
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def gough_stewart_rows() -> list[Row]:
    gs = pkdyn.load("gough_stewart")
    n = 101
    rows: list[Row] = []
    for limits, target in (
        (("stroke", "joint"), ">= 1e6/s"),
        (("stroke", "joint", "interference"), ">= 1e5/s"),
    ):
        ws = translation_workspace(gs, samples=n, limits=limits, progress=False)
        t = _median_s(
            lambda lim=limits: translation_workspace(gs, samples=n, limits=lim, progress=False),
            repeats=3,
        )
        rows.append(
            (
                f"Gough-Stewart translation workspace, {' + '.join(limits)}, {n}^3 grid",
                f"{ws.samples / t:.3g} poses/s ({ws.samples} poses in {t:.2f} s, "
                f"volume {ws.volume * 1e3:.2f} dm^3)",
                target,
            )
        )
    # interference alone, on every pose of a region where legs do interfere (yaw 0.16 rad)
    ev = HexapodEvaluator(gs)
    rng = np.random.default_rng(0)
    m = 200_000
    P = rng.uniform([-0.2, -0.2, 0.5], [0.2, 0.2, 0.68], (m, 3))
    R = pin.rpy.rpyToMatrix(0.0, 0.0, 0.16)
    v = ev.legs.leg_vectors(P, R)
    margin = 0.002
    li = ev.interference
    where = leg_placements(gs, ev.legs, P, R, v)
    t_vec = _median_s(lambda: li.bad(leg_placements(gs, ev.legs, P, R, v), m, margin), repeats=3)
    li.coal_calls = 0
    hits = li.bad(where, m, margin)
    npairs = len(li.checker.ids)
    rows.append(
        (
            f"Gough-Stewart interference alone (the definition: {npairs} pairs of the collision "
            "geometry; vectorised lower bounds, coal near contact), every pose",
            f"{m / t_vec:.3g} poses/s ({hits.mean() * 100:.0f}% of poses interfere, "
            f"{li.coal_calls / m:.2f} coal calls per pose)",
            ">= 1e5/s",
        )
    )
    k = 300
    t0 = time.perf_counter()
    coal_hits = np.array(
        [min(li.distance(c, n, where) for c in range(npairs)) < margin for n in range(k)]
    )
    t_coal = (time.perf_counter() - t0) / k
    assert np.array_equal(coal_hits, hits[:k])
    rows.append(
        (
            f"... coal on every pair, per pose ({npairs} `coal.distance`), same poses and verdicts",
            f"{1 / t_coal:.3g} poses/s: the bounds make it {t_coal * m / t_vec:.0f}x faster",
            "ratio",
        )
    )
    num = NumericEvaluator(gs)
    kinds = ("reach", "stroke", "joint", "interference")
    Pn = P[:200]
    t0 = time.perf_counter()
    num.violations(Pn, R, kinds, margin)
    t_num = (time.perf_counter() - t0) / len(Pn)
    rows.append(
        (
            "... general numeric path (inverse model + joint limits + coal on the URDF geometry)",
            f"{1 / t_num:.3g} poses/s",
            "-",
        )
    )
    return rows


def other_rows() -> list[Row]:
    delta = pkdyn.load("delta")
    n = 101
    ws = translation_workspace(delta, samples=n, progress=False)
    t = _median_s(lambda: translation_workspace(delta, samples=n, progress=False), repeats=3)
    rows: list[Row] = [
        (
            f"Delta translation workspace (Clavel inverse model), all limits, {n}^3 grid",
            f"{ws.samples / t:.3g} poses/s",
            "-",
        )
    ]
    t = _median_s(lambda: clavel_numeric(delta.params), repeats=1)
    rows.append(("Clavel's figures measured numerically (default sampling)", f"{t:.2f} s", "-"))
    gs = pkdyn.load("gough_stewart")
    t = _median_s(lambda: mel_study(gs, n1=180, n2=360, progress=False), repeats=1)
    rows.append(
        ("Merlet's MEL study (3 orientation maps, 180 x 360 samples each)", f"{t:.2f} s", "-")
    )
    return rows


def rows() -> list[Row]:
    return gough_stewart_rows() + other_rows()


if __name__ == "__main__":
    print("| benchmark | figure | target |\n|---|---|---|")
    for r in rows():
        print("| " + " | ".join(r) + " |")
