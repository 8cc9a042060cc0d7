"""Closure and pose-task Jacobians against central finite differences on the manifold.

The reference derivative of a residual ``r`` along a unit tangent direction ``d`` at ``q`` is
``(r(q + h d) - r(q - h d)) / 2h`` with ``q + h d = pin.integrate(model, q, h d)`` and
``h = 1e-6``; it must match ``J d`` to about 1e-6 relative. Configurations are random and mostly
*not* assembled (the derivative must hold everywhere, the solvers start off the manifold).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn import library
from solvers import ClosureSet, FramePoseTask

DATA = Path(__file__).parent / "data" / "closures"
FIXTURES = sorted(DATA.glob("*.urdf"))
STEP = 1e-6
RTOL = 1e-6
ATOL = 1e-9  # finite-difference round-off is ~1e-10 at this step

ROBOTS = [("family", name, ()) for name in sorted(library.FAMILIES)]
if "delta" in library.FAMILIES:
    ROBOTS.append(("family", "delta", (("bar_joint", "universal"),)))
ROBOTS += [("file", str(path), ()) for path in FIXTURES]


def _robot_id(spec: tuple) -> str:
    kind, name, params = spec
    label = Path(name).stem if kind == "file" else name
    return label + "".join(f"[{k}={v}]" for k, v in params)


@functools.cache
def _load(kind: str, name: str, params: tuple) -> pkdyn.Robot:
    return pkdyn.load(name, geometry=False, **dict(params))


def _random_configurations(model: pin.Model, q0: np.ndarray, rng, n: int = 3, spread=0.8):
    """``q0`` plus ``n`` random configurations around it (generally not assembled)."""
    qs = [q0]
    for _ in range(n):
        qs.append(pin.integrate(model, q0, rng.uniform(-spread, spread, model.nv)))
    return qs


def _directional_fd(residual, model: pin.Model, q: np.ndarray, d: np.ndarray) -> np.ndarray:
    rp = residual(pin.integrate(model, q, STEP * d))
    rm = residual(pin.integrate(model, q, -STEP * d))
    return (rp - rm) / (2 * STEP)


def _check_closure_set(cs: ClosureSet, model: pin.Model, q: np.ndarray, rng, ndir: int = 6):
    data = model.createData()
    r, J = cs.residual_and_jacobian(data, q)
    assert J.shape == (cs.nc, model.nv)
    np.testing.assert_allclose(r, cs.residual(model.createData(), q), rtol=0, atol=1e-14)
    for _ in range(ndir):
        d = rng.standard_normal(model.nv)
        d /= np.linalg.norm(d)
        fd = _directional_fd(lambda x: cs.residual(data, x), model, q, d)
        Jd = J @ d
        err = np.linalg.norm(fd - Jd)
        assert err <= RTOL * np.linalg.norm(Jd) + ATOL, (
            f"|J d - fd| = {err:.3g} for |J d| = {np.linalg.norm(Jd):.3g}"
        )


@pytest.mark.parametrize("spec", ROBOTS, ids=_robot_id)
def test_closure_jacobian_matches_finite_differences(spec):
    robot = _load(*spec)
    assert robot.closure_set.nc > 0
    rng = np.random.default_rng(20240611)
    for q in _random_configurations(robot.model, robot.q_home, rng):
        _check_closure_set(robot.closure_set, robot.model, q, rng)


@pytest.mark.parametrize("spec", ROBOTS, ids=_robot_id)
def test_closure_residual_vanishes_at_home(spec):
    # the finite-difference test starts from q_home: make sure it is an assembled point
    robot = _load(*spec)
    assert np.max(np.abs(robot.closure_set.residual(robot.data, robot.q_home))) < 1e-10


@pytest.mark.parametrize("kind", ["point", "weld"])
@pytest.mark.parametrize("universe_side", [1, 2])
def test_closure_attached_to_the_universe(kind, universe_side):
    """Constraints with joint id 0 on either side, built directly on a fixture's tree."""
    robot = _load("file", str(DATA / "weld_universal.urdf"), ())
    model = robot.model
    rng = np.random.default_rng(7 + universe_side)
    ctype = pin.ContactType.CONTACT_3D if kind == "point" else pin.ContactType.CONTACT_6D
    jid = model.getJointId("wrist")
    M_body = pin.exp6(pin.Motion(rng.uniform(-0.5, 0.5, 6)))
    M_world = pin.exp6(pin.Motion(rng.uniform(-0.5, 0.5, 6)))
    sides = [(jid, M_body), (0, M_world)]
    if universe_side == 1:
        sides.reverse()
    (j1, M1), (j2, M2) = sides
    cm = pin.RigidConstraintModel(ctype, model, j1, M1, j2, M2, pin.ReferenceFrame.LOCAL)
    cm.name = "to_universe"
    cs = ClosureSet(model, [cm])
    assert cs.nc == (3 if kind == "point" else 6)
    for q in _random_configurations(model, robot.q_home, rng):
        _check_closure_set(cs, model, q, rng)


@pytest.mark.parametrize("kind", ["point", "weld"])
def test_closure_between_a_body_and_its_ancestor(kind):
    """Both frames on one branch (shared support): only the joints in between contribute."""
    robot = _load("file", str(DATA / "weld_universal.urdf"), ())
    model = robot.model
    rng = np.random.default_rng(11)
    ctype = pin.ContactType.CONTACT_3D if kind == "point" else pin.ContactType.CONTACT_6D
    cm = pin.RigidConstraintModel(
        ctype,
        model,
        model.getJointId("cardan"),
        pin.exp6(pin.Motion(rng.uniform(-0.5, 0.5, 6))),
        model.getJointId("wrist"),
        pin.exp6(pin.Motion(rng.uniform(-0.5, 0.5, 6))),
        pin.ReferenceFrame.LOCAL,
    )
    cs = ClosureSet(model, [cm])
    yaw = model.joints[model.getJointId("yaw")].idx_v
    for q in _random_configurations(model, robot.q_home, rng):
        _check_closure_set(cs, model, q, rng)
        r, J = cs.residual_and_jacobian(model.createData(), q)
        # the common ancestor (yaw, about the world z axis) moves both frames together: the
        # relative placement is unchanged, the world vector p1 - p2 turns about z
        expected = np.cross([0.0, 0.0, 1.0], r) if kind == "point" else np.zeros(6)
        np.testing.assert_allclose(J[:, yaw], expected, rtol=0, atol=1e-12)


def test_mixed_closure_set_stacks_rows_in_order():
    """A set mixing point and weld constraints equals its members evaluated one by one."""
    robot = _load("file", str(DATA / "weld_universal.urdf"), ())
    model = robot.model
    rng = np.random.default_rng(3)
    ids = [model.getJointId(n) for n in ("yaw", "cardan", "slide", "wrist")]
    cms = []
    for k, ctype in enumerate(
        [pin.ContactType.CONTACT_3D, pin.ContactType.CONTACT_6D, pin.ContactType.CONTACT_3D]
    ):
        cm = pin.RigidConstraintModel(
            ctype,
            model,
            ids[k],
            pin.exp6(pin.Motion(rng.uniform(-0.5, 0.5, 6))),
            ids[k + 1] if k < 2 else 0,
            pin.exp6(pin.Motion(rng.uniform(-0.5, 0.5, 6))),
            pin.ReferenceFrame.LOCAL,
        )
        cm.name = f"c{k}"
        cms.append(cm)
    cs = ClosureSet(model, cms)
    assert cs.nc == 3 + 6 + 3
    q = _random_configurations(model, robot.q_home, rng, n=1)[1]
    r, J = cs.residual_and_jacobian(model.createData(), q)
    rows = 0
    for cm in cms:
        ri, Ji = ClosureSet(model, [cm]).residual_and_jacobian(model.createData(), q)
        np.testing.assert_allclose(r[rows : rows + ri.size], ri, rtol=0, atol=1e-14)
        np.testing.assert_allclose(J[rows : rows + ri.size], Ji, rtol=0, atol=1e-14)
        rows += ri.size
    _check_closure_set(cs, model, q, rng)


# --------------------------------------------------------------------------------------------
# FramePoseTask
# --------------------------------------------------------------------------------------------


def _task_cases():
    return [("family", name, ()) for name in sorted(library.FAMILIES)] + [
        ("file", str(path), ()) for path in FIXTURES
    ]


def _task_frame(robot: pkdyn.Robot) -> int:
    """The platform frame, else the body frame of the last link (fixtures without platform)."""
    if robot.platform_frame is not None:
        return robot.platform_frame
    model = robot.model
    return max(i for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY)


@pytest.mark.parametrize("spec", _task_cases(), ids=_robot_id)
def test_frame_pose_task_jacobian_matches_finite_differences(spec):
    robot = _load(*spec)
    model = robot.model
    data = model.createData()
    rng = np.random.default_rng(5)
    fid = _task_frame(robot)
    task = FramePoseTask(model, fid, np.arange(6))
    for q in _random_configurations(model, robot.q_home, rng):
        pin.framesForwardKinematics(model, data, q)
        # a target within ~1 rad of the frame keeps log3 away from its cut at pi
        task.target = data.oMf[fid] * pin.exp6(pin.Motion(rng.uniform(-0.5, 0.5, 6)))

        def residual(x: np.ndarray) -> np.ndarray:
            pin.framesForwardKinematics(model, data, x)
            return task.error(data.oMf[fid])

        pin.computeJointJacobians(model, data, q)
        r, J = task.residual_and_jacobian(data)
        np.testing.assert_allclose(r, residual(q), rtol=0, atol=1e-14)
        for _ in range(6):
            d = rng.standard_normal(model.nv)
            d /= np.linalg.norm(d)
            fd = _directional_fd(residual, model, q, d)
            Jd = J @ d
            assert np.linalg.norm(fd - Jd) <= RTOL * np.linalg.norm(Jd) + ATOL


def test_frame_pose_task_selects_rows():
    robot = _load("file", str(DATA / "weld_universal.urdf"), ())
    model = robot.model
    data = model.createData()
    rng = np.random.default_rng(9)
    q = pin.integrate(model, robot.q_home, rng.uniform(-0.5, 0.5, model.nv))
    target = pin.exp6(pin.Motion(rng.uniform(-0.5, 0.5, 6)))
    full = FramePoseTask(model, robot.platform_frame, np.arange(6))
    some = FramePoseTask(model, robot.platform_frame, np.array([0, 2, 4]))
    full.target = some.target = target
    pin.computeJointJacobians(model, data, q)
    r_full, J_full = full.residual_and_jacobian(data)
    r_some, J_some = some.residual_and_jacobian(data)
    np.testing.assert_allclose(r_some, r_full[[0, 2, 4]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(J_some, J_full[[0, 2, 4]], rtol=0, atol=1e-15)
    # independent reference for the error itself: position difference and log3
    pin.framesForwardKinematics(model, data, q)
    oMf = data.oMf[robot.platform_frame]
    np.testing.assert_allclose(r_full[:3], oMf.translation - target.translation, atol=1e-14)
    np.testing.assert_allclose(r_full[3:], pin.log3(target.rotation.T @ oMf.rotation), atol=1e-14)
