"""Merlet's orientation workspace (seed 002, chapters 2-3): arcs, closed-form ends, MEL study."""

import json
import math

import numpy as np
import pytest

import pkdyn
from pkdyn.workspace.legs import HexapodEvaluator, HexapodLegs
from pkdyn.workspace.limits import REACHABLE
from pkdyn.workspace.orientation import (
    mel_study,
    orientation_workspace,
    rotations,
    stroke_roots,
)


@pytest.fixture(scope="module")
def gs():
    return pkdyn.load("gough_stewart")


@pytest.fixture(scope="module")
def study(gs):
    return mel_study(gs, n1=36, n2=180, progress=False)


def test_stroke_arc_ends_are_merlets_closed_form_roots(gs):
    """Refined arc ends (bisection on samples) vs the roots of a1 sin + a2 cos + a3 (eq. 2.4)."""
    ow = orientation_workspace(gs, limits=("stroke",), n1=72, n2=180, progress=False)
    legs = HexapodLegs.from_robot(gs)
    checked = 0
    for t1, arcs in zip(ow.theta1, ow.arcs, strict=True):
        roots = stroke_roots(legs, ow.center, ow.X1, ow.X2, ow.R0, float(t1))
        for s, e in arcs:
            if e - s >= 2 * math.pi - 1e-9:
                continue
            for end in (s % (2 * math.pi), e % (2 * math.pi)):
                gap = np.abs((roots - end + math.pi) % (2 * math.pi) - math.pi)
                assert gap.min() < 1e-8, (t1, end)
                checked += 1
    assert checked > 20


def _dense_mismatch(gs, ow):
    ev = HexapodEvaluator(gs)
    t2 = np.linspace(0, 2 * math.pi, 3600, endpoint=False) + 1e-4
    bad = 0
    for t1, arcs in zip(ow.theta1, ow.arcs, strict=True):
        R = rotations(ow.X1, ow.X2, ow.R0, np.full(t2.size, t1), t2)
        ok = ev.violations(np.tile(ow.center, (t2.size, 1)), R, ow.kinds, 0.0) == REACHABLE
        inside = np.zeros(t2.size, dtype=bool)
        for s, e in arcs:
            inside |= ((t2 - s) % (2 * math.pi)) <= (e - s)
        bad += int(np.count_nonzero(inside != ok))
    return bad, len(ow.theta1) * t2.size


def test_stroke_and_joint_arcs_exact_even_with_coarse_sampling(gs):
    """Cut at Merlet's critical points, 24 samples per circle miss no stroke or joint arc."""
    ow = orientation_workspace(gs, limits=("stroke", "joint"), n1=16, n2=24, progress=False)
    assert _dense_mismatch(gs, ow) == (0, 16 * 3600)


def test_interference_arcs_match_dense_sampling(gs):
    """Interference ends are sampled then bisected: only arcs shorter than a step can be lost."""
    ow = orientation_workspace(gs, n1=16, n2=360, progress=False)
    bad, total = _dense_mismatch(gs, ow)
    assert bad < 1e-3 * total


def test_no_limits_cover_the_sphere(gs):
    ow = orientation_workspace(gs, limits=(), n1=90, n2=16, progress=False)
    assert ow.full_circles().all()
    assert ow.solid_angle() == pytest.approx(4 * math.pi, rel=1e-3)
    # theta1 in [0, pi) alone sweeps the sphere once
    assert ow.solid_angle(0) == pytest.approx(4 * math.pi, rel=1e-3)


def test_mel_study_limits_are_nested(study):
    cases = list(study.values())
    for a, b in zip(cases, cases[1:], strict=False):
        assert not np.any((b.codes == REACHABLE) & (a.codes != REACHABLE))
        assert b.solid_angle() < a.solid_angle()
    # strokes alone leave whole circles; the square holes and the 8 mm legs cut every one
    assert cases[0].full_circles().any()
    assert not cases[1].full_circles().any() and not cases[2].full_circles().any()
    assert cases[2].limits_hit["interference"] > 0


def test_merlet_fig_2_13_interference_cuts_every_circle(gs):
    """Section 2.5: for -y_r about x in [pi/2, 3pi/2] then z, strokes alone allow full turns
    about the vertical; with leg interference every circle is cut."""
    kw = dict(N=(0.0, -1.0, 0.0), n1=36, n2=180, progress=False)
    free = orientation_workspace(gs, limits=("stroke",), **kw)
    cut = orientation_workspace(gs, limits=("stroke", "interference"), **kw)
    sel = (free.theta1 >= math.pi / 2) & (free.theta1 <= 3 * math.pi / 2)
    assert free.full_circles()[sel].sum() > sel.sum() // 3
    assert not cut.full_circles()[sel].any()


def test_as_json_and_errors(gs, study):
    out = study["stroke+joint"].to_json()
    assert set(out) >= {"volume", "bounds", "samples", "limits_hit"}
    assert out["volume_unit"] == "sr" and out["samples"] == 36 * 180
    with pytest.raises(pkdyn.PkdynError, match="leg robot"):
        orientation_workspace(pkdyn.load("delta", geometry=False), progress=False)
    with pytest.raises(pkdyn.PkdynError, match="N"):
        orientation_workspace(gs, N=(0, 0, 0), progress=False)


def test_cli_mel_json_and_plot(capsys, tmp_path):
    from pkdyn.cli import main

    png = tmp_path / "mel.png"
    argv = ["workspace", "gough_stewart", "--kind", "orientation", "--mel", "--n1", "12"]
    code = main([*argv, "--n2", "90", "--json", "--plot", str(png)])
    out, _ = capsys.readouterr()
    assert code == 0
    res = json.loads(out)
    assert set(res) >= {"volume", "bounds", "samples", "limits_hit", "cases"}
    assert list(res["cases"]) == ["stroke", "stroke+joint", "stroke+joint+interference"]
    assert png.stat().st_size > 10_000
