"""The robot library: committed URDF files match their builders and open in URDF tools."""

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

import pkdyn
from pkdyn import library
from pkdyn.model.families import export_urdf

URDF = Path(__file__).resolve().parents[1] / "urdf"
FILES = sorted(URDF.glob("*.urdf"))


def test_every_family_is_registered():
    modules = {
        p.stem for p in Path(library.__file__).parent.glob("*.py") if not p.stem.startswith("_")
    }
    assert modules == set(library.FAMILIES)


def _flatten(text):
    """Element tags, attribute names and texts with numbers masked; numbers outside ``rpy``."""
    num = re.compile(r"-?\d+\.?\d*(?:[eE][-+]?\d+)?")
    shape, values = [], []
    for el in ET.fromstring(text).iter():
        shape.append(el.tag)
        for key, val in sorted(el.attrib.items()):
            shape.append(f"{key}={num.sub('#', val)}")
            if key != "rpy":
                values += [float(x) for x in num.findall(val)]
        shape.append(num.sub("#", (el.text or "").strip()))
    return shape, np.array(values)


@pytest.mark.parametrize("name", list(library.FAMILIES))
def test_committed_urdf_matches_builder(name):
    """Same elements and names as the builder's output, numbers and models equal to 1e-12.

    Numbers are compared with a tolerance: the last digit of a round-trip double can differ
    between numpy builds; rpy angles at gimbal lock (pitch = +-pi/2) split roll and yaw
    differently for the same rotation, so they are compared through the models' placements.
    """
    fam = library.FAMILIES[name]
    path = URDF / f"{name}.urdf"
    assert path.is_file(), f"run `make urdf`: {path} is missing"
    committed, built = path.read_text(), export_urdf(name, fam.params())
    shape_c, num_c = _flatten(committed)
    shape_b, num_b = _flatten(built)
    assert shape_c == shape_b, f"{path} drifted from pkdyn.library.{name}; run `make urdf`"
    np.testing.assert_allclose(num_c, num_b, rtol=1e-12, atol=1e-15)
    by_file = pin.buildModelFromXML(committed)
    by_builder = pin.buildModelFromXML(built)
    for j in range(1, by_file.njoints):
        assert by_file.jointPlacements[j].isApprox(by_builder.jointPlacements[j], 1e-12)
        assert by_file.inertias[j].isApprox(by_builder.inertias[j], 1e-12)
    for f1, f2 in zip(by_file.frames, by_builder.frames, strict=True):
        assert f1.name == f2.name and f1.placement.isApprox(f2.placement, 1e-12)


def test_urdf_dir_has_files():
    assert len(FILES) >= len(library.FAMILIES)


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_urdf_loads_in_pinocchio(path):
    model = pin.buildModelFromUrdf(str(path))
    assert model.nq > 0


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_urdf_loads_in_yourdfpy(path):
    robot = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)
    assert len(robot.robot.links) > 1


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_urdf_file_loads_in_pkdyn_like_library(path):
    """Loading the file gives the robot the family name gives: model, parameters, home."""
    by_file = pkdyn.load(str(path), geometry=False)
    by_name = pkdyn.load(path.stem, geometry=False)
    assert by_file.nq == by_name.nq and by_file.nv == by_name.nv
    assert len(by_file.closures) == len(by_name.closures)
    assert pkdyn.closure_residual(by_file, by_file.q_home) < 1e-10
    np.testing.assert_allclose(by_file.q_home, by_name.q_home, atol=1e-10)
    M_file = by_file.platform_placement(by_file.q_home)
    M_name = by_name.platform_placement(by_name.q_home)
    assert M_file.isApprox(M_name, 1e-10)
    module = library.FAMILIES[path.stem]._module()
    resolved = module.resolved if hasattr(module, "resolved") else (lambda p: p)
    assert resolved(by_file.params) == resolved(by_name.params)


def test_delta_urdf_assembles_at_its_documented_home_and_keeps_clavel():
    """urdf/delta.urdf used to assemble at z = -0.308 m and was refused by --clavel."""
    robot = pkdyn.load(str(URDF / "delta.urdf"), geometry=True)
    z = robot.platform_placement(robot.q_home).translation[2]
    assert z == pytest.approx(-0.35, abs=1e-10)
    from pkdyn.cli import main

    assert main(["workspace", str(URDF / "delta.urdf"), "--clavel", "--rays", "12", "--json"]) == 0


def test_an_edited_family_file_is_refused_not_misread(tmp_path):
    """A file whose geometry no longer matches its recorded parameters would get closed forms
    for another robot: it is refused, naming the difference."""
    text = (URDF / "delta.urdf").read_text().replace('value="0.38"', 'value="0.40"', 1)
    path = tmp_path / "edited.urdf"
    path.write_text(text)
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load(str(path), geometry=False)
    assert "<pkdyn:family name='delta'>" in str(err.value) and "edited.urdf" in str(err.value)
    assert "pkdyn urdf delta" in str(err.value)
    # without the element it is a robot of its own (the general numeric path)
    start, end = text.index("  <pkdyn:family"), text.index("</pkdyn:family>") + 15
    path.write_text(text[:start] + text[end:])
    robot = pkdyn.load(str(path), geometry=False)
    assert robot.params is None


def test_unknown_parameter_names_the_parameter():
    with pytest.raises(pkdyn.ParameterError, match="'nope'"):
        pkdyn.load("delta", nope=1.0)


LENGTHS = {
    "delta": ("ra", "rb", "la", "lb", "bar_spacing", "arm_radius", "bar_radius"),
    "gough_stewart": (
        "A",
        "B",
        "rho_min",
        "rho_max",
        "leg_radius",
        "cylinder_length",
        "platform_radius",
    ),
    "planar_3rrr": ("l1", "l2", "h", "base_radius", "link_radius"),
    "five_bar": ("d", "l1", "l2", "link_radius"),
    "parallel_ankle": ("h", "d", "x_motor", "crank", "rod", "x_foot", "e", "z_foot", "rod_radius"),
    "four_bar_knee": ("a", "x_motor", "r1", "r3", "shank_length", "link_radius"),
    "tripod": (
        "r_p",
        "foothold_radius",
        "foot_height",
        "nacelle_height",
        "tool_offset",
        "stroke_min",
        "stroke_max",
        "cylinder_radius",
        "rod_radius",
    ),
}
"""The length parameters of each family: scaling them all gives a similar robot."""


def _scaled(value, k):
    if isinstance(value, tuple):
        return tuple(_scaled(v, k) for v in value)
    return value * k


@pytest.mark.parametrize("k", [0.05, 0.5, 4.0, 30.0])
@pytest.mark.parametrize("name", list(library.FAMILIES))
def test_any_size_works(name, k):
    """Every family scaled as a whole loads, assembles at a home inside its reach, and its home
    platform position scales with it (to the rounding of the derived homes)."""
    fam = library.FAMILIES[name]
    default = fam.params()
    over = {p: _scaled(getattr(default, p), k) for p in LENGTHS[name]}
    robot = pkdyn.load(name, geometry=False, **over)
    ref = pkdyn.load(name, geometry=False)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-10 * max(1.0, k)
    P = robot.platform_placement(robot.q_home).translation
    P0 = ref.platform_placement(ref.q_home).translation
    np.testing.assert_allclose(P, k * P0, atol=0.05 * k * max(float(np.linalg.norm(P0)), 0.1))
    # the geometric models work at that size
    ik = pkdyn.inverse_geometry(robot, robot.platform_placement(robot.q_home))
    fk = pkdyn.forward_geometry(robot, ik.qa)
    np.testing.assert_allclose(fk.position, P, atol=1e-9 * max(1.0, k))


@pytest.mark.parametrize(
    "name, over",
    [
        ("delta", {"la": 0.3, "lb": 0.8}),  # the example: z_home used to be -0.35 m
        ("delta", {"la": 0.1, "lb": 0.2, "ra": 0.08, "rb": 0.02}),
        ("delta", {"alpha_min": 0.2, "alpha_max": 1.2}),
        ("five_bar", {"l1": 0.5, "l2": 0.9}),
        ("five_bar", {"d": 0.05, "l1": 0.1, "l2": 0.12}),
        ("planar_3rrr", {"base_points": "((0.1, 0.0), (0.7, 0.1), (0.4, 0.6))"}),
    ],
)
def test_home_follows_the_parameters(name, over):
    robot = pkdyn.load(name, geometry=False, **over)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-10
    qa = robot.q_home[robot.actuated_q]
    lo = robot.model.lowerPositionLimit[robot.actuated_q]
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    assert np.all((lo <= qa) & (qa <= hi))


def test_explicit_home_outside_reach_names_the_parameter():
    with pytest.raises(pkdyn.ParameterError, match="z_home") as err:
        pkdyn.load("delta", z_home=-2.0, geometry=False)
    assert "leave z_home unset" in str(err.value)
    with pytest.raises(pkdyn.ParameterError, match="nacelle_height") as err:
        pkdyn.load("tripod", stroke_max=0.65, geometry=False)
    assert "must lie in" in str(err.value)


def test_every_builder_parameter_is_in_the_guide_table():
    import dataclasses

    page = Path(__file__).resolve().parents[1] / "docs" / "guide" / "library.md"
    readme = page.read_text(encoding="utf-8")
    rows = {
        line.split("|")[1].strip().strip("`"): line
        for line in readme.splitlines()
        if line.startswith("| `")
    }
    for name, fam in library.FAMILIES.items():
        assert name in rows, f"the guide's library table has no row for {name}"
        missing = [
            f.name
            for f in dataclasses.fields(fam.params)
            if not re.search(rf"`{f.name}[ =`]|\b{f.name}\b", rows[name])
        ]
        assert not missing, f"{name}: parameters missing from the guide's table: {missing}"
