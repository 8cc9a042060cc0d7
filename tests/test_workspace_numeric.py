"""The numeric workspace path (continuation over the grid) against the closed forms.

Same grid, same limits: the numeric classification (inverse geometric model per sample, stroke,
passive-joint limits, coal distances) equals the closed-form evaluators' (leg vectors for the
Gough-Stewart platform, Clavel's inverse model for the Delta) on every sample, for each limit
kind and several orientations. The cheap reach bound never rejects a pose the closed forms
reach; the grid split over two processes gives the serial answer; the tripod's level workspace is
not empty (its overlapping-by-design collision pairs are left out).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.closed_form import delta as delta_cf
from pkdyn.closed_form import planar_3rrr as rrr_cf
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE
from pkdyn.workspace.numeric import NumericEvaluator, ReachBound
from pkdyn.workspace.translation import translation_workspace

ALL = ("stroke", "joint", "interference")


@pytest.fixture(scope="module")
def robots() -> dict[str, pkdyn.Robot]:
    return {name: pkdyn.load(name) for name in ("gough_stewart", "delta", "tripod")}


def _compare(robot, limits, rpy, samples):
    closed = translation_workspace(
        robot, rpy=rpy, samples=samples, limits=limits, method="closed", progress=False
    )
    box = np.array([[a[0], a[-1]] for a in closed.axes])
    ev = NumericEvaluator(robot, workers=1)
    numeric = translation_workspace(
        robot, rpy=rpy, bounds=box, samples=samples, limits=limits, evaluator=ev, progress=False
    )
    return closed.codes, numeric.codes


@pytest.mark.parametrize(
    ("limits", "rpy"),
    [
        (("stroke",), (0.0, 0.0, 0.0)),
        (("stroke",), (0.1, -0.1, 0.2)),
        (("stroke", "joint"), (0.0, 0.0, 0.0)),
        (("stroke", "joint"), (0.15, 0.05, -0.1)),
        (ALL, (0.0, 0.0, 0.16)),
        # each kind alone: joints, and interference (the one definition, both paths: coal on
        # the collision geometry; level, the rods of short legs pass through the base plate,
        # which the leg-axis check missed on 89 of these 729 samples)
        (("joint",), (0.0, 0.0, 0.0)),
        (("interference",), (0.0, 0.0, 0.0)),
        (("interference",), (0.1, -0.05, 0.16)),
        (("stroke", "interference"), (0.0, 0.0, 0.16)),
    ],
)
def test_gough_stewart_grid_matches_the_leg_vectors(robots, limits, rpy):
    closed, numeric = _compare(robots["gough_stewart"], limits, rpy, 9)
    np.testing.assert_array_equal(numeric, closed)
    assert (closed == REACHABLE).any() and (closed != REACHABLE).any()


@pytest.mark.parametrize(
    "limits", [("stroke",), ("stroke", "joint"), ALL, ("joint",), ("interference",)]
)
def test_delta_grid_matches_clavels_inverse_model(robots, limits):
    """The numeric solver must stay in the home assembly mode: ball-jointed parallelograms can
    also close crossed, with the nacelle turned, where arm angles differ (the closed form's
    working mode is the home one)."""
    closed, numeric = _compare(robots["delta"], limits, (0.0, 0.0, 0.0), 11)
    np.testing.assert_array_equal(numeric, closed)
    kinds = set(np.unique(closed).tolist())
    assert {REACHABLE, LIMIT_KINDS.index("reach"), LIMIT_KINDS.index(limits[0])} <= kinds


@pytest.mark.parametrize("name", ["gough_stewart", "delta"])
def test_the_collision_checker_gives_the_workspace_verdicts(robots, name):
    """``distance_report`` (the ``collisions`` command) at solved samples of an
    interference-only grid says in collision exactly where the closed form says interference."""
    from pkdyn.analysis.collisions import distance_report

    robot = robots[name]
    ws = translation_workspace(
        robot, samples=7, limits=("interference",), method="closed", progress=False
    )
    ev = NumericEvaluator(robot, workers=1)
    hit = LIMIT_KINDS.index("interference")
    idx = np.argwhere(np.isin(ws.codes, [REACHABLE, hit]))
    rng = np.random.default_rng(3)
    chosen = idx[rng.choice(len(idx), size=min(40, len(idx)), replace=False)]
    both = set()
    R = pin.rpy.rpyToMatrix(ws.rpy)
    for i, j, k in chosen:
        P = np.array([ws.axes[0][i], ws.axes[1][j], ws.axes[2][k]])
        q = ev.solve(pin.SE3(R, P), robot.q_home)
        assert q is not None
        rep = distance_report(robot, q)
        assert rep.in_collision == (ws.codes[i, j, k] == hit), (P, rep.pairs[0])
        both.add(rep.in_collision)
    assert both == {True, False}


def test_reach_bound_never_rejects_a_reachable_pose():
    rng = np.random.default_rng(4)
    for name, inverse, height in (
        ("planar_3rrr", rrr_cf.inverse, None),
        ("delta", delta_cf.inverse, (-0.6, -0.05)),
    ):
        robot = pkdyn.load(name, geometry=False)
        bound = ReachBound(robot)
        assert bound.bounds  # rotary chains: one bound per closure
        P = rng.uniform(-0.8, 0.8, (4000, 3))
        if height is None:
            P[:, 2] = robot.platform_placement(robot.q_home).translation[2]
            _, ok = inverse(robot.params, np.column_stack([P[:, :2], np.zeros(len(P))]))
        else:
            P[:, 2] = rng.uniform(*height, len(P))
            _, ok = inverse(robot.params, P)
        admitted = bound.admits(P, np.eye(3))
        assert not np.any(ok & ~admitted)
        assert np.any(~admitted)  # and it does reject


def test_parallel_grid_equals_serial(robots):
    robot = robots["gough_stewart"]
    R = pin.rpy.rpyToMatrix(0.05, 0.0, 0.1)
    xs, ys, zs = np.linspace(-0.2, 0.2, 7), np.linspace(-0.2, 0.2, 6), np.linspace(0.45, 0.7, 5)
    kinds = ("reach", "stroke", "joint")
    serial = NumericEvaluator(robot, workers=1).box_grid(xs, ys, zs, R, kinds, 0.0)
    split = NumericEvaluator(robot, workers=2).box_grid(xs, ys, zs, R, kinds, 0.0)
    np.testing.assert_array_equal(split, serial)


def test_tripod_level_workspace_is_not_empty(robots):
    """At roll = pitch = yaw = 0 the tripod reaches poses around home with every limit kind
    checked; twelve same-branch collision pairs overlap by design (they already interpenetrate
    at home) and are left out of the interference check."""
    robot = robots["tripod"]
    ev = NumericEvaluator(robot, workers=1)
    home = robot.platform_placement(robot.q_home).translation
    box = np.column_stack([home - 0.15, home + 0.15])
    ws = translation_workspace(robot, bounds=box, samples=5, evaluator=ev, progress=False)
    assert ws.to_json()["reachable"] > 0
    assert len(ev.excluded_pairs) == 12
    assert all(a.split("_")[0] == b.split("_")[0] for a, b in ev.excluded_pairs)
