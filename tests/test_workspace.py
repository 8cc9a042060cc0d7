"""Translation workspace: closed-form evaluators against the general numeric path."""

import json

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.closed_form import gough_stewart as gs_cf
from pkdyn.closed_form import planar_3rrr as rrr_cf
from pkdyn.workspace.delta import DeltaEvaluator
from pkdyn.workspace.legs import HexapodEvaluator, HexapodLegs
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE
from pkdyn.workspace.numeric import NumericEvaluator, configuration_violation
from pkdyn.workspace.translation import translation_workspace

ALL = ("reach", "stroke", "joint", "interference")


@pytest.fixture(scope="module")
def gs():
    return pkdyn.load("gough_stewart")


@pytest.fixture(scope="module")
def delta_geom():
    return pkdyn.load("delta")


def test_legs_read_from_the_description(gs):
    legs = HexapodLegs.from_robot(gs)
    p = gs.params
    np.testing.assert_allclose(legs.A, p.a, atol=1e-12)
    np.testing.assert_allclose(legs.B, p.b, atol=1e-12)
    np.testing.assert_allclose(legs.rho_min, p.rho_min)
    np.testing.assert_allclose(legs.rho_max, p.rho_max)
    np.testing.assert_allclose(legs.radius, 0.008)
    assert all(lim is not None for lim in legs.limits)


@pytest.mark.parametrize("rpy", [(0.2, 0.0, 0.2), (0.3, 0.2, 0.15), (0.0, 0.0, 0.22)])
def test_hexapod_closed_form_matches_numeric_path(gs, rpy):
    """Each sample: IK, joint limits from q and coal distances vs the leg-vector formulas."""
    rng = np.random.default_rng(0)
    R = pin.rpy.rpyToMatrix(np.array(rpy))
    P = rng.uniform([-0.35, -0.35, 0.42], [0.35, 0.35, 0.72], (200, 3))
    a = HexapodEvaluator(gs).violations(P, R, ALL, 0.0)
    b = NumericEvaluator(gs, warm_start=False).violations(P, R, ALL, 0.0)
    np.testing.assert_array_equal(a, b)
    assert len(set(a.tolist())) >= 3  # the samples exercise several limits


def test_hexapod_grid_path_equals_pointwise(gs):
    ev = HexapodEvaluator(gs)
    xs, ys = np.linspace(-0.3, 0.3, 31), np.linspace(-0.3, 0.3, 29)
    for rpy, z in (((0.0, 0.0, 0.3), 0.6), ((0.2, -0.1, 0.0), 0.55)):
        R = pin.rpy.rpyToMatrix(np.array(rpy))
        grid = ev.grid(xs, ys, z, R, ALL, 0.002)
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        P = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)])
        np.testing.assert_array_equal(grid.ravel(), ev.violations(P, R, ALL, 0.002))


def test_delta_closed_form_matches_the_model(delta_geom):
    """Arm limits, cone limits and interference from the assembled URDF model (Pinocchio
    kinematics, coal distances) against the vectorised Delta evaluator."""
    robot = delta_geom
    ev = DeltaEvaluator(robot)
    rng = np.random.default_rng(1)
    P = rng.uniform([-0.3, -0.3, -0.55], [0.3, 0.3, -0.15], (150, 3))
    codes = ev.violations(P, np.eye(3), ALL, 0.0)
    alpha, ok = pkdyn.closed_form.delta.inverse(robot.params, P)
    np.testing.assert_array_equal(codes == LIMIT_KINDS.index("reach"), ~ok)
    checker = NumericEvaluator(robot).checker()
    seen = set()
    for k in np.flatnonzero(ok):
        q = pkdyn.forward_geometry(robot, alpha[k], check_limits=False).q
        seen.add(int(codes[k]))
        assert configuration_violation(robot, q, ALL, 0.0, checker) == codes[k], P[k]
    assert {REACHABLE, 1, 2} <= seen


def test_stroke_volume_against_independent_monte_carlo(gs):
    """The stroke-only workspace volume: grid count vs Monte Carlo on the existing leg-length
    closed form, in the same box."""
    box = np.array([[-0.35, 0.35], [-0.35, 0.35], [0.3, 0.75]])
    ws = translation_workspace(gs, bounds=box, samples=61, limits=("stroke",), progress=False)
    rng = np.random.default_rng(2)
    n = 400_000
    P = rng.uniform(box[:, 0], box[:, 1], (n, 3))
    rho = gs_cf.leg_lengths(gs.params.a, gs.params.b, P, np.eye(3))
    inside = np.all((rho >= gs.params.rho_min) & (rho <= gs.params.rho_max), axis=1)
    v_mc = inside.mean() * np.prod(box[:, 1] - box[:, 0])
    sigma = np.sqrt(inside.mean() * (1 - inside.mean()) / n) * np.prod(box[:, 1] - box[:, 0])
    assert abs(ws.volume - v_mc) < 4 * sigma + 0.01 * v_mc


def test_volume_converges_under_refinement(gs):
    box = np.array([[-0.4, 0.4], [-0.4, 0.4], [0.35, 0.75]])
    vols = [
        translation_workspace(gs, bounds=box, step=h, limits=("stroke", "joint"), progress=False)
        for h in (0.02, 0.01, 0.005)
    ]
    v = [w.volume for w in vols]
    e1, e2 = abs(v[1] - v[0]), abs(v[2] - v[1])
    assert e2 < e1 and e2 / v[2] < 0.01
    # limits_hit partitions the samples
    w = vols[-1]
    assert sum(w.limits_hit.values()) + int(w.reachable.sum()) == w.samples


def test_slices_boundary_bounds(gs):
    ws = translation_workspace(gs, samples=31, progress=False)
    b = ws.bounds
    pts = ws.points()
    np.testing.assert_allclose(b[:, 0], pts.min(axis=0))
    np.testing.assert_allclose(b[:, 1], pts.max(axis=0))
    edge = ws.boundary()
    assert 0 < len(edge) < len(pts)
    # every reachable sample not on the boundary has its 6 neighbours reachable
    m = ws.reachable
    inner = m & ~ws.boundary_mask()
    i, j, k = np.nonzero(inner)
    for di, dj, dk in ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)):
        assert m[i + di, j + dj, k + dk].all()
    u, v, codes = ws.slice("z", gs.params.home_height())
    assert codes.shape == (u.size, v.size) and (codes == REACHABLE).any()
    with pytest.raises(pkdyn.PkdynError, match="axis"):
        ws.slice("w", 0.0)


def test_more_limits_and_margin_never_grow_the_workspace(gs):
    box = np.array([[-0.45, 0.45], [-0.45, 0.45], [0.3, 0.8]])
    prev = None
    for lim in (("stroke",), ("stroke", "joint"), ("stroke", "joint", "interference")):
        ws = translation_workspace(
            gs,
            rpy=(0.0, 0.0, 0.16),
            bounds=box,
            samples=25,
            limits=lim,
            margin=0.002,
            progress=False,
        )
        if prev is not None:
            assert not np.any(ws.reachable & ~prev.reachable)
        prev = ws
    assert prev.limits_hit["interference"] > 0  # a yaw of 0.16 rad brings legs together
    safe = translation_workspace(
        gs, rpy=(0.0, 0.0, 0.16), bounds=box, samples=25, margin=0.003, progress=False
    )
    assert not np.any(safe.reachable & ~prev.reachable) and safe.volume < prev.volume


def test_planar_3rrr_numeric_path_matches_closed_form():
    """Numeric path (LM per pose) on an area: reach agrees with Pasqui's inverse model."""
    robot = pkdyn.load("planar_3rrr", geometry=False)
    ws = translation_workspace(robot, samples=11, limits=(), progress=False)
    assert ws.to_json()["volume_unit"] == "m^2" and ws.axes[2].size == 1
    pts = ws.points(np.ones_like(ws.reachable))
    poses = np.column_stack([pts[:, 0], pts[:, 1], np.zeros(len(pts))])
    _, ok = rrr_cf.inverse(robot.params, poses)
    np.testing.assert_array_equal(ws.reachable.ravel(), ok)
    assert 0 < ok.sum() < ok.size


def test_errors(gs):
    with pytest.raises(pkdyn.PkdynError, match="limits"):
        translation_workspace(gs, limits=("stroke", "collisions"), progress=False)
    with pytest.raises(pkdyn.PkdynError, match="bounds"):
        translation_workspace(gs, bounds=[[0, 1], [0, 1]], progress=False)
    bare = pkdyn.load("gough_stewart", geometry=False)
    with pytest.raises(pkdyn.PkdynError, match="geometry"):
        translation_workspace(bare, samples=5, progress=False)


def test_cli_translation_json_and_plot(capsys, tmp_path):
    from pkdyn.cli import main

    png = tmp_path / "ws.png"
    code = main(
        [
            "workspace",
            "gough_stewart",
            "--kind",
            "translation",
            "--samples",
            "21",
            "--json",
            "--plot",
            str(png),
        ]
    )
    out, _ = capsys.readouterr()
    assert code == 0, out
    res = json.loads(out)
    assert set(res) >= {"volume", "bounds", "samples", "limits_hit"}
    assert res["samples"] == 21**3 and set(res["limits_hit"]) == set(ALL)
    assert png.stat().st_size > 10_000


def test_cone_limited_hexapod_grid_and_numeric_agree():
    """The same legs with cone limits at the base joints (edited description): grid path,
    pointwise path and the general numeric path agree."""
    import re

    from pkdyn.library import gough_stewart as lib

    p = lib.Params()
    xml = re.sub(
        r'<pkdyn:pyramid axis="0 0 1" ref="[^"]*" half_angles="[^"]*"/>',
        '<pkdyn:cone axis="0 0 1" half_angle="0.25"/>',
        lib.build_urdf(p),
    )
    assert xml.count("pkdyn:cone") == 6
    robot = pkdyn.load_string(xml, "gs_cone", home=lib.home(p))
    ev = HexapodEvaluator(robot)
    R = pin.rpy.rpyToMatrix(0.1, 0.0, 0.05)
    xs, ys, z = np.linspace(-0.3, 0.3, 41), np.linspace(-0.3, 0.3, 41), 0.56
    grid = ev.grid(xs, ys, z, R, ALL, 0.0)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    P = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)])
    np.testing.assert_array_equal(grid.ravel(), ev.violations(P, R, ALL, 0.0))
    assert (grid == LIMIT_KINDS.index("joint")).any() and (grid == REACHABLE).any()
    idx = np.random.default_rng(5).choice(len(P), 120, replace=False)
    num = NumericEvaluator(robot, warm_start=False).violations(P[idx], R, ALL, 0.0)
    np.testing.assert_array_equal(num, grid.ravel()[idx])
