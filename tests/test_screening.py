"""Cheaper paths of the Delta study that must decide exactly as the exhaustive ones (issue 37).

- :func:`pkdyn.dynamics.delta.unit_dets`: the triple products stand for LAPACK's determinants
  only where the bound proves every sign and every ``|det| <= tol`` decision the same; drawn
  matrices include singular ones, ones at the threshold within the bound, and non-finite rows.
- The Delta's bar clearance from its nine segments (directions and squared lengths once per
  segment) equals the pairwise :func:`pkdyn.analysis.collisions.segment_distance` bit for bit,
  and the required check's clearance, made from the limits' elbows, equals the evaluator's own.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pkdyn.analysis.collisions import segment_distance
from pkdyn.analysis.kinematics import SINGULAR_TOL
from pkdyn.dynamics.delta import DET_BOUND, unit_dets

_unit = st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)).filter(
    lambda v: 0.1 < float(np.linalg.norm(v))
)


def _rows(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit rows as the Delta's dynamics makes them: ``d / |d|``, and the norms."""
    n = np.linalg.norm(d, axis=-1)
    return d / n[..., None], n


def _same_decisions(U: np.ndarray, norms: np.ndarray, tol: float) -> None:
    got = unit_dets(U, norms, tol)
    want = np.linalg.det(U)
    assert got.shape == want.shape
    assert np.array_equal(np.abs(got) <= tol, np.abs(want) <= tol)
    assert np.array_equal(np.sign(got), np.sign(want))
    # the crossing test of the dynamics: products of neighbours' signs
    assert np.array_equal(got[1:] * got[:-1] < 0.0, want[1:] * want[:-1] < 0.0)


@pytest.mark.filterwarnings("ignore:divide by zero:RuntimeWarning")  # (LAPACK det of singular)
@settings(max_examples=200, deadline=None)
@given(
    u0=_unit,
    u1=_unit,
    mix=st.tuples(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0)),
    off=st.sampled_from([0.0, 1.0, -1.0, 1e-3, -1e-3])
    | st.floats(-3.0 * SINGULAR_TOL, 3.0 * SINGULAR_TOL)
    | st.sampled_from([SINGULAR_TOL, -SINGULAR_TOL, SINGULAR_TOL + DET_BOUND])
    | st.floats(SINGULAR_TOL - 2 * DET_BOUND, SINGULAR_TOL + 2 * DET_BOUND),
    scale=st.sampled_from([1e-3, 1.0, 0.4, 250.0]),
    tol=st.sampled_from([SINGULAR_TOL, 0.0, 1e-3]),
)
def test_unit_dets_decide_as_lapack(u0, u1, mix, off, scale, tol) -> None:
    a, b = np.asarray(u0), np.asarray(u1)
    n = np.cross(a, b)
    n = n / np.linalg.norm(n) if np.linalg.norm(n) > 0 else np.array([0.0, 0.0, 1.0])
    c = mix[0] * a + mix[1] * b + off * n
    if not np.linalg.norm(c) > 0:
        c = n
    # a short series around the drawn matrix (singular ones, threshold ones, their neighbours)
    base = np.array([a, b, c]) * scale
    d = np.stack([base, base[[1, 0, 2]], base + 1e-9 * scale, -base, base[[2, 1, 0]]])
    U, norms = _rows(d)
    _same_decisions(U, norms, tol)


def test_unit_dets_random_batches_take_the_cheap_path_and_agree() -> None:
    rng = np.random.default_rng(5)
    for _ in range(50):
        U, norms = _rows(rng.standard_normal((501, 3, 3)))
        got = unit_dets(U, norms, SINGULAR_TOL)
        want = np.linalg.det(U)
        assert np.array_equal(np.sign(got), np.sign(want))
        assert np.all(np.abs(got - want) <= DET_BOUND)  # (the bound's claim, with room)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # (LAPACK det of NaN rows)
def test_unit_dets_exact_where_undecided() -> None:
    rng = np.random.default_rng(2)
    U, norms = _rows(rng.standard_normal((20, 3, 3)))
    U[7, 2] = U[7, 0]  # singular: LAPACK's value everywhere
    assert np.array_equal(unit_dets(U, norms, SINGULAR_TOL), np.linalg.det(U))
    U[7, 2] = np.nan
    got = unit_dets(U, norms, SINGULAR_TOL)
    assert np.isnan(got[7]) and np.array_equal(got, np.linalg.det(U), equal_nan=True)
    V, n2 = _rows(rng.standard_normal((20, 3, 3)))
    n2[3, 1] = 1e-120  # rows rounded beyond the bound: LAPACK's path
    assert np.array_equal(unit_dets(V, n2, SINGULAR_TOL), np.linalg.det(V))


# ---------------------------------------------------------------------- Delta clearance


def _pairwise_clearance(ev, P: np.ndarray, E: list[np.ndarray], tip: np.ndarray) -> np.ndarray:
    """The clearance as it was computed: every pair's four end points stacked, then the pairs."""
    ends = [P + p_nac for _, _, p_nac, _ in ev.bars]
    O = np.array([m.translation for m in ev.M_arm])
    p1, q1, p2, q2, radii = [], [], [], [], []
    for b1, (k1, _, _, _) in enumerate(ev.bars):
        for b2 in range(b1 + 1, len(ev.bars)):
            if ev.bars[b2][0] != k1:
                p1 += [E[b1]]
                q1 += [ends[b1]]
                p2 += [E[b2]]
                q2 += [ends[b2]]
                radii.append(2 * ev.bar_r)
        for k in range(3):
            if k != k1:
                p1 += [E[b1]]
                q1 += [ends[b1]]
                p2 += [np.broadcast_to(O[k], P.shape)]
                q2 += [tip[:, k]]
                radii.append(ev.bar_r + ev.arm_r[k])
    d, _, _ = segment_distance(np.stack(p1), np.stack(q1), np.stack(p2), np.stack(q2))
    return np.min(d - np.array(radii)[:, None], axis=0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_delta_clearance_from_segments_is_the_pairwise_one(seed: int) -> None:
    from pkdyn.design.context import DesignContext
    from pkdyn.design.evaluate import build
    from pkdyn.design.study import Study
    from pkdyn.exceptions import PkdynError

    study = Study(
        "delta",
        {"la": (0.15, 0.35), "lb": (0.30, 0.70), "ra": (0.08, 0.22)},
        fixed={"z_home": -0.35},
        metrics=["required"],
        requirement={"kind": "cylinder", "D": 0.4, "H": 0.1, "center": [0, 0, -0.35], "samples": 5},
        n=12,
        seed=seed,
    )
    checked = 0
    for x in study.designs():
        try:
            robot = build(study, x)
        except PkdynError:
            continue
        chk: Any = DesignContext(robot, study.conditions).required()
        ok = chk.reached
        if not ok.any():
            continue
        ev = chk._evaluator
        alpha = chk._solved[0][ok]
        _, E, tip = ev._elbows(alpha)
        want = _pairwise_clearance(ev, chk.P[ok], E, tip)
        assert ev._clearance(chk.P[ok], E, tip).tobytes() == want.tobytes()
        # the required check's, from the limits' elbows, and the evaluator's own
        assert chk.clearance[ok].tobytes() == want.tobytes()
        assert ev.clearance(chk.P[ok], alpha).tobytes() == want.tobytes()
        assert np.all(np.isnan(chk.clearance[~ok]))
        checked += 1
    assert checked >= 3


# ---------------------------------------------------------------------- Delta bar cones


@pytest.fixture(scope="module")
def delta_bars() -> tuple[Any, np.ndarray, Any]:
    """A library Delta's evaluator, arm angles of poses within the strokes, elbows."""
    from pkdyn.design.context import DesignContext
    from pkdyn.design.evaluate import build
    from pkdyn.design.study import Study

    study = Study(
        "delta",
        {"la": (0.2, 0.2001), "lb": (0.45, 0.4501), "ra": (0.15, 0.1501)},
        fixed={"z_home": -0.35},
        metrics=["required"],
        requirement={"kind": "cylinder", "D": 0.4, "H": 0.1, "center": [0, 0, -0.35], "samples": 5},
        n=1,
    )
    robot = build(study, study.designs()[0])
    chk: Any = DesignContext(robot, study.conditions).required()
    ev = chk._evaluator
    alpha, ok = chk._solved
    a = alpha[ok]
    a = a[~np.any((a < ev.lo) | (a > ev.hi), axis=1)]
    P = chk.P[ok][~np.any((alpha[ok] < ev.lo) | (alpha[ok] > ev.hi), axis=1)]
    assert len(a) > 100
    return ev, a, (P, *ev._elbows(a))


@settings(max_examples=150, deadline=None)
@given(
    bar=st.integers(0, 5),
    pose=st.integers(0, 10_000),
    offset=st.sampled_from([0.0, 1e-15, -1e-15, 1e-12, -1e-12, 1e-9, -1e-9, 3e-9, -3e-9])
    | st.floats(-0.3, 0.3),
)
def test_cone_screening_gives_direction_margins_verdicts(delta_bars, bar, pose, offset) -> None:
    from pkdyn.model.description import ConeLimit
    from pkdyn.workspace.limits import direction_margin

    ev, a, (P, R_arm, E, _) = delta_bars
    k, Mb, p_nac, lim = ev.bars[bar]
    assert isinstance(lim, ConeLimit)
    u = P + p_nac - E[bar]
    d = np.einsum("nji,nj->ni", R_arm[:, k] @ Mb.rotation, u)
    tilt = np.arccos(np.clip(d @ lim.axis / np.linalg.norm(d, axis=-1), -1.0, 1.0))
    # a cone whose edge passes at (or next to) one of the poses' tilts
    half = float(np.clip(tilt[pose % len(tilt)] + offset, 0.0, np.pi))
    cone = ConeLimit(lim.axis, half)
    want = direction_margin(cone, d) < 0.0
    got = ev._outside_cone(k, Mb, cone, (np.cos(a), np.sin(a)), u)
    if got is None:  # undecided somewhere: the caller computes direction_margin
        assert np.min(np.abs(np.cos(tilt) - np.cos(half))) <= 10 * 1e-9 or half in (0.0, np.pi)
    else:
        assert np.array_equal(got, want)


def test_cone_screening_decides_the_library_cones(delta_bars) -> None:
    from pkdyn.workspace.limits import direction_margin

    ev, a, (P, R_arm, E, _) = delta_bars
    for b, (k, Mb, p_nac, lim) in enumerate(ev.bars):
        u = P + p_nac - E[b]
        d = np.einsum("nji,nj->ni", R_arm[:, k] @ Mb.rotation, u)
        got = ev._outside_cone(k, Mb, lim, (np.cos(a), np.sin(a)), u)
        assert got is not None
        assert np.array_equal(got, direction_margin(lim, d) < 0.0)
