"""``solvers.energy.KineticEnergy``: ``0.5 v^T M v`` with every joint's armature.

Pinocchio 4.1's ``computeKineticEnergy`` leaves out the armature of revolute joints about
unaligned axes (MJCF hinges about ``-1 0 0`` with an ``armature``: the Menagerie grippers), which
its ``crba`` includes: an energy balance then fails by ``0.5 armature v^2``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from solvers.energy import KineticEnergy

AXIS = np.array([0.0, 0.6, 0.8])
JOINTS = [
    pin.JointModelRX(),
    pin.JointModelRevoluteUnaligned(AXIS),
    pin.JointModelRUBX(),
    pin.JointModelPX(),
    pin.JointModelPrismaticUnaligned(AXIS),
    pin.JointModelSpherical(),
    pin.JointModelSphericalZYX(),
    pin.JointModelUniversal(np.array([1.0, 0, 0]), np.array([0, 1.0, 0])),
    pin.JointModelFreeFlyer(),
    pin.JointModelPlanar(),
    pin.JointModelTranslation(),
]


@pytest.mark.parametrize("jm", JOINTS, ids=lambda jm: jm.shortname())
def test_kinetic_energy_is_half_v_m_v_with_armature(jm):
    model = pin.Model()
    parent = 0
    for k in range(2):  # the joint on a moving parent too
        parent = model.addJoint(parent, jm, pin.SE3(np.eye(3), np.array([0.3, 0, 0])), f"j{k}")
        model.appendBodyToJoint(parent, pin.Inertia.Random(), pin.SE3.Identity())
    model.armature[:] = np.linspace(0.5, 1.5, model.nv)
    rng = np.random.default_rng(0)
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    v = rng.normal(size=model.nv)
    data = model.createData()
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    assert KineticEnergy(model)(model, data, q, v) == pytest.approx(0.5 * v @ M @ v, rel=1e-12)
