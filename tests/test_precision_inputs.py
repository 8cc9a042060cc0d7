"""Bad input for the precision features, class by class (issues 26 item 8, 27 item 6, 29, 24).

The commands ``stiffness``, ``modes``, ``accuracy``, ``calibrate``, ``identify`` and their public
Python functions, tried as a careless or hostile user would. Classes: numbers checked before
arithmetic (negative, NaN, infinite, absurd), wrong counts of values, singular poses (one line
saying the stiffness is undefined, never inf or NaN), API types at the public boundary, data
files (missing or extra columns, NaN, text, empty, header only, FIFOs, devices, huge files, too
few poses, an unexciting motion), unbounded work refused up front with the estimate, outputs
checked before the work, and signals (no traceback, exit 130, no output file). Every user error:
a typed pkdyn exception naming the culprit; the CLI prints one line and exits 1.
"""

from __future__ import annotations

import importlib
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.exceptions import InvalidInputError, PkdynError


def _one_line(capsys, argv, code=1):
    assert main(argv) == code, argv
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("pkdyn: error:"), err
    return err


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Measurement and motion files, good and bad, in one directory."""
    d = tmp_path_factory.mktemp("inputs")
    delta = pkdyn.load("delta", geometry=False)
    rng = np.random.default_rng(0)
    home = delta.q_home[delta.actuated_q]
    qa = home + 0.2 * rng.uniform(-1, 1, (30, 3))
    pos = np.array(
        [pkdyn.forward_geometry(delta, r, check_limits=False).placement.translation for r in qa]
    )
    hdr = "qa_motor1,qa_motor2,qa_motor3,x,y,z"
    rows = [",".join(repr(float(v)) for v in (*a, *b)) for a, b in zip(qa, pos, strict=True)]

    def w(name, text):
        (d / name).write_text(text)
        return str(d / name)

    def cal(name, body, header=hdr):
        return w(name, header + "\n" + "\n".join(body) + "\n")

    five = pkdyn.load("five_bar", geometry=False)
    t = np.arange(0, 2, 0.01)
    q5 = five.q_home[five.actuated_q] + 0.2 * np.sin(np.outer(t, [1.3, 2.1]))
    ihdr = "t,qa_motor1,qa_motor2,tau_motor1,tau_motor2"
    irows = [
        ",".join(repr(float(v)) for v in (ti, *q, 0.1, 0.2)) for ti, q in zip(t, q5, strict=True)
    ]

    def ident(name, body, header=ihdr):
        return w(name, header + "\n" + "\n".join(body) + "\n")

    still = [",".join(repr(float(v)) for v in (ti, *q5[0], 0.1, 0.2)) for ti in t]
    big = d / "big.csv"
    with big.open("w") as fh:
        fh.write(hdr + "\n")
        fh.truncate(17_000_000)  # sparse: 17 MB of nothing, instantly
    bigger = d / "bigger.csv"
    with bigger.open("w") as fh:
        fh.write(ihdr + "\n")
        fh.truncate(600_000_000)
    fifo = d / "fifo"
    os.mkfifo(fifo)
    bad = rows[:3]
    return {
        "dir": str(d),
        "fifo": str(fifo),
        "good": cal("good.csv", rows),
        "empty": w("empty.csv", ""),
        "header only": cal("hdr.csv", []),
        "missing z": w("mc.csv", "qa_motor1,qa_motor2,qa_motor3,x,y\n1,2,3,4,5\n"),
        "extra w": cal("ec.csv", [r + ",0" for r in rows], hdr + ",w"),
        "repeated x": cal("dc.csv", [r + ",0" for r in rows], hdr + ",x"),
        "nan": cal("nan.csv", [*bad, "nan,0,0,0,0,0", *rows[3:]]),
        "text": cal("text.csv", [*bad, "abc,0,0,0,0,0", *rows[3:]]),
        "inf": cal("inf.csv", [*bad, "inf,0,0,0,0,0", *rows[3:]]),
        "reading 1e308": cal("r308.csv", [*bad, "1e308,0,0,0,0,0", *rows[3:]]),
        "position 1e308": cal("p308.csv", [*bad, rows[3].rsplit(",", 1)[0] + ",1e308"]),
        "position 1e6": cal("p1e6.csv", [*bad, rows[3].rsplit(",", 1)[0] + ",1e6", *rows[4:]]),
        "ragged": cal("rag.csv", [*bad, "1,2", *rows[3:]]),
        "two poses": cal("few.csv", rows[:2]),
        "binary": w("bin.csv", "\x00\x01\xff"),
        "group 1e300": w(
            "grp.csv",
            "qa_motor1,qa_motor2,qa_motor3,group\n"
            + "\n".join(",".join(repr(float(v)) for v in (*a, 1e300)) for a in qa)
            + "\n",
        ),
        "big": str(big),
        "motion": ident("id.csv", irows),
        "motion header only": ident("ihdr.csv", []),
        "motion missing tau": w("imc.csv", "t,qa_motor1,qa_motor2,tau_motor1\n0,1,2,3\n"),
        "motion repeated t": ident("idc.csv", [r + ",0" for r in irows], ihdr + ",t"),
        "motion text": ident("itext.csv", [*irows[:3], "0.1,abc,0,0,0", *irows[3:]]),
        "motion tau 1e308": ident("i308.csv", [*irows[:3], "0.035,0,0,0,1e308", *irows[4:]]),
        "motion dt 1e-300": ident(
            "itd.csv",
            [
                ",".join(repr(float(v)) for v in (ti * 1e-300, *q, 0.1, 0.2))
                for ti, q in zip(t, q5, strict=True)
            ],
        ),
        "motion backwards": ident("iback.csv", irows[::-1]),
        "motion two rows": ident("itwo.csv", irows[:2]),
        "motion still": ident("istill.csv", still),
        "motion bigger": str(bigger),
    }


# --------------------------------------------------------------------------------------------
# numbers checked before arithmetic, and counts of values (command line)

S = ["stiffness", "delta", "--qa", "0", "0", "0"]
M = ["modes", "delta", "--qa", "0", "0", "0"]
A = ["accuracy", "delta", "--qa", "0", "0", "0"]
K = ["--actuator-stiffness", "1e4"]
NUMBERS = {
    "stiffness negative": ([*S, "--actuator-stiffness", "-1"], "must be > 0"),
    "stiffness nan": ([*S, "--actuator-stiffness", "nan"], "--actuator-stiffness: is nan"),
    "stiffness zero": ([*S, "--actuator-stiffness", "0"], "must be > 0"),
    "stiffness 1e308": ([*S, "--actuator-stiffness", "1e308"], "beyond any plausible"),
    "stiffness undescribed": (S, "no stiffness described for actuator 'motor1'"),
    "material unknown": ([*S, *K, "--material", "unobtanium"], "unknown material"),
    "wrench nan": ([*S, *K, "--wrench", "nan", "0", "0"], "--wrench: value #1 is nan"),
    "wrench inf": ([*S, *K, "--wrench", "inf", "0", "0"], "component 1 is inf"),
    "wrench 1e308": ([*S, *K, "--wrench", "1e308", *"00000"], "beyond any plausible force"),
    "point nan": ([*S, *K, "--point", "nan", "0", "0"], "point: value #1 is nan"),
    "point 1e308": ([*S, *K, "--point", "1e308", "0", "0"], "point: value #1"),
    "qa nan": (["stiffness", "delta", "--qa", "nan", "0", "0", *K], "value #1 is nan"),
    "qa 1e308": (["stiffness", "delta", "--qa", "1e308", "0", "0", *K], "beyond any reachable"),
    "pose 1e308": (["stiffness", "delta", "--pose", "1e308", "0", "-0.8", *K], "out of reach"),
    "loaded without wrench": ([*S, *K, "--loaded"], "needs a wrench"),
    # (at qa = 0.5: qa = 0 is near a serial singularity of the Delta, where the sign of the
    # loaded stiffness's lowest eigenvalue under 1e9 N is decided by the BLAS kernel's rounding)
    "loaded buckles": (
        [*S[:2], "--qa", *["0.5"] * 3, *K, "--loaded", "--wrench", "0", "0", "1e9"],
        "unstable",
    ),
    "modes top 0": ([*M, *K, "--top", "0"], "--top"),
    "modes stiffness 1e308": ([*M, "--actuator-stiffness", "1e308"], "beyond any plausible"),
    "modes mode 99": ([*M, *K, "--mode", "99", "--html", "m.html"], "not a mode number"),
    "resolution negative": ([*A, "--resolution", "-1"], "negative"),
    "resolution nan": ([*A, "--resolution", "nan"], "nan"),
    "resolution 1e308": ([*A, "--resolution", "1e308"], "beyond any plausible"),
    "backlash inf": ([*A, "--backlash", "inf"], "inf"),
    "tolerance nan": ([*A, "--tolerance", "nan"], "nan"),
    "tolerance 1e308": ([*A, "--tolerance", "1e308"], "beyond any plausible"),
    "samples negative": ([*A, "--samples", "-5"], "samples"),
    "top negative": ([*A, "--top", "-1"], "--top"),
    "seed negative": ([*A, "--samples", "3", "--seed", "-1"], "--seed"),
    "grid 0": (["accuracy", "delta", "--map", "xy", "--grid", "0"], "samples"),
    "extent nan": (["accuracy", "delta", "--map", "xy", "--extent", "nan"], "extent"),
    "extent 1e308": (["accuracy", "delta", "--map", "xy", "--extent", "1e308"], "extent"),
    "center nan": (["accuracy", "delta", "--map", "xy", "--center", "nan", "0", "0"], "center"),
}
COUNTS = {
    "stiffness 2 for 3": ([*S, "--actuator-stiffness", "1", "2"], "2 values for 3 actuators"),
    "stiffness 4 for 3": ([*S, "--actuator-stiffness", *"1234"], "4 values for 3 actuators"),
    "wrench of 5": ([*S, *K, "--wrench", *"12345"], "5 values"),
    "qa of 2": (["stiffness", "delta", "--qa", "0", "0", *K], "expected 3 values, got 2"),
    "pose of 2": (["stiffness", "delta", "--pose", "0", "0", *K], "3 or 6 values"),
    "resolution 2 for 3": ([*A, "--resolution", "1", "2"], "expected 3 values"),
    "backlash 4 for 3": ([*A, "--backlash", *"1234"], "expected 3 values"),
    "tolerance of 4": ([*A, "--tolerance", *"1111"], "LENGTH [ANGLE [GAIN]]"),
    "readings of 2": (["fk", "delta", "--readings", "0", "0"], "expected 3 values"),
}


@pytest.mark.parametrize("argv, needle", NUMBERS.values(), ids=list(NUMBERS))
def test_numbers_are_checked_before_arithmetic(capsys, tmp_path, monkeypatch, argv, needle):
    monkeypatch.chdir(tmp_path)
    assert needle in _one_line(capsys, argv)


@pytest.mark.parametrize("argv, needle", COUNTS.values(), ids=list(COUNTS))
def test_wrong_counts_of_values_are_named(capsys, argv, needle):
    assert needle in _one_line(capsys, argv)


# --------------------------------------------------------------------------------------------
# singular poses: one line, never inf or NaN

SINGULAR = ["five_bar", "--qa", "1.0471975511965976", "2.0943951023931953"]  # elbows together


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["stiffness", *SINGULAR, "--actuator-stiffness", "1e4"], "stiffness is undefined here"),
        (["stiffness", *SINGULAR[:1], "--qa", "1.04719755", "2.0943951", *K], "undefined here"),
        (["modes", *SINGULAR, "--actuator-stiffness", "1e4"], "stiffness is undefined here"),
        (["accuracy", *SINGULAR, "--resolution", "1e-3"], "parallel singularity"),
    ],
    ids=["stiffness", "stiffness 1e-8 away", "modes", "accuracy"],
)
def test_singular_poses_say_so_in_one_line(capsys, argv, needle):
    assert needle in _one_line(capsys, argv)


# --------------------------------------------------------------------------------------------
# API types and values at the public boundary


@pytest.fixture(scope="module")
def api():
    from pkdyn.calibration import Measurements
    from pkdyn.precision import elastic_model
    from pkdyn.precision.parameters import parameter_model

    d = pkdyn.load("delta", geometry=False)
    h = d.q_home[d.actuated_q]
    qa = np.array([h + 0.1 * np.sin(np.arange(3) + i) for i in range(20)])
    return d, elastic_model(d, 1e4), parameter_model(d), Measurements("position", qa, 0 * qa)


def _stiffness(a, **kw):
    from pkdyn.precision import stiffness

    return stiffness(a[1], a[0].q_home, **kw)


def _calibrate(a, **kw):
    from pkdyn.calibration import calibrate

    return calibrate(a[0], a[3], **kw)


def _accuracy(name):
    from pkdyn.precision import accuracy

    return getattr(accuracy, name)


API = {
    "stiffness of a name": (
        lambda a: __import__("pkdyn.precision").precision.stiffness("delta", a[0].q_home, 1e4),
        "robot",
    ),
    "stiffness k complex": (lambda a: _stiffness((a[0], a[0]), actuator_stiffness=1j), "number"),
    "stiffness k string": (lambda a: _stiffness((a[0], a[0]), actuator_stiffness="x"), "number"),
    "stiffness k bool": (lambda a: _stiffness((a[0], a[0]), actuator_stiffness=True), "number"),
    "stiffness q string": (
        lambda a: __import__("pkdyn.precision").precision.stiffness(a[1], "abc"),
        "q",
    ),
    "wrench string": (lambda a: _stiffness(a, wrench="abc"), "wrench"),
    "wrench 1e308": (lambda a: _stiffness(a, wrench=[1e308, 0, 0]), "wrench"),
    "loaded 'yes'": (lambda a: _stiffness(a, wrench=[0, 0, 1], loaded="yes"), "loaded"),
    "modes gravity 'no'": (
        lambda a: __import__("pkdyn.precision").precision.modes(a[1], a[0].q_home, gravity="no"),
        "gravity",
    ),
    "figures of a string": (
        lambda a: __import__("pkdyn.precision").precision.pose_figures(
            a[0], "abc", actuator_stiffness=1e4
        ),
        "P",
    ),
    "figures of 5e6 poses": (
        lambda a: __import__("pkdyn.precision").precision.pose_figures(
            a[0], np.zeros((100_000_000, 3)), actuator_stiffness=1e4
        ),
        "at most",
    ),
    "figures general 1e6": (
        lambda a: __import__("pkdyn.precision").precision.pose_figures(
            a[0], np.zeros((1_000_000, 3)), actuator_stiffness=1e4, method="general"
        ),
        "min at",
    ),
    "map samples 2.5": (
        lambda a: __import__("pkdyn.precision").precision.precision_map(
            a[0], samples=2.5, actuator_stiffness=1e4
        ),
        "samples",
    ),
    "map value 1e308": (
        lambda a: __import__("pkdyn.precision").precision.precision_map(
            a[0], samples=3, value=1e308, actuator_stiffness=1e4
        ),
        "value",
    ),
    "resolution string": (
        lambda a: _accuracy("actuator_errors")(a[0], a[0].q_home, "x"),
        "resolution",
    ),
    "tolerance string": (
        lambda a: _accuracy("geometric_errors")(a[0], a[0].q_home, a[2], "x"),
        "tolerance",
    ),
    "model name": (
        lambda a: _accuracy("geometric_errors")(a[0], a[0].q_home, "auto", 1e-5),
        "model",
    ),
    "monte carlo 1e9": (
        lambda a: _accuracy("monte_carlo")(a[0], a[0].q_home, a[2], 1e-5, 10**9),
        "samples",
    ),
    "monte carlo 2.5": (
        lambda a: _accuracy("monte_carlo")(a[0], a[0].q_home, a[2], 1e-5, 2.5),
        "samples",
    ),
    "monte carlo seed -1": (
        lambda a: _accuracy("monte_carlo")(a[0], a[0].q_home, a[2], 1e-5, 3, seed=-1),
        "seed",
    ),
    "grid extent inf": (lambda a: _accuracy("slice_grid")([0, 0, -0.8], "xy", np.inf, 3), "extent"),
    "map of a string": (lambda a: _accuracy("accuracy_map")(a[0], "x", 1e-3), "positions"),
    "calibrate a file name": (
        lambda a: __import__("pkdyn.calibration").calibration.calibrate(a[0], "m.csv"),
        "measurements",
    ),
    "noise string": (lambda a: _calibrate(a, noise="x"), "noise"),
    "noise 1e308": (lambda a: _calibrate(a, noise=1e308), "noise"),
    "holdout string": (lambda a: _calibrate(a, holdout="x"), "holdout"),
    "seed -1": (lambda a: _calibrate(a, seed=-1), "seed"),
    "max_iter 2.5": (lambda a: _calibrate(a, max_iter=2.5), "max_iter"),
    "rtol nan": (lambda a: _calibrate(a, rtol=np.nan), "rtol"),
    "prior negative": (lambda a: _calibrate(a, prior=(-1, 0.1, 0.01)), "prior"),
    "readings string": (
        lambda a: __import__("pkdyn.calibration").calibration.Measurements(
            "position", "abc", np.zeros((1, 3))
        ),
        "qa",
    ),
    "readings 3-D": (
        lambda a: __import__("pkdyn.calibration").calibration.Measurements(
            "position", np.zeros((2, 3, 3)), np.zeros((2, 3))
        ),
        "dimensions",
    ),
    "positions 1e308": (
        lambda a: __import__("pkdyn.calibration").calibration.Measurements(
            "position", a[3].qa, np.full((20, 3), 1e308)
        ),
        "position",
    ),
    "a million poses": (
        lambda a: __import__("pkdyn.calibration").calibration.Measurements(
            "position", np.zeros((1_000_000, 3)), np.zeros((1_000_000, 3))
        ),
        "at most",
    ),
}


def _selection(name):
    from pkdyn.calibration import selection

    return getattr(selection, name)


def _plan(a, **kw):
    from pkdyn.calibration.planner import plan_calibration

    return plan_calibration(a[0], **{"target": 1e-4, **kw})


API.update(
    {
        "candidates 1e9": (lambda a: _selection("candidate_poses")(a[0], 10**9), "count"),
        "candidates 2.5": (lambda a: _selection("candidate_poses")(a[0], 2.5), "count"),
        "spread nan": (lambda a: _selection("candidate_poses")(a[0], 5, spread=np.nan), "spread"),
        "spread 1e308": (lambda a: _selection("candidate_poses")(a[0], 5, spread=1e308), "spread"),
        "candidates seed -1": (lambda a: _selection("candidate_poses")(a[0], 5, seed=-1), "seed"),
        "select 1e9": (lambda a: _selection("select_poses")(np.ones((10, 3, 4)), 10**9), "count"),
        "select a string": (lambda a: _selection("select_poses")("x", 3), "blocks"),
        "plan 1e9 poses": (lambda a: _plan(a, poses=[10**9]), "poses"),
        "plan 1e9 trials": (lambda a: _plan(a, trials=10**9), "trials"),
        "plan noise negative": (lambda a: _plan(a, noise=[-1]), "noise"),
        "plan target nan": (lambda a: _plan(a, target=np.nan), "target"),
        "plan runs 1e6": (
            lambda a: _plan(a, trials=1000, noise=list(np.linspace(1e-6, 1e-4, 100))),
            "simulated calibrations",
        ),
        "identify a file name": (
            lambda a: __import__("pkdyn.identification").identification.identify(a[0], "data.csv"),
            "data",
        ),
        "excitation 1e9 samples": (
            lambda a: __import__(
                "pkdyn.identification.excitation"
            ).identification.excitation.excitation_trajectory(a[0], samples=10**9),
            "samples",
        ),
        "excitation 1e6 harmonics": (
            lambda a: __import__(
                "pkdyn.identification.excitation"
            ).identification.excitation.excitation_trajectory(a[0], harmonics=10**6),
            "harmonics",
        ),
        "excitation period nan": (
            lambda a: __import__(
                "pkdyn.identification.excitation"
            ).identification.excitation.excitation_trajectory(a[0], period=np.nan),
            "period",
        ),
    }
)


@pytest.mark.parametrize("call, culprit", API.values(), ids=list(API))
def test_api_types_and_values_are_checked_at_the_boundary(api, call, culprit):
    with pytest.raises(InvalidInputError) as err:
        call(api)
    text = str(err.value)
    assert "\n" not in text and culprit in text, text


# --------------------------------------------------------------------------------------------
# data files

CAL_FILES = {
    "missing file": ("nope", "cannot be read"),
    "a directory": ("dir", "a directory, not a regular file"),
    "a FIFO": ("fifo", "a FIFO (named pipe), not a regular file"),
    "/dev/zero": ("/dev/zero", "a character device"),
    "empty": ("empty", "is empty"),
    "header only": ("header only", "no measurement rows"),
    "missing column": ("missing z", "missing column(s) z"),
    "extra column": ("extra w", "unexpected column(s) w"),
    "duplicated column": ("repeated x", "column x is given twice"),
    "NaN": ("nan", "line 5, column qa_motor1: nan"),
    "text in numbers": ("text", "line 5, column qa_motor1: 'abc' is not a number"),
    "inf": ("inf", "line 5, column qa_motor1: inf"),
    "absurd reading": ("reading 1e308", "line 5: the nominal delta cannot be assembled"),
    "absurd position": ("position 1e308", "beyond any plausible"),
    "far position": ("position 1e6", "more than 100 times its size"),
    "ragged row": ("ragged", "line 5 has 2 cells"),
    "fewer poses than parameters": ("two poses", "measure at least 7 poses"),
    "binary": ("binary", "a NUL byte: a binary file"),
    "huge file": ("big", "more than the 16 MB accepted"),
}
MOTION_FILES = {
    "missing file": ("nope", "cannot be read"),
    "a directory": ("dir", "a directory, not a regular file"),
    "a FIFO": ("fifo", "not a regular file"),
    "/dev/zero": ("/dev/zero", "not a regular file"),
    "header only": ("motion header only", "no data rows"),
    "missing column": ("motion missing tau", "missing column tau_motor2"),
    "duplicated column": ("motion repeated t", "column t is given twice"),
    "text in numbers": ("motion text", "'abc'"),
    "absurd effort": ("motion tau 1e308", "line 5, column tau_motor2: 1e+308 is beyond"),
    "absurd time step": ("motion dt 1e-300", "a time step of"),
    "times backwards": ("motion backwards", "times must increase"),
    "too few samples": ("motion two rows", "record at least"),
    "unexciting motion": ("motion still", "does not excite every base parameter"),
    "huge file": ("motion bigger", "more than the 512 MB accepted"),
}


def _path(files, key):
    return key if key.startswith("/") else files.get(key, os.path.join(files["dir"], key))


@pytest.mark.parametrize("key, needle", CAL_FILES.values(), ids=list(CAL_FILES))
def test_measurement_files_are_refused_in_one_line(capsys, files, tmp_path, key, needle):
    out = tmp_path / "cal.urdf"
    argv = ["calibrate", "delta", "--measurements", _path(files, key), "-o", str(out)]
    assert needle in _one_line(capsys, argv)
    assert not out.exists()


@pytest.mark.parametrize("key, needle", MOTION_FILES.values(), ids=list(MOTION_FILES))
def test_motion_files_are_refused_in_one_line(capsys, files, tmp_path, key, needle):
    out = tmp_path / "id.urdf"
    argv = ["identify", "five_bar", "--measurements", _path(files, key), "-o", str(out)]
    assert needle in _one_line(capsys, argv)
    assert not out.exists()


CAL_OPTIONS = {
    "noise negative": (["--noise", "-1"], "noise"),
    "noise nan": (["--noise", "nan"], "noise"),
    "noise larger than the robot": (["--noise", "1e308"], "noise"),
    "noise of 3": (["--noise", "1", "2", "3"], "noise"),
    "holdout 1": (["--holdout", "1"], "holdout"),
    "holdout nan": (["--holdout", "nan"], "holdout"),
    "seed negative": (["--seed", "-1"], "seed"),
    "implicit without groups": (["--implicit", "point"], "missing column(s) group"),
}


@pytest.mark.parametrize("extra, needle", CAL_OPTIONS.values(), ids=list(CAL_OPTIONS))
def test_calibrate_options_are_checked(capsys, files, tmp_path, extra, needle):
    argv = ["calibrate", "delta", "--measurements", files["good"], "-o", str(tmp_path / "c")]
    assert needle in _one_line(capsys, [*argv, *extra])


def test_absurd_groups_and_identify_options(capsys, files, tmp_path):
    out = str(tmp_path / "x.urdf")
    argv = ["calibrate", "delta", "--measurements", files["group 1e300"], "-o", out]
    assert "group: line 2" in _one_line(capsys, [*argv, "--implicit", "point"])
    run = ["identify", "five_bar", "--measurements", files["motion"], "-o", out]
    for extra, needle in (
        (["--cutoff", "-1"], "cutoff"),
        (["--cutoff", "nan"], "cutoff"),
        (["--parameters", "mass"], "unknown group 'mass'"),
        (["--predict", files["fifo"]], "not a regular file"),
        (["--csv", str(tmp_path / "p.csv")], "needs --predict"),
    ):
        assert needle in _one_line(capsys, [*run, *extra])


def test_identical_poses_warn_what_they_cannot_identify(files, tmp_path):
    from pkdyn.calibration import calibrate, read_csv

    delta = pkdyn.load("delta", geometry=False)
    rows = Path(files["good"]).read_text().splitlines()
    same = tmp_path / "same.csv"
    same.write_text(rows[0] + "\n" + "\n".join([rows[1]] * 30) + "\n")
    with pytest.warns(UserWarning, match="identify 3 of the 18 parameters"):
        res = calibrate(delta, read_csv(same, delta), noise=1e-5)
    assert res.identifiability.rank == 3


# --------------------------------------------------------------------------------------------
# outputs checked before the work


@pytest.mark.parametrize(
    "target, needle",
    [
        ("/nonexistent/x.out", "does not exist"),
        ("DIR", "a directory"),
        ("/dev/full", "a character device"),
    ],
    ids=["missing dir", "a directory", "/dev/full"],
)
@pytest.mark.parametrize(
    "command", ["calibrate -o", "identify -o", "identify --csv", "modes", "accuracy"]
)
def test_outputs_are_checked_before_the_work(capsys, files, target, needle, command):
    t = files["dir"] if target == "DIR" else target
    argv = {
        "calibrate -o": ["calibrate", "delta", "--measurements", files["two poses"], "-o", t],
        "identify -o": ["identify", "five_bar", "--measurements", files["motion still"], "-o", t],
        "identify --csv": [
            "identify",
            "five_bar",
            "--measurements",
            files["motion still"],
            "-o",
            os.path.join(files["dir"], "i.urdf"),
            "--predict",
            files["motion"],
            "--csv",
            t,
        ],
        "modes": [*M, "--actuator-stiffness", "-1", "--html", t],
        "accuracy": [
            "accuracy",
            "delta",
            "--map",
            "xy",
            "--grid",
            "0",
            "--plot",
            t if t != "/dev/full" else t,
        ],
    }[command]
    err = _one_line(capsys, argv)
    assert needle in err or (command == "accuracy" and "file extension" in err), err


# --------------------------------------------------------------------------------------------
# signals: Ctrl-C during the long computations


def _five_bar_motion(path: Path, n: int) -> Path:
    """A five-bar motion file of ``n`` samples at 200 Hz (two sines, efforts made up)."""
    five = pkdyn.load("five_bar", geometry=False)
    t = np.arange(n) * 0.005
    qa = five.q_home[five.actuated_q] + 0.3 * np.sin(np.outer(t, [1.3, 2.1]))
    tau = 0.1 * np.sin(np.outer(t, [1.0, 2.0]))
    np.savetxt(
        path,
        np.column_stack([t, qa, tau]),
        delimiter=",",
        comments="",
        header="t,qa_motor1,qa_motor2,tau_motor1,tau_motor2",
    )
    return path


@pytest.fixture(scope="module")
def long_files(tmp_path_factory, files):
    d = tmp_path_factory.mktemp("long")
    rows = Path(files["good"]).read_text().splitlines()
    cal = d / "many.csv"
    cal.write_text(rows[0] + "\n" + "\n".join(rows[1:] * 200) + "\n")  # 6000 poses
    motion = _five_bar_motion(d / "long.csv", 12_000)
    return str(cal), str(motion), d


@pytest.mark.parametrize("command", ["calibrate", "identify", "accuracy map", "monte carlo"])
def test_ctrl_c_during_the_work_exits_130_without_traceback(
    capsys, monkeypatch, long_files, command
):
    cal, motion, d = long_files
    out = d / f"{command.replace(' ', '_')}.urdf"
    argv = {
        "calibrate": [
            "calibrate",
            "delta",
            "--measurements",
            cal,
            "-o",
            str(out),
            "--model",
            "placements",
        ],
        "identify": ["identify", "five_bar", "--measurements", motion, "-o", str(out)],
        "accuracy map": ["accuracy", "delta", "--map", "xy", "--grid", "201"],
        "monte carlo": ["accuracy", "delta", "--qa", "0", "0", "0", "--samples", "100000"],
    }[command]
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
    if command == "identify":
        # 12,000 samples take about a second on an idle machine: the signal is sent from
        # inside the sample loop, after its first batch, rather than by a race with a timer
        identify_module = importlib.import_module("pkdyn.identification.identify")
        bar = identify_module.progress_bar

        def interrupted_after_one_batch(items, *args, **kwargs):
            for k, item in enumerate(bar(items, *args, **kwargs)):
                if k == 1:
                    os.kill(os.getpid(), signal.SIGINT)
                yield item

        monkeypatch.setattr(identify_module, "progress_bar", interrupted_after_one_batch)
    else:
        timer.start()
    start = time.monotonic()
    try:
        code = main(argv)
    finally:
        timer.cancel()
    assert time.monotonic() - start < 30
    err = capsys.readouterr().err
    assert code == 130 and err.strip().splitlines()[-1] == "pkdyn: interrupted", err
    assert "Traceback" not in err and not out.exists()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_ctrl_c_stops_identification_workers(tmp_path, files):
    """A real process: SIGINT while two workers share the samples; nothing is left running."""
    motion = _five_bar_motion(tmp_path / "workers.csv", 100_000)
    exe = str(Path(sys.executable).with_name("pkdyn"))
    out = tmp_path / "w.urdf"
    proc = subprocess.Popen(
        [exe, "identify", "five_bar", "--measurements", str(motion), "-o", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        children = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            if children.exists() and children.read_text().split():
                break  # the workers have started
            time.sleep(0.1)
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130 and "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == "pkdyn: interrupted"
    assert not out.exists()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.killpg(proc.pid, 0)  # a worker of the session still alive?
        except ProcessLookupError:
            break
        time.sleep(0.2)
    else:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail("identification workers outlived the interrupted command")


def test_pkdyn_errors_are_typed():
    """Everything above raises subclasses of PkdynError (the CLI's one-line contract)."""
    assert issubclass(InvalidInputError, PkdynError)
