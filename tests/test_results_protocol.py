"""One way out: every result type derives from Result, with to_json, table and (some) plot.

Every subclass of :class:`pkdyn.results.Result` reachable from the public API is listed (every
module of ``pkdyn`` imported); each defines ``to_json`` and ``table``; each of the analysis,
dynamics, workspace, design, tripod and model results has an instance made here, whose
``to_json()`` is JSON (``allow_nan=False``) and whose ``table()`` is text with a unit on its
figures; the results with a picture draw it through ``plot()``; the old serialiser names warn.
"""

from __future__ import annotations

import importlib
import json
import pkgutil
import re
import warnings

import numpy as np
import pytest

import pkdyn
from pkdyn.results import Result, plotter_for

OWN = ("analysis", "dynamics", "workspace", "design", "tripod", "model")
"""Packages whose results this file makes instances of (others: their own tests)."""

UNIT = re.compile(
    r"[\d\]]\s*(?:[pnumkMGT]?(?:m|N|J|W|s|g|Hz|rad|sr)\b|N m|kg|%|deg|rpm|m\^\d|rad/s|m/s)"
)
"""A figure followed by a unit."""

HEADED = re.compile(
    r"\[(?:[pnumkMGT]?(?:m|N|J|W|s|kg|rad|Hz)|N m|rad/s|m/s)\b[^\]]*\]|dimensionless"
)
"""A unit in a column header (``x [m]``), or figures declared dimensionless."""

DIMENSIONLESS = {"MobilityResult"}
"""Results whose figures are counts (no unit to show)."""


def _all_results() -> list[type]:
    for mod in pkgutil.walk_packages(pkdyn.__path__, "pkdyn."):
        if mod.name.startswith(("pkdyn.viewer", "pkdyn.cli.__main__", "pkdyn.__main__")):
            continue
        importlib.import_module(mod.name)
    out, todo = [], list(Result.__subclasses__())
    while todo:
        cls = todo.pop()
        if cls not in out:
            out.append(cls)
            todo.extend(cls.__subclasses__())
    return sorted(out, key=lambda c: f"{c.__module__}.{c.__qualname__}")


RESULTS = _all_results()


@pytest.mark.parametrize("cls", RESULTS, ids=lambda c: c.__qualname__)
def test_every_result_type_defines_to_json_and_table(cls):
    assert cls.to_json is not Result.to_json, f"{cls.__qualname__}.to_json"
    assert cls.table is not Result.table, f"{cls.__qualname__}.table"


# ---------------------------------------------------------------------- instances


@pytest.fixture(scope="module")
def delta():
    return pkdyn.load("delta")


@pytest.fixture(scope="module")
def delta_geometry():
    return pkdyn.load("delta", geometry=True)


@pytest.fixture(scope="module")
def gs():
    return pkdyn.load("gough_stewart", geometry=True)


@pytest.fixture(scope="module")
def adept(delta):
    from pkdyn.dynamics.trajectory import named_trajectory

    return named_trajectory(delta, "adept", dt=0.005)


@pytest.fixture(scope="module")
def scenario():
    from pkdyn.tripod.analysis import run_scenario
    from pkdyn.tripod.scenario import WalkPlan

    robot = pkdyn.load("tripod", geometry=True)
    plan = WalkPlan(cycles=1, machining=None, dt=0.1)
    return run_scenario(robot, plan, stride=5, progress=False)


def _clearances():
    from pkdyn.tripod.clearance import Clearances

    n = 3
    return Clearances(
        leg_to_leg=np.array([0.03, 0.02, 0.025]),
        leg_to_nacelle=np.array([0.05, 0.04, 0.045]),
        stroke_margin=np.array([0.1, 0.09, 0.08]),
        singularity=np.array([0.2, 0.19, 0.18]),
        lengths=np.full((n, 6), 0.5),
        closest=[("branch1_cylL", "branch2_cylR")] * n,
        per_leg_to_nacelle=np.full((n, 12), 0.05),
    )


def _make(name, request):  # noqa: C901 (one branch per result type)
    fx = request.getfixturevalue
    if name == "GeometryResult":
        return pkdyn.forward_geometry(fx("delta"), [0.1, -0.36, -0.5])
    if name == "RobotInfo":
        from pkdyn.model.info import robot_info

        return robot_info(fx("delta"))
    if name == "MobilityResult":
        from pkdyn.analysis.mobility import mobility

        return mobility(pkdyn.load("five_bar"))
    if name == "KinematicModels":
        from pkdyn.analysis.kinematics import kinematic_models

        return kinematic_models(fx("delta"), fx("delta").q_home)
    if name == "SingularityReport":
        from pkdyn.analysis.singularity import classify

        return classify(fx("delta"), fx("delta").q_home)
    if name in ("StaticsResult", "Reaction"):
        from pkdyn.analysis.statics import static_equilibrium

        res = static_equilibrium(fx("delta"), fx("delta").q_home, [0, 0, -50], gravity=True)
        return res if name == "StaticsResult" else next(iter(res.reactions.values()))
    if name in ("CollisionReport", "PairDistance"):
        from pkdyn.analysis.collisions import distance_report

        robot = fx("delta_geometry")
        rep = distance_report(robot, robot.q_home)
        return rep if name == "CollisionReport" else rep.pairs[0]
    if name == "Dexterity":
        from pkdyn.analysis.dexterity import dexterity

        return dexterity(fx("delta"), fx("delta").q_home)
    if name == "DexterityMap":
        from pkdyn.analysis.dexterity import dexterity_map

        return dexterity_map(fx("delta"), [[0, 0, -0.3], [0.05, 0, -0.3], [9, 9, 9]])
    if name in ("ConditioningMap", "Conditioning"):
        from pkdyn.analysis.maps import delta_map

        m = delta_map(fx("delta").params, np.linspace(-0.1, 0.1, 5), np.linspace(-0.1, 0.1, 4),
                      -0.3)  # fmt: skip
        return m if name == "ConditioningMap" else m.data
    if name == "MapSamples":
        robot = pkdyn.load("five_bar")
        m = pkdyn.actuation_map(robot, ["distal1", "distal2"])
        qa0 = robot.q_home[m.act_q]
        return m.from_actuators(qa0 + np.array([[0.0, 0.0], [0.05, -0.05]]))
    if name in ("TranslationWorkspace",):
        from pkdyn.workspace.translation import translation_workspace

        return translation_workspace(fx("delta_geometry"), samples=7, progress=False)
    if name == "OrientationWorkspace":
        from pkdyn.workspace.orientation import orientation_workspace

        return orientation_workspace(fx("gs"), limits=("stroke",), n1=8, n2=12, progress=False)
    if name == "MelStudy":
        from pkdyn.workspace.orientation import MelStudy, orientation_workspace

        ow = orientation_workspace(fx("gs"), limits=("stroke",), n1=8, n2=12, progress=False)
        return MelStudy({"strokes": ow})
    if name in ("ClavelFigures", "ClavelComparison"):
        from pkdyn.workspace.clavel import ClavelComparison, clavel_closed_form

        cf = clavel_closed_form(fx("delta").params)
        return cf if name == "ClavelFigures" else ClavelComparison(cf, cf, 2 * cf.V, 0.7, 0.5)
    if name == "SimulationResult":
        from pkdyn.dynamics import simulate

        return simulate(pkdyn.load("five_bar"), 0.02, 1e-3, v0=np.array([1.0, -1.8, -1.0, 1.8]))
    if name in ("SizingResult", "ActuatorSizing", "EffortTrajectory"):
        from pkdyn.dynamics.sizing import size

        res = size(fx("delta"), fx("adept"), payload=0.5)
        return {"SizingResult": res, "ActuatorSizing": res.actuators[0],
                "EffortTrajectory": res.efforts}[name]  # fmt: skip
    if name in ("JointTrajectory", "TaskTrajectory"):
        return fx("adept") if name == "JointTrajectory" else fx("adept").task
    if name == "ActuatorTrajectory":
        from pkdyn.dynamics.delta import delta_inverse_dynamics

        return delta_inverse_dynamics(fx("delta"), fx("adept").task)
    if name == "FastestResult":
        from pkdyn.dynamics.fastest import fastest_trajectory
        from pkdyn.dynamics.trajectory import named_task

        task = named_task(fx("delta"), "adept", cycle_time=1.0, dt=0.02)
        return fastest_trajectory(fx("delta"), task)
    if name in ("Selection", "Candidate", "Check"):
        from pkdyn.dynamics.motors import load_catalog
        from pkdyn.dynamics.selection import select_drives

        sel = select_drives(fx("delta"), fx("adept"), load_catalog("example"))
        cand = sel.actuators[0].feasible[0]
        return {"Selection": sel, "Candidate": cand, "Check": cand.checks[0]}[name]
    if name == "BalancingResult":
        import pinocchio as pin

        from pkdyn.dynamics.balancing import balance_springs
        from pkdyn.model.description import FrameRef, SpringSpec
        from tests.test_balancing import ARM, D, H  # the pendulum of the balancing tests

        robot = pkdyn.load_string(ARM, "arm")
        spring = SpringSpec(
            "post",
            FrameRef("base", pin.SE3(np.eye(3), np.array([0.0, 0.0, H]))),
            FrameRef("arm", pin.SE3(np.eye(3), np.array([D, 0.0, 0.0]))),
            0.0,
        )
        return balance_springs(robot, [spring], np.linspace(-1.0, 1.0, 7)[:, None])
    if name == "SizingGrid":
        from pkdyn.dynamics.sizing_grid import sizing_grid

        return sizing_grid(fx("delta"), [0.5, 1.0], [0.0, 1.0], dt=0.01, progress=False)
    if name == "FastestGrid":
        from pkdyn.dynamics.fastest_grid import fastest_grid
        from pkdyn.dynamics.trajectory import named_task

        path = named_task(fx("delta"), "adept", cycle_time=1.0, dt=0.02)
        return fastest_grid(fx("delta"), path, [0.0, 1.0], progress=False)
    if name == "StudyResult":
        from pkdyn.design.run import run_study
        from pkdyn.design.study import Study

        study = Study("delta", {"la": (0.2, 0.3)}, metrics=["moving_mass"], n=2, seed=0)
        return run_study(study, workers=1, progress=False)
    if name in ("ScenarioReport", "PhaseReport"):
        rep = fx("scenario")
        return rep if name == "ScenarioReport" else rep.reports[0]
    if name == "Clearances":
        return _clearances()
    if name == "SwingSolution":
        from pkdyn.tripod.redundancy import SwingSolution

        n = 3
        return SwingSolution(
            branch=1,
            joints=("branch1_qL", "branch1_qR"),
            t=np.linspace(0, 1, n),
            r=np.full((n, 2), 0.5),
            r_d=np.zeros((n, 2)),
            r_dd=np.zeros((n, 2)),
            nacelle_R=np.tile(np.eye(3), (n, 1, 1)),
            nacelle_p=np.zeros((n, 3)),
            baseline=_clearances(),
            clearances=_clearances(),
            objective_baseline=0.02,
            objective=0.025,
            optimised=True,
            iterations=4,
            coefficients=np.zeros(2),
        )
    if name == "Comparison":
        from pkdyn.tripod.compare import Comparison, ComparisonRow

        rep = fx("scenario")
        rows = [
            ComparisonRow("tripod", "plane", 3, 40.0, 5.0, rep),
            ComparisonRow("walker", "plane", 4, 50.0, 5.0, None, "a reason"),
        ]
        return Comparison(rows)
    if name == "XfkmbResult":
        import pinocchio as pin

        from pkdyn.tripod.xfkmb import XfkmbResult

        return XfkmbResult(pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.6])), np.full(6, 0.5),
                           1e-13, 12)  # fmt: skip
    return None


def _own(cls) -> bool:
    return cls.__module__.split(".")[1] in OWN


OWN_RESULTS = [c for c in RESULTS if _own(c)]


@pytest.mark.parametrize("cls", OWN_RESULTS, ids=lambda c: c.__qualname__)
def test_results_are_json_and_tables_with_units(request, cls):
    res = _make(cls.__name__, request)
    assert res is not None, f"make an instance of {cls.__qualname__} here"
    assert isinstance(res, cls)
    data = res.to_json()
    assert isinstance(data, dict)
    json.dumps(data, allow_nan=False)  # finite numbers or None only
    text = res.table()
    assert isinstance(text, str) and text.strip()
    assert "-0 " not in text and "[-0," not in text and "nan" not in text.lower()
    if cls.__name__ not in DIMENSIONLESS:
        assert UNIT.search(text) or HEADED.search(text), text


PLOTTED = [
    "TranslationWorkspace",
    "OrientationWorkspace",
    "ClavelComparison",
    "SimulationResult",
    "SizingResult",
    "Selection",
    "StudyResult",
    "ScenarioReport",
    "ConditioningMap",
    "SizingGrid",
    "FastestGrid",
]


@pytest.mark.parametrize("name", PLOTTED)
def test_results_with_a_picture_draw_it(request, tmp_path, name):
    res = _make(name, request)
    assert plotter_for(type(res)) is not None
    path = tmp_path / f"{name}.png"
    fig = res.plot(path)
    assert fig is not None and path.stat().st_size > 1000


@pytest.mark.parametrize(
    "name, old, new",
    [
        ("MobilityResult", "as_json", "to_json"),
        ("CollisionReport", "as_json", "to_json"),
        ("TranslationWorkspace", "as_json", "to_json"),
        ("ClavelFigures", "as_json", "to_json"),
        ("SizingResult", "as_json", "to_json"),
        ("StudyResult", "summary", "table"),
        ("Clearances", "summary", "to_json"),
    ],
)
def test_old_serialiser_names_warn_and_agree(request, name, old, new):
    res = _make(name, request)
    with pytest.warns(DeprecationWarning, match=f"{old}.. is deprecated"):
        got = getattr(res, old)()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert got == getattr(res, new)()


def test_the_designs_table_moved_to_designs(request):
    res = _make("StudyResult", request)
    with pytest.warns(DeprecationWarning, match="StudyResult.designs"):
        rows = res.table.rows
    assert rows == res.designs.rows and len(res.designs) == 2
