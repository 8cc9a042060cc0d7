"""Home configurations: automatic search, the assembly tolerance, ``load(..., home=..., tol=...)``.

References: planar four-bar geometry (the rocker tip on the coupler tip, Grashof lengths),
closure residuals, and the rank of the closure Jacobian (straight line: rank drops).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.model.formats.urdf_writer import UrdfWriter
from pkdyn.model.home import singular

CRANK, COUPLER, ROCKER = 0.1, 0.25, 0.15


def _straight_four_bar(ground: float, z_offset: float = 0.0, kind: str = "hinge") -> str:
    """Crank, coupler and rocker all along +x at zero (rocker turned back): the straight line.

    With ``ground = CRANK + COUPLER + ROCKER`` the zero pose is assembled and singular; with a
    shorter ground it is not assembled (Levenberg-Marquardt cannot leave the line). The rocker
    base is lifted by ``z_offset`` out of the plane: an overconstrained hinge loop that cannot
    close exactly.
    """
    w = UrdfWriter("straight")
    w.link("ground")
    for name, length in (("crank", CRANK), ("coupler", COUPLER), ("rocker", ROCKER)):
        w.rod(name, 0.1, 0.005, (0, 0, 0), (length, 0, 0))
    w.joint("crank", "revolute", "ground", "crank", axis=(0, 0, 1), limit=(-3.1, 3.1, 5, 10))
    w.transmission("crank", "motor", 1.0)
    w.joint("coupler", "continuous", "crank", "coupler", xyz=(CRANK, 0, 0), axis=(0, 0, 1))
    w.joint(
        "rocker",
        "continuous",
        "ground",
        "rocker",
        xyz=(ground, 0, z_offset),
        rpy=(0, 0, math.pi),
        axis=(0, 0, 1),
    )
    w.closure(
        "pin",
        kind,
        ("coupler", (COUPLER, 0, 0), (0, 0, 0)),
        ("rocker", (ROCKER, 0, 0), (0, 0, 0)),
        axis=(0, 0, 1) if kind == "hinge" else None,
    )
    return w.to_string()


def _load(text: str, **kw) -> pkdyn.Robot:
    return pkdyn.load_string(text, "straight", geometry=False, **kw)


def _tips(robot: pkdyn.Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    a = data.oMf[robot.model.getFrameId("coupler", pin.BODY)].act(np.array([COUPLER, 0, 0]))
    b = data.oMf[robot.model.getFrameId("rocker", pin.BODY)].act(np.array([ROCKER, 0, 0]))
    return a, b


@pytest.mark.parametrize("ground", [CRANK + COUPLER + ROCKER, 0.45])
def test_straight_four_bar_gets_a_non_singular_home(ground):
    robot = _load(_straight_four_bar(ground))
    a, b = _tips(robot, robot.q_home)
    assert np.linalg.norm(a - b) < 1e-12
    assert not singular(robot, robot.q_home)
    assert robot.mobility() == 1
    # the straight line itself is singular (the closure Jacobian loses a rank there)
    if ground == CRANK + COUPLER + ROCKER:
        assert singular(robot, pin.neutral(robot.model))
        assert robot.mobility(pin.neutral(robot.model)) == 2


def test_a_given_home_is_kept_and_its_singularity_reported():
    text = _straight_four_bar(CRANK + COUPLER + ROCKER)
    with pytest.warns(UserWarning, match="singular"):
        robot = _load(text, home=[0.0])  # the crank at zero: the straight line
    np.testing.assert_allclose(robot.q_home, pin.neutral(robot.model), atol=1e-12)


def test_home_as_actuators_or_full_configuration():
    text = _straight_four_bar(0.45)
    robot = _load(text, home=[0.4])
    assert robot.q_home[robot.actuated_q][0] == pytest.approx(0.4, abs=1e-15)
    a, b = _tips(robot, robot.q_home)
    assert np.linalg.norm(a - b) < 1e-12
    full = _load(text, home=robot.q_home + 1e-3)
    np.testing.assert_allclose(full.q_home, robot.q_home, atol=1e-2)
    assert pkdyn.closure_residual(full, full.q_home) < 1e-12


@pytest.mark.parametrize(
    "home,message",
    [
        ([0.1, 0.2], r"2 values; give the 1 actuator coordinates \(motor\)"),
        ([math.nan], "NaN"),
        ("abc", "expected numbers"),
    ],
)
def test_bad_home(home, message):
    with pytest.raises(pkdyn.InvalidInputError, match=message):
        _load(_straight_four_bar(0.45), home=home)


@pytest.mark.parametrize("tol", [0.0, -1.0, math.nan, math.inf, "1e-3"])
def test_bad_tolerance(tol):
    with pytest.raises(pkdyn.InvalidInputError, match="tol"):
        _load(_straight_four_bar(0.45), tol=tol)


def test_cad_rounded_overconstrained_loop_is_closed_with_a_warning():
    """A hinge closes a planar loop whose rocker is 3 um out of the plane: no exact assembly."""
    text = _straight_four_bar(0.45, z_offset=3e-6)
    with pytest.warns(
        UserWarning, match=r"cannot be closed exactly \(closure 'pin' is off by 3e-06"
    ):
        robot = _load(text)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    assert robot.mobility() == 1
    (moved,) = robot.closures
    assert moved.frame2.placement.translation[2] == pytest.approx(-3e-6, abs=1e-9)


def test_beyond_the_tolerance_the_closure_is_named():
    text = _straight_four_bar(0.45, z_offset=2e-3)
    with pytest.raises(pkdyn.AssemblyError) as err:
        _load(text)
    assert err.value.closure == "pin"
    assert "closure 'pin' (between 'coupler' and 'rocker')" in str(err.value)
    assert err.value.residual == pytest.approx(2e-3, rel=1e-3)
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        robot = _load(text, tol=1e-2)  # a looser tolerance absorbs it
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12


def test_lengths_that_cannot_close_name_the_closure():
    text = _straight_four_bar(0.9, kind="point")  # ground longer than the three links
    with pytest.raises(pkdyn.AssemblyError, match="closure 'pin'.*keeps a residual of 0.4"):
        _load(text)


def test_library_family_home_override():
    robot = pkdyn.load("five_bar", home=[2.0, 1.0])
    np.testing.assert_allclose(robot.q_home[robot.actuated_q], [2.0, 1.0], atol=1e-15)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12


# ---------------------------------------------------------------------- the full-rank bound


def _with_singular_values(rng: np.random.Generator, s: np.ndarray, n: int) -> np.ndarray:
    """A matrix (m, n) with singular values ``s`` (m,) and random singular vectors."""
    m = s.size
    U, _ = np.linalg.qr(rng.standard_normal((m, m)))
    V, _ = np.linalg.qr(rng.standard_normal((n, m)))
    return (U * s) @ V.T


@pytest.mark.parametrize("seed", range(6))
def test_full_rank_bound_never_contradicts_rank(seed):
    """Where the bound proves ``rank(J) == m``, :func:`rank` counts every row (at the cut-off)."""
    from pkdyn.model.home import RANK_RTOL, full_rank_bound, rank

    rng = np.random.default_rng(seed)
    proved = refused = 0
    for _ in range(300):
        m, n_p, n_a = int(rng.integers(2, 19)), 0, int(rng.integers(1, 5))
        n_p = m + int(rng.integers(0, 8))
        top = 10.0 ** rng.uniform(-2, 3)
        s = np.sort(top * 10.0 ** rng.uniform(-3, 0, m))[::-1]
        # the smallest near the cut-off: 0.5x to 5x of RTOL * max(|J|, 1)
        s[-1] = RANK_RTOL * max(top, 1.0) * 10.0 ** rng.uniform(-0.5, 0.7)
        Jp = _with_singular_values(rng, s, n_p)
        Ja = rng.standard_normal((m, n_a)) * top * rng.uniform(0.0, 3.0)
        J = np.hstack([Ja, Jp])
        s_p = np.linalg.svd(Jp, compute_uv=False)
        if full_rank_bound(s_p, J):
            proved += 1
            assert rank(J) == m
            assert rank(Jp) == m
        else:
            refused += 1
    assert proved > 20 and refused > 20


def test_full_rank_bound_refuses_what_it_cannot_prove():
    from pkdyn.model.home import full_rank_bound

    J = np.eye(3, 5)
    assert full_rank_bound(np.linalg.svd(J[:, :3], compute_uv=False), J)
    assert not full_rank_bound(np.array([1.0, 1.0]), J)  # fewer values than rows
    assert not full_rank_bound(np.zeros(0), np.zeros((0, 4)))
    J[2, 2] = 1e-12
    assert not full_rank_bound(np.linalg.svd(J[:, :3], compute_uv=False), J)
    J[0, 0] = np.nan
    assert not full_rank_bound(np.array([1.0, 1.0, 1.0]), J)


@pytest.mark.parametrize("name", ["delta", "gough_stewart", "five_bar", "planar_3rrr"])
def test_singular_verdict_equals_the_exhaustive_one(name):
    """``singular`` at and near each family's home: the verdict of both ranks computed."""
    from pkdyn.model.home import rank

    robot = pkdyn.load(name)
    rng = np.random.default_rng(3)
    cs = robot.constraints
    asserted = 0
    for k in range(6):
        q = (
            robot.q_home
            if k == 0
            else pin.integrate(robot.model, robot.q_home, rng.uniform(-0.05, 0.05, robot.nv))
        )
        J = cs.jacobian(robot.data, q)
        r = rank(J)
        exhaustive_cut = robot.actuated_v.size and rank(J[:, robot.passive_v]) < r
        if exhaustive_cut or r < J.shape[0]:
            continue  # (the probe of the null space is unchanged)
        assert singular(robot, q) is False
        asserted += 1
    assert asserted > 0
