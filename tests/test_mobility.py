"""Mobility (issue 4, item 1): Grübler-Kutzbach and rank-based counts against the seeds.

Expected numbers come from the seeds (000: Clavel's Delta, section 1.3.6; 001: Pasqui's
examples) and from counting joints by hand, never from the code under test. Where Grübler's
count is wrong (overconstrained mechanisms) the expected mobility comes from the kinematics:
finite motions checked with the assembly solver.
"""

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.mobility import MobilityResult, format_mobility, mobility
from pkdyn.closed_form import delta as clavel
from pkdyn.model.formats.urdf_writer import UrdfWriter

DATA = Path(__file__).resolve().parent / "data" / "mobility"


def _load(name, **params):
    return pkdyn.load(name, geometry=False, **params)


@pytest.fixture(scope="module")
def delta_ball():
    robot = _load("delta")
    return robot, mobility(robot)


@pytest.fixture(scope="module")
def gs_sps():
    robot = _load("gough_stewart", base_joint="spherical")
    return robot, mobility(robot)


def _counts(res: MobilityResult):
    return res.grubler, res.mobility, res.useful, res.internal, res.hyperstatism


def _moves_freely(robot, q, v, steps=(0.3, -0.7, 1.5)):
    """Finite motions along ``v`` keep every closure closed (an exact mobility, not a tangent)."""
    return max(pkdyn.closure_residual(robot, pin.integrate(robot.model, q, t * v)) for t in steps)


# --- seed 000, section 1.3.6: Clavel's Delta ---------------------------------------------------


def test_delta_ball_joints_clavel(delta_ball):
    # 12 ball joints x 3 + 3 arms x 1 - 5 loops x 6 = 9 "alors que l'on attendait 3"
    _, res = delta_ball
    assert res.loops == 5 and res.d == 6
    assert res.joint_mobility == 12 * 3 + 3 * 1
    assert _counts(res) == (9, 9, 3, 6, 0)
    assert res.equations == 30 and res.closure_rank == 30


def test_delta_internal_mobilities_are_the_six_bar_spins(delta_ball):
    robot, res = delta_ball
    bars = {f"bar{i}{s}" for i in (1, 2, 3) for s in "ab"}
    assert {m.bodies for m in res.internal_modes} == {(b,) for b in bars}
    for mode in res.internal_modes:
        bar = mode.bodies[0]
        assert mode.description.startswith(f"{bar} spins about its axis")
        assert mode.joints == (f"{bar}_upper",)
        # a finite spin keeps the loops closed and moves neither the nacelle nor the arms
        assert _moves_freely(robot, res.q, mode.direction) < 1e-12
        q2 = pin.integrate(robot.model, res.q, 0.8 * mode.direction)
        np.testing.assert_allclose(q2[robot.actuated_q], res.q[robot.actuated_q], atol=0)
        P0 = robot.platform_placement(res.q)
        P1 = robot.platform_placement(q2)
        assert np.linalg.norm(pin.log6(P0.actInv(P1)).vector) < 1e-12
    assert len(res.internal_names) == 6


def test_delta_universal_bar_joint_gives_three(delta_ball):
    # "Un cardan à l'une des extrémités de chacune des six barres conduirait à ... 3"
    res = mobility(_load("delta", bar_joint="universal"))
    assert res.joint_mobility == 6 * 2 + 6 * 3 + 3
    assert _counts(res) == (3, 3, 3, 0, 0)
    assert res.internal_modes == ()


def test_delta_hinged_parallelograms_grubler_is_wrong():
    """Revolute parallelograms (Tsai): Grübler -6, true mobility 3 (pure translations)."""
    robot = _load("delta", parallelogram="hinge")
    res = mobility(robot)
    # 3 arms + 6 universal (2) + 3 beam revolutes + 6 hinge closures (1) = 24; 5 loops
    assert res.loops == 5
    assert res.joint_mobility == 3 + 6 * 2 + 3 + 6
    assert res.grubler == 24 - 30 == -6
    # each parallelogram loop (U R R U, swing + parallelogram: 2 motions) has 6 - 4 = 2
    # redundant equations, and the three legs all fix the nacelle's orientation (3 more)
    assert _counts(res) == (-6, 3, 3, 0, 2 * 3 + 3)


def test_hinged_delta_is_still_clavels_delta():
    """The hinged variant has the ball Delta's kinematics: FK equals Clavel's closed form."""
    robot = _load("delta", parallelogram="hinge")
    rng = np.random.default_rng(7)
    q = robot.q_home
    for _ in range(20):
        alpha = np.array(robot.q_home[robot.actuated_q]) + rng.uniform(-0.3, 0.3, 3)
        fk = pkdyn.forward_geometry(robot, alpha, q)
        P, ok = clavel.forward(robot.params, alpha)
        assert ok[0]
        np.testing.assert_allclose(fk.position, P[0], atol=1e-9)
        np.testing.assert_allclose(fk.placement.rotation, np.eye(3), atol=1e-9)
        q = fk.q


def test_hinge_variant_needs_a_known_name():
    with pytest.raises(pkdyn.ParameterError, match="parallelogram"):
        _load("delta", parallelogram="cardan")


# --- seed 001 (Pasqui): Gough-Stewart, planar 3-RRR -------------------------------------------


def test_gough_stewart_ups_six():
    # N_C = 14, N_L = 18, mu = 5, Ec = 30, Ic = 6 x 6 = 36 -> m = 6
    res = mobility(_load("gough_stewart"))
    assert res.loops == 5 and res.joint_mobility == 36 and res.equations == 30
    assert _counts(res) == (6, 6, 6, 0, 0)


def test_gough_stewart_sps_twelve_is_six_plus_six_internal(gs_sps):
    # Ic = 6 x 7 = 42 -> i_m = 12, m = 12 = 6 + 6: "Il y a 6 mobilités internes"
    robot, res = gs_sps
    assert res.joint_mobility == 42
    assert _counts(res) == (12, 12, 6, 6, 0)
    legs = {(f"leg{i}_cylinder", f"leg{i}_rod") for i in range(1, 7)}
    assert {m.bodies for m in res.internal_modes} == legs
    for mode in res.internal_modes:
        leg = mode.bodies[0].split("_")[0]
        assert mode.joints == (f"{leg}_S",)
        assert "spin about their common axis" in mode.description
        assert _moves_freely(robot, res.q, mode.direction) < 1e-12


def test_gough_stewart_default_joint_names_unchanged():
    robot = _load("gough_stewart")
    assert all(robot.model.existJointName(f"leg{i}_U") for i in range(1, 7))
    with pytest.raises(pkdyn.ParameterError, match="base_joint"):
        _load("gough_stewart", base_joint="ball")


def test_planar_3rrr_pasqui():
    # d = 3, mu = 2: Ec = 6; Ic = 9; rc = 6 -> m = 3, h = 0
    res = mobility(_load("planar_3rrr"))
    assert res.d == 3 and res.loops == 2
    assert (res.joint_mobility, res.equations, res.closure_rank) == (9, 6, 6)
    assert _counts(res) == (3, 3, 3, 0, 0)


def test_five_bar_two():
    res = mobility(_load("five_bar"))
    assert res.d == 3 and res.loops == 1 and res.joint_mobility == 5
    assert _counts(res) == (2, 2, 2, 0, 0)


def test_tripod_branch_triangles_are_redundant():
    # per branch: q6, b, c, a (R), qL, qR (P), hinge A (1), universal (2), welded foot (0) = 9;
    # 27 - 6 x 5 = -3, but each branch's triangle is a planar loop closed in space (3 redundant
    # equations each): m = 6 (the nacelle's pose), h = 9
    res = mobility(_load("tripod"))
    assert res.loops == 5 and res.joint_mobility == 27
    assert _counts(res) == (-3, 6, 6, 0, 9)


# --- where Grübler is wrong: planar loops modelled in space -----------------------------------


@pytest.fixture(scope="module")
def four_bar():
    return pkdyn.load(str(DATA / "four_bar.urdf"), geometry=False)


def test_four_bar_in_space(four_bar):
    res = mobility(four_bar)
    # 3 revolutes + 1 hinge closure - 6 x 1 loop = -2, yet the crank turns: m = 1, h = 3
    assert res.d == 6 and res.loops == 1 and res.joint_mobility == 4
    assert _counts(res) == (-2, 1, 1, 0, 3)
    assert "Grübler's count is wrong here: 3 closure equations are redundant" in (
        format_mobility(res)
    )


def test_four_bar_moves_with_its_crank(four_bar):
    """Independent check of m >= 1: the crank drives the coupler through a range of poses."""
    q = four_bar.q_home
    seen = []
    for crank in np.linspace(0.9, 1.4, 6):
        fk = pkdyn.forward_geometry(four_bar, [crank], q)
        assert fk.residual < 1e-10
        seen.append(fk.position)
        q = fk.q
    assert np.ptp(np.array(seen)[:, :2], axis=0).min() > 1e-3


def test_four_bar_as_planar(four_bar):
    res = mobility(four_bar, d=3)
    assert _counts(res) == (1, 1, 1, 0, 0)


def test_spinning_bar_between_two_tree_ball_joints():
    """A bar between two tree ball joints whose far body is welded: the spin needs both joints."""
    w = UrdfWriter("ss_bar")
    w.link("base")
    w.rod("bar", 0.1, 0.005, (0, 0, 0), (0, 0, 0.3))
    w.link("plate", 0.2, inertia=np.diag([2e-4, 2e-4, 4e-4]))  # pkdyn: no point masses
    w.spherical("s1", "base", "bar", (0, 0, 0))
    w.spherical("s2", "bar", "plate", (0, 0, 0.3))
    w.closure("fix", "weld", ("plate", (0, 0, 0), (0, 0, 0)), ("base", (0, 0, 0.3), (0, 0, 0)))
    w.platform("plate", ("x", "y", "z", "rx", "ry", "rz"))
    robot = pkdyn.load_string(w.to_string(), "ss_bar", geometry=False)
    res = mobility(robot)
    # 3 + 3 + 0 - 6 = 0; the bar still spins: m = 1, h = 1, nothing useful
    assert _counts(res) == (0, 1, 0, 1, 1)
    (mode,) = res.internal_modes
    assert mode.joints == ("s1", "s2") and mode.bodies == ("bar",)
    assert mode.description.startswith("bar spins about its axis")
    assert _moves_freely(robot, res.q, mode.direction) < 1e-12


def test_free_floating_base_is_counted_and_said():
    """A floating base's six coordinates are degrees of freedom (``Robot.mobility`` counts them,
    as a legged robot's mobility does), reported apart as ``floating``."""
    w = UrdfWriter("floater")
    w.link("base")
    w.link("body", 1.0)
    w.rod("arm", 0.1, 0.005, (0, 0, 0), (0.2, 0, 0))
    w.joint("root", "floating", "base", "body")
    w.joint("elbow", "revolute", "body", "arm", axis=(0, 0, 1), limit=(-3, 3, 1, 1))
    robot = pkdyn.load_string(w.to_string(), "floater", geometry=False)
    res = mobility(robot)
    assert (res.grubler, res.mobility, res.floating, res.loops) == (7, 7, 6, 0)
    assert res.mobility == robot.mobility() and res.as_json()["floating"] == 6
    assert "7 = 1 useful + 0 internal + 6 free-floating" in format_mobility(res)


# --- API ----------------------------------------------------------------------------------------


def test_generic_configuration_is_assembled_and_matches_dof(delta_ball):
    robot, res = delta_ball
    assert pkdyn.closure_residual(robot, res.q) < 1e-10
    assert not np.allclose(res.q, robot.q_home)
    assert res.mobility == robot.mobility(res.q)
    assert res.rank == res.closure_rows == 18
    again = mobility(robot, seed=0)
    np.testing.assert_array_equal(again.q, res.q)


def test_given_configuration(delta_ball):
    robot, _ = delta_ball
    res = mobility(robot, q=robot.q_home)
    np.testing.assert_allclose(res.q, robot.q_home, atol=1e-12)
    assert _counts(res) == (9, 9, 3, 6, 0)


def test_as_json_and_text(gs_sps):
    _, res = gs_sps
    out = json.loads(json.dumps(res.to_json()))
    assert {"grubler", "mobility", "internal", "hyperstatism", "rank", "d", "useful"} <= set(out)
    assert (out["grubler"], out["mobility"], out["internal"], out["hyperstatism"]) == (12, 12, 6, 0)
    assert (out["rank"], out["d"], out["useful"]) == (18, 6, 6)
    assert len(out["internal_names"]) == 6 and all("leg" in n for n in out["internal_names"])
    text = format_mobility(res)
    assert text.splitlines()[0] == (
        "gough_stewart: mobility 12 = 6 useful + 6 internal (spatial, d = 6, 5 loops)"
    )
    assert "MO = sum f_i - d * loops = 42 - 6 * 5 = 12" in text
    assert "Ic = 42, Ec = 30, rc = 30; m = Ic - rc = 12, h = Ec - rc = 0" in text
    assert text.count("spin about their common axis") == 6


def test_bad_inputs(delta_ball):
    robot, _ = delta_ball
    with pytest.raises(pkdyn.InvalidInputError, match="d"):
        mobility(robot, d=4)
    with pytest.raises(pkdyn.InvalidInputError, match="q"):
        mobility(robot, q=np.zeros(3))
    with pytest.raises(pkdyn.InvalidInputError, match="tol"):
        mobility(robot, tol=0.0)
