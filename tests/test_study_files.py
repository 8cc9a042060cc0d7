"""Study files and design options: checked where they enter, never a silent wrong answer.

Classes: fields of the wrong type (a traceback before), options that would make every design
fail (a "no feasible design" with exit 0 before), work beyond the budgets (a hang before), a
MemoryError read as "no design passes", and resumed studies that took rows that are not theirs.
Each bad input is one line ``pkdyn: error: ...`` naming the field, exit 1, before any design is
built.
"""

import math
import warnings

import pytest

from pkdyn.cli import main
from pkdyn.design import Metric, Study, run_study
from pkdyn.design.table import output_paths
from pkdyn.exceptions import InvalidInputError, ParameterError, PkdynError, StudyError

BASE = "family: delta\nranges: {la: [0.2, 0.3]}\nmetrics: [moving_mass]\nn: 2\n"


def _with(field: str) -> str:
    key = field.split(":")[0]
    kept = [line for line in BASE.splitlines() if not line.startswith(key + ":")]
    return "\n".join([*kept, field]) + "\n"


# ---------------------------------------------------------------------- inputs never type-checked

WRONG_TYPES = {
    "n: abc": "n: expected a whole number, got 'abc'",
    "n: 2.7": "n: expected a whole number, got 2.7",
    "n: true": "n: expected a whole number, got True",
    "payload: heavy": "payload: expected a number, got 'heavy'",
    "payload: true": "payload: expected a number, got True",
    "payload: .nan": "payload: must be finite",
    "constraints: [5]": "constraints: expected NAME>=VALUE, got 5",
    "family: [delta]": "family: expected a name, got ['delta']",
    "ranges: [1, 2]": "ranges: expected NAME: [LOW, HIGH] entries or NAME=LOW:HIGH, got 1",
    "ranges: {la: abc}": "range 'la': expected [low, high], got 'abc'",
    "ranges: {la: [a, 0.3]}": "range 'la' low: expected a number, got 'a'",
    "ranges: {la: [0.2, 0.3, 0.4]}": "range 'la': expected [low, high]",
    "metrics: [5]": "metrics: expected metric names, got 5",
    "fixed: [1]": "fixed: expected a mapping (NAME: VALUE), got [1]",
    "fixed: {lb: abc}": "parameter 'lb': cannot use 'abc'",
    "seed: -1": "seed: must be in 0..4294967295, got -1",
    "seed: abc": "seed: expected a whole number",
    "seed: 1.5": "seed: expected a whole number, got 1.5",
    "generations: x": "generations: expected a whole number",
    "sampler: 5": "sampler: expected a name, got 5",
    "sampler: halton": "sampler: unknown 'halton'",
    "trajectory: 5": "trajectory: expected a name, got 5",
    "trajectory_options: 5": "trajectory_options: expected a mapping",
    "requirement: 5": "requirement: expected a mapping",
    "requirement: {kind: box, dx: a, dy: 1, dz: 1}": "requirement box dx: expected a number",
    "requirement: {kind: box, dx: 0.1, dy: 0.1, dz: 0.1, center: 5}": "centre must be 3",
    "requirement: {kind: box, dx: 0.1, dy: 0.1, dz: 0.1, samples: x}": "samples (--samples): "
    "expected a whole number",
    "requirement: {kind: box}": "requirement: box: give its size dx",
    "settings: 5": "settings: expected a mapping",
    "settings: {workspace_samples: abc}": "workspace_samples: expected a whole number",
    "settings: {limits: 5}": "limits: expected a list of names, got 5",
    "settings: {limits: [reach, bogus]}": "limits: unknown kind 'bogus'",
    "settings: {length: abc}": "length: expected a number, got 'abc'",
    "settings: {gamma_max: 5}": "gamma_max: must be <= 3.14159 rad",
    "name: [1]": "name: expected a name, got [1]",
    "objectives: [5]": "objectives: expected min:NAME or max:NAME, got 5",
    "parametrisation: 5": "parametrisation: expected a name, got 5",
    "1: 2": "unknown key '1'",
}


@pytest.mark.parametrize("field", list(WRONG_TYPES))
def test_study_file_fields_of_the_wrong_type(tmp_path, capsys, field):
    f = tmp_path / "s.yaml"
    f.write_text(_with(field))
    out = tmp_path / "o.csv"
    assert main(["design", "--study", str(f), "--workers", "1", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("pkdyn: error:") and len(err.strip().splitlines()) == 1, err
    assert WRONG_TYPES[field] in err
    assert not output_paths(out)["partial"].exists()  # refused before any design


def test_study_file_that_is_not_a_mapping_or_too_deep(tmp_path):
    f = tmp_path / "s.yaml"
    for text, match in (("- a\n- b\n", "is a mapping"), ("[" * 1500 + "]" * 1500, "nest")):
        f.write_text(text)
        with pytest.raises(StudyError, match=match):
            Study.load(f)


def test_a_single_name_is_a_list_of_one():
    s = Study("delta", {"la": (0.2, 0.3)}, metrics="moving_mass", n=2)
    assert s.metric_names == ["moving_mass"]


# ---------------------------------------------------------------------- silent wrong answers

EVERY_DESIGN_FAILS = {
    "negative cycle time": (["--cycle-time", "-1"], "cycle_time: must be > 0"),
    "zero cycle time": (["--cycle-time", "0"], "cycle_time: must be > 0"),
    "negative step": (["--dt", "-0.001"], "dt: sample period must be > 0 s"),
    "step longer than a move": (["--dt", "0.2"], "dt: 0.2 s samples the"),
    "NaN depth": (["--depth", "nan"], "--depth: is nan"),
    "NaN fixed parameter": (["--param", "lb=nan"], "parameter 'lb': fixed at nan"),
    "infinite fixed parameter": (["--param", "lb=inf"], "parameter 'lb': fixed at inf"),
    "parametrisation missing its variables": (
        ["--parametrisation", "clavel"],
        "parameter 'r': the parametrisation 'clavel' needs it",
    ),
    "repeated range": (["--range", "la=0.3:0.4"], "--range: 'la' is given twice"),
    "samples without a requirement": (["--samples", "9"], "--samples: applies to a required"),
    "zero samples": (
        ["--samples", "0", "--require", "cylinder:D=0.1,H=0.1,z=-0.3"],
        "samples (--samples): must be >= 2",
    ),
    "repeated requirement size": (
        ["--require", "cylinder:D=0.1,D=0.2,z=-0.3"],
        "--require: 'D' is given twice",
    ),
    "negative seed": (["--seed", "-1"], "seed: must be in 0..4294967295"),
    "verify below 2": (["--verify", "1", "--require", "cylinder:D=0.1,H=0.1,z=-0.3"], "--verify"),
    "verify without requirement": (["--verify", "5"], "--verify: checks a required workspace"),
    "negative timeout": (["--timeout", "-1"], "--timeout: must be a number of seconds"),
    "NaN timeout": (["--timeout", "nan"], "--timeout: is nan"),
    "endless timeout": (["--timeout", "1e9"], "--timeout: must be a number of seconds"),
    "zero workers": (["--workers", "0"], "--workers: must be >= 1"),
}


@pytest.mark.parametrize("case", list(EVERY_DESIGN_FAILS))
def test_options_that_would_make_every_design_fail_are_refused(tmp_path, capsys, case):
    extra, match = EVERY_DESIGN_FAILS[case]
    out = tmp_path / "o.csv"
    args = ["design", "delta", "--range", "la=0.2:0.3", "--metric", "moving_mass", "peak_effort"]
    code = main([*args, "--n", "2", "--workers", "1", "--out", str(out), *extra])
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert match in err
    assert not output_paths(out)["partial"].exists()


def test_unknown_trajectory_in_python():
    with pytest.raises(InvalidInputError, match="trajectory: unknown 'zigzag'"):
        Study("delta", {"la": (0.2, 0.3)}, metrics=["peak_effort"], trajectory="zigzag")
    with pytest.raises(InvalidInputError, match="unexpected option 'cycle'"):
        Study("delta", {"la": (0.2, 0.3)}, metrics=["peak_effort"], trajectory_options={"cycle": 1})
    with pytest.raises(ParameterError, match="fixed at nan"):
        Study("delta", {"la": (0.2, 0.3)}, fixed={"lb": math.nan}, metrics=["moving_mass"])


def _raises_memory_error(robot, ctx):
    raise MemoryError


def test_a_memory_error_is_never_read_as_no_design_passes():
    s = Study("delta", {"la": (0.2, 0.3)}, metrics=[Metric("m", "-", _raises_memory_error)], n=2)
    with pytest.raises(StudyError, match="design 0: the memory ran out"):
        run_study(s, workers=1)


def test_a_memory_error_in_verify(monkeypatch):
    s = Study("delta", {"la": (0.2, 0.3)}, fixed={"z_home": -0.35}, metrics=["contains"],
              requirement="cylinder:D=0.05,H=0.02,z=-0.35", n=2, constraints=[])  # fmt: skip
    res = run_study(s, workers=1)
    assert res.best() is not None
    import pkdyn.design.required as required

    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(required, "_DeltaCheck", exhausted)
    with pytest.raises(StudyError, match="the memory ran out"):
        res.verify(samples=5)


# ---------------------------------------------------------------------- unbounded work

BUDGETS = {
    "required samples": (
        ["--require", "cylinder:D=0.1,H=0.1,z=-0.3", "--samples", "1000"],
        "poses per design, more than 100,000",
    ),  # fmt: skip
    "study x requirement": (
        ["--require", "box:dx=0.1,dy=0.1,dz=0.1,z=-0.3", "--samples", "40", "--n", "4000"],
        "64000 required poses = 2.56e+08 evaluations, more than the 2e+08 a study may ask in "
        "closed form",
    ),
    "study x requirement, numeric path": (
        [
            "--require",
            "box:dx=0.1,dy=0.1,dz=0.1,z=-0.3",
            "--samples",
            "40",
            "--n",
            "1000",
            "--param",
            "parallelogram=hinge",
        ],  # fmt: skip
        "64000 required poses = 6.4e+07 evaluations, more than the 2e+07 a study may ask (",
    ),
    "study x duty cycle": (
        ["--metric", "peak_effort", "--dt", "1e-5", "--n", "10000"],
        "duty-cycle samples",
    ),
    "verify": (["--require", "cylinder:D=0.1,H=0.1,z=-0.3", "--verify", "100"], "--verify"),
    "designs": (["--grid", "1001", "--range", "lb=0.4:0.6"], "more than 1000000"),
}


@pytest.mark.parametrize("case", list(BUDGETS))
def test_work_beyond_the_budgets_is_refused_up_front(tmp_path, capsys, case):
    extra, match = BUDGETS[case]
    code = main(["design", "delta", "--range", "la=0.2:0.3", "--metric", "moving_mass",
                 "--workers", "1", *extra])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert match in err


def test_the_closed_form_budget_admits_the_worked_study_at_100000_designs():
    """The library Delta's closed forms (a pose ~12 us, a duty-cycle sample ~3 us) have a
    larger budget than the numeric path's: the worked study runs at 100,000 designs."""
    req = {"kind": "cylinder", "D": 0.4, "H": 0.1, "center": [0, 0, -0.35], "samples": 5}
    duty = {"trajectory": "adept", "trajectory_options": {"cycle_time": 0.5}, "payload": 1.0}
    args = {"metrics": ["required", "peak_effort"], "requirement": req, "n": 100_000, **duty}
    s = Study("delta", {"la": (0.15, 0.35)}, **args)
    assert s.total * s.requirement.count == 42_500_000  # more than the numeric path's 2e7
    hinge = {"parallelogram": "hinge"}
    with pytest.raises(InvalidInputError, match="more than the 2e\\+07 a study may ask \\("):
        Study("delta", {"la": (0.15, 0.35)}, fixed=hinge, **args)
    with pytest.raises(InvalidInputError, match="duty-cycle samples = 5.01e\\+07 evaluations"):
        Study(
            "delta",
            {"la": (0.15, 0.35)},
            fixed=hinge,
            **{**args, "requirement": None, "metrics": ["peak_effort"]},
        )
    with pytest.raises(InvalidInputError, match="more than the 2e\\+08 a study may ask in closed"):
        Study("delta", {"la": (0.15, 0.35)}, **{**args, "n": 500_000})


# ---------------------------------------------------------------------- resumed studies


def test_a_resumed_study_takes_only_its_own_rows(tmp_path):
    s = Study("delta", {"la": (0.2, 0.3)}, metrics=["moving_mass"], n=6, seed=1)
    fresh = tmp_path / "fresh.csv"
    run_study(s, fresh, workers=1)
    lines = fresh.read_text().splitlines()
    header, rows = lines[0], lines[1:]
    moved = rows[2].split(",")
    moved[1] = repr(float(moved[1]) + 1e-3)  # a value the sampler does not give there
    foreign = [
        rows[0],
        rows[1],
        ",".join(moved),
        rows[3].replace(rows[3].split(",")[0], "17", 1),  # index outside 0..5
        rows[1],  # repeated
        "-1," + ",".join(rows[4].split(",")[1:]),
    ]
    out = tmp_path / "r.csv"
    partial = output_paths(out)["partial"]
    partial.write_text(f"# pkdyn design study {s.digest()}\n{header}\n" + "\n".join(foreign) + "\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = run_study(s, out, workers=1)
    msg = " ".join(str(w.message) for w in caught)
    assert "4 rows that do not belong to this study dropped" in msg
    assert "2 with an index outside 0..5" in msg and "1 with design values" in msg
    assert "1 with an index given again" in msg and "2 kept" in msg
    assert len(res.designs) == 6 and list(res.designs.index) == list(range(6))
    assert out.read_text() == fresh.read_text()


def test_a_complete_table_with_foreign_rows_is_not_reused(tmp_path):
    s = Study("delta", {"la": (0.2, 0.3)}, metrics=["moving_mass"], n=4)
    out = tmp_path / "c.csv"
    run_study(s, out, workers=1)
    good = out.read_text()
    lines = good.splitlines()
    out.write_text("\n".join([*lines, lines[-1].replace(lines[-1].split(",")[0], "9", 1)]) + "\n")
    with pytest.warns(UserWarning, match="index outside 0..3"):
        res = run_study(s, out, workers=1)
    assert len(res.designs) == 4 and out.read_text() == good


def test_errors_cross_process_boundaries():
    import pickle

    err = StudyError("design 3", "the memory ran out\n(detail)")
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is StudyError and back.culprit == "design 3"
    assert str(back) == "design 3: the memory ran out (detail)"  # and on one line
    assert isinstance(back, PkdynError)
