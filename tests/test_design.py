"""Design studies: spaces, requirements, metrics, runners, executors, files, resume, CLI."""

import json
import math

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.design import (
    Metric,
    Range,
    Requirement,
    Study,
    resolve_metrics,
    run_study,
)
from pkdyn.design.clavel import clavel_chart_study, clavel_chart_text
from pkdyn.design.executors import ProcessExecutor
from pkdyn.design.pareto import non_dominated
from pkdyn.design.required import required_check
from pkdyn.design.samplers import unit_points
from pkdyn.design.table import output_paths
from pkdyn.exceptions import InvalidInputError, ParameterError, StudyError, UnknownRobotError

CYL = "cylinder:D=0.3,H=0.06,z=-0.37"


def _delta_study(**kw):
    base = dict(
        family="delta",
        ranges={"la": (0.18, 0.26), "lb": (0.36, 0.5)},
        fixed={"z_home": -0.35},
        metrics=["clavel_D", "contains", "inv_cond_min", "peak_effort", "moving_mass"],
        requirement=CYL,
        trajectory_options={"cycle_time": 0.6, "dt": 1e-2},
        payload=0.5,
        constraints=["inv_cond_min>=0.2"],
        objectives=["min:peak_effort", "max:inv_cond_min"],
        sampler="sobol",
        n=8,
        seed=3,
    )
    base.update(kw)
    return Study(**base)


# ---------------------------------------------------------------------- definitions


@pytest.mark.parametrize(
    "ranges, error, match",
    [
        ({"la": (0.2, 0.2)}, InvalidInputError, "empty"),
        ({"la": (0.3, 0.2)}, InvalidInputError, "inverted"),
        ({"la": (0.2, math.inf)}, InvalidInputError, "finite"),
        ({"arm_length": (0.1, 0.2)}, ParameterError, "unknown"),
        ({"bar_joint": (0.0, 1.0)}, ParameterError, "not a number"),
        ({}, InvalidInputError, "at least one"),
    ],
)
def test_bad_ranges(ranges, error, match):
    with pytest.raises(error, match=match):
        Study("delta", ranges, metrics=["moving_mass"])


def test_other_bad_definitions():
    with pytest.raises(UnknownRobotError):
        Study("octopus", {"la": (0.1, 0.2)}, metrics=["moving_mass"])
    with pytest.raises(InvalidInputError, match="unknown metric 'stifness'"):
        Study("delta", {"la": (0.1, 0.2)}, metrics=["stifness"])
    with pytest.raises(ParameterError, match="twice"):
        Study("delta", {"la": (0.1, 0.2)}, fixed={"la": 0.2}, metrics=["moving_mass"])
    with pytest.raises(InvalidInputError, match="required workspace"):
        Study("delta", {"la": (0.1, 0.2)}, metrics=["inv_cond_min"])
    with pytest.raises(InvalidInputError, match="more than"):
        Study("delta", {"la": (0.1, 0.2), "lb": (0.3, 0.5)}, metrics=["moving_mass"],
              sampler="grid", n=1001)  # fmt: skip
    with pytest.raises(InvalidInputError, match="NAME>=VALUE"):
        Study("delta", {"la": (0.1, 0.2)}, metrics=["moving_mass"], constraints=["la = 3"])
    with pytest.raises(InvalidInputError, match="NAME=LOW:HIGH"):
        Range.parse("la=0.1")


def test_requirement_samples():
    req = Requirement.parse("cylinder:D=0.4,H=0.1,z=-0.35", samples=5)
    P = req.positions
    r = np.hypot(P[:, 0], P[:, 1])
    assert np.isclose(r.max(), 0.2) and np.isclose(P[:, 2].min(), -0.4)
    assert np.sum(np.isclose(r, 0.2)) == 5 * 48  # 12 (s - 1) on the rim at each of 5 levels
    box = Requirement.parse("box:dx=0.2,dy=0.1,dz=0.0,x=0.1")
    assert box.positions.shape == (25, 3) and np.isclose(box.positions[:, 0].max(), 0.2)
    ori = Requirement.parse("orientation:roll=0.1,pitch=0.2,z=0.6", samples=3)
    R = ori.rotations
    assert R.shape == (9, 3, 3)
    # at psi = 0 the set is roll-pitch-yaw (pinocchio's convention)
    rpy = np.array([pin.rpy.matrixToRpy(Ri) for Ri in R])
    assert np.isclose(np.abs(rpy[:, 0]).max(), 0.1) and np.isclose(np.abs(rpy[:, 1]).max(), 0.2)
    assert np.allclose(rpy[:, 2], 0.0)
    for bad in ("sphere:R=1", "cylinder:D=-1,H=0", "cylinder:D=0.1,W=3", "box:dx=a"):
        with pytest.raises(InvalidInputError):
            Requirement.parse(bad)


def test_samplers_are_seeded_and_cover_the_ranges():
    a = unit_points("lhs", 16, 3, seed=1)
    assert np.array_equal(a, unit_points("lhs", 16, 3, seed=1))
    assert not np.array_equal(a, unit_points("lhs", 16, 3, seed=2))
    # Latin hypercube: one point per stratum on each axis
    assert all(len(set(np.floor(a[:, k] * 16).astype(int))) == 16 for k in range(3))
    g = unit_points("grid", 3, 2)
    assert g.shape == (9, 2) and set(g[:, 0]) == {0.0, 0.5, 1.0}
    s = Study("delta", {"la": (0.1, 0.3), "lb": (0.3, 0.5)}, metrics=["moving_mass"],
              sampler="grid", n=3)  # fmt: skip
    X = s.designs()
    assert X[:, 0].min() == 0.1 and X[:, 0].max() == 0.3 and len(X) == 9


def test_pareto_mask_against_brute_force():
    rng = np.random.default_rng(0)
    F = rng.random((300, 2))
    F[7] = F[9]
    F[11, 0] = np.nan
    m = non_dominated(F)
    ok = np.isfinite(F).all(axis=1)
    brute = np.array(
        [
            ok[i] and not np.any(ok & np.all(F <= F[i], axis=1) & np.any(F < F[i], axis=1))
            for i in range(len(F))
        ]
    )
    assert np.array_equal(m, brute)


# ---------------------------------------------------------------------- metrics


def test_user_metric_and_units():
    calls = []

    def ratio(robot, ctx):
        calls.append(1)
        return robot.params.lb / robot.params.la

    s = Study("delta", {"la": (0.2, 0.3)}, metrics=["peak_speed_2", Metric("ratio", "-", ratio)],
              sampler="grid", n=2, trajectory_options={"dt": 1e-2})  # fmt: skip
    assert s.metric_names == ["peak_speed_2", "ratio"]
    assert s.units["peak_speed_2"] == "rad/s"
    res = run_study(s, workers=1)
    assert np.allclose(res.designs.column("ratio"), [0.38 / 0.2, 0.38 / 0.3])
    assert len(calls) == 2
    bad = Study("delta", {"la": (0.2, 0.3)}, metrics=[Metric("nan", "-", lambda r, c: math.nan)],
                sampler="grid", n=2)  # fmt: skip
    rows = run_study(bad, workers=1).designs.rows
    assert not rows[0].feasible and "not finite" in rows[0].reason
    assert [m.name for m in resolve_metrics(["clavel"])][:2] == ["clavel_D", "clavel_S"]


def test_delta_required_check_against_the_general_path():
    """Closed-form containment, 1/cond and clearance = the numeric path (IK, dexterity, coal)."""
    robot = pkdyn.load("delta", la=0.22, lb=0.42)
    req = Requirement.parse("cylinder:D=0.5,H=0.1,z=-0.38", samples=3)
    fast = required_check(robot, req)
    from pkdyn.design.required import _NumericCheck

    slow = _NumericCheck(robot, req.positions, req.rotations, fast.kinds, None)
    assert 0 < fast.fraction < 1  # some poses out: the comparison sees both kinds
    assert np.array_equal(fast.codes, slow.codes)
    ok = fast.reached
    assert np.allclose(fast.inv_cond[ok], slow.inv_cond[ok], rtol=1e-7, atol=1e-9)
    # clearance: bars of different arms, bars against other arms, as coal capsules
    import dataclasses

    import coal

    from pkdyn.analysis.collisions import CollisionChecker

    gm = robot.collision_model.copy()
    for g in gm.geometryObjects:
        if isinstance(g.geometry, coal.Cylinder):
            g.geometry = coal.Capsule(g.geometry.radius, 2 * g.geometry.halfLength)
    capsules = dataclasses.replace(robot, collision_model=gm)
    names = [g.name for g in gm.geometryObjects]
    bars = [n for n in names if n.startswith("bar")]
    pairs = [(a, b) for i, a in enumerate(bars) for b in bars[i + 1 :] if a[3] != b[3]]
    pairs += [(b, f"arm{k}_0") for b in bars for k in (1, 2, 3) if int(b[3]) != k]
    checker = CollisionChecker(capsules, pairs)
    for k in np.flatnonzero(ok)[::5]:
        q = pkdyn.inverse_geometry(robot, req.positions[k]).q
        assert abs(np.min(checker.distances(q)) - fast.clearance[k]) < 1e-8


def test_hexapod_required_check_against_the_general_path():
    robot = pkdyn.load("gough_stewart")
    req = Requirement.parse("orientation:roll=0.9,pitch=0.9,yaw=0.3,z=0.6", samples=3)
    fast = required_check(robot, req, length=0.1)
    from pkdyn.analysis.collisions import CollisionChecker
    from pkdyn.design.required import _NumericCheck

    slow = _NumericCheck(robot, req.positions, req.rotations, fast.kinds, 0.1)
    assert np.array_equal(fast.codes, slow.codes)
    ok = fast.reached
    assert ok.any() and not ok.all()
    assert np.allclose(fast.inv_cond[ok], slow.inv_cond[ok], rtol=1e-7)
    # legs as capsules along A_i B_i: never closer than coal's cylinder and rod pieces
    pieces = {i: [f"leg{i}_cylinder_0", f"leg{i}_rod_0"] for i in range(1, 7)}
    pairs = [(a, b) for i in range(1, 7) for j in range(i + 1, 7)
             for a in pieces[i] for b in pieces[j]]  # fmt: skip
    checker = CollisionChecker(robot, pairs)
    for k in np.flatnonzero(ok):
        q = slow._solved[1][k]
        assert np.min(checker.distances(q)) >= fast.clearance[k] - 1e-9


# ---------------------------------------------------------------------- evaluation and runs


def test_infeasible_designs_are_recorded_with_their_reason():
    s = _delta_study(ranges={"la": (0.05, 0.3), "lb": (0.2, 0.5)}, sampler="grid", n=3)
    rows = run_study(s, workers=1).designs.rows
    reasons = [r.reason for r in rows if not r.feasible]
    assert any(r.startswith("build: ParameterError") for r in reasons)  # z_home out of reach
    assert any("breaks" in r for r in reasons) or any("TrajectoryError" in r for r in reasons)
    built = [r for r in rows if "build:" not in r.reason]
    assert all(np.isfinite(r.values[0]) for r in built)


def test_executors_give_identical_tables(tmp_path):
    s = _delta_study()
    serial = run_study(s, tmp_path / "serial.csv", workers=1)
    with ProcessExecutor(2) as ex:
        pooled = run_study(s, tmp_path / "pool.csv", executor=ex)
    a = (tmp_path / "serial.csv").read_text()
    assert a == (tmp_path / "pool.csv").read_text()
    assert len(serial.designs) == 8 and serial.best() == pooled.best()
    assert serial.designs.feasible.any()


def test_dask_local_cluster_gives_the_serial_table(tmp_path):
    from distributed import Client, LocalCluster

    s = _delta_study(n=6)
    serial = run_study(s, workers=1).designs.to_csv()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:  # fmt: skip
        res = run_study(s, tmp_path / "dask.csv", client=client)
        by_address = run_study(s, scheduler=cluster.scheduler_address)
    assert "Dask" in res.executor and "Dask" in by_address.executor
    assert (tmp_path / "dask.csv").read_text() == serial
    assert by_address.designs.to_csv() == serial


def test_files_study_file_and_rerun(tmp_path, capsys):
    s = _delta_study()
    out = tmp_path / "delta.csv"
    res = run_study(s, out, workers=1)
    paths = output_paths(out)
    assert not paths["partial"].exists()
    import pyarrow.parquet as pq

    t = pq.read_table(paths["parquet"])
    assert t.num_rows == 8 and t.schema.field("peak_effort").metadata[b"unit"] == b"N m"
    assert np.array_equal(t.column("peak_effort").to_numpy(), res.designs.column("peak_effort"),
                          equal_nan=True)  # fmt: skip
    again = Study.load(paths["study"])
    assert again.digest() == s.digest()
    assert main(["design", "--study", str(paths["study"]), "--out", str(tmp_path / "b.csv"),
                 "--workers", "1", "--json"]) == 0  # fmt: skip
    summary = json.loads(capsys.readouterr().out)
    assert summary["best"]["index"] == res.designs.rows[res.best()].index
    assert (tmp_path / "b.csv").read_text() == out.read_text()
    res.write_urdf(tmp_path / "best.urdf")
    robot = pkdyn.load(str(tmp_path / "best.urdf"))
    assert robot.nq == res.robot().nq


class _Interrupt:
    """A metric that counts calls and interrupts the study at one design (first run only)."""

    calls = 0
    stop_at: float | None = None

    @staticmethod
    def fn(robot, ctx):
        _Interrupt.calls += 1
        if _Interrupt.stop_at is not None and _Interrupt.calls == _Interrupt.stop_at:
            raise KeyboardInterrupt
        return 1.0


def test_resume_after_an_interruption(tmp_path):
    metric = Metric("counted", "-", _Interrupt.fn)
    s = _delta_study(metrics=["clavel_D", metric], sampler="lhs", n=10)
    out = tmp_path / "r.csv"
    _Interrupt.calls, _Interrupt.stop_at = 0, 7
    with pytest.raises(KeyboardInterrupt):
        run_study(s, out, workers=1)
    paths = output_paths(out)
    assert not out.exists() and not paths["parquet"].exists() and not paths["study"].exists()
    assert paths["partial"].exists()
    _Interrupt.calls, _Interrupt.stop_at = 0, None
    res = run_study(s, out, workers=1)
    built = sum(1 for r in res.designs.rows if "build:" not in r.reason)
    assert _Interrupt.calls <= built - 5  # the designs done before the interruption are kept
    _Interrupt.calls = 0
    fresh = run_study(s, tmp_path / "fresh.csv", workers=1)
    assert out.read_text() == (tmp_path / "fresh.csv").read_text()
    _Interrupt.calls = 0
    run_study(s, out, workers=1)  # complete: nothing to redo
    assert _Interrupt.calls == 0
    other = _delta_study(metrics=["clavel_D", metric], sampler="lhs", n=11)
    paths["partial"].write_text("# pkdyn design study 0123456789abcdef\n")
    with pytest.raises(StudyError, match="different study"):
        run_study(other, out, workers=1)
    assert fresh.best() is None or fresh.designs.feasible.any()


def test_nsga2_is_reproducible_and_improves(tmp_path):
    s = _delta_study(sampler="nsga2", n=8, generations=3, seed=5,
                     metrics=["peak_effort", "inv_cond_min"])  # fmt: skip
    a = run_study(s, tmp_path / "a.csv", workers=1)
    run_study(s, tmp_path / "b.csv", workers=1)
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()
    assert len(a.designs) == 24
    assert len(a.pareto()) >= 1 and a.best() is not None
    # resume from a partial file made of the first generation
    text = (tmp_path / "a.csv").read_text().splitlines(keepends=True)
    paths = output_paths(tmp_path / "c.csv")
    paths["partial"].write_text(f"# pkdyn design study {s.digest()}\n" + "".join(text[:9]))
    run_study(s, tmp_path / "c.csv", workers=1)
    assert (tmp_path / "c.csv").read_text() == (tmp_path / "a.csv").read_text()


def test_unreachable_requirement(tmp_path, capsys):
    s = _delta_study(requirement="cylinder:D=2.0,H=0.1,z=-0.4", n=4)
    with pytest.raises(StudyError, match="no design of the 4 reaches"):
        run_study(s, tmp_path / "u.csv", workers=1)


def test_clavel_chart_numeric_prism_height():
    s = clavel_chart_study(r=(0.5, 0.8), b=(1.8, 2.2), grid=2, rays=12)
    res = run_study(s, workers=1)
    h, hn = res.designs.column("clavel_h"), res.designs.column("clavel_h_numeric")
    assert res.designs.feasible.all()
    assert np.max(np.abs(h - hn)) < 1e-5  # mechanism sampled with Clavel's limits
    d, b = res.designs.column("clavel_d"), res.designs.column("clavel_b")
    assert np.allclose(d, 2 * b * np.sin(np.radians(40)))  # seed: d = 2 b sin(gamma_max)
    text = clavel_chart_text(res)
    assert "Tableau 21" in text and len(text.splitlines()) == 6


def test_parametrisation_mel():
    s = Study("gough_stewart", {"base_scale": (0.9, 1.1)}, fixed={"platform_scale": 1.0,
              "leg_scale": 1.0}, parametrisation="mel", metrics=["moving_mass"],
              sampler="grid", n=2)  # fmt: skip
    p = s.space.params([1.0])
    from pkdyn.library.gough_stewart import MEL_A

    assert np.allclose(np.array(p.A), np.array(MEL_A))
    with pytest.raises(ParameterError, match="unknown"):
        Study("gough_stewart", {"base": (0.9, 1.1)}, parametrisation="mel", metrics=["moving_mass"])


# ---------------------------------------------------------------------- command line


@pytest.mark.parametrize(
    "args, match",
    [
        (["--range", "la=0.3:0.3"], "empty"),
        (["--range", "la=0.3:0.2"], "inverted"),
        (["--range", "arm=0.1:0.2"], "unknown"),
        (["--range", "la=0.1:0.2", "--metric", "stiffness"], "unknown metric"),
        (
            [
                "--range",
                "la=0.2:0.25",
                "--require",
                "cylinder:D=3,H=0.1,z=-0.4",
                "--n",
                "2",
                "--metric",
                "contains",
            ],
            "no design",
        ),  # fmt: skip
        (
            [
                "--range",
                "la=0.2:0.25",
                "--scheduler",
                "tcp://127.0.0.1:9",
                "--timeout",
                "0.5",
                "--metric",
                "moving_mass",
            ],
            "cannot connect",
        ),  # fmt: skip
    ],
)
def test_cli_bad_input(tmp_path, capsys, args, match):
    out = tmp_path / "bad.csv"
    code = main(["design", "delta", *args, "--workers", "1", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 1
    assert err.startswith("pkdyn: error:") and len(err.strip().splitlines()) == 1
    assert match in err
    if match != "no design":
        assert not out.exists() and not output_paths(out)["parquet"].exists()
    assert not output_paths(out)["partial"].exists() or match == "no design"


def test_cli_study_with_plot_and_urdf(tmp_path, capsys):
    code = main(
        ["design", "delta", "--range", "la=0.18:0.26", "lb=0.36:0.5", "--param", "z_home=-0.35",
         "--require", CYL, "--payload", "0.5", "--cycle-time", "0.6", "--dt", "0.01",
         "--constraint", "inv_cond_min>=0.2", "--minimize", "peak_effort", "--maximize",
         "inv_cond_min", "--n", "6", "--workers", "1", "--out", str(tmp_path / "s.csv"),
         "--plot", str(tmp_path / "p.png"), "--urdf", str(tmp_path / "c.urdf")]
    )  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0 and "chosen" in out and "pkdyn size delta" in out
    assert (tmp_path / "p.png").stat().st_size > 1000
    assert "<robot" in (tmp_path / "c.urdf").read_text()


def test_committed_study_files_load():
    from pathlib import Path

    files = sorted((Path(__file__).resolve().parents[1] / "studies").glob("*.yaml"))
    assert len(files) >= 2
    for f in files:
        s = Study.load(f)
        assert s.total > 0 and s.metric_list
        assert Study.from_dict(s.as_dict()).digest() == s.digest()


def test_any_registered_family():
    """A study runs on every registered family (here: a mass swept, moving mass measured)."""
    import dataclasses

    from pkdyn.model.families import FAMILIES

    for name, fam in FAMILIES.items():
        default = fam.params()
        field = next(f.name for f in dataclasses.fields(default) if "mass" in f.name)
        m0 = getattr(default, field)
        s = Study(name, {field: (m0, 2 * m0)}, metrics=["moving_mass"], sampler="grid", n=2)
        t = run_study(s, workers=1).designs
        assert t.feasible.all(), (name, [r.reason for r in t.rows])
        mass = t.column("moving_mass")
        assert mass[1] - mass[0] >= m0 - 1e-12, name  # at least one body carries it


def test_verify_picks_a_design_that_passes_a_denser_requirement():
    """A minimum sits at the edge: the denser check may reject it, never a passing design."""
    s = _delta_study(n=16, requirement="cylinder:D=0.36,H=0.1,z=-0.35", constraints=[])
    res = run_study(s, workers=1)
    first = res.best()
    chosen = res.verify(samples=9)
    assert chosen is not None and res.best() == chosen
    dense = Requirement.parse("cylinder:D=0.36,H=0.1,z=-0.35", samples=9)
    robot = res.robot()
    assert required_check(robot, dense).fraction == 1.0
    if chosen != first:  # the sweep's best misses a sliver of the cylinder
        assert required_check(res.robot(first), dense).fraction < 1.0
    assert "9 samples per axis" in res.table()
