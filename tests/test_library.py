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
    committed, built = path.read_text(), fam.build_urdf(fam.params())
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
    """Loading the file gives the same model as loading the family by name."""
    by_file = pkdyn.load(str(path), geometry=False)
    by_name = pkdyn.load(path.stem, geometry=False)
    assert by_file.nq == by_name.nq and by_file.nv == by_name.nv
    assert len(by_file.closures) == len(by_name.closures)
    assert pkdyn.closure_residual(by_file, by_file.q_home) < 1e-10


def test_unknown_parameter_names_the_parameter():
    with pytest.raises(pkdyn.ParameterError, match="'nope'"):
        pkdyn.load("delta", nope=1.0)
