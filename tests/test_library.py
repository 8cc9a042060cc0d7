"""The robot library: committed URDF files match their builders and open in URDF tools."""

from pathlib import Path

import pinocchio as pin
import pytest
import yourdfpy

import pkdyn
from pkdyn import library

URDF = Path(__file__).resolve().parents[1] / "urdf"
FILES = sorted(URDF.glob("*.urdf"))


def test_every_family_is_registered():
    assert set(library.MODULES) == set(library.FAMILIES)


@pytest.mark.parametrize("name", library.MODULES)
def test_committed_urdf_matches_builder(name):
    fam = library.FAMILIES[name]
    path = URDF / f"{name}.urdf"
    assert path.is_file(), f"run `make urdf`: {path} is missing"
    assert path.read_text() == fam.build_urdf(fam.params()), (
        f"{path} drifted from pkdyn.library.{name}; regenerate it with `make urdf`"
    )


def test_urdf_dir_has_files():
    assert len(FILES) >= len(library.MODULES)


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
