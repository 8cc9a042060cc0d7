"""Body inertias of the MJCF export, as MuJoCo accepts them (or the one line why not).

MuJoCo refuses two things pkdyn loads:

- **a moving body with rotational inertia and no mass** (a rotor whose mass its carrier holds,
  as legged-robot descriptions model their motors): "mass and inertia of moving bodies must be
  larger than mjMINVAL". The export lends such a body a mass ``eps`` =
  :data:`LENT_MASS` x its carrier's mass, placed at its joint's origin, and takes the same point
  mass away from the carrier at the same point. A revolute joint's origin lies on its axis: the
  point does not move when the rotor turns, so it is the same point of the carrier's frame
  whichever body holds it, and the two models have the same mass matrix and bias forces, exactly
  (to rounding). A rotor on a joint that is not a revolute one, or whose carrier has no mass, is
  refused.
- **inertia tensors that break the triangle inequality** (MuJoCo checks ``A + B >= C``
  exactly and asks for ``balanceinertia``, which changes them): refused, naming the body and the
  links merged into it; ``pkdyn.load(..., repair_inertias=True)`` gives the nearest valid ones.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.robot import Robot

__all__ = ["LENT_MASS", "mujoco_inertias"]

LENT_MASS = 1e-12
"""Mass a massless rotor borrows from its carrier in the MJCF export, as a fraction of the
carrier's mass (MuJoCo's ``mjMINVAL`` is 1e-15 kg)."""


def _links(robot: Robot, jid: int) -> str:
    names = [
        f.name for f in robot.model.frames if f.type == pin.FrameType.BODY and f.parentJoint == jid
    ]
    return ", ".join(names) or robot.model.names[jid]


def _pure_rotation(jm: pin.JointModel) -> bool:
    """A 1-DoF joint that turns about an axis through its origin (a revolute joint)."""
    single = pin.Model()
    single.addJoint(0, jm, pin.SE3.Identity(), "j")
    data = single.createData()
    pin.computeJointJacobians(single, data, pin.neutral(single))
    J = pin.getJointJacobian(single, data, 1, pin.ReferenceFrame.LOCAL)
    S = np.reshape(np.asarray(J), (6, -1))[:, 0]  # a (6,) array when nv = 1
    return bool(np.linalg.norm(S[3:]) > 0.0 and np.linalg.norm(S[:3]) <= 1e-12)


def _triangle(I: np.ndarray) -> bool:
    """MuJoCo's test of a body's principal moments: ``A + B >= C`` for each, exactly."""
    ev = np.linalg.eigvalsh(0.5 * (I + I.T))
    return bool(ev[0] + ev[1] >= ev[2] and ev[0] >= 0.0)


def mujoco_inertias(robot: Robot) -> list[pin.Inertia]:
    """Each joint body's inertia as the MJCF export writes it (see the module docstring).

    Args:
        robot: The robot.

    Returns:
        Inertias indexed like ``robot.model.inertias`` (index 0, the world, unchanged).

    Raises:
        DescriptionError: An inertia MuJoCo refuses and the export cannot make acceptable
            (naming the body, its links and the remedy).

    """
    model = robot.model
    out = [pin.Inertia(I) for I in model.inertias]
    total = sum(float(I.mass) for I in out[1:])
    for j in range(1, model.njoints):
        I = out[j]
        if I.mass > 0.0 or not np.any(I.inertia):
            continue
        jm, parent = model.joints[j], int(model.parents[j])
        where = f"body '{model.names[j]}' (links {_links(robot, j)})"
        if jm.nv != 1 or not _pure_rotation(jm):
            raise DescriptionError(
                robot.source,
                where,
                "has rotational inertia and no mass on a joint that is not a revolute one: "
                "MuJoCo needs a mass on every moving body and no point of this body is fixed "
                "to lend it one exactly; give it a mass",
            )
        carrier = float(out[parent].mass) if parent > 0 else max(total, 1.0)
        if carrier <= 0.0:
            raise DescriptionError(
                robot.source,
                where,
                "has rotational inertia and no mass, and so has the body it turns in: MuJoCo "
                "needs a mass on every moving body; give one of them a mass",
            )
        eps = LENT_MASS * carrier
        out[j] = pin.Inertia(eps, np.zeros(3), np.asarray(I.inertia))  # on the joint's axis
        if parent > 0:  # the same point mass taken from the carrier, at the same point
            point = pin.Inertia(eps, model.jointPlacements[j].translation, np.zeros((3, 3)))
            params = out[parent].toDynamicParameters() - point.toDynamicParameters()
            out[parent] = pin.Inertia.FromDynamicParameters(params)
    for j in range(1, model.njoints):
        I = out[j]
        if I.mass > 0.0 and not _triangle(np.asarray(I.inertia)):
            ev = np.linalg.eigvalsh(np.asarray(I.inertia))
            raise DescriptionError(
                robot.source,
                f"body '{model.names[j]}' (links {_links(robot, j)})",
                f"principal moments {' '.join(f'{v:.6g}' for v in ev)} kg m^2 break the "
                "triangle inequality, which MuJoCo refuses: load the description with "
                "repair_inertias=True (--repair-inertias) for the nearest valid tensors",
            )
    return out
