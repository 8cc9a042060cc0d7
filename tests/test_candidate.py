"""Family candidates written in place (pkdyn.model.candidate) against the URDF build, bit for bit.

The reference is the robot ``pkdyn.load(family, **params)`` builds (the builder's URDF text,
parsed by Pinocchio and pkdyn, assembled): the in-place candidate must give the same numbers
in every field its metrics could read (model, geometry, constraints, description, home).
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.exceptions import PkdynError
from pkdyn.model.candidate import CandidateBuilder, difference, urdf_pose
from pkdyn.model.families import FAMILIES
from pkdyn.model.formats.urdf_writer import UrdfWriter, _v

pytestmark = pytest.mark.filterwarnings("ignore")


def _random_params(name: str, rng: np.random.Generator, **fixed: object) -> object:
    """The family's defaults with every non-zero float scaled by U(0.85, 1.15), valid ones."""
    base = dataclasses.replace(FAMILIES[name].params(), **fixed)
    for _ in range(100):
        kw = {
            f.name: getattr(base, f.name) * rng.uniform(0.85, 1.15)
            for f in dataclasses.fields(base)
            if type(getattr(base, f.name)) is float and getattr(base, f.name) != 0.0
        }
        try:
            return dataclasses.replace(base, **kw)
        except PkdynError:
            continue
    raise AssertionError(f"no valid random parameters for {name}")


def _reference(name: str, params: object) -> pkdyn.Robot:
    """The robot of the URDF path (a fresh builder: its first candidate is built from text)."""
    return CandidateBuilder(name, collision=True).robot(params)


@pytest.mark.parametrize("name", list(FAMILIES))
def test_in_place_equals_urdf_build(name: str) -> None:
    rng = np.random.default_rng(sum(map(ord, name)))
    builder = CandidateBuilder(name, collision=True)
    for _ in range(5):
        p = _random_params(name, rng)
        robot = builder.robot(p)
        assert difference(robot, _reference(name, p)) == ""
    assert builder.written == 4 and builder.built == 1  # one structure: built once


@pytest.mark.parametrize(
    ("name", "structure"),
    [
        ("delta", {"parallelogram": "hinge"}),
        ("delta", {"arms": 4}),
        ("delta", {"rotor_inertia": 1e-5, "efficiency": 0.9}),
        ("tripod", {"branches": 4}),
    ],
)
def test_other_structures(name: str, structure: dict[str, object]) -> None:
    rng = np.random.default_rng(7)
    builder = CandidateBuilder(name, collision=True)
    for _ in range(3):
        p = _random_params(name, rng, **structure)
        assert difference(builder.robot(p), _reference(name, p)) == ""
    assert builder.written == 2


def test_structure_change_makes_a_template_of_its_own() -> None:
    rng = np.random.default_rng(3)
    builder = CandidateBuilder("delta")
    for parallelogram in ("ball", "hinge", "ball", "hinge"):
        p = _random_params("delta", rng, parallelogram=parallelogram)
        assert difference(builder.robot(p), _reference_without_geometry("delta", p)) == ""
    assert (builder.built, builder.written) == (2, 2)


def _reference_without_geometry(name: str, params: object) -> pkdyn.Robot:
    return CandidateBuilder(name).robot(params)


def test_universal_joints() -> None:
    # the bars' first axes are aligned with a frame axis and their second constant: in place
    rng = np.random.default_rng(4)
    builder = CandidateBuilder("delta", collision=True)
    for _ in range(2):
        p = _random_params("delta", rng, bar_joint="universal")
        for _ in range(2):  # (the second time in place: its axes make the same skeleton)
            assert difference(builder.robot(p), _reference("delta", p)) == ""
    assert builder.written >= 2


def test_joint_models_with_numbers_have_no_skeleton() -> None:
    # an unaligned revolute axis is a number of its joint model: the URDF path every time
    from pkdyn.model.candidate import _skeleton

    w = UrdfWriter("r")
    w.link("a")
    w.link("b", 1.0, (0, 0, 0), np.eye(3))
    w.joint("j", "revolute", "a", "b", axis=(0.6, 0.8, 0.0), limit=(-1, 1, 1, 1))
    assert _skeleton(w.records) is None
    w.records[-1].args["axis"] = (0.0, 1.0, 0.0)
    assert _skeleton(w.records) is not None


def test_candidate_is_what_load_builds() -> None:
    p = FAMILIES["five_bar"].params(l1=0.12, l2=0.21)
    builder = CandidateBuilder("five_bar")
    builder.robot(FAMILIES["five_bar"].params())
    robot = builder.robot(p)
    assert builder.written == 1
    ref = pkdyn.load("five_bar", geometry=False, l1=0.12, l2=0.21)
    assert difference(robot, ref) == ""


@pytest.mark.parametrize(
    ("name", "field", "scale"),
    [
        ("delta", "ra", 3.0),  # a home outside the arm limits: JointLimitError
        ("planar_3rrr", "l1", 0.3),  # the builder writes NaN: DescriptionError naming it
        ("four_bar_knee", "r1", 0.05),  # a NaN home: InvalidInputError
    ],
)
def test_errors_are_those_of_load(name: str, field: str, scale: float) -> None:
    # parameters past their own validation (set on a valid instance): the URDF path's error
    fam = FAMILIES[name]
    builder = CandidateBuilder(name)
    builder.robot(fam.params())
    p = fam.params()
    object.__setattr__(p, field, getattr(p, field) * scale)
    with pytest.raises(PkdynError) as ref:
        _reference_without_geometry(name, p)
    with pytest.raises(type(ref.value)) as info:
        builder.robot(p)
    assert str(info.value) == str(ref.value)


def test_urdf_pose_is_the_parser_s() -> None:
    rng = np.random.default_rng(0)
    w = UrdfWriter("r")
    w.link("l0")
    poses = []
    for k in range(300):
        xyz, rpy = rng.uniform(-1.0, 1.0, 3), rng.uniform(-4.0, 4.0, 3)
        if k % 3 == 0:
            rpy[rng.integers(3)] = 0.0
        poses.append((xyz, rpy))
        w.link(f"l{k + 1}", 1.0, (0, 0, 0), np.eye(3))
        w.joint(f"j{k}", "revolute", "l0", f"l{k + 1}", xyz, rpy, (0, 0, 1), (-1, 1, 1, 1))
    model = pin.buildModelFromXML(w.to_string())
    for k, (xyz, rpy) in enumerate(poses):
        M = model.jointPlacements[model.getJointId(f"j{k}")]
        E = urdf_pose(xyz, rpy)
        assert np.array_equal(M.rotation, E.rotation), _v(rpy)
        assert np.array_equal(M.translation, E.translation)


def test_layout_renders_build_urdf() -> None:
    for fam in FAMILIES.values():
        p = fam.params()
        text = fam.layout(p).to_string()
        body = fam.build_urdf(p)
        # the same elements; build_urdf adds its generated-by comment
        assert text.split("<robot", 1)[1] == body.split("<robot", 1)[1]


def test_design_rows_do_not_depend_on_the_path() -> None:
    from pkdyn.design import Study
    from pkdyn.design.evaluate import evaluate_design
    from pkdyn.design.table import Table

    def study() -> Study:
        return Study(
            "delta",
            {"la": (0.15, 0.35), "lb": (0.30, 0.70), "ra": (0.08, 0.22)},
            fixed={"z_home": -0.35},
            metrics=["clavel", "required", "sizing", "moving_mass"],
            requirement="cylinder:D=0.4,H=0.1,z=-0.35",
            trajectory="adept",
            trajectory_options={"cycle_time": 0.5},
            payload=1.0,
            n=24,
            seed=5,
        )

    fast = study()
    X = fast.designs()
    rows = [evaluate_design(fast, i, x) for i, x in enumerate(X)]
    # each design on a fresh study: its first candidate, built by the URDF path
    ref = [evaluate_design(study(), i, x) for i, x in enumerate(X)]
    assert [Table.csv_fields(r) for r in rows] == [Table.csv_fields(r) for r in ref]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert sum(r.feasible for r in rows) > 0


@pytest.mark.parametrize("name", list(FAMILIES))
def test_moved_constraint_layer_is_a_new_one(name: str) -> None:
    """A candidate's constraint layer (the template's moved in place where its rows allow) has
    the rows of the set made anew from its description, bit for bit, at random configurations;
    the candidates of a family whose rows do not depend on the placements share one set."""
    from pkdyn.model.build import constraint_set

    rng = np.random.default_rng(7 + sum(map(ord, name)))
    builder = CandidateBuilder(name, collision=True)
    layers = set()
    for _ in range(4):
        robot = builder.robot(_random_params(name, rng))
        layers.add(id(robot.constraints))
        fresh = constraint_set(
            robot.model, robot.description.closures, robot.description.couplings, robot.source
        )
        assert list(fresh.names) == list(robot.constraints.names)
        for _ in range(3):
            q = pin.randomConfiguration(
                robot.model, -np.ones(robot.model.nq), np.ones(robot.model.nq)
            )
            r_got, J_got = robot.constraints.residual_and_jacobian(robot.data, q)
            d2 = robot.model.createData()
            r_want, J_want = fresh.residual_and_jacobian(d2, q)
            assert r_got.tobytes() == r_want.tobytes()
            assert J_got.tobytes() == J_want.tobytes()
    template = next(iter(builder._templates.values()), None)
    if template is not None and template.robot.constraints.movable:
        assert len(layers) == 1  # (moved in place, not made again)
