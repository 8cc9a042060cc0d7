"""Clavel's Delta workspace (seed 000, section 1.4): closed form against the mechanism."""

import json
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.workspace.clavel import (
    AB_MIN,
    GAMMA_MAX,
    clavel_angles,
    clavel_closed_form,
    clavel_numeric,
    clavel_valid,
)


@dataclass(frozen=True)
class G:
    ra: float
    rb: float
    la: float
    lb: float


def _geometry(r, b, la=0.2, rb=0.025):
    return G(ra=r * la + rb, rb=rb, la=la, lb=b * la)


def test_seed_coefficients():
    """Section 1.4: d = 2 b sin(gamma_max) ~ 1.3 b, s = 1.431 b^2 (the seed's figures)."""
    for b in (1.5, 1.9, 2.5):
        f = clavel_closed_form(_geometry(0.625, b)).dimensionless()
        assert f["d"] / b == pytest.approx(1.2856, abs=1e-4)
        assert f["s"] / b**2 == pytest.approx(1.431, abs=5e-4)
    # z_h for (alpha+beta)_min = 30 deg: -sqrt(1 + b^2 - b sqrt 3) (seed, Fig. 19)
    b = 1.9
    f = clavel_closed_form(_geometry(0.625, b)).dimensionless()
    assert f["z_h"] == pytest.approx(-math.sqrt(1 + b * b - b * math.sqrt(3)), abs=1e-12)


def _lowest_reachable(robot: pkdyn.Robot, xy: np.ndarray) -> float:
    """Lowest height [m] the nacelle reaches above ``xy``: bisection on the numeric inverse
    geometric model of the Pinocchio mechanism (no joint limits), to 1e-10 m."""
    hi, lo, q = -0.25, -0.75, None
    while hi - lo > 1e-10:
        z = 0.5 * (hi + lo)
        try:
            q = pkdyn.inverse_geometry(robot, [*xy, z], q_init=q, check_limits=False).q
            hi = z
        except pkdyn.PkdynError:
            lo = z
    return hi


def test_prism_bottom_measured_on_the_mechanism():
    """Fig. 20, measured: the prism's vertical edges are at ``2 b sin(gamma_max) / sqrt 3`` (LA
    units) from the axis. Above the edge opposite arm 1 (T) arm 1 runs out of reach first (arm
    and bars aligned, gamma_1 = 0); above the edge on arm 1's side (T'), arms 2 and 3 do
    (gamma = gamma_max). The lowest reachable points there are the seed's z_T and z_T' (z_T'
    with its minus sign), their maximum is the closed form's z_b, and they cross between
    r = 0.62 and 0.64 (the seed: r = 0.63 for gamma_max = 40 deg)."""
    la, b, g = 0.2, 1.9, GAMMA_MAX
    corner = 2 * b * math.sin(g) / math.sqrt(3)
    gap = []
    for r in (0.5, 0.62, 0.64, 0.8):
        geo = _geometry(r, b, la=la)
        robot = pkdyn.load("delta", ra=geo.ra, rb=geo.rb, la=geo.la, lb=geo.lb, geometry=False)
        z_t = _lowest_reachable(robot, np.array([-corner * la, 0.0]))
        z_tp = _lowest_reachable(robot, np.array([corner * la, 0.0]))
        # the seed's formulas (section 1.4), in LA units
        seed_t = -math.sqrt((1 + b) ** 2 - (r + 2 * b * math.sin(g) / math.sqrt(3)) ** 2)
        seed_tp = -math.sqrt((1 + b * math.cos(g)) ** 2 - (r + b * math.sin(g) / math.sqrt(3)) ** 2)
        assert z_t == pytest.approx(seed_t * la, abs=2e-9)
        assert z_tp == pytest.approx(seed_tp * la, abs=2e-9)
        assert clavel_closed_form(geo).zb == pytest.approx(max(z_t, z_tp), abs=2e-9)
        gap.append(z_t - z_tp)
    assert gap[0] < 0 and gap[1] < 0 < gap[2] < gap[3]


def test_angles_match_the_pinocchio_model(delta):
    """gamma_i and alpha_i + beta_i from Clavel's closed form vs the assembled URDF model."""
    rng = np.random.default_rng(0)
    p = delta.params
    model, data = delta.model, delta.data
    for _ in range(10):
        P = np.array([*rng.uniform(-0.12, 0.12, 2), rng.uniform(-0.45, -0.3)])
        ik = pkdyn.inverse_geometry(delta, P, check_limits=False)
        pin.forwardKinematics(model, data, ik.q)
        alpha, ab, gamma = clavel_angles(p, P[None])
        for i, theta in enumerate(np.deg2rad([0.0, 120.0, 240.0])):
            e_r = np.array([np.cos(theta), np.sin(theta), 0.0])
            e_t = np.array([-np.sin(theta), np.cos(theta), 0.0])
            for side in "ab":
                jid = model.getJointId(f"bar{i + 1}{side}_upper")
                u = data.oMi[jid].rotation[:, 2]  # bar axis, world
                assert math.asin(u @ e_t) == pytest.approx(gamma[0, i], abs=1e-9)
                beta = math.atan2(-u[2], -(u @ e_r))
                assert alpha[0, i] + beta == pytest.approx(ab[0, i], abs=1e-9)
            assert ik.qa[i] == pytest.approx(alpha[0, i], abs=1e-9)


@pytest.mark.parametrize(
    "r, b, gamma_deg, ab_deg",
    [(0.625, 1.9, 40, 30), (0.3, 2.5, 40, 30), (1.0, 1.5, 40, 30), (0.625, 1.9, 55, 20)],
)
def test_closed_form_against_numeric(r, b, gamma_deg, ab_deg):
    """Both branches of z_b (r below and above 0.63) and other limits: agreement to 1e-8 m."""
    g = _geometry(r, b)
    gm, ab = math.radians(gamma_deg), math.radians(ab_deg)
    cf = clavel_closed_form(g, gm, ab)
    nu, v_ws = clavel_numeric(g, gm, ab, rays=36, fractions=11, heights=60)
    for key in ("D", "H", "Hmax", "zh", "zb"):
        assert getattr(nu, key) == pytest.approx(getattr(cf, key), abs=1e-8), key
    assert nu.S == pytest.approx(cf.S, abs=1e-8)
    assert nu.V == pytest.approx(cf.V, rel=1e-7)
    # the workspace is the prism plus a dome above and a cap below
    assert v_ws > 1.1 * cf.V


def test_numeric_prism_is_inside_the_workspace_and_tight():
    """Independent sampling: every point of the closed-form prism is valid; just outside is not."""
    p = pkdyn.load("delta", geometry=False).params
    cf = clavel_closed_form(p)
    rng = np.random.default_rng(1)
    # random points of the hexagon (|P . t_i| <= D/2 for the three arm planes)
    xy = rng.uniform(-0.3, 0.3, (40000, 2))
    theta = np.deg2rad([0.0, 120.0, 240.0])
    t = np.column_stack([-np.sin(theta), np.cos(theta)])
    xy = xy[np.all(np.abs(xy @ t.T) <= cf.D / 2 * (1 - 1e-9), axis=1)]
    z = rng.uniform(cf.zb + 1e-9, cf.zh - 1e-9, len(xy))
    assert clavel_valid(p, np.column_stack([xy, z])).all()
    # the prism's top is touched under each arm axis, its bottom at the hexagon's corners
    A = (p.ra - p.rb) * np.array([1.0, 0.0])
    assert not clavel_valid(p, np.array([[*A, cf.zh + 1e-6]]))[0]
    corner = cf.D / 2 / math.cos(math.pi / 6) * np.array([-0.5, math.sqrt(3) / 2])
    assert not clavel_valid(p, np.array([[*corner * (1 - 1e-9), cf.zb - 1e-6]]))[0]


def test_workspace_volume_converges_under_refinement():
    p = pkdyn.load("delta", geometry=False).params
    vols = [
        clavel_numeric(p, rays=n, fractions=n // 3, heights=60, refine=False)[1]
        for n in (24, 48, 96)
    ]
    e1, e2 = abs(vols[1] - vols[0]), abs(vols[2] - vols[1])
    assert e2 < 0.5 * e1
    assert e2 / vols[2] < 5e-3


def test_no_complete_prism():
    """Hexagon corners beyond reach above the prism top: both give H = 0, the projection is
    smaller than the hexagon (its corners cannot be reached)."""
    g = _geometry(1.5, 3.0)
    cf = clavel_closed_form(g)
    nu, _ = clavel_numeric(g, rays=36, fractions=11, heights=60, refine=False)
    assert cf.H == 0.0 and nu.H == 0.0 and cf.V == 0.0
    assert nu.S < cf.S and nu.D == pytest.approx(cf.D, abs=1e-8)


def test_bad_limits():
    with pytest.raises(pkdyn.PkdynError, match="gamma_max"):
        clavel_closed_form(_geometry(0.6, 1.9), gamma_max=2.0)
    with pytest.raises(pkdyn.PkdynError, match="alpha"):
        clavel_closed_form(_geometry(0.6, 1.9), ab_min=-0.1)


def test_cli_clavel_json(capsys):
    from pkdyn.cli import main

    code = main(["workspace", "delta", "--clavel", "--json", "--rays", "36"])
    out, _ = capsys.readouterr()
    assert code == 0
    res = json.loads(out)
    for part in ("closed_form", "numeric"):
        assert set(res[part]) >= {"D", "S", "H", "Hmax", "V", "zh"}
    assert res["numeric"]["H"] == pytest.approx(res["closed_form"]["H"], abs=1e-8)
    assert res["limits"]["gamma_max"] == pytest.approx(GAMMA_MAX)
    assert res["limits"]["ab_min"] == pytest.approx(AB_MIN)
    code = main(["workspace", "gough_stewart", "--clavel"])
    _, err = capsys.readouterr()
    assert code == 1 and "clavel" in err.lower()


def test_delta_580_figures():
    """The DELTA 580 figures of docs/guide/workspace.md (Clavel's limits: gamma_max 40 deg,
    (alpha+beta)_min 30 deg): the closed form from the seed's dimensionless formulas (section 1.4,
    z_T' with its minus sign) with ra = 150, rb = 25, la = 200, lb = 380 mm (seed's table: r =
    0.625, b = 1.9), the mechanism's measurement (clavel_numeric, default resolution) to 2e-10 m,
    and the whole workspace's volume (recorded figure of the numeric measurement)."""
    p = pkdyn.load("delta", geometry=False).params
    r, b, la, g = 0.625, 1.9, 0.2, GAMMA_MAX
    assert ((p.ra - p.rb) / p.la, p.lb / p.la, p.la) == pytest.approx((r, b, la), abs=1e-15)
    z_h = -math.sqrt(1 + b * b - 2 * b * math.cos(AB_MIN))
    z_t = -math.sqrt((1 + b) ** 2 - (r + 2 * b * math.sin(g) / math.sqrt(3)) ** 2)
    z_tp = -math.sqrt((1 + b * math.cos(g)) ** 2 - (r + b * math.sin(g) / math.sqrt(3)) ** 2)
    d, s = 2 * b * math.sin(g), 2 * math.sqrt(3) * math.sin(g) ** 2 * b**2
    h, h_max = z_h - max(z_t, z_tp), math.sqrt((1 + b) ** 2 - r**2) + z_h
    seed = {"D": d * la, "S": s * la**2, "H": h * la, "Hmax": h_max * la, "V": s * h * la**3}
    seed["zh"] = z_h * la
    cf = clavel_closed_form(p)
    for key, value in seed.items():
        assert getattr(cf, key) == pytest.approx(value, rel=1e-12), key
    # as printed in the guide
    readme = {"D": 0.4885, "S": 0.2067, "H": 0.1831, "Hmax": 0.3367, "V": 0.0378, "zh": -0.2297}
    for key, value in readme.items():
        assert round(getattr(cf, key), 4) == value, key
    nu, v_ws = clavel_numeric(p, progress=False)
    for key in ("D", "H", "Hmax", "zh", "zb"):
        assert getattr(nu, key) == pytest.approx(getattr(cf, key), abs=2e-10), key
    # recorded: the whole workspace 0.0593 m^3 = 1.57 V
    assert v_ws == pytest.approx(0.05927, rel=1e-3)
    assert v_ws / cf.V == pytest.approx(1.566, abs=1e-3)
