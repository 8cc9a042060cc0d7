"""Bad input, class by class: each case raises the documented error type, whose message names
the culprit (element, parameter, option, file) - never a traceback, a hang, a crash or a silent
wrong answer.

Classes: descriptions (numbers, physics, tree, pkdyn elements, namespace, meshes), sizes that
would exhaust memory or crash Pinocchio, builder parameters, geometric-model inputs, numeric
arguments of the analyses and of the dynamics, bounded work, simulation faults, outputs.
"""

from __future__ import annotations

import numpy as np
import pytest

import pkdyn
from pkdyn.analysis.collisions import CollisionChecker
from pkdyn.exceptions import (
    DescriptionError,
    InvalidInputError,
    OutputError,
    ParameterError,
    SimulationError,
    UnreachablePoseError,
)

# --------------------------------------------------------------------------------------------
# descriptions

NS = 'xmlns:pkdyn="urn:pkdyn:urdf:1"'
INERTIA = '<inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/>'


def doc(
    mass="1",
    inertia=("0.01", "0.01", "0.01"),
    geom='<cylinder radius="0.01" length="0.3"/>',
    axis="0 0 1",
    limit='lower="-1" upper="1" effort="5" velocity="3"',
    extra="",
    ns=NS,
    arm_parent="base",
    transmissions=1,
) -> str:
    """A pendulum (``arm`` on revolute ``j``) hinged back to the base by a closure, a pkdyn
    description; each argument is one thing a case breaks."""
    ixx, iyy, izz = inertia
    trans = "".join(
        f'<transmission name="t{k}"><type>transmission_interface/SimpleTransmission</type>'
        f'<joint name="j"/><actuator name="m{k}"><mechanicalReduction>1</mechanicalReduction>'
        "</actuator></transmission>"
        for k in range(transmissions)
    )
    return (
        f'<robot name="bad" {ns}><link name="base"/>'
        f'<link name="arm"><inertial><mass value="{mass}"/>'
        + INERTIA.format(ixx=ixx, iyy=iyy, izz=izz)
        + f"</inertial><collision><geometry>{geom}</geometry></collision></link>"
        f'<joint name="j" type="revolute"><parent link="{arm_parent}"/><child link="arm"/>'
        f'<axis xyz="{axis}"/><limit {limit}/></joint>'
        '<pkdyn:closure name="c" type="hinge"><pkdyn:frame link="arm"/>'
        '<pkdyn:frame link="base"/></pkdyn:closure>'
        '<pkdyn:platform link="arm" task="rz"/>'
        f"{trans}{extra}</robot>"
    )


def test_the_base_document_is_valid():
    robot = pkdyn.load_string(doc(), "ok.urdf", geometry=True)
    assert robot.nv == 1 and len(robot.closures) == 1 and len(robot.actuators) == 1


BAD_DESCRIPTIONS = {
    # masses
    "negative mass": (doc(mass="-1"), "link 'arm' <mass value='-1'>"),
    "zero mass": (doc(mass="0", inertia=("0", "0", "0")), "link 'arm' <mass value='0'>"),
    "nan mass": (doc(mass="nan"), "link 'arm' <mass> attribute value='nan'"),
    "text mass": (doc(mass="heavy"), "link 'arm' <mass> attribute value='heavy'"),
    # inertias
    "negative moment": (doc(inertia=("-0.01", "0.01", "0.01")), "link 'arm' <inertia>"),
    "indefinite inertia": (
        doc(inertia=("0.01", "0.01", "0.01")).replace('ixy="0"', 'ixy="0.05"'),
        "not positive semi-definite",
    ),
    "triangle violated": (doc(inertia=("0.01", "0.01", "0.05")), "triangle inequality"),
    "text inertia": (doc(inertia=("a", "0.01", "0.01")), "<inertia> attribute ixx='a'"),
    # joints
    "zero axis": (doc(axis="0 0 0"), "joint 'j' <axis xyz='0 0 0'>"),
    "inverted limits": (doc(limit='lower="1" upper="-1" effort="5" velocity="3"'), "lower='1'"),
    "negative effort": (doc(limit='lower="-1" upper="1" effort="-5" velocity="3"'), "effort"),
    # tree
    "own parent": (doc(arm_parent="arm"), "joint 'j'"),
    "two parents": (
        doc(
            extra='<link name="b2"/><joint name="j2" type="fixed"><parent link="b2"/>'
            '<child link="arm"/></joint>'
        ),
        "joint 'j2'",
    ),
    "cycle": (
        doc(
            extra='<link name="x"/><link name="y"/>'
            '<joint name="jx" type="fixed"><parent link="y"/><child link="x"/></joint>'
            '<joint name="jy" type="fixed"><parent link="x"/><child link="y"/></joint>'
        ),
        "cycle",
    ),
    "unknown parent link": (doc(arm_parent="nowhere"), "joint 'j' <parent link='nowhere'>"),
    # pkdyn elements
    "two transmissions on one joint": (doc(transmissions=2), "transmission 't1'"),
    "duplicate pkdyn:joint": (
        doc(
            extra='<pkdyn:joint name="j" type="spherical"/><pkdyn:joint name="j" type="spherical"/>'
        ),
        "pkdyn:joint 'j'",
    ),
    "two platforms": (doc(extra='<pkdyn:platform link="base"/>'), "<pkdyn:platform>"),
    "unknown pkdyn element": (doc(extra='<pkdyn:closur name="x"/>'), "<pkdyn:closur>"),
    "mistyped namespace": (doc(ns='xmlns:pkdyn="urn:pkdyn:urdf:2"'), "urn:pkdyn:urdf:2"),
    "misspelt namespace": (doc(ns='xmlns:pkdyn="urn:pkydn:urdf:1"'), "urn:pkydn:urdf:1"),
}


@pytest.mark.parametrize("text, culprit", BAD_DESCRIPTIONS.values(), ids=list(BAD_DESCRIPTIONS))
def test_bad_descriptions_name_the_element(text, culprit):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, "bad.urdf", geometry=True, package_dirs=[])
    message = str(err.value)
    assert culprit in message, message
    assert message.startswith("bad.urdf: ") and "\n" not in message


MALFORMED_SHAPES = {
    # geometry sizes: the shape is left out with a warning naming its line (as a missing mesh)
    "nan radius": ('<sphere radius="nan"/>', "<sphere> attribute radius='nan'"),
    "inf length": ('<cylinder radius="0.01" length="inf"/>', "length='inf'"),
    "negative box": ('<box size="0.1 -0.2 0.1"/>', "<box> attribute size="),
    "zero radius": ('<sphere radius="0"/>', "<sphere> attribute radius='0'"),
    "box two sizes": ('<box size="0.1 0.2"/>', "expected 3 numbers"),
    "zero mesh scale": ('<mesh filename="x.stl" scale="0 1 1"/>', "<mesh> attribute scale"),
    "typo in a radius": ("<sphere radius='0.1\"'/>", "<sphere> attribute radius='0.1\"'"),
}


@pytest.mark.parametrize("geom, culprit", MALFORMED_SHAPES.values(), ids=list(MALFORMED_SHAPES))
def test_malformed_shapes_are_left_out_with_a_warning_naming_them(geom, culprit):
    """A typo in one shape costs that shape, not the robot; collision checks then say so."""
    text = doc(geom=geom)
    with pytest.warns(UserWarning, match="<collision> \\(line 1\\)") as caught:
        robot = pkdyn.load_string(text, "bad.urdf", geometry=True, package_dirs=[])
    assert any(culprit in str(w.message) for w in caught), [str(w.message) for w in caught]
    assert len(robot.collision_model.geometryObjects) == 0
    assert robot.dropped_collisions and "link 'arm'" in robot.dropped_collisions[0]
    with pytest.raises(pkdyn.PkdynError, match="left out when it was loaded"):
        CollisionChecker(robot)
    visual = text.replace("<collision>", "<visual>").replace("</collision>", "</visual>")
    with pytest.warns(UserWarning, match="<visual> \\(line 1\\).*visual shape is left out"):
        robot = pkdyn.load_string(visual, "bad.urdf", geometry=True, package_dirs=[])
    assert robot.dropped_collisions == () and len(robot.visual_model.geometryObjects) == 0


def test_plain_urdf_keeps_zero_masses_and_warns_for_impossible_inertias():
    """ROS descriptions give massless frames mass 0 and often rounded inertias: they load."""
    text = doc(mass="0", ns="").replace("<pkdyn:", "<x_").replace("</pkdyn:", "</x_")
    with pytest.raises(DescriptionError, match="<x_closure name='c'> \\(line 1\\)"):
        pkdyn.load_string(text, "plain.urdf", geometry=False)  # a loop pkdyn cannot read
    ignore = ("x_closure", "x_platform")
    with pytest.warns(UserWarning, match="rotational inertia and no mass.*'arm'"):
        robot = pkdyn.load_string(text, "plain.urdf", geometry=False, ignore_elements=ignore)
    assert robot.closures == ()
    odd = doc(inertia=("0.01", "0.01", "0.05"), ns="")
    odd = odd.replace("<pkdyn:", "<x_").replace("</pkdyn:", "</x_")
    with pytest.warns(UserWarning, match="link 'arm'.*triangle inequality"):
        pkdyn.load_string(odd, "plain.urdf", geometry=False, ignore_elements=ignore)


def chain(n: int, parent=lambda i: f"l{i - 1}", jtype="revolute") -> str:
    links = "".join(
        f'<link name="l{i}"><inertial><mass value="1"/>'
        + INERTIA.format(ixx="0.01", iyy="0.01", izz="0.01")
        + "</inertial></link>"
        for i in range(1, n + 1)
    )
    joints = "".join(
        f'<joint name="j{i}" type="{jtype}"><parent link="{parent(i)}"/><child link="l{i}"/>'
        '<origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(1, n + 1)
    )
    return f'<robot name="chain"><link name="l0"/>{links}{joints}</robot>'


@pytest.mark.parametrize(
    "n, parent, culprit",
    [
        (5000, lambda i: f"l{i - 1}", "deeper than 1000"),  # segfaulted inside Pinocchio
        (1500, lambda i: f"l{i - 1}", "deeper than 1000"),
        (600, lambda i: "l0", "nv = 600"),  # createData would need ~14 GB
        (300, lambda i: f"l{i - 1}", "nv = 300"),
    ],
    ids=["chain 5000", "chain 1500", "star 600", "chain 300"],
)
def test_models_too_large_for_pinocchio_are_refused_before_it_runs(n, parent, culprit):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(chain(n, parent), "big.urdf", geometry=False)
    assert culprit in str(err.value) and "big.urdf" in str(err.value)


def test_a_large_but_reasonable_chain_loads():
    robot = pkdyn.load_string(chain(120), "chain.urdf", geometry=False)
    assert robot.nv == 120


# --------------------------------------------------------------------------------------------
# builder parameters

BAD_PARAMETERS = [
    ("delta", {"la": -0.2}, "la"),
    ("delta", {"lb": "long"}, "lb"),
    ("delta", {"z_home": 0.5}, "z_home"),  # above the base
    ("delta", {"z_home": -3.0}, "z_home"),  # out of reach
    ("delta", {"arms": 5}, "arms"),
    ("five_bar", {"y_home": 0.9}, "y_home"),
    ("five_bar", {"q_max": -3.0}, "y_home"),  # no home within the limits
    ("tripod", {"stroke_max": 0.62}, "nacelle_height"),
    ("gough_stewart", {"rho_min": "(0.1,)"}, "rho_min"),
    ("planar_3rrr", {"l1": 0.01, "l2": 0.01}, "x_home"),
]


@pytest.mark.parametrize("family, over, culprit", BAD_PARAMETERS)
def test_bad_parameters_name_the_parameter(family, over, culprit):
    with pytest.raises(ParameterError) as err:
        pkdyn.load(family, geometry=False, **over)
    assert f"parameter '{culprit}'" in str(err.value) and family in str(err.value)


# --------------------------------------------------------------------------------------------
# geometric models and analyses


@pytest.fixture(scope="module")
def delta():
    return pkdyn.load("delta", geometry=False)


@pytest.mark.parametrize(
    "call, error, culprit",
    [
        (lambda r: pkdyn.inverse_geometry(r, [0, 0, -0.4, 0, 0, 0.2]), UnreachablePoseError, "yaw"),
        (lambda r: pkdyn.inverse_geometry(r, [0, 0]), InvalidInputError, "pose"),
        (lambda r: pkdyn.inverse_geometry(r, [0, np.nan, -0.4]), InvalidInputError, "pose"),
        (lambda r: pkdyn.inverse_geometry(r, [0, 0, 0.2]), UnreachablePoseError, "0.2"),
        (lambda r: pkdyn.forward_geometry(r, [0.1, 0.2]), InvalidInputError, "actuat"),
        (lambda r: pkdyn.forward_geometry(r, [0, np.inf, 0]), InvalidInputError, "actuat"),
        (lambda r: pkdyn.project(r, np.zeros(3)), InvalidInputError, "q"),
    ],
    ids=["yaw", "short pose", "nan pose", "above base", "2 of 3", "inf", "short q"],
)
def test_bad_geometric_inputs(delta, call, error, culprit):
    with pytest.raises(error) as err:
        call(delta)
    assert culprit in str(err.value)


def test_statics_refuses_an_overflowing_wrench(delta):
    from pkdyn.analysis.statics import static_equilibrium

    q = pkdyn.inverse_geometry(delta, [0, 0, -0.4]).q
    for F in ([1e308, 0, 0], [0, 0, -1e200]):
        with pytest.raises(InvalidInputError, match="F: wrench"):
            static_equilibrium(delta, q, F)


# --------------------------------------------------------------------------------------------
# dynamics: numeric arguments, bounded work, faults


@pytest.mark.parametrize(
    "options, culprit",
    [
        ({"dt": 10.0}, "dt: 10 s samples"),
        ({"dt": 0.03}, "dt: 0.03 s samples"),  # the 0.5 s cycle's 45 ms moves
        ({"cycles": 0}, "cycles"),
        ({"cycles": -1}, "cycles"),
        ({"cycles": 2.5}, "cycles"),
        ({"cycles": 10**6}, "cycles"),
        ({"dt": 1e-9}, "dt"),
        ({"dt": -1e-3}, "dt"),
    ],
)
def test_trajectory_options_are_checked(delta, options, culprit):  # noqa: D103
    from pkdyn.dynamics.trajectory import named_task

    with pytest.raises(InvalidInputError) as err:
        named_task(delta, "adept", **options)
    assert culprit in str(err.value)


def test_coarse_sampling_warns(delta, monkeypatch):
    from pkdyn.dynamics import trajectory
    from pkdyn.dynamics.trajectory import named_task

    monkeypatch.setattr(trajectory, "_WARNED", [])  # once per process
    with pytest.warns(UserWarning, match="may be underestimated"):
        named_task(delta, "adept", dt=0.01)


@pytest.mark.parametrize(
    "kwargs, error, culprit",
    [
        ({"duration": 1.0, "dt": 5.0}, InvalidInputError, "longer than the duration"),
        ({"duration": 1e5, "dt": 1e-5}, InvalidInputError, "steps"),
        ({"duration": -1.0, "dt": 1e-3}, InvalidInputError, "duration"),
        ({"duration": 0.1, "dt": 1e-3, "viscous": -0.5}, InvalidInputError, "viscous"),
        ({"duration": 0.1, "dt": 1e-3, "coulomb": [-1.0] * 4}, InvalidInputError, "coulomb"),
        (
            {"duration": 0.2, "dt": 1e-3, "torque": lambda t, q, v: [1e7, -1e7]},
            SimulationError,
            "blows up",
        ),
        (
            {"duration": 0.1, "dt": 1e-3, "torque": lambda t, q, v: [np.nan, 0.0]},
            SimulationError,
            "torque function",
        ),
    ],
    ids=[
        "dt > duration",
        "1e10 steps",
        "negative duration",
        "viscous",
        "coulomb",
        "blow-up",
        "nan",
    ],
)
def test_simulation_inputs_and_faults(kwargs, error, culprit):
    from pkdyn.dynamics import simulate

    robot = pkdyn.load("five_bar", geometry=False)
    with pytest.raises(error) as err:
        simulate(robot, **kwargs)
    assert culprit in str(err.value)


def test_adaptive_step_count_is_bounded():
    """A state the error control cannot follow stops with a clear error, not a hang."""
    from pkdyn.dynamics.actuation import actuation
    from solvers import ForwardDynamics, IntegrationError

    robot = pkdyn.load("five_bar", geometry=False)
    fd = ForwardDynamics(
        robot.model, list(robot.constraint_models), actuation(robot), max_substeps=5, atol=1e-16
    )
    with pytest.raises(IntegrationError, match="more than 5 substeps"):
        fd.simulate(robot.q_home, np.full(robot.nv, 3.0), 0.2, 0.05)  # moving, 1e-16 tolerance


def test_zero_energy_run_has_no_drift():
    from pkdyn.dynamics import simulate

    robot = pkdyn.load("five_bar", geometry=False)
    robot.model.gravity.linear[:] = 0.0  # nothing moves: the energy is round-off
    res = simulate(robot, 0.05, 1e-3)
    assert res.energy_drift() < 1e-6


@pytest.mark.parametrize(
    "call, culprit",
    [
        (lambda r: _ws(r, samples=1000), "1000 x 1000 x 1000 grid"),
        (lambda r: _ws(r, step=1e-5), "grid is"),
        (lambda r: _ws(r, samples=1), "samples"),
    ],
    ids=["1e9 samples", "tiny step", "one sample"],
)
def test_workspace_grids_are_bounded(call, culprit):
    robot = pkdyn.load("gough_stewart")
    with pytest.raises(InvalidInputError) as err:
        call(robot)
    assert culprit in str(err.value)


def _ws(robot, **kw):
    from pkdyn.workspace import translation_workspace

    return translation_workspace(robot, progress=False, **kw)


def test_orientation_and_clavel_samplings_are_bounded():
    from pkdyn.workspace import clavel_numeric, orientation_workspace

    robot = pkdyn.load("gough_stewart")
    with pytest.raises(InvalidInputError, match="orientations"):
        orientation_workspace(robot, n1=10_000, n2=10_000, progress=False)
    with pytest.raises(InvalidInputError, match="fewer rays"):
        clavel_numeric(pkdyn.load("delta", geometry=False).params, 0.7, 0.5, rays=10**7)


# --------------------------------------------------------------------------------------------
# outputs


@pytest.mark.parametrize(
    "name, culprit",
    [("plot", "no file extension"), ("plot.xyz", "unknown figure format '.xyz'")],
)
def test_figures_need_a_known_format(tmp_path, name, culprit):
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from pkdyn.plotting._save import save_figure

    with pytest.raises(OutputError) as err:
        save_figure(Figure(), tmp_path / name, dpi=50)
    assert culprit in str(err.value) and str(tmp_path / name) in str(err.value)
    assert list(tmp_path.iterdir()) == []


def test_an_interrupted_write_keeps_the_previous_file(tmp_path):
    from pkdyn.files import atomic_write

    target = tmp_path / "out.csv"
    target.write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(target) as fh:
            fh.write("half a new fi")
            raise KeyboardInterrupt
    assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]
