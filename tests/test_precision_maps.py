"""Precision maps, closed forms, design metrics, CLI and description elements (issue 26, 4-8).

The vectorised closed forms are checked against the general path (virtual-joint stiffness and
modes pose by pose); the CLI commands against the library functions; the description elements
against their errors.
"""

import json

import numpy as np
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.design import Study
from pkdyn.design.evaluate import evaluate_design
from pkdyn.exceptions import DescriptionError, InvalidInputError
from pkdyn.precision import stiffness
from pkdyn.precision.maps import pose_figures, precision_map
from pkdyn.precision.modes import modes
from pkdyn.precision.vectorised import inv3, sym3_min_eig


def test_closed_forms_match_the_general_path(delta, gough_stewart):
    rng = np.random.default_rng(7)
    # Gough-Stewart: tilted platform, a tool point, a wrench with a moment
    home = gough_stewart.platform_placement(gough_stewart.q_home).translation
    P = home + rng.uniform(-0.03, 0.03, (4, 3))
    R = pkdyn.model.pose.pose_from_vector([0, 0, 0, 0.05, -0.04, 0.1]).rotation
    k = rng.uniform(1e6, 3e6, 6)
    w = np.array([30.0, -20.0, -200.0, 2.0, 1.0, -3.0])
    opts = dict(point=[0.01, 0.02, 0.1], wrench=w)
    fast = pose_figures(gough_stewart, P, R, k, **opts)
    slow = pose_figures(gough_stewart, P, R, k, method="general", progress=False, **opts)
    assert fast.method == "closed form" and slow.method == "general"
    assert np.allclose(fast.stiffness_min, slow.stiffness_min, rtol=1e-9)
    assert np.allclose(fast.deflection, slow.deflection, rtol=1e-9)
    # Delta: stiffness, deflection and lowest frequency
    home = delta.platform_placement(delta.q_home).translation
    P = home + rng.uniform(-0.08, 0.08, (4, 3))
    k = rng.uniform(1e4, 3e4, 3)
    opts = dict(wrench=[5.0, -3.0, -40.0, 0.0, 0.0, 0.0], frequency=True)
    fast = pose_figures(delta, P, None, k, **opts)
    slow = pose_figures(delta, P, None, k, method="general", progress=False, **opts)
    assert fast.method == "closed form"
    for name in ("stiffness_min", "deflection", "f1"):
        assert np.allclose(getattr(fast, name), getattr(slow, name), rtol=1e-9), name


def test_three_by_three_closed_forms():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(200, 3, 3))
    A = X @ np.swapaxes(X, 1, 2) + np.eye(3) * rng.uniform(0, 1, (200, 1, 1))
    assert np.allclose(sym3_min_eig(A), np.linalg.eigvalsh(A)[:, 0], rtol=1e-9, atol=1e-12)
    inv, det = inv3(X)
    assert np.allclose(inv, np.linalg.inv(X)) and np.allclose(det, np.linalg.det(X))


def test_map_of_the_delta_and_its_worst_pose(delta):
    m = precision_map(delta, "xz", samples=15, actuator_stiffness=2e4, frequency=True,
                      wrench=[0.0, 0.0, -50.0, 0.0, 0.0, 0.0])  # fmt: skip
    assert m.method == "closed form"
    assert set(m.values) == {"stiffness_min", "deflection", "f1"}
    inside = m.reachable
    assert 0 < inside.sum() < inside.size
    assert np.all(np.isfinite(m.values["f1"][inside])) and np.all(np.isnan(m.values["f1"][~inside]))
    # the worst pose of the map, recomputed on the general path
    iu, iv = np.unravel_index(np.nanargmin(m.values["f1"]), inside.shape)  # values[i_u, i_v]
    q = pkdyn.inverse_geometry(delta, [m.u[iu], m.fixed["y"], m.v[iv]]).q
    assert modes(delta, q, 2e4).f1 == pytest.approx(m.extreme("f1"), rel=1e-9)
    from pkdyn.plotting import plot_precision_map

    fig = plot_precision_map(m, "f1", reference=150.0)
    assert fig.axes


def test_design_metrics_trade_stiffness(tmp_path):
    s = Study(
        family="delta",
        ranges={"la": (0.18, 0.26)},
        fixed={"z_home": -0.35},
        metrics=["stiffness_min", "f1_min"],
        requirement="cylinder:D=0.2,H=0.04,z=-0.37",
        settings={"actuator_stiffness": 2e4},
        sampler="grid",
        n=2,
    )
    rows = [evaluate_design(s, i, x) for i, x in enumerate(s.designs())]
    assert all(r.feasible for r in rows)
    (k_short, f_short), (k_long, f_long) = (r.values[:2] for r in rows)  # (then contains)
    assert k_short > k_long and f_short > f_long  # longer arms: softer, slower
    # the metric is the worst of the required poses, as the general path finds it
    robot = pkdyn.load("delta", la=0.18, z_home=-0.35)
    from pkdyn.design.context import Conditions, DesignContext

    ctx = DesignContext(robot, Conditions(requirement=s.requirement))
    chk = ctx.required()
    P = chk.P[chk.reached]
    k = [stiffness(robot, pkdyn.inverse_geometry(robot, p).q, 2e4).translational_min for p in P]
    assert min(k) == pytest.approx(k_short, rel=1e-9)
    with pytest.raises(InvalidInputError, match="actuator_stiffness"):
        Study(family="delta", ranges={"la": (0.18, 0.26)}, metrics=["stiffness_min"],
              settings={"actuator_stiffness": -1.0})  # fmt: skip


def test_cli_stiffness_and_modes(capsys, tmp_path):
    base = ["delta", "--pose", "0.02", "0", "-0.36", "--actuator-stiffness", "2e4"]
    assert main(["stiffness", *base, "--wrench", "0", "0", "-50", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    robot = pkdyn.load("delta")
    q = pkdyn.inverse_geometry(robot, [0.02, 0.0, -0.36]).q
    S = stiffness(robot, q, 2e4, wrench=[0, 0, -50])
    assert np.allclose(out["K"], S.K) and np.allclose(out["compliance"], S.compliance)
    assert np.allclose(out["deflection"], S.deflection)
    assert out["principal"]["translation"]["stiffness"] == pytest.approx(
        list(S.translation.stiffness)
    )
    html = tmp_path / "mode.html"
    assert main(["modes", *base, "--top", "2", "--json", "--html", str(html)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["frequencies"] == pytest.approx(list(modes(robot, q, 2e4).frequencies[:2]))
    assert out["internal_mobilities"] == 6 and html.stat().st_size > 1e5
    for argv, words in (
        (["stiffness", *base[:-1], "-5"], "-5 for actuator 'motor1'"),
        (["stiffness", *base, "--wrench", "1", "2"], "wrench: 2 values"),
        (["stiffness", *base[:5]], "no stiffness described"),
        (["modes", *base, "--material", "cheese"], "unknown material 'cheese'"),
        (["modes", *base, "--mode", "9", "--html", str(html)], "9 is not a mode number"),
    ):
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert err.startswith("pkdyn: error: ") and words in err and err.count("\n") == 1


@pytest.mark.parametrize(
    "element, words",
    [
        ('<pkdyn:compliance link="nowhere" rigid="true"/>', "no link of that name"),
        ('<pkdyn:compliance link="arm1" compliance="1 2 3"/>', "expected 6 values > 0"),
        ('<pkdyn:compliance link="arm1" rigid="maybe"/>', "expected true or false"),
        ('<pkdyn:compliance link="arm1" rigid="true" material="steel"/>', "give one of"),
        ('<pkdyn:compliance link="arm1" inner_radius="-1"/>', "must be a finite number >= 0"),
        ('<pkdyn:material name="steel"/><pkdyn:material name="carbon"/>', "given 2 times"),
        ('<pkdyn:material E="1e9"/>', "missing attribute 'name'"),
    ],
)
def test_description_elements_are_checked(element, words, tmp_path):
    xml = pkdyn.library.delta.build_urdf(pkdyn.library.delta.Params())
    path = tmp_path / "delta.urdf"
    path.write_text(xml.replace("</robot>", element + "</robot>"))
    with pytest.raises(DescriptionError, match=words):
        pkdyn.load(str(path))


def test_transmission_stiffness_is_checked(tmp_path):
    xml = pkdyn.library.delta.build_urdf(pkdyn.library.delta.Params())
    path = tmp_path / "delta.urdf"
    for value, words in (("-2", "must be a finite stiffness > 0"), ("nan", "NaN")):
        path.write_text(xml.replace("<mechanicalReduction>", f'<pkdyn:stiffness value="{value}"/>'
                                    "<mechanicalReduction>", 1))  # fmt: skip
        with pytest.raises(DescriptionError, match=words):
            pkdyn.load(str(path))
    # a described material and a bore: the beams of the description
    path.write_text(xml.replace("</robot>", '<pkdyn:material name="carbon"/><pkdyn:compliance '
                                'link="bar1a" inner_radius="0.004"/></robot>'))  # fmt: skip
    robot = pkdyn.load(str(path))
    from pkdyn.precision import link_compliances

    links = {lc.link: lc for lc in link_compliances(robot)}
    assert len(links) == 9 and links["bar1a"].section.inner_radius == 0.004
    assert links["bar1a"].compliance[2] > links["bar1b"].compliance[2]  # a tube is softer
