"""Grids of sizings and of fastest cycles (what ``pkdyn demo`` prints through their tables).

Physics, not the code's own numbers: the speeds of a motion run in cycle time ``T`` scale as
``1 / T`` whatever the payload (the speed margins say so exactly), efforts grow with the payload;
the fastest cycle is slower with a heavier payload and with a rotor to accelerate, and every
one of them stays within the torque limit by the independent inverse-dynamics check.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import pkdyn
from pkdyn.dynamics.fastest_grid import FastestGrid, fastest_grid
from pkdyn.dynamics.sizing_grid import MAX_CELLS, SizingGrid, sizing_grid
from pkdyn.dynamics.trajectory import named_task
from pkdyn.exceptions import InvalidInputError


@pytest.fixture(scope="module")
def delta():
    return pkdyn.load("delta", geometry=False)


@pytest.fixture(scope="module")
def grid(delta):
    return sizing_grid(delta, (0.4, 0.5, 0.8), (0.0, 1.0, 2.0), dt=2.5e-3)


def test_speeds_scale_with_the_cycle_time_and_efforts_with_the_payload(delta, grid):
    assert isinstance(grid, SizingGrid)
    limit = delta.actuators[0].velocity
    peak_speed = (1.0 - grid.speed_margin) * limit  # (the fastest actuator of each cell)
    T = np.asarray(grid.cycle_times)[:, None]
    # the same motion in time T: speeds ~ 1 / T (to the sampling of the peak at 2.5 ms), the
    # same for every payload
    np.testing.assert_allclose(peak_speed, peak_speed[:, :1] + 0 * peak_speed, rtol=1e-12)
    np.testing.assert_allclose(peak_speed * T, peak_speed[0, 0] * T[0, 0], rtol=5e-3)
    assert np.all(np.diff(grid.peak, axis=1) > 0.0)  # heavier: larger efforts
    assert np.all(np.diff(grid.peak, axis=0) < 0.0)  # slower: smaller efforts
    # a cell is feasible exactly when both its margins are >= 0
    ok = (grid.margin >= -1e-6) & (grid.speed_margin >= -1e-6)
    np.testing.assert_array_equal(grid.feasible, ok)
    assert not grid.feasible[0].any() and grid.feasible[-1].all()


def test_the_grid_prints_and_serialises_with_units(grid):
    text = grid.table()
    assert "peak effort [N m]" in text and "0.4" in text and "2 kg" in text
    assert text.count("!") == 1 + int((~grid.feasible).sum())  # (the legend's, and each cell's)
    data = json.loads(json.dumps(grid.to_json(), allow_nan=False))
    assert len(data["cells"]) == 9 and data["effort_unit"] == "N m"
    cell = data["cells"][-1]
    assert cell["cycle_time"] == 0.8 and cell["payload"] == 2.0 and cell["feasible"]
    assert cell["peak"] == pytest.approx(grid.peak[-1, -1])


def test_the_grid_draws(grid, tmp_path):
    fig = grid.plot(tmp_path / "grid.png")
    assert (tmp_path / "grid.png").stat().st_size > 0
    assert fig.axes[0].get_xlabel() == "payload [kg]"


@pytest.mark.parametrize(
    ("times", "masses", "culprit"),
    [
        ((0.5, -1.0), (0.0,), "cycle_times"),
        ((0.5,), (float("nan"),), "payloads"),
        ((), (0.0,), "cycle_times"),
        ("0.5", (0.0,), "cycle_times"),
        (tuple(np.linspace(0.3, 1.0, MAX_CELLS)), (0.0, 1.0), "cycle_times"),
    ],
)
def test_bad_grids_are_refused_naming_the_input(delta, times, masses, culprit):
    with pytest.raises(InvalidInputError, match=culprit):
        sizing_grid(delta, times, masses)


@pytest.fixture(scope="module")
def fastest(delta):
    path = named_task(delta, "adept", cycle_time=1.0, dt=1.0 / 125)
    return fastest_grid(delta, path, (0.0, 2.0), (0.0, 5e-5, None))


def test_heavier_payloads_and_rotors_make_the_fastest_cycle_slower(delta, fastest):
    assert isinstance(fastest, FastestGrid)
    T = fastest.cycle_time
    assert np.all(T[1] > T[0])  # a payload costs time
    assert np.all(T[:, 1] > T[:, 0])  # so does a rotor to accelerate
    # the robot's own drives are lossless and without rotor: the 0 kg m^2 column
    np.testing.assert_allclose(T[:, 2], T[:, 0], rtol=1e-9)
    assert np.all(fastest.rotor_peak[:, 0] == 0.0) and np.all(fastest.rotor_peak[:, 1] > 0.0)
    assert fastest.torque_utilisation <= 1.0 + 1e-6  # the independent check
    text = fastest.table()
    assert "cycle [s]" in text and "rms [N m]" in text and "'drives'" in text
    json.dumps(fastest.to_json(), allow_nan=False)


def test_bad_fastest_grids_are_refused(delta):
    path = named_task(delta, "adept", cycle_time=1.0, dt=1.0 / 125)
    with pytest.raises(InvalidInputError, match="path"):
        fastest_grid(delta, "adept", (0.0,))  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="rotor_inertias"):
        fastest_grid(delta, path, (0.0,), (-1.0,))
    with pytest.raises(InvalidInputError, match="rotor_inertias"):
        fastest_grid(delta, path, (0.0,), 5e-5)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="payloads"):
        fastest_grid(delta, path, ())
