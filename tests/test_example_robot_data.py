"""Plain URDFs (every robot of example-robot-data) load through pkdyn exactly as in Pinocchio.

Without pkdyn elements a description is a plain kinematic tree: no loops, the same sizes, joint
placements and inertias as ``pin.buildModelFromUrdf``. Its link poses, mass matrix, gravity
torques and inverse-dynamics power are checked against an independent reading of the same file:
yourdfpy's parser and forward kinematics, with the Jacobians and the mass matrix assembled here.
"""

from __future__ import annotations

import importlib.metadata
import logging
import warnings
import zlib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

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
    """The loader adds nothing to a plain URDF but its ``<mimic>`` couplings: the same model as
    ``pin.buildModelFromUrdf`` (whose mimic joints stay tree joints too), assembled on them;
    an actuated ``continuous`` joint (a transmission on a wheel) has one coordinate, not
    Pinocchio's (cos, sin) pair."""
    ref = _plain_model(path)
    total, broken = _mimics(path)
    ignore: tuple[str, ...] = ()
    if broken:  # a mimic of a joint that does not exist (one file): refused, as documented
        with pytest.raises(pkdyn.DescriptionError, match="<mimic>"):
            pkdyn.load(path, geometry=False)
        ignore, total = ("mimic",), 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # elements pkdyn does not read (gazebo, ros2_control)
        robot = pkdyn.load(path, geometry=False, ignore_elements=ignore)
    model = robot.model
    assert robot.closures == ()
    assert len(robot.constraint_models) == 0
    assert robot.constraints.nc == 0
    assert robot.constraints.nk == len(robot.couplings)
    assert len(robot.couplings) == total
    if robot.couplings:
        assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    unbounded = sum(ref.joints[ref.getJointId(a.joint)].nq == 2 for a in robot.actuators)
    assert (model.nq + unbounded, model.nv, model.njoints) == (ref.nq, ref.nv, ref.njoints)
    assert list(model.names) == list(ref.names)
    for a, b in zip(model.inertias, ref.inertias, strict=True):
        assert a.isApprox(b, 1e-14)
    for a, b in zip(model.jointPlacements, ref.jointPlacements, strict=True):
        assert a.isApprox(b, 1e-14)


def _load(path: Path, geometry: bool) -> pkdyn.Robot:
    """The file as a user loads it: mimics of missing or fixed joints left out explicitly."""
    ignore = ("mimic",) if _mimics(path)[1] else ()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # elements pkdyn does not read (gazebo, ros2_control)
        return pkdyn.load(path, geometry=geometry, ignore_elements=ignore)


def _mimics(path: Path) -> tuple[int, int]:
    """Mimic elements of a file, and those whose joints are not both moving 1-DoF joints."""
    import xml.etree.ElementTree as ET

    joints = ET.parse(path).getroot().findall("joint")
    kinds = {j.get("name"): j.get("type") for j in joints}
    ok = ("revolute", "continuous", "prismatic")
    mimics = [(j.get("name"), m.get("joint")) for j in joints if (m := j.find("mimic")) is not None]
    broken = sum(1 for a, b in mimics if not (kinds.get(a) in ok and kinds.get(b) in ok))
    return len(mimics), broken


def _yourdfpy_model(path: Path) -> yourdfpy.URDF:
    """The URDF parsed by yourdfpy, mimic tags dropped (Pinocchio gives mimic joints their own
    coordinates, as a plain tree joint)."""
    logging.getLogger("yourdfpy").setLevel(logging.ERROR)  # mimic targets missing in one file
    parsed = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False).robot
    for joint in parsed.joints:
        joint.mimic = None
    return yourdfpy.URDF(robot=parsed, build_scene_graph=True, load_meshes=False)


def _independent_dynamics(
    y: yourdfpy.URDF, model: pin.Model, q: np.ndarray
) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """Link poses, mass matrix and gravity torques from yourdfpy's kinematics and inertias.

    The link poses come from yourdfpy's forward kinematics; the Jacobian of a link's centre of
    mass is built from its ancestor joints (revolute: ``a x (c - o)``, ``a``; prismatic: ``a``,
    axes and origins in world from yourdfpy's child-link poses); then ``M = sum m Jv^T Jv +
    Jw^T I Jw`` and ``g = -sum m Jv^T g0``. Pinocchio only maps ``q`` to yourdfpy's joint values
    and names the velocity columns.
    """
    cfg, column = {}, {}
    for i in range(1, model.njoints):
        joint = model.joints[i]
        # continuous joints: (cos, sin) in Pinocchio, an angle in yourdfpy
        value = np.arctan2(q[joint.idx_q + 1], q[joint.idx_q]) if joint.nq == 2 else q[joint.idx_q]
        cfg[model.names[i]], column[model.names[i]] = float(value), joint.idx_v
    y.update_cfg(cfg)
    poses = {link.name: y.get_transform(link.name) for link in y.robot.links}
    by_child = {j.child: j for j in y.robot.joints}
    M, g = np.zeros((model.nv, model.nv)), np.zeros(model.nv)
    g0 = np.array([0.0, 0.0, -9.81])
    for link in y.robot.links:
        inertial = link.inertial
        if inertial is None:
            continue
        T = poses[link.name] @ (np.eye(4) if inertial.origin is None else inertial.origin)
        c, R = T[:3, 3], T[:3, :3]
        inertia = np.zeros((3, 3)) if inertial.inertia is None else inertial.inertia
        mass = float(inertial.mass or 0.0)
        Jv, Jw = np.zeros((3, model.nv)), np.zeros((3, model.nv))
        name = link.name
        while name in by_child:
            joint = by_child[name]
            if joint.type != "fixed":
                frame = poses[joint.child]
                axis = frame[:3, :3] @ (joint.axis / np.linalg.norm(joint.axis))
                k = column[joint.name]
                if joint.type == "prismatic":
                    Jv[:, k] = axis
                else:
                    Jv[:, k], Jw[:, k] = np.cross(axis, c - frame[:3, 3]), axis
            name = joint.parent
        M += mass * Jv.T @ Jv + Jw.T @ (R @ inertia @ R.T) @ Jw
        g -= mass * Jv.T @ g0
    return poses, M, g


@pytest.mark.parametrize("path", URDFS, ids=_id)
def test_plain_urdf_dynamics_match_yourdfpy(path):
    """Link poses, mass matrix, gravity and the power of the inverse dynamics against yourdfpy's
    kinematics and inertias (an independent parser and forward kinematics)."""
    _plain_model(path)  # skips the files Pinocchio itself rejects
    robot = _load(path, geometry=False)
    model, data = robot.model, robot.data
    y = _yourdfpy_model(path)
    rng = np.random.default_rng(zlib.crc32(_id(path).encode()))
    q = pin.integrate(model, pin.neutral(model), rng.uniform(-1.0, 1.0, model.nv))
    v = rng.uniform(-1.0, 1.0, model.nv)
    a = rng.uniform(-1.0, 1.0, model.nv)
    poses, M_ref, g_ref = _independent_dynamics(y, model, q)
    pin.framesForwardKinematics(model, data, q)
    for link, T in poses.items():
        frame = data.oMf[model.getFrameId(link, pin.FrameType.BODY)]
        np.testing.assert_allclose(frame.homogeneous, T, rtol=0, atol=1e-12, err_msg=link)
    scale = max(1.0, float(np.max(np.abs(M_ref), initial=0.0)))
    np.testing.assert_allclose(_upper(pin.crba(model, data, q)), M_ref, atol=1e-12 * scale)
    tau = pin.rnea(model, data, q, v, a)
    scale = max(1.0, float(np.max(np.abs(g_ref), initial=0.0)))
    np.testing.assert_allclose(
        pin.rnea(model, data, q, np.zeros(model.nv), np.zeros(model.nv)),
        g_ref,
        atol=1e-12 * scale,
    )
    # power of the inverse dynamics: v.tau = v.M a + 1/2 v.(dM/dt) v + v.g (Lagrange);
    # dM/dt along v by a fourth-order central difference of the independent mass matrix
    # (steps of 1e-3: yourdfpy's scene graph may miss much smaller updates)
    h = 1e-3
    M_at = [
        _independent_dynamics(y, model, pin.integrate(model, q, s * h * v))[1]
        for s in (-2.0, -1.0, 1.0, 2.0)
    ]
    M_dot = (M_at[0] - 8.0 * M_at[1] + 8.0 * M_at[2] - M_at[3]) / (12.0 * h)
    power = v @ M_ref @ a + 0.5 * v @ M_dot @ v + v @ g_ref
    scale = max(1.0, float(np.abs(v) @ np.abs(tau)))
    assert float(v @ tau) == pytest.approx(power, abs=1e-8 * scale)


@pytest.mark.parametrize("sub", GEOMETRY_SAMPLES)
def test_geometry_matches_pinocchio(sub):
    path = ROBOTS / sub
    if not path.is_file():
        pytest.skip(f"{sub} is not shipped by this example-robot-data release")
    share = ROBOTS.parent.parent  # package://example-robot-data/robots/... resolves here
    _, ref_collision, ref_visual = pin.buildModelsFromUrdf(str(path), package_dirs=[str(share)])
    robot = _load(path, geometry=True)
    for geom, ref in ((robot.visual_model, ref_visual), (robot.collision_model, ref_collision)):
        assert geom.ngeoms == ref.ngeoms > 0
        for g, r in zip(geom.geometryObjects, ref.geometryObjects, strict=True):
            assert (g.name, g.parentJoint, g.meshPath) == (r.name, r.parentJoint, r.meshPath)
            assert g.placement.isApprox(r.placement, 1e-12)
