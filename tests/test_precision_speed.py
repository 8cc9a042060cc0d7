"""The fast paths of the precision figures against their references (issue 37).

- the closed-form first-order sensitivities of the library Delta and Gough-Stewart against finite
  differences of the direct geometric model and against the general path
  (:func:`pkdyn.precision.sensitivity.pose_sensitivity`); the worst case over every vertex;
- the Monte Carlo of the Delta's family parameters by Clavel's closed form against the general
  path, sample by sample (the same seed draws the same robots);
- family placements written in place against the URDF build; kept elastic models and solvers
  against fresh ones (the same numbers).
"""

from __future__ import annotations

import dataclasses
import importlib
import itertools

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics import inverse_dynamics, simulate
from pkdyn.dynamics.trajectory import named_trajectory
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.families import FAMILIES
from pkdyn.precision import stiffness
from pkdyn.precision.budgets import (
    actuator_errors,
    box_worst,
    closed_form_position_worst,
    closed_form_sensitivity,
    default_resolution,
    largest_position_error,
)
from pkdyn.precision.family_parameters import _built_placements, _resolved, built_placements
from pkdyn.precision.parameters import parameter_model
from pkdyn.precision.placements import placements
from pkdyn.precision.sensitivity import pose_sensitivity

pytestmark = pytest.mark.filterwarnings("ignore")

monte_carlo_module = importlib.import_module("pkdyn.precision.monte_carlo")


def _poses(robot: pkdyn.Robot, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, list]:
    """Platform poses near home (N, 3), (N, 3, 3) and their configurations."""
    rng = np.random.default_rng(seed)
    home = robot.platform_placement(robot.q_home)
    P, R, Q = [], [], []
    for _ in range(n):
        target = pin.SE3(home.rotation, home.translation + rng.uniform(-0.03, 0.03, 3))
        q = pkdyn.inverse_geometry(robot, target).q
        P.append(target.translation)
        R.append(target.rotation)
        Q.append(q)
    return np.array(P), np.array(R), Q


@pytest.mark.parametrize("name", ["delta", "gough_stewart"])
def test_closed_form_sensitivity_is_the_general_one(name: str) -> None:
    robot = pkdyn.load(name)
    P, R, Q = _poses(robot, 8, 1)
    J = closed_form_sensitivity(robot, P, R, reached=True)
    assert J is not None and J.shape == (8, 3, len(robot.actuators))
    for k, q in enumerate(Q):
        ref = pose_sensitivity(robot, q).J[:3]
        assert np.allclose(J[k], ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())


@pytest.mark.parametrize("name", ["delta", "gough_stewart"])
def test_closed_form_sensitivity_is_the_finite_difference(name: str) -> None:
    robot = pkdyn.load(name)
    P, R, Q = _poses(robot, 3, 2)
    J = closed_form_sensitivity(robot, P, R, reached=True)
    assert J is not None
    h = 1e-6
    for k, q in enumerate(Q):
        qa = q[robot.actuated_q]
        fd = np.empty((3, qa.size))
        for i in range(qa.size):
            x = []
            for s in (1.0, -1.0):
                qs = qa.copy()
                qs[i] += s * h
                x.append(forward_geometry(robot, qs, q_init=q, check_limits=False).placement)
            fd[:, i] = (x[0].translation - x[1].translation) / (2 * h)
        assert np.allclose(J[k], fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())


@pytest.mark.parametrize("name", ["delta", "gough_stewart"])
def test_closed_form_worst_case_is_the_general_one(name: str) -> None:
    robot = pkdyn.load(name)
    P, R, Q = _poses(robot, 6, 3)
    res = default_resolution(robot)
    fast = closed_form_position_worst(robot, P, R, 0.5 * res, reached=True)
    assert fast is not None
    slow = [actuator_errors(robot, q, res).position_worst for q in Q]
    assert np.allclose(fast, slow, rtol=1e-9)
    # the design metric's function: the same figure as the pose-by-pose path
    general = dataclasses.replace(robot, params=None)  # (no family: the general path)
    assert closed_form_sensitivity(general, P, R, reached=True) is None
    assert largest_position_error(robot, P, R, reached=True) == pytest.approx(
        largest_position_error(general, P, R), rel=1e-9
    )


def test_closed_forms_decline_outside_their_reach() -> None:
    robot = pkdyn.load("delta")
    P = np.array([[0.0, 0.0, -2.0]])  # far below the reach
    assert closed_form_sensitivity(robot, P, np.eye(3)) is None
    with pytest.raises(pkdyn.InvalidInputError):
        largest_position_error(robot, P)


def test_box_worst_is_the_largest_vertex() -> None:
    rng = np.random.default_rng(0)
    for n in (1, 2, 3, 5, 6):
        A = rng.normal(size=(3, n))
        half = rng.uniform(0.1, 1.0, n)
        brute = max(
            float(np.linalg.norm(A @ (half * np.array(s))))
            for s in itertools.product((-1.0, 1.0), repeat=n)
        )
        assert float(box_worst(A, half)) == pytest.approx(brute, rel=1e-14)


@pytest.mark.parametrize("distribution", ["uniform", "normal"])
def test_delta_family_monte_carlo_is_the_general_path(
    distribution: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    robot = pkdyn.load("delta")
    model = parameter_model(robot, "family", gains=True)
    kw = dict(samples=40, distribution=distribution, seed=5, progress=False)
    fast = monte_carlo_module.monte_carlo(robot, robot.q_home, model, 1e-4, **kw)
    monkeypatch.setattr(monte_carlo_module, "_delta_closed_form", lambda *a: False)
    slow = monte_carlo_module.monte_carlo(robot, robot.q_home, model, 1e-4, **kw)
    assert fast.failed == slow.failed == 0
    assert float(np.abs(slow.errors).max()) > 1e-6  # (the errors are not all zero)
    # the general path solves each robot to the assembly tolerance (1e-12 of the closures)
    atol = 1e-9 * robot.length_scale
    assert np.allclose(fast.errors, slow.errors, rtol=0.0, atol=atol)


def _gough_stewart_both_ways(
    robot: pkdyn.Robot, tolerance: float, monkeypatch: pytest.MonkeyPatch, **kw: object
) -> tuple[object, object]:
    """The Monte Carlo of the family's joint centres and gains: batched, then general."""
    model = parameter_model(robot, "family", gains=True)
    assert monte_carlo_module._gough_stewart_closed_form(robot, model)
    fast = monte_carlo_module.monte_carlo(robot, robot.q_home, model, tolerance, **kw)
    with monkeypatch.context() as m:
        m.setattr(monte_carlo_module, "_gough_stewart_closed_form", lambda *a: False)
        slow = monte_carlo_module.monte_carlo(robot, robot.q_home, model, tolerance, **kw)
    return fast, slow


@pytest.mark.parametrize(
    ("base_joint", "distribution"),
    [("universal", "uniform"), ("universal", "normal"), ("spherical", "uniform")],
)
def test_gough_stewart_family_monte_carlo_is_the_general_path(
    base_joint: str, distribution: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    robot = pkdyn.load("gough_stewart", geometry=False, base_joint=base_joint)
    kw = dict(samples=40, distribution=distribution, seed=5, progress=False)
    fast, slow = _gough_stewart_both_ways(robot, 1e-4, monkeypatch, **kw)
    assert fast.failed == slow.failed == 0
    assert float(np.abs(slow.errors[:, 3:]).max()) > 1e-6  # (rotations too: not all zero)
    # the general path solves each robot to the assembly tolerance (1e-12 of the closures)
    atol = 1e-9 * robot.length_scale
    assert np.allclose(fast.errors, slow.errors, rtol=0.0, atol=atol)


def test_gough_stewart_family_monte_carlo_fails_the_general_path_s_samples(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # 6 cm on 80 cm: some joint centres put a leg off its stroke at home (the family refuses
    # them), some platforms move far (the general path solves them): the same samples fail
    robot = pkdyn.load("gough_stewart", geometry=False)
    kw = dict(samples=40, distribution="uniform", seed=1, progress=False)
    fast, slow = _gough_stewart_both_ways(robot, 0.06, monkeypatch, **kw)
    assert 0 < fast.failed == slow.failed < 40
    atol = 1e-9 * robot.length_scale
    assert np.allclose(fast.errors, slow.errors, rtol=0.0, atol=atol)


def test_gough_stewart_family_monte_carlo_is_the_general_path_away_from_home(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    robot = pkdyn.load("gough_stewart", geometry=False)
    home = robot.platform_placement(robot.q_home)
    turned = pin.SE3(
        pin.exp3(np.array([0.1, -0.08, 0.2])), home.translation + np.array([0.03, -0.02, 0.04])
    )
    q = pkdyn.inverse_geometry(robot, turned).q
    model = parameter_model(robot, "family", gains=True)
    kw = dict(samples=30, seed=2, progress=False)
    fast = monte_carlo_module.monte_carlo(robot, q, model, 1e-4, **kw)
    monkeypatch.setattr(monte_carlo_module, "_gough_stewart_closed_form", lambda *a: False)
    slow = monte_carlo_module.monte_carlo(robot, q, model, 1e-4, **kw)
    assert fast.failed == slow.failed == 0
    atol = 1e-9 * robot.length_scale
    assert np.allclose(fast.errors, slow.errors, rtol=0.0, atol=atol)


def test_gough_stewart_batched_direct_model_inverts_the_leg_lengths() -> None:
    from pkdyn.closed_form.gough_stewart import forward, leg_lengths, rotation_log

    p = _resolved(pkdyn.load("gough_stewart", geometry=False))
    rng = np.random.default_rng(7)
    n = 200
    A = p.a + rng.uniform(-0.01, 0.01, (n, 6, 3))
    B = p.b + rng.uniform(-0.01, 0.01, (n, 6, 3))
    start = np.array([0.0, 0.0, p.home_height()])
    P = start + rng.uniform(-0.05, 0.05, (n, 3))
    w = rng.uniform(-0.15, 0.15, (n, 3))
    R = np.stack([pin.exp3(x) for x in w])
    rho = leg_lengths(A, B, P, R)
    for k in range(3):  # (one set of joint centres per platform: each its own lengths)
        assert np.array_equal(rho[k], leg_lengths(A[k], B[k], P[k], R[k])[0])
    Ps, Rs, ok = forward(A, B, rho, start, np.eye(3), 1e-13 * p.home_height())
    assert ok.all()
    assert np.allclose(Ps, P, rtol=0.0, atol=1e-12)
    assert np.allclose(rotation_log(Rs), w, rtol=0.0, atol=1e-12)
    # lengths no platform has (legs of 1 cm and of 5 m between joints 1 m apart at most):
    # not converged, and said so
    impossible = np.tile([0.01, 0.01, 0.01, 5.0, 5.0, 5.0], (5, 1))
    _, _, ok = forward(A[:5], B[:5], impossible, start, np.eye(3), 1e-13)
    assert not ok.any()


def test_rotation_log_is_pinocchio_s() -> None:
    from pkdyn.closed_form.gough_stewart import rotation_log

    rng = np.random.default_rng(8)
    u = rng.normal(size=(300, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    for lo, hi in ((0.0, 1e-9), (1e-9, 1e-4), (1e-4, 1.0), (1.0, 3.0), (3.0, np.pi - 1e-9)):
        w = u * rng.uniform(lo, hi, (300, 1))
        R = np.stack([pin.exp3(x) for x in w])
        ref = np.stack([pin.log3(x) for x in R])
        assert np.allclose(rotation_log(R), ref, rtol=0.0, atol=1e-12)


def test_gough_stewart_family_shortcut_declines_other_robots() -> None:
    from pkdyn.precision.perturbation import with_placements
    from pkdyn.precision.placements import local_placement

    robot = pkdyn.load("gough_stewart", geometry=False)
    model = parameter_model(robot, "family")
    assert monte_carlo_module._gough_stewart_closed_form(robot, model)
    # a joint moved: no longer the robot its parameters build
    where = placements(robot)
    values = [local_placement(robot, pl) for pl in where]
    values[0].translation = values[0].translation + np.array([1e-3, 0.0, 0.0])
    moved = with_placements(robot, where, values, assemble=False)
    assert not monte_carlo_module._gough_stewart_closed_form(moved, model)
    # a model with a parameter that is neither a joint centre nor a gain
    other = dataclasses.replace(model, names=("rho_min[0]",) + model.names[1:])
    assert not monte_carlo_module._gough_stewart_closed_form(robot, other)
    # no family: the general path
    assert not monte_carlo_module._gough_stewart_closed_form(
        dataclasses.replace(robot, params=None), model
    )


@pytest.mark.parametrize("name", list(FAMILIES))
def test_family_placements_written_in_place_are_the_urdf_ones(name: str) -> None:
    robot = pkdyn.load(name, geometry=False)
    rng = np.random.default_rng(4)
    base = _resolved(robot)
    for _ in range(3):
        changes = {
            f.name: getattr(base, f.name) * rng.uniform(0.97, 1.03)
            for f in dataclasses.fields(base)
            if type(getattr(base, f.name)) is float and f.name in ("la", "lb", "l1", "l2", "a")
        }
        try:
            p = dataclasses.replace(base, **changes)
        except pkdyn.PkdynError:
            continue
        ours = built_placements(robot, p)
        ref = _built_placements(robot, FAMILIES[name].build_urdf(p), placements(robot))
        for a, b in zip(ours, ref, strict=True):
            assert np.array_equal(a.homogeneous, b.homogeneous)


@pytest.mark.parametrize(
    ("name", "k", "material"),
    [("gough_stewart", 2e6, None), ("delta", 2e4, "steel"), ("five_bar", 1e3, "aluminium")],
)
def test_batched_stiffness_is_the_per_configuration_one(
    name: str, k: float, material: str | None
) -> None:
    from pkdyn.exceptions import PkdynError
    from pkdyn.precision import elastic_model
    from pkdyn.precision.batched import batchable, translational_batch
    from pkdyn.precision.maps import translational

    robot = pkdyn.load(name, geometry=material is not None)
    em = elastic_model(robot, k, material=material)
    assert batchable(em)
    rng = np.random.default_rng(6)
    home = robot.platform_placement(robot.q_home)
    planar = len(robot.task_rows) < 6 and name == "five_bar"
    Q = []
    for _ in range(12):
        step = rng.uniform(-0.02, 0.02, 3) * (np.array([1, 1, 0]) if planar else 1.0)
        try:
            Q.append(
                pkdyn.inverse_geometry(robot, pin.SE3(home.rotation, home.translation + step)).q
            )
        except PkdynError:
            continue
    assert len(Q) >= 8
    w = np.array([10.0, -5.0, 3.0, 0.1, 0.2, -0.1])
    kb, db, nb, ob = translational_batch(em, np.array(Q), np.zeros(3), w)
    assert ob.all()
    for i, q in enumerate(Q):
        kr, dr, nr = translational(em, q, np.zeros(3), w)
        assert kb[i] == pytest.approx(kr, rel=1e-12) and db[i] == pytest.approx(dr, rel=1e-12)
        assert nb[i] == nr


def test_kept_elastic_models_give_the_same_stiffness() -> None:
    robot = pkdyn.load("gough_stewart")
    fresh = pkdyn.load("gough_stewart")
    kw = dict(actuator_stiffness=1e6, material="steel")
    a = stiffness(robot, robot.q_home, **kw)
    b = stiffness(robot, robot.q_home, **kw)  # (the kept model)
    c = stiffness(fresh, fresh.q_home, **kw)
    assert np.array_equal(a.K, b.K) and np.array_equal(a.K, c.K)


def test_kept_solvers_give_the_same_efforts_and_motions() -> None:
    for name, kw in (("delta", {}), ("delta", {"arms": 4})):
        robot = pkdyn.load(name, geometry=False, **kw)
        jt = named_trajectory(robot, "adept")
        first = inverse_dynamics(robot, jt).tau
        again = inverse_dynamics(robot, jt).tau
        fresh = inverse_dynamics(pkdyn.load(name, geometry=False, **kw), jt).tau
        assert np.array_equal(first, again) and np.array_equal(first, fresh)
    robot = pkdyn.load("five_bar", geometry=False)
    a = simulate(robot, 0.02, 1e-3).q
    b = simulate(robot, 0.02, 1e-3).q
    assert np.array_equal(a, b)


def test_monte_carlo_on_workers_draws_the_same_robots(tmp_path) -> None:
    kw = dict(samples=130, seed=2, progress=False)
    for name, kind in (("gough_stewart", "shortcuts"), ("five_bar", "family")):
        robot = pkdyn.load(name)
        model = parameter_model(robot, kind)
        one = monte_carlo_module.monte_carlo(robot, robot.q_home, model, 1e-5, **kw)
        two = monte_carlo_module.monte_carlo(robot, robot.q_home, model, 1e-5, workers=2, **kw)
        assert np.array_equal(one.errors, two.errors) and one.failed == two.failed
    # a description file: rebuilt from its path in the workers
    path = tmp_path / "planar.urdf"
    path.write_text(FAMILIES["planar_3rrr"].build_urdf(FAMILIES["planar_3rrr"].params()))
    robot = pkdyn.load(path)
    assert robot.params is None
    model = parameter_model(robot, "placements")
    one = monte_carlo_module.monte_carlo(robot, robot.q_home, model, 1e-5, **kw)
    two = monte_carlo_module.monte_carlo(robot, robot.q_home, model, 1e-5, workers=2, **kw)
    assert np.array_equal(one.errors, two.errors)
    # one the workers cannot rebuild as it is (changed after loading): refused, not wrong
    robot.model.jointPlacements[1].translation += 1e-6
    with pytest.raises(pkdyn.StudyError, match="one worker"):
        monte_carlo_module.monte_carlo(robot, robot.q_home, model, 1e-5, workers=2, **kw)


def test_maps_on_workers() -> None:
    from pkdyn.precision import pose_figures

    robot = pkdyn.load("gough_stewart")
    home = robot.platform_placement(robot.q_home).translation
    P = home + np.random.default_rng(1).uniform(-0.02, 0.02, (150, 3))
    kw = dict(material="steel", method="general", progress=False)
    one = pose_figures(robot, P, None, 2e6, **kw)
    two = pose_figures(robot, P, None, 2e6, workers=2, **kw)
    assert one.valid.all() and np.array_equal(one.valid, two.valid)
    # (the second chunk starts its inverse geometric model from home: the same poses, solved
    # to the assembly tolerance)
    assert np.allclose(one.stiffness_min, two.stiffness_min, rtol=1e-9)


def test_command_line_workers(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from pkdyn.cli import main

    base = ["accuracy", "gough_stewart", "--pose", "0", "0", "0.6", "--samples", "80"]
    base += ["--tolerance", "1e-5", "--json"]
    assert main([*base, "--workers", "1"]) == 0
    one = json.loads(capsys.readouterr().out)
    assert main([*base, "--workers", "2"]) == 0
    two = json.loads(capsys.readouterr().out)
    assert one["monte_carlo"] == two["monte_carlo"]
    assert main([*base, "--workers", "0"]) == 1
    assert "--workers: must be >= 1" in capsys.readouterr().err
    assert main([*base, "--timeout", "-1"]) == 1
    assert "--timeout" in capsys.readouterr().err
