"""Error budgets (issue 26, item 3): worst cases against brute force, first order against Monte
Carlo of exactly solved robots, maps, bad input."""

import itertools

import numpy as np
import pytest

import pkdyn
from pkdyn.exceptions import InvalidInputError
from pkdyn.precision.accuracy import (
    accuracy_map,
    actuator_errors,
    geometric_errors,
    monte_carlo,
    pose_error,
    slice_grid,
    worst_norm,
)
from pkdyn.precision.parameters import family_parameters, family_shortcuts, placement_parameters


@pytest.fixture(scope="module")
def delta():
    return pkdyn.load("delta", geometry=False)


@pytest.fixture(scope="module")
def hexapod():
    return pkdyn.load("gough_stewart", geometry=False)


def test_worst_norm_is_the_largest_vertex():
    rng = np.random.default_rng(0)
    for d in (2, 3):
        A = rng.normal(size=(d, 7))
        half = rng.uniform(0.1, 1.0, 7)
        brute = max(
            np.linalg.norm(A @ (half * np.array(s))) for s in itertools.product((-1, 1), repeat=7)
        )
        assert worst_norm(A, half) == pytest.approx(brute, rel=1e-12)


def test_actuator_worst_case_against_the_exact_forward_geometry(delta):
    """Every vertex of the error box solved exactly: the largest is the first-order worst case."""
    q = pkdyn.inverse_geometry(delta, [0.05, -0.03, -0.32]).q
    res, back = 1e-4, 2e-4
    acc = actuator_errors(delta, q, res, back)
    e = 0.5 * (res + back)
    M0 = delta.platform_placement(q)
    errs = []
    for s in itertools.product((-1, 1), repeat=3):
        g = pkdyn.forward_geometry(delta, q[delta.actuated_q] + e * np.array(s), q_init=q)
        errs.append(pose_error(M0, g.placement))
    errs = np.array(errs)
    assert acc.position_worst == pytest.approx(
        np.max(np.linalg.norm(errs[:, :3], axis=1)), rel=2e-3
    )
    np.testing.assert_allclose(acc.worst[:3], np.max(np.abs(errs[:, :3]), axis=0), rtol=2e-3)
    assert acc.orientation_worst < 1e-12  # the parallelograms keep the nacelle level
    # RMS: independent uniform errors, sampled and solved exactly
    rng = np.random.default_rng(1)
    mc = []
    for _ in range(400):
        d = rng.uniform(-res / 2, res / 2, 3) + rng.uniform(-back / 2, back / 2, 3)
        g = pkdyn.forward_geometry(delta, q[delta.actuated_q] + d, q_init=q)
        mc.append(pose_error(M0, g.placement))
    mc_rms = np.sqrt(np.mean(np.sum(np.array(mc)[:, :3] ** 2, axis=1)))
    assert acc.position_rms == pytest.approx(mc_rms, rel=0.1)  # 400 samples: ~4 % scatter


def test_monte_carlo_agrees_with_first_order_for_small_tolerances(hexapod):
    model = family_shortcuts(hexapod)
    q = pkdyn.inverse_geometry(hexapod, [0.02, -0.01, 0.6, 0.05, 0.0, -0.03]).q
    tol = model.tolerances(2e-5, 1e-4)
    geo = geometric_errors(hexapod, q, model, tol)
    mc = monte_carlo(hexapod, q, model, tol, samples=300, seed=2)
    assert mc.failed == 0
    # RMS of 300 samples: ~4 % scatter per component
    np.testing.assert_allclose(mc.rms, geo.rms, rtol=0.15)
    assert mc.position_rms == pytest.approx(geo.position_rms, rel=0.1)
    assert mc.position_max <= geo.position_worst * 1.001
    ranking = geo.ranking()
    assert sum(r["share"] for r in ranking) == pytest.approx(1.0)
    shares = [r["share"] for r in ranking]
    assert shares == sorted(shares, reverse=True)


def test_family_dimensions_monte_carlo_rebuilds_with_the_builder(delta):
    model = family_parameters(delta)
    q = delta.q_home
    tol = np.full(model.size, 5e-5)
    geo = geometric_errors(delta, q, model, tol, distribution="normal")
    mc = monte_carlo(delta, q, model, tol, samples=60, distribution="normal", seed=3)
    assert mc.position_rms == pytest.approx(geo.position_rms, rel=0.3)  # 60 samples: ~9 %
    top = geo.ranking(2)
    assert {r["name"] for r in top} <= {"lb", "ra", "rb", "la"}
    # on the axis only z moves with the Clavel dimensions
    assert geo.rms[0] < 1e-12 and geo.rms[1] < 1e-12


def test_placement_budget_leaves_out_what_the_planar_loop_cannot_absorb():
    robot = pkdyn.load("five_bar", geometry=False)
    model = placement_parameters(robot)
    geo = geometric_errors(robot, robot.q_home, model, model.tolerances(1e-5, 1e-4))
    assert "distal2.rx" in geo.not_assembling and "distal2.tx" not in geo.not_assembling
    assert geo.position_rms > 0.0


def test_accuracy_map_and_its_plot(delta, tmp_path):
    from pkdyn.plotting import plot_accuracy_map

    P, shape = slice_grid([0.0, 0.0, -0.35], "xy", 0.1, 3)
    amap = accuracy_map(delta, P, 1e-4, 0.0, family_shortcuts(delta), 1e-5, shape=shape)
    assert amap.valid.all()
    centre = actuator_errors(delta, pkdyn.inverse_geometry(delta, P[4]).q, 1e-4)
    assert amap.field("actuator_worst")[1, 1] == pytest.approx(centre.position_worst)
    assert np.all(amap.geometric_rms > 0)
    plot_accuracy_map(amap, "geometric_rms", path=tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 1000


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"resolution": -1e-4}, "negative"),
        ({"resolution": [1e-4, 1e-4]}, "expected 3 values"),
        ({"backlash": float("nan")}, "finite"),
    ],
)
def test_bad_actuator_errors(delta, kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        actuator_errors(delta, delta.q_home, **kwargs)


def test_bad_tolerances(delta):
    model = family_shortcuts(delta)
    with pytest.raises(InvalidInputError, match="negative"):
        geometric_errors(delta, delta.q_home, model, -1e-5)
    with pytest.raises(InvalidInputError, match="distribution"):
        geometric_errors(delta, delta.q_home, model, 1e-5, distribution="cauchy")
    with pytest.raises(InvalidInputError, match="samples"):
        monte_carlo(delta, delta.q_home, model, 1e-5, samples=0)


def test_cli_accuracy_json(capsys):
    import json

    from pkdyn.cli import main

    argv = ["accuracy", "delta", "--pose", "0", "0", "-0.35", "--resolution", "1e-4"]
    assert main([*argv, "--json", "--samples", "20"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["actuators"]["position_worst"] > 0 and len(out["geometric"]["ranking"]) == 10
    assert out["monte_carlo"]["samples"] == 20
    assert main(["accuracy", "delta", "--pose", "0", "0", "-0.35", "--resolution", "-1"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "negative" in err


def test_error_max_design_metric(delta):
    from pkdyn.design.context import Conditions, DesignContext
    from pkdyn.design.metrics import resolve_metrics
    from pkdyn.design.requirement import Requirement
    from pkdyn.precision.accuracy import DEFAULT_RESOLUTION

    req = Requirement.parse("box:dx=0.1,dy=0.1,dz=0.04,z=-0.35", samples=2)
    ctx = DesignContext(delta, Conditions(requirement=req))
    (metric,) = resolve_metrics(["error_max"])
    value = metric(delta, ctx)
    # the largest of the per-pose worst cases, each checked above against brute force
    per_pose = [
        actuator_errors(
            delta, pkdyn.inverse_geometry(delta, p).q, DEFAULT_RESOLUTION[0]
        ).position_worst
        for p in req.positions
    ]
    assert value == pytest.approx(max(per_pose))
    assert metric.unit == "m"
