"""The Delta's study shortcuts give the numbers of the paths they replace, bit for bit.

- :class:`pkdyn.library.delta.Params` takes its home's arm angles from the inverse model that
  validates ``z_home`` (one inverse model instead of two): the verdict and the angles are those
  of :meth:`~pkdyn.library.delta.Params._reachable` and of the separate inverse model;
- :func:`pkdyn.library.delta.layout` takes the arms' unit vectors and yaw once per arm count;
- :func:`pkdyn.precision.vectorised._delta_mass` sums its outer products in two work arrays.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.kinematics import SINGULAR_TOL
from pkdyn.closed_form import delta as cf
from pkdyn.dynamics.delta import DeltaDynamics
from pkdyn.exceptions import ParameterError
from pkdyn.library import delta
from pkdyn.precision import vectorised
from pkdyn.precision.vectorised import _delta_jacobian, _delta_mass, _outer
from solvers.vec3 import cross


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def _draws(n: int, seed: int) -> list[dict[str, Any]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        out.append(
            {
                "la": float(rng.uniform(0.1, 0.4)),
                "lb": float(rng.uniform(0.2, 0.8)),
                "ra": float(rng.uniform(0.06, 0.25)),
                "rb": float(rng.uniform(0.01, 0.05)),
                "alpha_min": float(rng.uniform(-1.2, -0.3)),
                "alpha_max": float(rng.uniform(0.8, 1.8)),
                "arms": int(rng.choice([3, 4])),
                "z_home": float(rng.uniform(-1.2, 0.0)),
            }
        )
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_params_home_from_validation_equals_separate_inverse(seed: int) -> None:
    checked = refused = 0
    for draw in _draws(150, seed):
        z = float(draw.pop("z_home"))
        if draw["ra"] <= draw["rb"]:
            continue
        try:
            p0 = delta.Params(**draw)  # z_home derived: the geometry and limits alone
        except ParameterError:
            continue
        # the previous path: the verdict of _reachable (x = y = -0.0), then the home's own
        # inverse model (x = y = +0.0)
        reachable = bool(p0._reachable(np.array([z]))[0])
        try:
            p = delta.Params(**draw, z_home=z)
        except ParameterError as err:
            assert not reachable
            assert err.name == "z_home"
            refused += 1
            continue
        assert reachable
        alpha, _ = cf.inverse(p, np.array([0.0, 0.0, p.home_height()]))
        expected = tuple(float(a) for a in alpha[0])
        assert _same(np.array(p._home), np.array(expected))
        assert delta.home(p) == list(expected)
        checked += 1
    assert checked > 30 and refused > 10


def test_params_home_equals_without_z_home() -> None:
    """Without ``z_home`` the home is still computed on first use, as before."""
    p = delta.Params(la=0.25, lb=0.5, ra=0.15)
    alpha, _ = cf.inverse(p, np.array([0.0, 0.0, p.home_height()]))
    assert _same(np.array(delta.home(p)), alpha[0])


@pytest.mark.parametrize("arms", [3, 4])
def test_arm_frames_equal_the_layout_arithmetic(arms: int) -> None:
    p = delta.Params(arms=arms)
    frames = delta._arm_frames(arms)
    assert len(frames) == arms
    for (theta, u, t, yaw), th, alpha in zip(frames, p.theta, delta.home(p), strict=True):
        assert type(theta) is type(th) and _same(np.array(theta), np.array(th))
        assert _same(u, np.array([np.cos(th), np.sin(th), 0.0]))
        assert _same(t, np.array([-np.sin(th), np.cos(th), 0.0]))
        # the arm's rotation as layout made it before
        before = pin.rpy.rpyToMatrix(0.0, 0.0, th) @ pin.rpy.rpyToMatrix(0.0, alpha, 0.0)
        assert _same(yaw @ pin.rpy.rpyToMatrix(0.0, alpha, 0.0), before)
        assert not (u.flags.writeable or t.flags.writeable or yaw.flags.writeable)


def _delta_jacobian_reference(dd: DeltaDynamics, P: np.ndarray) -> tuple[np.ndarray, ...]:
    """``_delta_jacobian`` as it was: (N, arm, component) arrays throughout."""
    alpha, ok = cf.inverse(dd.params, P - dd.f_off)
    reached = np.array(ok, dtype=bool)
    alpha = np.where(np.isfinite(alpha), alpha, 0.0)
    c, s = np.cos(alpha), np.sin(alpha)
    E = dd.O[None] + dd._in_world(c, s, dd.elbow)
    d = P[:, None, :] + dd.attach[None] - E
    E1 = cross(dd.axis[None], E - dd.O[None])
    g = np.sum(d * E1, axis=-1)
    scale = np.sqrt(np.sum(d * d, axis=-1) * np.sum(E1 * E1, axis=-1))
    margin = np.min(np.abs(g) / np.where(scale > 0.0, scale, 1.0), axis=1)
    ok = ok & (margin > SINGULAR_TOL)
    g = np.where(ok[:, None], g, 1.0)
    return ok, d / g[..., None], E1, d, reached, margin


def _poses(rng: np.random.Generator, z: float, n: int) -> np.ndarray:
    """Poses around a height: random, on the axis and the coordinate planes, out of reach."""
    P = np.column_stack(
        [rng.uniform(-0.2, 0.2, n), rng.uniform(-0.2, 0.2, n), rng.uniform(z - 0.1, z + 0.1, n)]
    )
    P[: n // 8, :2] = 0.0  # on the axis (exact zeros in the products)
    P[n // 8 : n // 4, 0] = 0.0
    P[n // 4 : n // 3, 1] = -0.0
    P[-5:] = [[0.0, 0.0, 0.5], [3.0, 0.0, z], [0.0, 0.0, -5.0], [0.0, 0.0, 0.0], [0.0, 0.0, z]]
    return P


def _delta_mass_reference(
    dd: DeltaDynamics, Jinv: np.ndarray, E1: np.ndarray, d: np.ndarray
) -> np.ndarray:
    """``_delta_mass`` as it was: one new array per operation."""
    N = Jinv.shape[0]
    scalar = dd.nacelle_mass + float(np.sum(dd.m_pp))
    M = np.zeros((N, 3, 3))
    for k in range(3):
        J, e1 = Jinv[:, k], E1[:, k]
        u = d[:, k] / dd.length[k]
        b = dd.inertia_t[k] / dd.length[k] ** 2
        ue = (u * e1).sum(axis=-1)
        e = e1 - u * ue[:, None]
        e1e1 = (e1 * e1).sum(axis=-1)
        ux = e1e1 - ue**2
        a = dd.arm_axial[k] + dd.m_ee[k] * e1e1 + b * ux
        M += a[:, None, None] * _outer(J, J)
        o = _outer(e1, J)
        M += dd.m_ep[k] * (o + np.swapaxes(o, 1, 2))
        o = _outer(e, J)
        M -= b * (_outer(u, u) + o + np.swapaxes(o, 1, 2))
        scalar += b
    M += scalar * np.eye(3)[None]
    return 0.5 * (M + np.swapaxes(M, 1, 2))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_delta_mass_in_place_equals_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    la, lb, ra = rng.uniform(0.15, 0.35), rng.uniform(0.3, 0.7), rng.uniform(0.08, 0.22)
    robot = pkdyn.load(
        "delta",
        la=float(la),
        lb=float(lb),
        ra=float(ra),
        rotor_inertia=float(rng.uniform(0.0, 1e-4)),
    )
    dd = DeltaDynamics(robot)
    P = _poses(rng, robot.params.home_height(), 400)
    got_all = _delta_jacobian(dd, P)
    for got, want in zip(got_all, _delta_jacobian_reference(dd, P), strict=True):
        assert _same(got, want)
        assert not isinstance(got, np.ndarray) or got.flags.c_contiguous == want.flags.c_contiguous
    ok, Jinv, E1, d, reached, _ = got_all
    assert ok.sum() > 100 and not reached.all()
    got = _delta_mass(dd, Jinv[ok], E1[ok], d[ok])
    assert _same(got, _delta_mass_reference(dd, Jinv[ok], E1[ok], d[ok]))
    # and the lowest frequency it gives, through the public closed form
    fig = vectorised.delta_figures(robot, P, np.full(3, 2e4), frequency=True)
    assert np.isfinite(fig.f1[fig.valid]).all()


def test_delta_mass_handles_one_pose() -> None:
    robot = pkdyn.load("delta")
    dd = DeltaDynamics(robot)
    ok, Jinv, E1, d, _, _ = _delta_jacobian(dd, np.array([[0.0, 0.0, -0.35]]))
    assert ok.all()
    assert _same(_delta_mass(dd, Jinv, E1, d), _delta_mass_reference(dd, Jinv, E1, d))


def test_params_are_still_frozen_and_equal() -> None:
    p = delta.Params(z_home=-0.35)
    q = dataclasses.replace(p)
    assert p == q and hash(p) == hash(q)
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.la = 0.3  # type: ignore[misc]


def _hex(v: object) -> object:
    """Numbers as exact text (the sign of zero included), structures kept."""
    if isinstance(v, np.ndarray):
        return (v.shape, v.tobytes().hex())
    if isinstance(v, tuple | list):
        return tuple(_hex(x) for x in v)
    if isinstance(v, float | np.floating):
        return float(v).hex()
    return v


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"arms": 4},
        {"bar_joint": "universal"},
        {"parallelogram": "hinge"},
        {"la": 0.31, "lb": 0.62, "ra": 0.09, "z_home": -0.35},
        {"la": 0.17, "lb": 0.41, "ra": 0.2, "rb": 0.04},
    ],
)
def test_layout_numbers_equal_the_previous_arithmetic(options: dict[str, object]) -> None:
    """The arms' and bars' numbers the layout writes, against the expressions it used before."""
    p = delta.Params(**options)  # type: ignore[arg-type]
    records = {
        (r.kind, r.args.get("name")): r.args for r in delta.layout(p).records if "name" in r.args
    }
    s = 0.5 * p.bar_spacing
    P = np.array([0.0, 0.0, p.home_height()])
    checked = 0
    for i, (theta, alpha) in enumerate(zip(p.theta, delta.home(p), strict=True), start=1):
        u = np.array([np.cos(theta), np.sin(theta), 0.0])
        t = np.array([-np.sin(theta), np.cos(theta), 0.0])
        R_arm = pin.rpy.rpyToMatrix(0.0, 0.0, theta) @ pin.rpy.rpyToMatrix(0.0, alpha, 0.0)
        O = p.ra * u
        arm = records[("joint", f"arm{i}")]
        assert _hex(arm["xyz"]) == _hex(p.ra * u)
        assert _hex(arm["rpy"]) == _hex((0.0, 0.0, theta))
        for side, sign in (("a", 1.0), ("b", -1.0)):
            elbow_w = O + R_arm @ np.array([p.la, sign * s, 0.0])
            attach = P + p.rb * u + sign * s * t
            d_arm = R_arm.T @ (attach - elbow_w)
            upper = records[("joint", f"bar{i}{side}_upper")]
            if p.parallelogram == "ball":
                from pkdyn.model.formats.urdf_writer import rpy_z_to

                assert _hex(upper["rpy"]) == _hex(rpy_z_to(d_arm))
                loop = records[("closure", f"loop{i}{side}")]
                assert _hex(loop["frame2"][1]) == _hex(p.rb * u + sign * s * t)
                checked += 1
        if p.parallelogram == "hinge":
            loop = records[("closure", f"loop{i}")]
            assert _hex(loop["frame2"][1]) == _hex(p.rb * u)
            checked += 1
    assert checked >= p.arms


def _inv3_reference(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``inv3`` as it was: the adjugate stacked."""
    a, b, c = A[:, 0, 0], A[:, 0, 1], A[:, 0, 2]
    d, e, f = A[:, 1, 0], A[:, 1, 1], A[:, 1, 2]
    g, h, i = A[:, 2, 0], A[:, 2, 1], A[:, 2, 2]
    co = np.stack(
        [
            np.stack([e * i - f * h, c * h - b * i, b * f - c * e], -1),
            np.stack([f * g - d * i, a * i - c * g, c * d - a * f], -1),
            np.stack([d * h - e * g, b * g - a * h, a * e - b * d], -1),
        ],
        -2,
    )
    det = a * co[:, 0, 0] + b * co[:, 1, 0] + c * co[:, 2, 0]
    safe = np.where(det != 0.0, det, 1.0)
    return co / safe[:, None, None], det


def test_inv3_equals_the_stacked_adjugate() -> None:
    rng = np.random.default_rng(5)
    A = rng.standard_normal((500, 3, 3)) * 10.0 ** rng.uniform(-6, 6, (500, 1, 1))
    A[:50, 2] = A[:50, 0]  # singular
    A[50:100, 1, :] = -0.0
    A[100:110] = np.nan
    for M in (A, np.swapaxes(A, 1, 2), A[::2], A[:0]):
        got, want = vectorised.inv3(M), _inv3_reference(M)
        assert _same(got[0], want[0]) and _same(got[1], want[1])
        assert got[0].flags.c_contiguous


@pytest.mark.parametrize("seed", [0, 1])
def test_delta_figures_equal_the_previous_path(seed: int) -> None:
    """The public closed form, against its previous arithmetic assembled from the references."""
    from pkdyn.precision.vectorised import _FREE, _chol3, _gram, sym3_min_eig

    rng = np.random.default_rng(seed)
    robot = pkdyn.load("delta", la=float(rng.uniform(0.18, 0.3)), lb=float(rng.uniform(0.35, 0.6)))
    P = _poses(rng, robot.params.home_height(), 425)
    for poses in (P, P[: 425 // 8]):  # some out of reach; then all on the axis, all reached
        k = np.array([2e4, 3e4, 2.5e4])
        got = vectorised.delta_figures(robot, poses, k, frequency=True)
        dd = DeltaDynamics(robot)
        ok, Jinv, E1, d, _, margin = _delta_jacobian_reference(dd, poses)
        K = _gram(Jinv, k, slice(0, 3), slice(0, 3))
        kmin = sym3_min_eig(K)
        ok = ok & (kmin > _FREE * np.einsum("nii->n", K))
        M = _delta_mass_reference(dd, Jinv[ok], E1[ok], d[ok])
        L_inv, _ = _inv3_reference(_chol3(M))
        A = np.matmul(np.matmul(L_inv, K[ok]), np.swapaxes(L_inv, 1, 2))
        A = 0.5 * (A + np.swapaxes(A, 1, 2))
        f1 = np.full(poses.shape[0], np.nan)
        f1[ok] = np.sqrt(np.maximum(sym3_min_eig(A), 0.0)) / (2.0 * np.pi)
        assert _same(got.valid, ok)
        assert _same(got.stiffness_min, np.where(ok, kmin, np.nan))
        assert _same(got.f1, f1)
        assert np.isfinite(got.f1[ok]).all()
        assert ok.all() if poses is not P else not ok.all()  # (both branches)
