"""Precision results on the result protocol, one map convention, the mode animation (issues 34
item 4, 35 item 5).

- every result type: ``to_json()`` is JSON (no NaN or Infinity), ``table()`` has units, and
  ``plot()`` draws where a picture helps (maps with axes and units, modes, Monte Carlo, ranking);
- ``precision_map`` and ``accuracy_map`` take the same arguments and index values ``[i_u, i_v]``:
  a cell of each is recomputed at its position on the single-pose path; the old spellings warn;
- ``stiffness --map``, ``modes --map`` and ``accuracy --map`` with ``--plot`` and ``--csv``;
- the mode animation keeps the compliant bars on the nacelle.
"""

import csv
import json

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.precision import accuracy_budget, elastic_model, modes, stiffness
from pkdyn.precision.accuracy_maps import accuracy_map, slice_grid
from pkdyn.precision.budgets import actuator_errors
from pkdyn.precision.maps import precision_map
from pkdyn.precision.parameters import family_shortcuts
from pkdyn.results import Result


@pytest.fixture(scope="module")
def delta():
    return pkdyn.load("delta")


def _json(result):
    payload = result.to_json()
    json.dumps(payload, allow_nan=False)
    return payload


def test_every_result_speaks_the_protocol(delta, tmp_path):
    q = pkdyn.inverse_geometry(delta, [0.03, 0.0, -0.36]).q
    model = family_shortcuts(delta)
    S = stiffness(delta, q, 2e4, wrench=[0, 0, -50])
    M = modes(delta, q, 2e4)
    acc = accuracy_budget(delta, q, model, 1e-4, None, None, samples=8, top=3)
    results = [S, M, acc, acc.actuators, acc.geometric, acc.geometric.ranked(3), acc.monte_carlo]
    for r in results:
        assert isinstance(r, Result)
        payload = _json(r)
        text = r.table()
        assert text and "nan" not in text.lower()
        assert (
            "valid" in payload
            or isinstance(r, type(acc.geometric.ranked(3)))
            or (r is acc.monte_carlo)
        )
    assert " kN/m" in S.table() and " um" in S.table() and " Hz" in M.table()
    assert "assumed (not given): actuator backlash 0" in acc.table()
    assert "+-50 um on lengths, +-0.5 mrad on angles" in acc.table()
    for r, name in ((M, "modes"), (acc.monte_carlo, "mc"), (acc.geometric.ranked(3), "rank")):
        path = tmp_path / f"{name}.png"
        r.plot(path)
        assert path.stat().st_size > 1000


def _cell(m, field):
    """Indices and position of the worst evaluated cell."""
    x = np.asarray(m.values[field])
    k = np.nanargmin(x) if m.worst[field] == "min" else np.nanargmax(x)
    i, j = np.unravel_index(int(k), x.shape)
    return i, j, float(x[i, j])


def test_one_map_convention(delta, tmp_path):
    common = dict(center=[0.0, 0.0, -0.36], extent=0.12, samples=5)
    pm = precision_map(delta, "xz", **common, actuator_stiffness=2e4, frequency=True)
    am = accuracy_map(delta, "xz", **common, resolution=1e-4)
    for m in (pm, am):
        assert m.values[next(iter(m.values))].shape == (m.u.size, m.v.size) == (5, 5)
        assert m.axes == ("x", "z") and m.fixed["y"] == pytest.approx(0.0)
    i, j, f1 = _cell(pm, "f1")
    q = pkdyn.inverse_geometry(delta, [pm.u[i], 0.0, pm.v[j]]).q
    assert modes(delta, q, 2e4).f1 == pytest.approx(f1, rel=1e-9)
    i, j, worst = _cell(am, "actuator_worst")
    q = pkdyn.inverse_geometry(delta, [am.u[i], 0.0, am.v[j]]).q
    assert actuator_errors(delta, q, 1e-4).position_worst == pytest.approx(worst, rel=1e-9)
    # the old spellings, for one release
    with pytest.warns(DeprecationWarning, match="center="):
        old = precision_map(delta, "xz", value=0.0, samples=5, bounds=(-0.12, 0.12, -0.48, -0.24),
                            actuator_stiffness=2e4)  # fmt: skip
    np.testing.assert_allclose(old.values["stiffness_min"], pm.values["stiffness_min"])
    P, shape = slice_grid([0.0, 0.0, -0.36], "xz", 0.12, 5)
    with pytest.warns(DeprecationWarning, match="plane="):
        old = accuracy_map(delta, P, 1e-4, shape=shape, axes=("x", "z"))
    new = am.values["actuator_worst"]  # (the new call also holds the passive joints' limits)
    both = np.isfinite(new)
    assert both.sum() >= 15 and np.all(np.isfinite(old.field("actuator_worst"))[both])
    np.testing.assert_allclose(old.field("actuator_worst")[both], new[both], rtol=1e-12)
    # a picture with axes and units, and the cells as CSV
    fig = pm.plot(tmp_path / "f1.png", field="f1")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x [m]" and ax.get_ylabel() == "z [m]"
    assert "[Hz]" in fig.axes[1].get_ylabel()
    am.write_csv(tmp_path / "cells.csv")
    rows = list(csv.DictReader((tmp_path / "cells.csv").open()))
    assert len(rows) == 25 and set(rows[0]) >= {"x_m", "z_m", "status", "actuator_worst_m"}


@pytest.mark.parametrize(
    "argv, field",
    [
        (["stiffness", "delta", "--actuator-stiffness", "2e4", "--wrench", "0", "0", "-50"],
         "deflection"),
        (["modes", "delta", "--actuator-stiffness", "2e4"], "f1"),
        (["accuracy", "delta", "--resolution", "1e-4"], "actuator_rms"),
    ],
)  # fmt: skip
def test_map_commands(argv, field, tmp_path, capsys):
    opts = ["--map", "xz", "--center", "0", "0", "-0.36", "--extent", "0.1", "--grid", "4"]
    png, cells = tmp_path / "map.png", tmp_path / "map.csv"
    out = [*opts, "--plot", str(png), "--csv", str(cells), "--field", field]
    assert main([*argv, *out]) == 0
    text = capsys.readouterr().out
    assert "cells evaluated" in text and png.stat().st_size > 1000 and cells.stat().st_size > 100
    assert main([*argv, *opts, "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["plane"] == "xz" and payload["indexing"] == "values[i_u][i_v]"
    assert main([*argv[:2], "--qa", "0", "0", "0", "--plot", str(png)]) == 1
    assert "give --map" in capsys.readouterr().err


def test_mode_animation_keeps_the_bars_on_the_nacelle(delta):
    from pkdyn.precision.modes import mode_trajectory
    from pkdyn.viewer.modes import display_robot

    em = elastic_model(delta, 2e4, "carbon")
    result = modes(em, delta.q_home)
    shown = display_robot(em)
    _, Q = mode_trajectory(em, result, 0, amplitude=0.05 * delta.length_scale, cycles=1)
    model, data = shown.model, shown.model.createData()
    geo = shown.visual_model
    ends = [g for g in geo.geometryObjects if g.name.startswith("bar1a")]
    ends = [g for g in ends if g.name.endswith("/tip")]
    assert ends, [g.name for g in geo.geometryObjects][:20]
    cm = next(c for c in shown.constraint_models if c.name.startswith("loop1a"))
    worst = 0.0
    for q in Q:
        pin.forwardKinematics(model, data, q)
        nacelle = (data.oMi[cm.joint2_id] * cm.joint2_placement).translation
        tips = []
        for g in ends:
            M = data.oMi[g.parentJoint] * g.placement
            h = g.geometry.halfLength
            tips += [M.act(np.array([0.0, 0.0, s * h])) for s in (-1.0, 1.0)]
        worst = max(worst, min(np.linalg.norm(t - nacelle) for t in tips))
    assert worst < 1e-3 * delta.length_scale  # the bar's end stays at its ball joint
