"""Bounded work: what would run for hours or exhaust the memory is refused up front, with the
estimate, in one line.

Classes: catalogs (entries, motor x gearbox pairs along the trajectory), the fastest cycle's
path, the tripod scenario (cycles, phase durations, lift, tilt), actuation maps on millions of
rows, continuations towards absurdly far targets. (Design studies: ``test_study_files``.)
"""

import time

import numpy as np
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.dynamics.motors import MAX_CATALOG_ENTRIES, load_catalog
from pkdyn.exceptions import CatalogError, InvalidInputError, PkdynError


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("pkdyn: error:") and len(err.strip().splitlines()) == 1, err
    return err


# ---------------------------------------------------------------------- catalogs


def _catalogs(tmp_path, motors: int, gears: int):
    m = tmp_path / "motors.csv"
    m.write_text(
        "name,rated_torque [N m],peak_torque,rated_speed [rpm],max_speed [rpm],"
        "rotor_inertia [kg cm^2],mass\n"
        + "".join(f"M{i},1.3,3.8,3000,6000,0.4,1.5\n" for i in range(motors))
    )
    g = tmp_path / "gears.csv"
    g.write_text(
        "name,ratio,efficiency,rated_torque,peak_torque,max_input_speed [rpm],inertia\n"
        + "".join(f"G{i},10,97 %,20,40,6000,1e-5\n" for i in range(gears))
    )
    return str(m), str(g)


def test_millions_of_pairs_are_refused_before_the_selection(tmp_path):
    from types import SimpleNamespace

    from pkdyn.dynamics.selection import select_drives

    motors, gears = _catalogs(tmp_path, 300, 300)
    catalog = load_catalog(motors) + load_catalog(gears)
    trajectory = SimpleNamespace(t=np.linspace(0.0, 0.5, 501))  # only its length is read first
    t0 = time.monotonic()
    with pytest.raises(InvalidInputError) as err:
        select_drives(pkdyn.load("delta"), trajectory, catalog)
    assert "300 motors x 300 gearboxes on 3 actuators along 501 samples" in str(err.value)
    assert "pair-samples, more than 5e+07" in str(err.value) and time.monotonic() - t0 < 10


def test_too_many_entries(tmp_path):
    motors, _ = _catalogs(tmp_path, MAX_CATALOG_ENTRIES + 1, 1)
    with pytest.raises(CatalogError, match=f"{MAX_CATALOG_ENTRIES + 1} entries, more than"):
        load_catalog(motors)


# ---------------------------------------------------------------------- fastest cycle


@pytest.mark.parametrize(
    "args, match",
    [
        (["--cycle-time", "100", "--dt", "1e-4"], "is 1e+06 samples, more than the 100,000"),
        (["--cycles", "3"], "--cycles: --fastest traverses the path once"),
        (["--dt", "1e-7"], "1e+07 samples"),
        (["--trajectory", "sine", "--cycle-time", "0.001"], "half period"),
    ],
)
def test_fastest_cycle_options(capsys, args, match):
    t0 = time.monotonic()
    assert main(["size", "delta", "--fastest", *args]) == 1
    assert match in _one_line(capsys) and time.monotonic() - t0 < 30


# ---------------------------------------------------------------------- tripod scenario

SAMPLES = "samples (each an inverse geometry and dynamics, ~1 ms); at most 2e+05"


@pytest.mark.parametrize(
    "args, match",
    [
        (["--cycles", "1000000"], "cycles: must be a whole number <= 1000, got 1000000"),
        (["--swing-time", "1e9"], SAMPLES),
        (["--reconfiguration-time", "1e9"], SAMPLES),
        (["--lift", "1e9"], "lift: 1e+09 m is beyond any plausible value (at most 1)"),
        (["--tilt", "1e9"], "tilt: 1e+09 rad is beyond any plausible value (at most 1.5708)"),
        (["--tilt", "nan"], "--tilt: is nan (not a number)"),
    ],
)
def test_tripod_scenario_bounds(capsys, args, match):
    t0 = time.monotonic()
    assert main(["tripod", "scenario", "--no-machining", *args]) == 1
    assert match in _one_line(capsys) and time.monotonic() - t0 < 30


def test_tripod_plan_types():
    from pkdyn.tripod.scenario import WalkPlan

    for bad in (1.5, True, "2", float("inf")):
        with pytest.raises(InvalidInputError, match="cycles"):
            WalkPlan(cycles=bad)


# ---------------------------------------------------------------------- actuation maps


def test_actuation_map_on_millions_of_rows():
    from pkdyn.analysis.actuation_map import MAX_SAMPLES

    ankle = pkdyn.load("parallel_ankle")
    m = pkdyn.actuation_map(ankle, ["ankle_pitch", "ankle_roll"])
    rows = np.zeros((MAX_SAMPLES + 1, 2))
    t0 = time.monotonic()
    with pytest.raises(InvalidInputError, match=f"{MAX_SAMPLES + 1:,} samples, more than"):
        m.from_joints(rows)
    assert time.monotonic() - t0 < 1.0


# ---------------------------------------------------------------------- continuations


@pytest.mark.parametrize("far", [1e6, 1e12, 1e300])
def test_far_targets_do_not_run_away(far):
    delta = pkdyn.load("delta")
    t0 = time.monotonic()
    with pytest.raises(PkdynError):
        pkdyn.inverse_geometry(delta, [far, 0.0, -0.3])
    assert time.monotonic() - t0 < 30
