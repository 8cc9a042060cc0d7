"""Dextrous workspace (Merlet, seed 002, chapter 4): shells and pyramids, containment, witnesses."""

import json

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.workspace.dextrous import dextrous_violations, dextrous_workspace
from pkdyn.workspace.legs import HexapodEvaluator, HexapodLegs
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE, direction_margin, pyramid_normals
from pkdyn.workspace.translation import translation_workspace

# longer strokes and wider holes than the MEL prototype, whose dextrous workspace is tiny
WIDE = dict(rho_min=(0.45,) * 6, rho_max=(0.8,) * 6, pyramid_half_angle=0.6)


@pytest.fixture(scope="module")
def wide():
    return pkdyn.load("gough_stewart", geometry=False, **WIDE)


def _random_rotations(rng, n):
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return [pin.Quaternion(*x).toRotationMatrix() for x in q]


@pytest.mark.parametrize("joint_limits", [False, True])
def test_dextrous_inside_every_orientations_translation_workspace(wide, joint_limits):
    rng = np.random.default_rng(0)
    dw = dextrous_workspace(wide, samples=25, joint_limits=joint_limits, progress=False)
    assert dw.volume > 0
    box = np.array([[a[0], a[-1]] for a in dw.axes])
    limits = ("stroke", "joint") if joint_limits else ("stroke",)
    for R in [np.eye(3), *_random_rotations(rng, 20)]:
        rpy = pin.rpy.matrixToRpy(R)
        ws = translation_workspace(
            wide, rpy=rpy, bounds=box, samples=25, limits=limits, progress=False
        )
        assert not np.any(dw.reachable & ~ws.reachable)


def test_every_rejected_position_has_a_failing_orientation(wide):
    """Tightness: for a position outside a shell, the platform turned so that b_i points along
    (or against) A_i C breaks that leg's stroke."""
    legs = HexapodLegs.from_robot(wide)
    ev = HexapodEvaluator(wide)
    rng = np.random.default_rng(1)
    C = rng.uniform([-0.2, -0.2, 0.45], [0.2, 0.2, 0.65], (300, 3))
    codes = dextrous_violations(legs, C, joint_limits=False)
    rb = np.linalg.norm(legs.B, axis=1)
    stroke = LIMIT_KINDS.index("stroke")
    assert 0 < np.count_nonzero(codes == stroke) < len(C)
    for c, code in zip(C, codes, strict=True):
        d = np.linalg.norm(c - legs.A, axis=1)
        if code == REACHABLE:
            assert np.all((d >= legs.rho_min + rb) & (d <= legs.rho_max - rb))
            continue
        i = int(np.argmax(np.maximum(legs.rho_min + rb - d, d - legs.rho_max + rb)))
        target = (c - legs.A[i]) / d[i] * (1.0 if d[i] > legs.rho_max[i] - rb[i] else -1.0)
        R = pin.Quaternion.FromTwoVectors(legs.B[i] / rb[i], target).toRotationMatrix()
        assert ev.violations(c[None], R, ("reach", "stroke"), 0.0)[0] == stroke


def test_pyramid_faces_match_the_angular_definition(wide):
    legs = HexapodLegs.from_robot(wide)
    lim = legs.limits[0]
    d = np.random.default_rng(2).normal(size=(5000, 3))
    inside = direction_margin(lim, d) >= 0
    np.testing.assert_array_equal(inside, np.all(d @ pyramid_normals(lim).T >= 0, axis=1))


def test_mel_dextrous_workspace_is_tiny():
    """MEL strokes: the shells of legs 1-3 are 5 mm thick; a few cubic centimetres remain,
    none with the base joints' square holes."""
    mel = pkdyn.load("gough_stewart", geometry=False)
    box = [[-0.03, 0.03], [-0.03, 0.03], [0.55, 0.6]]
    dw = dextrous_workspace(mel, bounds=box, step=0.001, progress=False)
    assert 0 < dw.volume < 2e-6 and not dw.touches_box
    assert (
        dextrous_workspace(mel, bounds=box, step=0.001, joint_limits=True, progress=False).volume
        == 0
    )


def test_cli_dextrous_json(capsys):
    from pkdyn.cli import main

    params = [x for k, v in WIDE.items() for x in ("--param", f"{k}={v}")]
    code = main(
        [
            "workspace",
            "gough_stewart",
            *params,
            "--kind",
            "dextrous",
            "--samples",
            "21",
            "--joint-limits",
            "--json",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    res = json.loads(out)
    assert set(res) >= {"volume", "bounds", "samples", "limits_hit"}
    assert res["kind"] == "dextrous" and res["volume"] > 0 and res["limits_hit"]["joint"] > 0


def test_joint_rejections_have_a_failing_orientation(wide):
    """Tightness of the shrunk pyramids: B_i pushed out through the face C is too close to."""
    legs = HexapodLegs.from_robot(wide)
    ev = HexapodEvaluator(wide)
    rng = np.random.default_rng(3)
    C = rng.uniform([-0.25, -0.25, 0.45], [0.25, 0.25, 0.65], (3000, 3))
    codes = dextrous_violations(legs, C, joint_limits=True)
    joint = LIMIT_KINDS.index("joint")
    rb = np.linalg.norm(legs.B, axis=1)
    tested = 0
    for c in C[codes == joint][:40]:
        for i, lim in enumerate(legs.limits):
            normals = legs.sign[i] * (pyramid_normals(lim) @ legs.R0[i].T)  # world, inward
            depth = (c - legs.A[i]) @ normals.T
            f = int(np.argmin(depth))
            if depth[f] >= rb[i]:
                continue
            R = pin.Quaternion.FromTwoVectors(legs.B[i] / rb[i], -normals[f]).toRotationMatrix()
            assert ev.violations(c[None], R, ("reach", "joint"), 0.0)[0] == joint
            tested += 1
            break
    assert tested >= 20
