"""Public models, as users have them (``tests/data/public``, text only, licences beside them).

Each loads, assembles (closure residual < 1e-9, or the CAD-rounding warning with the amount),
reports its mobility, and runs inverse dynamics along a short actuator motion. The physics
check is the power balance of the inverse dynamics: the actuators' power equals the rate of
change of the mechanical energy (the efforts realise the motion, closures doing no work).

Floating-base robots (Cassie) have their pelvis held (the free joint removed), as on a stand.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from conftest import null_space

import pkdyn
from pkdyn.analysis.mobility import mobility
from pkdyn.dynamics import inverse_dynamics
from pkdyn.dynamics.joint_motion import actuator_trajectory

DATA = Path(__file__).parent / "data" / "public"


def _cassie_mjcf_on_a_stand() -> pkdyn.Robot:
    text = (DATA / "menagerie_cassie" / "cassie.xml").read_text()
    text = re.sub(r"<keyframe>.*</keyframe>", "", text, flags=re.S).replace("<freejoint/>", "")
    return pkdyn.load_string(text, "cassie (MJCF, on a stand)")


def _cassie_sdf_on_a_stand() -> pkdyn.Robot:
    text = (
        (DATA / "erd_cassie_sdf" / "cassie_v2.sdf")
        .read_text()
        .replace(
            "</model>",
            '<joint name="stand" type="fixed"><parent>world</parent><child>pelvis</child></joint>'
            "</model>",
        )
    )
    return pkdyn.load_string(
        text, "cassie (SDFormat, on a stand)", sidecar=DATA / "erd_cassie_sdf" / "cassie_v2.yaml"
    )


MODELS = {
    # name: (loader, closures, mobility, CAD-rounding warning expected)
    "menagerie_cassie_mjcf": (_cassie_mjcf_on_a_stand, 4, 16, False),
    "erd_cassie_sdf": (_cassie_sdf_on_a_stand, 4, 12, False),
    "gepetto_battobot": (
        lambda: pkdyn.load(DATA / "gepetto_battobot" / "robot.urdf"),
        6,
        12,
        False,
    ),
    "reachy_mini_onshape": (lambda: pkdyn.load(DATA / "reachy_mini" / "robot.urdf"), 5, 15, True),
}


@pytest.fixture(scope="module", params=list(MODELS))
def model(request):
    loader, closures, dof, cad = MODELS[request.param]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = loader()
    return robot, closures, dof, cad, [str(w.message) for w in caught]


def test_loads_and_assembles(model):
    robot, closures, dof, cad, messages = model
    assert len(robot.closures) == closures
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9
    rounding = [m for m in messages if "CAD rounding" in m]
    assert bool(rounding) == cad
    if cad:
        assert re.search(r"misses the closures by up to \d\.\de-0[5-8]", rounding[0])


def test_mobility_report(model):
    robot, _, dof, _, _ = model
    mob = mobility(robot)
    assert mob.mobility == dof == robot.mobility()
    assert mob.loops == robot.loops >= 1
    assert mob.to_json()["mobility"] == dof


def test_inverse_dynamics_along_a_short_motion(model):
    robot, *_ = model
    T, n = 0.4, len(robot.actuators)
    t = np.linspace(0.0, T, 11)
    w = 2 * np.pi / T
    amp = 0.01 * np.ones(n)
    qa0 = robot.q_home[robot.actuated_q]
    traj = actuator_trajectory(
        robot,
        t,
        qa0 + np.outer(np.sin(w * t), amp),
        np.outer(w * np.cos(w * t), amp),
        np.outer(-(w**2) * np.sin(w * t), amp),
    )
    efforts = inverse_dynamics(robot, traj)
    assert np.all(np.isfinite(efforts.tau))
    # the efforts satisfy the dynamics over the motions the closures allow, rebuilt here from
    # RNEA (rotor armature included), the closure Jacobian and the passive forces
    model, data = robot.model, robot.model.createData()
    S = np.zeros((n, robot.nv))
    S[np.arange(n), robot.actuated_v] = 1.0
    for k in range(0, t.size, 2):
        q, v, a = traj.q[k], traj.v[k], traj.a[k]
        b = pin.rnea(model, data, q, v, a)
        if robot.passive is not None:
            b = b - robot.passive.force(q, v)
        Z = null_space(robot.closure_set.jacobian(model.createData(), q))
        scale = max(1.0, float(np.abs(Z.T @ b).max()))
        assert np.abs(Z.T @ (S.T @ efforts.tau[k] - b)).max() < 1e-7 * scale
    assert np.max(np.abs(efforts.residual)) < 1e-8
    # power balance at every sample: sum tau_i qa_dot_i = dE/dt, dE/dt = v . (M a + C v + g)
    # is the same as v^T (S^T tau) since closure forces do no work on closure-consistent v;
    # with springs, dampers and friction (robot.passive): v . (M a + C v + g - f_passive)
    data = robot.model.createData()
    for k in range(len(t)):
        q, v, a = traj.q[k], traj.v[k], traj.a[k]
        rnea = pin.rnea(robot.model, data, q, v, a)
        if robot.passive is not None:
            rnea = rnea - robot.passive.force(q, v)
        assert efforts.tau[k] @ traj.qa_dot[k] == pytest.approx(
            v @ rnea, abs=1e-8 * max(1.0, np.abs(rnea).max())
        )
