"""Self-calibration from extra sensors: encoders on passive joints (issue 27 item 1, "implicit
(extra sensors or a constrained platform)").

Truth: the library five-bar's description edited within +-2 mm, +-0.5 deg in its plane; the
measurements are the truth's passive elbow angles (``q_distal1``, ``q_distal2``) at actuator
readings, plus 10 urad noise: no external measurement of the platform. The calibration must fit
the elbow angles to the noise on held-out poses, recover the identifiable combinations within
their standard deviations, and report what joint angles cannot tell (the scale of the
mechanism, where it stands in the world: angles are blind to both).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from support.urdf_edit import family_xml, load_like, where_of, with_twists

import pkdyn
from pkdyn.calibration import Measurements, calibrate, read_csv, write_csv
from pkdyn.cli import main
from pkdyn.exceptions import InvalidInputError
from pkdyn.precision.parameters import placement_parameters

SIGMA = 1e-5  # [rad]
IN_PLANE = (".tx", ".ty", ".rz", ".offset")
JOINTS = ("distal1", "distal2")


@pytest.fixture(scope="module")
def case():
    robot = pkdyn.load("five_bar", geometry=False)
    pm = placement_parameters(robot)
    rng = np.random.default_rng(3)
    p_true = rng.uniform(-1, 1, pm.size) * pm.tolerances(2e-3, np.deg2rad(0.5), 0.0)
    p_true = np.where([n.endswith(IN_PLANE) for n in pm.names], p_true, 0.0)
    xi = pm.twists(p_true)
    twists = {where_of(pl): x for pl, x in zip(pm.placements, xi, strict=True) if np.any(x)}
    truth = load_like(with_twists(family_xml(robot), twists), robot)
    home = robot.q_home[robot.actuated_q]
    qa = []
    while len(qa) < 60:
        a = home + 0.4 * rng.uniform(-1, 1, 2)
        try:
            pkdyn.forward_geometry(robot, a)
        except pkdyn.PkdynError:
            continue
        qa.append(a)
    qa = np.array(qa)
    iq = [robot.model.joints[robot.model.getJointId(j)].idx_q for j in JOINTS]
    Q = np.array(
        [
            pkdyn.forward_geometry(truth, a, q_init=truth.q_home, check_limits=False).q[iq]
            for a in qa
        ]
    )
    m = Measurements("joints", qa, joints=JOINTS, q=Q + rng.normal(0.0, SIGMA, Q.shape))
    res = calibrate(robot, m, pm, noise=(1e-5, SIGMA), holdout=0.25)
    return robot, pm, p_true, m, res


def test_elbow_encoders_identify_the_five_bar(case):
    robot, pm, p_true, m, res = case
    assert res.before.joint_rms > 100 * SIGMA
    assert res.after.joint_rms < 1.5 * SIGMA
    assert res.validation_after.joint_rms < 1.5 * SIGMA  # poses the calibration never saw
    ident = res.identifiability
    est = ident.identifiable
    exp = p_true[est].copy()
    for j, c in ident.combinations.items():
        if j < pm.size:
            exp += c * p_true[j]
    z = np.abs(res.p[est] - exp) / res.std[est]
    assert z.max() < 4.5, (z.max(), pm.names[est[int(np.argmax(z))]])
    # angles are blind to the scale and to where the robot stands: those are reported
    unid = {pm.names[j] for j in ident.unidentifiable if j < pm.size}
    assert {"proximal1.tx", "proximal1.ty"} & unid
    assert len(unid) >= 4 and np.all(res.p[list(ident.unidentifiable)] == 0.0)


def test_joints_sensitivity_matches_finite_differences(case):
    """The Jacobian rows the encoders see: joint coordinates per parameter at fixed readings."""
    from pkdyn.precision.perturbation import perturbed
    from pkdyn.precision.sensitivity import pose_sensitivity

    robot, pm, *_ = case
    qa = robot.q_home[robot.actuated_q] + 0.2
    q = pkdyn.forward_geometry(robot, qa).q
    V = pose_sensitivity(robot, q, pm).joints
    iv = [robot.model.joints[robot.model.getJointId(j)].idx_v for j in JOINTS]
    eps = 1e-7
    for j in [k for k, n in enumerate(pm.names) if n.endswith(IN_PLANE)]:
        dp = np.zeros(pm.size)
        dp[j] = eps
        P = perturbed(robot, pm, dp)
        q1 = pkdyn.forward_geometry(
            P.robot, P.joint_coordinates(qa), q_init=q, check_limits=False
        ).q
        np.testing.assert_allclose(V[iv, j], (q1 - q)[iv] / eps, atol=2e-5 * np.abs(V).max())


def test_cli_reads_joint_columns(case, tmp_path, capsys):
    robot, pm, p_true, m, res = case
    csv = tmp_path / "elbows.csv"
    write_csv(csv, robot, m)
    assert read_csv(csv, robot).kind == "joints"
    out = tmp_path / "cal.urdf"
    argv = ["calibrate", "five_bar", "--measurements", str(csv), "-o", str(out)]
    assert main([*argv, "--model", "placements", "--noise", "1e-5", "1e-5", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["validation_after"]["joint_rms"] < 1.5 * SIGMA
    assert pkdyn.load(out, geometry=False).actuator_names == robot.actuator_names
    assert main([*argv, "--model", "placements", "--noise", "1e-5", "1e-5"]) == 0
    assert "passive joint error RMS" in capsys.readouterr().out


@pytest.mark.parametrize(
    "column, needle",
    [
        ("q_distal3", "did you mean 'distal2'"),
        ("q_proximal1", "not a passive 1-DoF joint"),
    ],
)
def test_bad_joint_columns_are_named(case, tmp_path, column, needle):
    robot = case[0]
    p = tmp_path / "bad.csv"
    p.write_text(f"qa_motor1,qa_motor2,{column}\n0.1,0.2,0.3\n")
    with pytest.raises(InvalidInputError, match=needle):
        read_csv(p, robot)


def test_joints_measurements_are_checked():
    with pytest.raises(InvalidInputError, match="joint names and their coordinates"):
        Measurements("joints", np.zeros((3, 2)))
    with pytest.raises(InvalidInputError, match="expected 3 rows of 2 values"):
        Measurements("joints", np.zeros((3, 2)), joints=("a", "b"), q=np.zeros((3, 1)))
    with pytest.raises(InvalidInputError, match="q"):
        Measurements("joints", np.zeros((1, 2)), joints=("a",), q=[[np.nan]])
