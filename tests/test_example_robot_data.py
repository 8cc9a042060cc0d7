"""Plain URDFs (every robot of example-robot-data) load through pkdyn exactly as in Pinocchio.

Without pkdyn elements a description is a plain kinematic tree: no loops, the same sizes, and
the same mass matrix (CRBA) and inverse dynamics (RNEA) as ``pin.buildModelFromUrdf``.
"""

from __future__ import annotations

import importlib.metadata
import zlib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn


def _robots_dir() -> Path | None:
    """The ``robots`` directory of example-robot-data (Python helper or cmeel data files)."""
    try:
        import example_robot_data  # older releases ship a Python module

        return Path(example_robot_data.getModelPath("ur_description/urdf/ur5_robot.urdf"))
    except Exception:  # noqa: BLE001 - absent module: fall back to the installed data files
        pass
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    return path if path.is_dir() else None


ROBOTS = _robots_dir()
URDFS = sorted(ROBOTS.glob("**/*.urdf")) if ROBOTS is not None else []
GEOMETRY_SAMPLES = [
    "ur_description/urdf/ur5_robot.urdf",
    "panda_description/urdf/panda.urdf",
    "talos_data/robots/talos_reduced.urdf",
]

pytestmark = pytest.mark.skipif(not URDFS, reason="example-robot-data is not installed")


def _id(path: Path) -> str:
    return str(path.relative_to(ROBOTS)) if ROBOTS is not None else path.name


def _plain_model(path: Path) -> pin.Model:
    try:
        return pin.buildModelFromUrdf(str(path))
    except (RuntimeError, ValueError) as err:
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        pytest.skip(f"plain pin.buildModelFromUrdf rejects {path.name} too: {first}")


def _upper(M: np.ndarray) -> np.ndarray:
    """Symmetric matrix from its upper triangle (what CRBA fills)."""
    return np.triu(M) + np.triu(M, 1).T


@pytest.mark.parametrize("path", URDFS, ids=_id)
def test_plain_urdf_matches_pinocchio(path):
    ref = _plain_model(path)
    robot = pkdyn.load(path, geometry=False)
    model = robot.model
    assert robot.closures == ()
    assert len(robot.constraint_models) == 0
    assert robot.closure_set.nc == 0
    assert (model.nq, model.nv, model.njoints) == (ref.nq, ref.nv, ref.njoints)
    assert list(model.names) == list(ref.names)
    data, ref_data = model.createData(), ref.createData()
    rng = np.random.default_rng(zlib.crc32(_id(path).encode()))
    for _ in range(3):
        q = pin.integrate(ref, pin.neutral(ref), rng.uniform(-1.0, 1.0, ref.nv))
        v = rng.uniform(-1.0, 1.0, ref.nv)
        a = rng.uniform(-1.0, 1.0, ref.nv)
        M_ref = _upper(pin.crba(ref, ref_data, q))
        M = _upper(pin.crba(model, data, q))
        scale = max(1.0, float(np.max(np.abs(M_ref), initial=0.0)))
        np.testing.assert_allclose(M, M_ref, rtol=0, atol=1e-10 * scale)
        tau_ref = pin.rnea(ref, ref_data, q, v, a)
        tau = pin.rnea(model, data, q, v, a)
        scale = max(1.0, float(np.max(np.abs(tau_ref), initial=0.0)))
        np.testing.assert_allclose(tau, tau_ref, rtol=0, atol=1e-10 * scale)


@pytest.mark.parametrize("sub", GEOMETRY_SAMPLES)
def test_geometry_matches_pinocchio(sub):
    path = ROBOTS / sub
    if not path.is_file():
        pytest.skip(f"{sub} is not shipped by this example-robot-data release")
    share = ROBOTS.parent.parent  # package://example-robot-data/robots/... resolves here
    _, ref_collision, ref_visual = pin.buildModelsFromUrdf(str(path), package_dirs=[str(share)])
    robot = pkdyn.load(path, geometry=True)
    for geom, ref in ((robot.visual_model, ref_visual), (robot.collision_model, ref_collision)):
        assert geom.ngeoms == ref.ngeoms > 0
        for g, r in zip(geom.geometryObjects, ref.geometryObjects, strict=True):
            assert (g.name, g.parentJoint, g.meshPath) == (r.name, r.parentJoint, r.meshPath)
            assert g.placement.isApprox(r.placement, 1e-12)
