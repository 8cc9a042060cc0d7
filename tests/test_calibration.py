"""Geometric calibration against an independent truth (issue 27, items 1, 3, 6).

Each truth robot is the nominal description with its numbers edited as text (dimensions within
+-2 mm, angles within +-0.5 deg) and loaded by :func:`pkdyn.load_string`; its forward geometry
at actuator readings inside the workspace, plus Gaussian noise, is the measurement. Calibration
must recover the identifiable errors within their standard deviations, predict held-out poses to
the noise level, and report (not invent) what it cannot identify.
"""

import json

import numpy as np
import pytest
from support.calibration_truth import draw as _draw
from support.calibration_truth import measure as _measure
from support.calibration_truth import readings as _readings
from support.calibration_truth import truth_of as _truth
from support.urdf_edit import family_xml

import pkdyn
from pkdyn.calibration import Measurements, calibrate, identifiability, observability, write_csv
from pkdyn.calibration.planner import plan_calibration
from pkdyn.calibration.selection import candidate_poses, design_matrix, select_poses
from pkdyn.cli import main
from pkdyn.exceptions import InvalidInputError
from pkdyn.precision.parameters import family_shortcuts, placement_parameters
from solvers import numerics


def _expected(res, p_true):
    """What the identifiable parameters estimate: their truth plus the unidentifiable ones'."""
    ident = res.identifiability
    n = res.model.size
    exp = p_true[ident.identifiable].copy()
    for j, c in ident.combinations.items():
        if j < n:
            exp += c * p_true[j]
    return exp


def _check_recovered(res, p_true, k=4.5):
    est = res.identifiability.identifiable
    err = res.p[est] - _expected(res, p_true)
    std = res.std[est]
    assert np.all(np.isfinite(std)) and np.all(std > 0)
    ratio = np.abs(err) / std
    assert ratio.max() < k, (ratio.max(), res.model.names[est[int(np.argmax(ratio))]])
    not_est = np.setdiff1d(np.arange(res.model.size), est)
    assert np.all(res.p[not_est] == 0.0) and np.all(np.isnan(res.std[not_est]))


# ---------------------------------------------------------------------------------- Delta


@pytest.fixture(scope="module")
def delta_case():
    robot = pkdyn.load("delta", geometry=False)
    rng = np.random.default_rng(7)
    model = family_shortcuts(robot)
    p_true = _draw(model, rng)
    truth, _ = _truth(robot, model, p_true)
    readings = _readings(robot, 50, seed=1)
    m, exact = _measure(truth, readings, "position", 1e-5, rng)
    res = calibrate(robot, m, model, noise=1e-5, holdout=0.2, seed=0)
    return robot, truth, model, p_true, m, exact, res


def test_delta_recovers_the_clavel_errors_and_reports_ra_rb(delta_case):
    robot, truth, model, p_true, m, exact, res = delta_case
    unid = {model.names[j] for j in res.identifiability.unidentifiable}
    # only ra - rb is seen by the nacelle (Clavel's reduced model): one of each pair is not
    # identifiable, and it is reported, held at zero
    assert len(unid) == 3 and all({f"ra{i}", f"rb{i}"} & unid for i in (1, 2, 3))
    for j in res.identifiability.unidentifiable:
        coeff = dict(res.identifiability.combination(j))
        partner = (
            model.names[j].replace("ra", "rb")
            if "ra" in model.names[j]
            else model.names[j].replace("rb", "ra")
        )
        assert coeff[partner] == pytest.approx(-1.0, abs=1e-6)
    _check_recovered(res, p_true)
    # held-out poses to the noise level (norm of a 3-D noise of 10 um per axis: 17 um)
    assert res.validation_before.position_rms > 1e-3
    assert res.validation_after.position_rms < 1.5 * np.sqrt(3) * 1e-5
    assert res.scale == pytest.approx(1.0, abs=0.3)
    assert res.converged


def test_delta_calibrated_urdf_reproduces_the_measurements(delta_case, tmp_path):
    robot, truth, model, p_true, m, exact, res = delta_case
    path = tmp_path / "delta_calibrated.urdf"
    res.write_urdf(path)
    loaded = pkdyn.load(path, geometry=False)
    assert loaded.family is None and loaded.nq == robot.nq
    err_truth, err_meas = [], []
    for r, M_true, x in zip(m.qa, exact, m.position, strict=True):
        g = pkdyn.forward_geometry(loaded, loaded.joint_coordinates(r), check_limits=False)
        err_truth.append(np.linalg.norm(g.placement.translation - M_true.translation))
        err_meas.append(np.linalg.norm(g.placement.translation - x))
    assert max(err_truth) < 2e-5  # against the noise-free truth
    assert np.sqrt(np.mean(np.square(err_meas))) < 1.5 * np.sqrt(3) * 1e-5


# --------------------------------------------------------------------------- Gough-Stewart


@pytest.fixture(scope="module")
def hexapod():
    return pkdyn.load("gough_stewart", geometry=False)


def test_gough_stewart_full_pose_gains_and_outliers(hexapod):
    robot = hexapod
    model = family_shortcuts(robot, gains=True)
    rng = np.random.default_rng(11)
    p_true = _draw(model, rng)
    truth, gains = _truth(robot, model, p_true)
    readings = _readings(robot, 45, seed=2, spread=0.05)
    m, _ = _measure(truth, readings, "pose", 1e-5, rng, sigma_rot=2e-5, gains=gains)
    m.position[[3, 17, 29]] += 1e-3  # three gross measurement errors
    res = calibrate(robot, m, model, noise=(1e-5, 2e-5), holdout=0.0)
    assert res.identifiability.rank == 48  # joint centres, leg offsets and gains: full pose
    assert set(res.outliers) == {3, 17, 29}
    _check_recovered(res, p_true)
    idx = res.identifiability.indices
    assert idx["O4"] == pytest.approx(idx["O3"] ** 2 / res.identifiability.singular_values[0])


# ------------------------------------------------------------------------------- five-bar


def test_five_bar_every_placement_in_the_plane():
    robot = pkdyn.load("five_bar", geometry=False)
    model = placement_parameters(robot)
    rng = np.random.default_rng(3)
    p_true = _draw(model, rng, names=(".tx", ".ty", ".rz", ".offset"))  # in the plane
    truth, _ = _truth(robot, model, p_true)
    readings = _readings(robot, 40, seed=4, spread=0.4)
    m, _ = _measure(truth, readings, "position", 1e-5, rng)
    res = calibrate(robot, m, model, noise=1e-5)
    # out-of-plane errors cannot be absorbed by the planar loop: reported, not estimated
    assert "distal2.rx" in res.not_assembling and "proximal1.tx" not in res.not_assembling
    assert res.identifiability.rank < model.size - len(res.not_assembling)
    _check_recovered(res, p_true)
    assert res.validation_after.position_rms < 1.5 * np.sqrt(2) * 1e-5 * 1.3


# --------------------------------------------------------------------------------- tripod


def test_tripod_pp_mode_offsets_and_footholds():
    robot = pkdyn.load("tripod", geometry=False)  # mode PP: feet welded, platform = spindle
    model = placement_parameters(robot)
    rng = np.random.default_rng(5)
    footholds = tuple(
        f"branch{i}_foothold/2.{c}" for i in (1, 2, 3) for c in ("tx", "ty", "tz", "rx", "ry", "rz")
    )
    p_true = _draw(model, rng, names=(".offset", *footholds))
    truth, _ = _truth(robot, model, p_true)
    readings = _readings(robot, 40, seed=6, spread=0.04)
    m, _ = _measure(truth, readings, "pose", 1e-5, rng, sigma_rot=1e-5)
    res = calibrate(robot, m, model, noise=1e-5)
    assert res.identifiability.rank < model.size
    _check_recovered(res, p_true)
    assert res.validation_after.position_rms < 2.0 * np.sqrt(3) * 1e-5
    assert res.validation_before.position_rms > 20 * res.validation_after.position_rms


# ------------------------------------------------------------------------ self-calibration


def test_delta_touching_three_unknown_planes(delta_case):
    """Implicit measurements: only the readings where the nacelle touches a plane are known."""
    robot, truth, model, p_true, *_ = delta_case
    rng = np.random.default_rng(9)
    normals = [np.array([0.0, 0.0, 1.0]), np.array([0.3, 0.0, 1.0]), np.array([0.0, -0.25, 1.0])]
    readings, groups = [], []
    for g, n in enumerate(normals):
        n = n / np.linalg.norm(n)
        c = np.array([0.0, 0.0, -0.33 - 0.02 * g])
        t1 = np.cross(n, [1.0, 0, 0])
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(n, t1)
        for _ in range(13):
            P = c + rng.uniform(-0.1, 0.1) * t1 + rng.uniform(-0.1, 0.1) * t2
            q = pkdyn.inverse_geometry(truth, P, q_init=truth.q_home).q
            readings.append(q[truth.actuated_q] + rng.normal(0.0, 2e-5, 3))
            groups.append(g)
    m = Measurements("plane", np.array(readings), group=np.array(groups))
    res = calibrate(robot, m, model, noise=2e-5 * 0.3)
    unit = [n / np.linalg.norm(n) for n in normals]
    found = [np.sign(f[2]) * f[:3] for f in res.nuisance["planes"]]
    for i, j in ((0, 1), (0, 2), (1, 2)):  # the angles between the planes (their common tilt
        # trades against the arm heights: see below)
        angle = np.arccos(np.clip(unit[i] @ unit[j], -1, 1))
        assert np.arccos(np.clip(found[i] @ found[j], -1, 1)) == pytest.approx(angle, abs=5e-3)
    assert res.validation_before.position_rms > 10 * res.validation_after.position_rms
    names = [res.identifiability.names[j] for j in res.identifiability.unidentifiable]
    assert "ra1" in names or "rb1" in names  # still not identifiable, and said so
    # planes do not see a height shared by the arms, nor a turn about the vertical
    assert any(n.startswith("z") for n in names) and any(n.startswith("theta") for n in names)


# ---------------------------------------------------------------------- identifiability


def test_pivoted_qr_and_combinations_on_a_known_matrix():
    import scipy.linalg

    rng = np.random.default_rng(0)
    W = rng.normal(size=(40, 6))
    W[:, 4] = 2.0 * W[:, 1] - 0.5 * W[:, 3]  # a known dependent column
    W[:, 5] = 0.0  # a parameter nothing measures
    qr = numerics.column_qr(W[:, :5], rtol=0.0)
    _, R2, piv2 = scipy.linalg.qr(W[:, :5], mode="economic", pivoting=True)
    np.testing.assert_allclose(np.abs(np.diag(qr.R)), np.abs(np.diag(R2)), rtol=1e-10, atol=1e-12)
    assert numerics.column_qr(W[:, :5]).rank == 4  # the rule: the fifth is a combination
    ident = identifiability(W, list("abcdef"), poses=10)
    assert ident.rank == 4
    assert set(ident.unidentifiable) >= {5}
    j = int(ident.unidentifiable[0])
    combo = dict(ident.combination(j))
    if j == 4:
        assert combo == pytest.approx({"b": 2.0, "d": -0.5})
    assert ident.combination(5) == []
    s = np.linalg.svd(W[:, ident.identifiable], compute_uv=False)
    idx = observability(s, 10)
    assert idx["O1"] == pytest.approx(np.prod(s) ** (1 / 4) / np.sqrt(10))
    assert idx["O2"] == pytest.approx(s[-1] / s[0]) and idx["O3"] == pytest.approx(s[-1])
    assert idx["O4"] == pytest.approx(s[-1] ** 2 / s[0])
    assert idx["O5"] == pytest.approx(1 / np.sum(1 / s))
    assert ident.indices == pytest.approx(idx)


def test_selected_poses_observe_better_than_random_ones(delta_case):
    robot, *_ = delta_case
    model = family_shortcuts(robot)
    qs = candidate_poses(robot, 40, seed=4)
    blocks = design_matrix(robot, qs, model)
    sel = select_poses(blocks, 12)
    rng = np.random.default_rng(0)
    cols = sel.identifiable
    for _ in range(10):
        pick = rng.choice(len(qs), 12, replace=False)
        s = np.linalg.svd(blocks[pick][:, :, cols].reshape(-1, cols.size), compute_uv=False)
        assert observability(s, 12)["O1"] < sel.values["O1"]


def test_planner_says_what_reaches_a_target():
    robot = pkdyn.load("five_bar", geometry=False)
    plan = plan_calibration(
        robot,
        2e-5,
        "placements",
        poses=(12, 30),
        noise=(1e-6, 1e-4),
        trials=2,
        candidates=60,
        validation=20,
    )
    assert plan.before > 1e-3
    assert np.all(plan.rms[:, 0] < plan.rms[:, 1])  # less noise, more accurate
    assert plan.rms[1, 1] < plan.rms[0, 1]  # more poses, more accurate
    rec = plan.recommendation()
    assert rec[1e-6] is not None and rec[1e-4] is None
    assert "1 um" in plan.summary() and "um" in plan.table()
    json.dumps(plan.to_json(), allow_nan=False)
    assert len(plan.plot().axes) == 1


# ---------------------------------------------------------------------- CLI and bad input


def test_cli_calibrate_writes_a_loadable_urdf(delta_case, tmp_path, capsys):
    robot, truth, model, p_true, m, exact, res = delta_case
    csv = tmp_path / "m.csv"
    write_csv(csv, robot, m)
    out = tmp_path / "cal.urdf"
    argv = ["calibrate", "delta", "--measurements", str(csv), "-o", str(out), "--noise", "1e-5"]
    assert main([*argv, "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["validation_after"]["position_rms"] < 1.5 * np.sqrt(3) * 1e-5
    unid = {u["name"] for u in got["unidentifiable"]}
    assert len(unid) == 3 and all({f"ra{i}", f"rb{i}"} & unid for i in (1, 2, 3))
    loaded = pkdyn.load(out, geometry=False)
    g = pkdyn.forward_geometry(loaded, m.qa[0], check_limits=False)
    assert np.linalg.norm(g.placement.translation - exact[0].translation) < 2e-5


def _csv(tmp_path, header, rows):
    p = tmp_path / "bad.csv"
    p.write_text(",".join(header) + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n")
    return str(p)


def _one_line_error(capsys, argv, *needles):
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("pkdyn: error:"), err
    for n in needles:
        assert n in err, err


def test_cli_calibrate_bad_input(delta_case, tmp_path, capsys):
    robot, truth, model, p_true, m, exact, res = delta_case
    base = ["qa_motor1", "qa_motor2", "qa_motor3", "x", "y", "z"]
    rows = np.hstack([m.qa, m.position]).tolist()
    out = str(tmp_path / "o.urdf")
    cmd = ["calibrate", "delta", "-o", out, "--measurements"]
    _one_line_error(
        capsys, [*cmd, _csv(tmp_path, base[:5], [r[:5] for r in rows])], "missing column(s) z"
    )
    _one_line_error(
        capsys,
        [*cmd, _csv(tmp_path, [*base, "w"], [[*r, 0] for r in rows])],
        "unexpected column(s) w",
    )
    bad = [list(r) for r in rows]
    bad[4][2] = "nan"
    _one_line_error(capsys, [*cmd, _csv(tmp_path, base, bad)], "line 6", "qa_motor3")
    _one_line_error(
        capsys,
        [*cmd, _csv(tmp_path, base, rows[:5]), "--holdout", "0"],
        "5 calibration poses give 15 measured values",
        "measure at least",
    )
    assert not (tmp_path / "o.urdf").exists()


def test_too_few_poses_and_bad_options(hexapod):
    m = Measurements(
        "pose",
        np.tile(hexapod.q_home[hexapod.actuated_q], (3, 1)),
        np.zeros((3, 3)),
        np.zeros((3, 3)),
    )
    with pytest.raises(InvalidInputError, match="measure at least"):
        calibrate(hexapod, m, "shortcuts", holdout=0.0)
    with pytest.raises(InvalidInputError, match="robust"):
        calibrate(hexapod, m, robust="l1")
    with pytest.raises(InvalidInputError, match="group 1 has 1 calibration"):
        Measurements("point", np.zeros((3, 6)), group=[0, 0, 1]).check_groups()


def test_description_home_and_encoder_gain_elements(tmp_path):
    from pkdyn.exceptions import DescriptionError

    robot = pkdyn.load("five_bar", geometry=False)
    xml = family_xml(robot)
    q = " ".join(repr(float(v)) for v in robot.q_home)
    text = xml.replace("</robot>", f'<pkdyn:home q="{q}"/></robot>').replace(
        "<mechanicalReduction>", '<pkdyn:encoder gain="1.002"/><mechanicalReduction>', 1
    )
    loaded = pkdyn.load_string(text, "x.urdf", geometry=False)
    np.testing.assert_allclose(loaded.q_home, robot.q_home, atol=1e-12)  # the described mode
    assert [a.encoder_gain for a in loaded.actuators] == [1.002, 1.0]
    np.testing.assert_allclose(loaded.joint_coordinates([1.0, 1.0]), [1.002, 1.0])
    bad = text.replace('gain="1.002"', 'gain="-1"')
    with pytest.raises(DescriptionError, match="encoder"):
        pkdyn.load_string(bad, "x.urdf", geometry=False)
    with pytest.raises(DescriptionError, match="home"):
        pkdyn.load_string(text.replace(f'q="{q}"', 'q="a b"'), "x.urdf", geometry=False)


def test_gough_stewart_self_calibration_on_fixed_points(hexapod):
    """Implicit: the platform origin held in a socket (unknown point) while the platform turns."""
    robot = hexapod
    model = family_shortcuts(robot)
    rng = np.random.default_rng(21)
    p_true = _draw(model, rng)
    truth, _ = _truth(robot, model, p_true)
    readings, groups = [], []
    for g, c in enumerate(([0.02, 0.0, 0.59], [-0.03, 0.03, 0.61])):
        q = truth.q_home
        for _ in range(12):
            rpy = rng.uniform(-0.12, 0.12, 3)
            q = pkdyn.inverse_geometry(truth, [*c, *rpy], q_init=q).q
            readings.append(q[truth.actuated_q] + rng.normal(0.0, 5e-6, 6))
            groups.append(g)
    m = Measurements("point", np.array(readings), group=np.array(groups))
    res = calibrate(robot, m, model, noise=5e-6)
    assert res.validation_before.position_rms > 20 * res.validation_after.position_rms
    names = {res.identifiability.names[j] for j in res.identifiability.unidentifiable}
    assert names  # a fixed point does not see the whole geometry: said, not invented
    assert res.after.position_rms < 3e-5
