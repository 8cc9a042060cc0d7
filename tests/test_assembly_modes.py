"""The geometric models answer in the mode the user is in, and singularities are scale-aware.

References are independent of the numeric path: Clavel's closed forms (seed 000) for the Delta,
the circle intersections for the five-bar, constructed singular configurations.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import pkdyn
from pkdyn.analysis.singularity import classify
from pkdyn.cli import main
from pkdyn.closed_form import delta as dcf
from pkdyn.closed_form import five_bar as fcf


@pytest.fixture(scope="module")
def delta():
    return pkdyn.load("delta", geometry=False)


def reachable_delta_points(p, n, rng):
    """Random nacelle positions the arms reach within their limits (working branch)."""
    out = np.zeros((0, 3))
    while len(out) < n:
        P = rng.uniform([-0.35, -0.35, -0.62], [0.35, 0.35, -0.05], (4 * n, 3))
        out = np.vstack([out, P[_valid(p, P)]])
    return out[:n]


def _valid(p, P):
    """Reached in the working modes, arms within their limits."""
    alpha, ok = dcf.inverse(p, P)
    C = dcf.elbow_points(p, np.where(np.isfinite(alpha), alpha, 0.0))
    n = np.cross(C[:, 1] - C[:, 0], C[:, 2] - C[:, 0])
    n *= np.sign(n[:, 2:3])
    below = np.einsum("ij,ij->i", P - C[:, 0], n) < 0.0  # under the elbows' plane
    with np.errstate(invalid="ignore"):
        return ok & below & np.all((alpha >= p.alpha_min) & (alpha <= p.alpha_max), axis=1)


def boundary_delta_points(p, n, rng):
    """Nacelle positions on the workspace boundary (reach or arm limits), found by bisection
    along random rays from the home point to within 1e-15 m, on the reachable side."""
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    c = np.array([0.0, 0.0, p.home_height()])
    lo, hi = np.zeros(n), np.full(n, 1.0)
    assert _valid(p, c[None, :]).all() and not _valid(p, c + u * hi[:, None]).any()
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        ok = _valid(p, c + u * mid[:, None])
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return c + u * lo[:, None]


def test_closed_form_round_trip_on_thousands_of_poses(delta):
    """Clavel's direct model (lower root) inverts the inverse model everywhere, boundary
    included: 20,000 interior and 2,000 boundary poses."""
    p = delta.params
    rng = np.random.default_rng(0)
    for P in (reachable_delta_points(p, 20000, rng), boundary_delta_points(p, 2000, rng)):
        alpha, ok = dcf.inverse(p, P)
        assert ok.all()
        back, ok2 = dcf.forward(p, alpha)
        assert ok2.all()
        assert np.max(np.abs(back - P)) < 1e-9


def test_fk_of_ik_stays_below_the_base_on_interior_and_boundary_poses(delta):
    """The numeric path: FK(IK(pose)) = pose to 1e-9 m on 1,000 random reachable poses and 200
    on the workspace boundary, the nacelle always below the base."""
    p = delta.params
    rng = np.random.default_rng(1)
    P = np.vstack([reachable_delta_points(p, 1000, rng), boundary_delta_points(p, 200, rng)])
    worst = 0.0
    for target in P:
        ik = pkdyn.inverse_geometry(delta, target)
        fk = pkdyn.forward_geometry(delta, ik.qa)
        assert fk.position[2] < 0.0
        worst = max(worst, float(np.linalg.norm(fk.position - target)))
        np.testing.assert_allclose(ik.qa, dcf.inverse(p, target)[0][0], atol=2e-7)
    assert worst < 1e-9


def test_issue_example_fk_of_ik_at_055(capsys):
    """`pkdyn ik delta --pose 0 0 -0.55` then `fk` used to put the nacelle above the base."""
    assert main(["ik", "delta", "--pose", "0", "0", "-0.55", "--json"]) == 0
    qa = json.loads(capsys.readouterr().out)["qa"]
    assert main(["fk", "delta", "--qa", *map(str, qa), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(out["position"], [0.0, 0.0, -0.55], atol=1e-9)


def test_fk_from_a_warm_start_keeps_its_mode(delta):
    """A warm start far away keeps the mode; the other mode is still found by assembly_modes."""
    p = delta.params
    rng = np.random.default_rng(2)
    P = reachable_delta_points(p, 200, rng)
    alpha, _ = dcf.inverse(p, P)
    q = delta.q_home
    for k in range(len(P)):
        fk = pkdyn.forward_geometry(delta, alpha[k], q_init=q)
        np.testing.assert_allclose(fk.position, P[k], atol=1e-9)
        q = fk.q
    modes = pkdyn.assembly_modes(delta, delta.q_home[delta.actuated_q], starts=24)
    assert len(modes) >= 2 and any(m.position[2] > 0 for m in modes)


def test_five_bar_fk_keeps_the_assembly_mode_of_its_start():
    robot = pkdyn.load("five_bar", geometry=False)
    p = robot.params
    rng = np.random.default_rng(3)
    E = np.column_stack([rng.uniform(-0.1, 0.1, 400), rng.uniform(0.12, 0.4, 400)])
    theta, ok = fcf.inverse(p, E)
    ok &= np.all((theta >= p.q_min) & (theta <= p.q_max), axis=1)
    q = robot.q_home
    for k in np.flatnonzero(ok):
        ref, okf = fcf.forward(p, theta[k], 1)
        if not okf[0]:
            continue
        fk = pkdyn.forward_geometry(robot, theta[k], q_init=q if k % 2 else None)
        np.testing.assert_allclose(fk.position[:2], ref[0], atol=1e-9)
        q = fk.q


def test_general_robots_keep_their_mode_by_continuation():
    """The Gough-Stewart has no closed-form direct model: the actuators move from the start's
    values in steps, so a far jump lands in the start's mode (the closed-form leg lengths of
    the result are the inputs, the pose is the one they came from)."""
    from pkdyn.closed_form import gough_stewart as gcf

    robot = pkdyn.load("gough_stewart", geometry=False)
    p = robot.params
    z = p.home_height()
    poses = np.array([[0.06, -0.04, z + 0.05, 0.15, -0.1, 0.2], [-0.05, 0.05, z - 0.04, 0, 0.2, 0]])
    for pose in poses:
        rho = gcf.leg_lengths_rpy(p.a, p.b, pose)[0]
        fk = pkdyn.forward_geometry(robot, rho)
        np.testing.assert_allclose(fk.position, pose[:3], atol=1e-9)
        np.testing.assert_allclose(fk.rpy, pose[3:], atol=1e-9)


# ---------------------------------------------------------------------------------- yaw / roll


@pytest.mark.parametrize(
    "pose, culprit",
    [
        ([0.0, 0.0, -0.4, 0.0, 0.0, 0.3], "yaw = 0.3"),
        ([0.0, 0.0, -0.4, 0.2, 0.0, 0.0], "roll = 0.2"),
    ],
)
def test_delta_refuses_an_orientation_it_cannot_make(delta, pose, culprit):
    with pytest.raises(pkdyn.UnreachablePoseError) as err:
        pkdyn.inverse_geometry(delta, pose)
    assert culprit in str(err.value) and "controls only x y z" in str(err.value)
    # the orientation it keeps is accepted
    ik = pkdyn.inverse_geometry(delta, [0.0, 0.0, -0.4, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(ik.position, [0, 0, -0.4], atol=1e-12)


def test_planar_robot_refuses_a_height(capsys):
    assert main(["ik", "planar_3rrr", "--pose", "0.01", "0.02", "0.1"]) == 1
    assert "z = 0.1" in capsys.readouterr().err


# ------------------------------------------------------------------------------ singularities


def test_exactly_singular_pose_is_reported_serial(delta, capsys):
    """All three arms stretched along their bars (the workspace's lowest point on the axis):
    B collapses as a whole, so cond(B) stays small; the scale-aware margin sees it."""
    z = lowest(delta.params)  # arm and bars aligned: |C' - P| = la + lb on the axis
    assert z == pytest.approx(-0.566370020393029, abs=1e-12)  # the issue's pose
    ik = pkdyn.inverse_geometry(delta, [0.0, 0.0, z], check_limits=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rep = classify(delta, ik.q)
    assert rep.kind == "serial" and rep.margin < 3e-8
    assert rep.serial_directions.shape == (3, 3)  # every arm
    assert main(["singularity", "delta", "--pose", "0", "0", str(z), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["kind"] == "serial"


@pytest.mark.parametrize("k", [0.01, 1.0, 100.0])
def test_singularity_tests_do_not_depend_on_the_robot_size(k):
    """The same Delta at 1/100 and 100 times the size: same kinds, same margins."""
    base = pkdyn.load("delta", geometry=False)
    p = base.params
    over = {n: getattr(p, n) * k for n in ("ra", "rb", "la", "lb", "bar_spacing")}
    robot = pkdyn.load("delta", geometry=False, **over)
    for P, kind in (([0.02, 0.03, -0.4], "regular"), ([0.0, 0.0, lowest(p)], "serial")):
        scaled = [0.0, 0.0, lowest(robot.params)] if kind == "serial" else np.array(P) * k
        ik = pkdyn.inverse_geometry(robot, scaled, check_limits=False)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rep = classify(robot, ik.q)
            ref = classify(base, pkdyn.inverse_geometry(base, P, check_limits=False).q)
        assert rep.kind == kind
        if kind == "regular":
            assert rep.margin == pytest.approx(ref.margin, rel=1e-6)
        else:  # at a fold the configuration is known to ~sqrt(eps): margins ~1e-8 and below
            assert rep.margin < 3e-8 and ref.margin < 3e-8


def lowest(p) -> float:
    """Height of the lowest point on the axis: every arm stretched along its bars."""
    R = p.ra - p.rb
    a = float(np.arctan2(np.sqrt((p.la + p.lb) ** 2 - R**2), R))
    return -(p.la + p.lb) * np.sin(a)
