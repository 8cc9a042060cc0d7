"""MJCF import: MuJoCo itself is the reference (kinematics, inertias, mass matrix, bias forces).

- Round trip: every library robot exported by ``pkdyn mjcf`` and imported back has the same mass
  matrix, closure residuals and actuators (1e-9) at random configurations.
- Agility Cassie from MuJoCo Menagerie (``tests/data/public/menagerie_cassie``, defaults with
  ``childclass``, ``xyaxes``, joint ``ref``, degrees, ``connect`` equalities by body and anchor,
  a free joint, the ``home`` keyframe): body poses, mass matrix and bias forces equal MuJoCo's
  at random ``qpos`` (1e-9), the closures hold after assembly.
- Synthetic models for the rest: every orientation attribute and Euler sequence, several
  joints in one body, ``<frame>``, ``<include>``, several grounded branches (Pinocchio's own
  MJCF parser drops all but the first), inertias from geoms, site-based equalities, welds.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.model.formats.mjcf import StateMap, to_mjcf

mujoco = pytest.importorskip("mujoco")

DATA = Path(__file__).parent / "data" / "public" / "menagerie_cassie"
CASSIE = DATA / "cassie.xml"
LIBRARY = sorted(pkdyn.library.FAMILIES)


def _q_of_qpos(model, qpos: np.ndarray) -> np.ndarray:
    """Pinocchio configuration of a MuJoCo ``qpos``: same order, quaternions reordered."""
    out = []
    for j in range(model.njnt):
        a, t = model.jnt_qposadr[j], model.jnt_type[j]
        if t == mujoco.mjtJoint.mjJNT_FREE:
            v = qpos[a : a + 7]
            out += [*v[:3], v[4], v[5], v[6], v[3]]
        elif t == mujoco.mjtJoint.mjJNT_BALL:
            w, x, y, z = qpos[a : a + 4]
            out += [x, y, z, w]
        else:
            out.append(qpos[a])
    return np.array(out)


def _velocity_map(model, q: np.ndarray, nv: int) -> np.ndarray:
    """``T`` with ``qvel = T v``: MuJoCo's free-joint linear velocity is in world axes."""
    T = np.eye(nv)
    for j in range(model.njnt):
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            d, a = model.jnt_dofadr[j], model.jnt_qposadr[j]
            R = pin.XYZQUATToSE3(q[a : a + 7]).rotation  # same indices in Pinocchio's q
            T[d : d + 3, d : d + 3] = R
    return T


def _full(M: np.ndarray) -> np.ndarray:
    return np.triu(M) + np.triu(M, 1).T


def _compare_with_mujoco(robot: pkdyn.Robot, mj_model, samples: int = 4, spread=0.3, seed=0):
    """Body poses, mass matrix and bias forces of pkdyn and MuJoCo at random ``qpos``."""
    data = mujoco.MjData(mj_model)
    rng = np.random.default_rng(seed)
    worst = 0.0
    for k in range(samples):
        qpos = mj_model.qpos0.copy()
        if k:
            mujoco.mj_integratePos(mj_model, qpos, spread * rng.standard_normal(mj_model.nv), 1.0)
        qvel = rng.standard_normal(mj_model.nv)
        for j in range(mj_model.njnt):  # free bases at rest: the bias forces then compare
            if mj_model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:  # without a Coriolis map
                qvel[mj_model.jnt_dofadr[j] : mj_model.jnt_dofadr[j] + 6] = 0.0
        data.qpos[:], data.qvel[:] = qpos, qvel
        mujoco.mj_forward(mj_model, data)
        q = _q_of_qpos(mj_model, qpos)
        T = _velocity_map(mj_model, q, mj_model.nv)
        v = np.linalg.solve(T, qvel)
        model, pdata = robot.model, robot.model.createData()
        pin.framesForwardKinematics(model, pdata, q)
        for b in range(1, mj_model.nbody):
            name = mj_model.body(b).name
            M = pdata.oMf[model.getFrameId(name, pin.BODY)]
            np.testing.assert_allclose(M.translation, data.xpos[b], atol=1e-9, err_msg=name)
            np.testing.assert_allclose(M.rotation, data.xmat[b].reshape(3, 3), atol=1e-9)
        Mj = np.zeros((mj_model.nv, mj_model.nv))
        mujoco.mj_fullM(mj_model, data, Mj)
        Mp = _full(pin.crba(model, pdata, q))
        np.testing.assert_allclose(T.T @ Mj @ T, Mp, atol=1e-9)
        # bias forces: Pinocchio's rnea(q, v, 0) = T^T qfrc_bias (power), minus MuJoCo's
        # passive forces pkdyn does not model here (springs, damping)
        h = pin.rnea(model, pdata, q, v, np.zeros(model.nv))
        np.testing.assert_allclose(T.T @ data.qfrc_bias, h, atol=1e-9 * max(1.0, np.abs(h).max()))
        worst = max(worst, float(np.max(np.abs(T.T @ Mj @ T - Mp))))
    return worst


# ---------------------------------------------------------------------------------- round trip


@pytest.fixture(scope="module", params=LIBRARY)
def round_trip(request, tmp_path_factory):
    robot = pkdyn.load(request.param)
    path = tmp_path_factory.mktemp("mjcf") / f"{request.param}.xml"
    path.write_text(to_mjcf(robot))
    return robot, pkdyn.load(path), StateMap(robot)


def _imported_q(smap: StateMap, q: np.ndarray) -> np.ndarray:
    """Configuration of the re-imported model: MuJoCo's qpos, quaternions in x y z w."""
    qpos = smap.qpos(q)
    out: list[float] = []
    for jm in smap.joints:
        a = jm.qpos
        if jm.kind == "ball":
            w, x, y, z = qpos[a : a + 4]
            out += [x, y, z, w]
        elif jm.kind == "free":
            v = qpos[a : a + 7]
            out += [*v[:3], v[4], v[5], v[6], v[3]]
        else:
            out += list(qpos[a : a + len(jm.mj_joints)])
    return np.array(out)


def test_round_trip_same_mass_matrix_closures_and_actuators(round_trip):
    robot, back, smap = round_trip
    P = np.zeros((smap.nv, robot.nv))
    P[smap._dof_of_v, np.arange(robot.nv)] = 1.0  # MuJoCo's (and the import's) dof order
    assert [a.name for a in back.actuators] == [a.name for a in robot.actuators]
    for a, b in zip(robot.actuators, back.actuators, strict=True):
        assert b.reduction == pytest.approx(a.reduction, rel=1e-12)
        assert b.effort == pytest.approx(a.effort, rel=1e-12)
    assert back.closure_set.names == robot.closure_set.names
    assert back.closure_set.nc == robot.closure_set.nc
    rng = np.random.default_rng(3)
    for k in range(4):
        q = (
            robot.q_home
            if k == 0
            else pin.integrate(robot.model, robot.q_home, 0.4 * rng.standard_normal(robot.nv))
        )
        q2 = _imported_q(smap, q)
        M1 = _full(pin.crba(robot.model, robot.data, q))
        M2 = _full(pin.crba(back.model, back.data, q2))
        np.testing.assert_allclose(P @ M1 @ P.T, M2, atol=1e-9)
        r1 = robot.closure_set.residual(robot.data, q)
        r2 = back.closure_set.residual(back.data, q2)
        np.testing.assert_allclose(r2, r1, atol=1e-9)
    np.testing.assert_allclose(_imported_q(smap, robot.q_home), back.q_home, atol=1e-9)
    assert pkdyn.closure_residual(back, back.q_home) < 1e-9


# ---------------------------------------------------------------------------------- Cassie


@pytest.fixture(scope="module")
def cassie():
    return pkdyn.load(CASSIE)


def test_cassie_matches_mujoco(cassie):
    mj = mujoco.MjModel.from_xml_path(str(CASSIE))
    assert (cassie.nq, cassie.nv) == (mj.nq, mj.nv)
    assert [cassie.model.names[j] for j in range(2, cassie.model.njoints)] == [
        mj.joint(i).name for i in range(1, mj.njnt)
    ]
    _compare_with_mujoco(cassie, mj)


def test_cassie_closures_actuators_home(cassie):
    kinds = {c.name: c.kind for c in cassie.closures}
    assert kinds == {f"connect{k}": "point" for k in range(1, 5)}
    assert cassie.model.joints[1].shortname() == "JointModelFreeFlyer"  # the floating base
    assert len(cassie.actuators) == 10
    knee = next(a for a in cassie.actuators if a.name == "left-knee")
    assert (knee.joint, knee.reduction, knee.effort) == (
        "left-knee",
        16.0,
        pytest.approx(12.2 * 16),
    )
    assert pkdyn.closure_residual(cassie, cassie.q_home) < 1e-9
    # home: the "home" keyframe (off the closures by 1.5 mm), assembled close to it
    mj = mujoco.MjModel.from_xml_path(str(CASSIE))
    key = _q_of_qpos(mj, mj.key_qpos[0])
    assert np.max(np.abs(pin.difference(cassie.model, key, cassie.q_home))) < 0.05
    # 6 (floating base) + 2 x (10 joints + 3 for the Achilles ball - 6 closure equations + the
    # Achilles rod's spin about its axis)
    assert cassie.mobility() == 22
    assert cassie.loops == 4


def test_cassie_ref_keeps_mujoco_coordinates(cassie):
    """``ref`` (knee -45 deg, tarsus 58 deg): qpos0 of MuJoCo is the description's pose."""
    mj = mujoco.MjModel.from_xml_path(str(CASSIE))
    q0 = _q_of_qpos(mj, mj.qpos0)
    i = cassie.model.joints[cassie.model.getJointId("left-knee")].idx_q
    assert q0[i] == pytest.approx(math.radians(-45))
    lo = cassie.model.lowerPositionLimit[i]
    assert lo == pytest.approx(math.radians(-164))


# ---------------------------------------------------------------------------------- synthetic

ORIENTATIONS = """
<mujoco model="orient">
  <compiler angle="{angle}" eulerseq="{seq}"/>
  <default>
    <joint damping="0.1"/>
    <default class="arm"><geom type="capsule" size="0.02"/><joint axis="0 1 0"/></default>
  </default>
  <worldbody>
    <frame pos="0.1 0 0.2" euler="{e1}">
      <body name="a" pos="0 0.1 0" quat="0.9 0.1 -0.3 0.2" childclass="arm">
        <inertial pos="0.01 0 0.02" mass="0.7" diaginertia="0.01 0.02 0.015"
                  euler="{e2}"/>
        <joint name="a1" type="hinge" pos="0.02 0 0" ref="{ref}"/>
        <joint name="a2" type="hinge" axis="1 0 0" pos="0 0.03 0"/>
        <geom fromto="0 0 0 0.3 0 0"/>
        <body name="b" pos="0.3 0 0" axisangle="1 1 0 {aa}">
          <inertial pos="0.1 0 0" mass="0.4" fullinertia="0.002 0.01 0.011 0.0001 -0.0002 0.0003"/>
          <joint name="b1" type="slide" axis="0 0 1" ref="0.05"/>
          <joint name="b2" type="ball" pos="0 0 0.01"/>
          <body name="c" pos="0.2 0 0" xyaxes="0 1 0 -1 0.2 0">
            <inertial pos="0 0 0.05" mass="0.2" diaginertia="0.001 0.001 0.0005"/>
            <joint name="c1" type="hinge" axis="0 0 1" pos="0.01 0.02 0"/>
          </body>
          <body name="d" pos="0.1 0.05 0" zaxis="0.3 -0.2 1">
            <inertial pos="0 0 0.05" mass="0.2" diaginertia="0.001 0.001 0.0005"/>
            <joint name="d1" type="hinge" axis="0.3 0.4 0.5"/>
          </body>
        </body>
      </body>
    </frame>
    <body name="e" pos="-0.2 0 0.1">
      <freejoint name="e_free"/>
      <geom type="box" size="0.05 0.04 0.03" mass="0.3"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize(
    "angle,seq,scale",
    [
        ("radian", "xyz", 1.0),
        ("degree", "zyx", 180 / math.pi),
        ("radian", "XYZ", 1.0),
        ("degree", "zXy", 180 / math.pi),
    ],
)
def test_orientations_multi_joint_bodies_frames_match_mujoco(tmp_path, angle, seq, scale):
    text = ORIENTATIONS.format(
        angle=angle,
        seq=seq,
        e1=f"{0.3 * scale} {-0.2 * scale} {0.5 * scale}",
        e2=f"{0.1 * scale} {0.2 * scale} {-0.4 * scale}",
        ref=0.25 * scale,
        aa=0.7 * scale,
    )
    path = tmp_path / "orient.xml"
    path.write_text(text)
    robot = pkdyn.load(path)
    mj = mujoco.MjModel.from_xml_path(str(path))
    assert robot.nq == mj.nq
    _compare_with_mujoco(robot, mj, samples=5, spread=0.6)
    np.testing.assert_allclose(robot.model.damping, mj.dof_damping, atol=0)


TWO_ARMS = """
<mujoco model="two_arms">
  <compiler angle="radian"/>
  <worldbody>
    <body name="left" pos="-0.1 0 0">
      <joint name="l1" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/>
      <body name="left2" pos="0.1 0 0">
        <joint name="l2" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.15 0 0" size="0.01"/>
        <site name="tip" pos="0.15 0 0"/>
      </body>
    </body>
    <body name="right" pos="0.1 0 0">
      <joint name="r1" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0.1" size="0.01"/>
      <body name="right2" pos="0.1 0 0.1">
        <joint name="r2" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 -0.15 0 0" size="0.01"/>
      </body>
    </body>
  </worldbody>
  <equality>
    <connect name="tips" body1="left2" body2="right2" anchor="0.15 0 0"/>
  </equality>
  <actuator>
    <motor joint="l1" gear="2" ctrlrange="-3 3"/>
    <position name="p_r1" joint="r1" kp="10" forcerange="-5 5"/>
  </actuator>
</mujoco>
"""


def test_several_grounded_branches_with_inertias_from_geoms(tmp_path):
    """Pinocchio's parser keeps only the first top-level body; pkdyn keeps both arms."""
    path = tmp_path / "two.xml"
    path.write_text(TWO_ARMS)
    robot = pkdyn.load(path)
    mj = mujoco.MjModel.from_xml_path(str(path))
    assert robot.nq == mj.nq == 4
    for b in range(1, mj.nbody):
        I = robot.model.inertias[robot.model.getJointId(["l1", "l2", "r1", "r2"][b - 1])]
        assert I.mass == pytest.approx(mj.body_mass[b], rel=1e-12)
    _compare_with_mujoco(robot, mj)
    assert [c.name for c in robot.closures] == ["tips"]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    assert robot.mobility() == 2  # a planar five-bar (point closure of rank 2 in the plane)
    a = {x.name: x for x in robot.actuators}
    assert a["actuator1"].effort == pytest.approx(6.0)  # |ctrl| <= 3, gear 2
    assert a["p_r1"].effort == pytest.approx(5.0)  # forcerange only (a position servo)
    pin_model = pin.buildModelFromMJCF(str(path))
    assert pin_model.nq == 2  # the peer drops the second branch


def test_include_and_site_equalities(tmp_path):
    (tmp_path / "robot.xml").write_text(
        TWO_ARMS.replace(
            'body1="left2" body2="right2" anchor="0.15 0 0"', 'site1="tip" site2="meet"'
        ).replace(
            '<geom type="capsule" fromto="0 0 0 -0.15 0 0" size="0.01"/>',
            '<geom type="capsule" fromto="0 0 0 -0.15 0 0" size="0.01"/>'
            '<site name="meet" pos="-0.15 0 0"/>',
        )
    )
    (tmp_path / "scene.xml").write_text(
        '<mujoco model="scene"><include file="robot.xml"/>'
        '<worldbody><geom type="plane" size="1 1 0.1"/></worldbody></mujoco>'
    )
    robot = pkdyn.load(tmp_path / "scene.xml")
    assert robot.nq == 4 and [c.name for c in robot.closures] == ["tips"]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12


def test_weld_equality_by_bodies(tmp_path):
    text = TWO_ARMS.replace(
        '<connect name="tips" body1="left2" body2="right2" anchor="0.15 0 0"/>',
        '<weld name="glue" body1="left2" body2="right2"/>',
    )
    path = tmp_path / "weld.xml"
    path.write_text(text)
    robot = pkdyn.load(path)
    assert [(c.name, c.kind) for c in robot.closures] == [("glue", "weld")]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    assert robot.mobility() == 1  # the weld also locks the relative rotation in the plane


# ---------------------------------------------------------------------------------- bad input


def _load_text(tmp_path, text, name="bad.xml"):
    path = tmp_path / name
    path.write_text(text)
    return pkdyn.load(path, geometry=True)


@pytest.mark.parametrize(
    "old,new,culprit",
    [
        (
            '<connect name="tips"',
            '<joint joint1="l1" joint2="r1" polycoef="0 1 0 0 0 0"/><connect name="tips"',
            r"<joint name='joint1'> \(line 24\).*polycoef='0 1 0 0 0 0': 6 coefficients",
        ),
        (
            '<joint name="l2" axis="0 1 0"/>',
            '<joint name="l2" type="screw"/>',
            r"<joint name='l2'> \(line 9\).*joint type 'screw'",
        ),
        (
            '<site name="tip" pos="0.15 0 0"/>',
            '<composite type="grid" count="2 2 1"/>',
            r"<composite> \(line \d+\).*not supported",
        ),
        ('body2="right2"', 'body2="nowhere"', "body2='nowhere' is not a body"),
        ('<motor joint="l1"', '<motor joint="l9"', "joint='l9' is not a joint"),
        ('<motor joint="l1" gear="2"', '<motor joint="l1" gear="0"', "gear 0"),
        (
            '<body name="left" pos="-0.1 0 0">',
            '<body name="left" quat="0 0 0 0">',
            r"<body name='left'> \(line \d+\): quat='0 0 0 0': zero quaternion",
        ),
        (
            '<body name="left" pos="-0.1 0 0">',
            '<body name="left" quat="1 0 0 0" euler="0 0 1">',
            "orientation given twice",
        ),
    ],
)
def test_bad_mjcf_names_the_element_and_its_line(tmp_path, old, new, culprit):
    text = TWO_ARMS.replace(old, new, 1)
    with pytest.raises(pkdyn.DescriptionError, match=culprit):
        _load_text(tmp_path, text)


def test_missing_mesh_warns_once_naming_the_file(tmp_path):
    text = TWO_ARMS.replace(
        "<worldbody>",
        '<asset><mesh name="m" file="nowhere/part.stl"/><mesh file="gone.obj"/></asset><worldbody>',
    ).replace(
        '<site name="tip" pos="0.15 0 0"/>',
        '<site name="tip" pos="0.15 0 0"/><geom type="mesh" mesh="m"/>'
        '<geom type="mesh" mesh="gone"/>',
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = _load_text(tmp_path, text)
    mesh_warnings = [w for w in caught if "mesh file" in str(w.message)]
    assert len(mesh_warnings) == 1
    assert "part.stl" in str(mesh_warnings[0].message) and "gone.obj" in str(
        mesh_warnings[0].message
    )
    assert robot.nq == 4


def test_actuators_on_tendons_are_left_out_with_a_warning(tmp_path):
    text = TWO_ARMS.replace("</actuator>", '<motor name="pull" tendon="t1"/></actuator>').replace(
        "<actuator>",
        '<tendon><fixed name="t1"><joint joint="l1" coef="1"/></fixed></tendon><actuator>',
    )
    with pytest.warns(UserWarning, match=r"pull \(tendon\)"):
        robot = _load_text(tmp_path, text)
    assert [a.name for a in robot.actuators] == ["actuator1", "p_r1"]


def test_keyframe_of_the_wrong_size(tmp_path):
    text = TWO_ARMS.replace(
        "</mujoco>", '<keyframe><key name="home" qpos="0 0 0"/></keyframe></mujoco>'
    )
    with pytest.raises(pkdyn.DescriptionError, match=r"<key name='home'> \(line \d+\).*nq = 4"):
        _load_text(tmp_path, text)


def test_inactive_equality_is_named(tmp_path):
    text = TWO_ARMS.replace('<connect name="tips"', '<connect name="tips" active="false"')
    with pytest.warns(UserWarning, match="inactive"):
        robot = _load_text(tmp_path, text)
    assert robot.closures == ()


def test_format_is_read_from_the_root_element(tmp_path):
    (tmp_path / "arms.urdf").write_text(TWO_ARMS)  # the extension does not matter
    assert pkdyn.load(tmp_path / "arms.urdf").nq == 4
    (tmp_path / "x.xml").write_text("<scene/>")
    with pytest.raises(pkdyn.DescriptionError, match="cannot tell the format"):
        pkdyn.load(tmp_path / "x.xml")
    (tmp_path / "y.xml").write_text("closed_loop: []\n")
    with pytest.raises(pkdyn.DescriptionError, match="not an XML document"):
        pkdyn.load(tmp_path / "y.xml")
