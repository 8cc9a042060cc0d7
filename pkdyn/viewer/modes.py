"""A natural mode of vibration played slowly in a meshcat scene, the mechanism kept assembled.

The scene plays :func:`pkdyn.precision.modes.mode_trajectory`: the whole extended configuration
(joints, actuators and the links' deflections) along the mode, re-projected onto the closures at
every frame, so the loops stay closed. A compliant link deforms in the model by a virtual joint
at its elastic centre; drawn as one rigid piece on its root, its far end would leave what it
carries (the bars of a Delta leaving the nacelle). Here each beam is drawn in two halves: the
root half on the link's root, the tip half (and every other shape nearer the tip) on the piece
after its last virtual joint, so both ends stay on what they are attached to and the beam shows
its bending as a kink at its middle.
"""

from __future__ import annotations

import dataclasses

import coal
import numpy as np
import pinocchio as pin

from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.modes import Modes, mode_trajectory
from pkdyn.viewer.scene import Scene

__all__ = ["animate_mode", "display_robot"]


def _tip_joints(em: ElasticModel) -> dict[int, int]:
    """Extended joint id of the last virtual joint of each compliant link (by base joint id)."""
    model = em.robot.model
    by_v = {int(model.joints[j].idx_v): j for j in range(1, model.njoints)}
    out: dict[int, int] = {}
    for lc, iv in zip(em.links, em.deflection_v, strict=True):
        out[lc.joint] = by_v[int(iv[0])]  # (pieces in order: the last one wins)
    return out


def display_robot(em: ElasticModel) -> Robot:
    """The extended robot with its beams drawn in two halves (module docstring).

    Args:
        em: An elastic model.

    Returns:
        ``em.robot`` with new visual and collision models (the same kinematics).

    """
    if not em.links:
        return em.robot
    model = em.robot.model
    tips = _tip_joints(em)
    ext_root = {
        lc.joint: int(model.getJointId(str(em.base.model.names[lc.joint]))) for lc in em.links
    }
    first = {lc.joint: lc for lc in reversed(em.links)}
    last = {lc.joint: lc for lc in em.links}

    def split(gm: pin.GeometryModel) -> pin.GeometryModel:
        out = pin.GeometryModel()
        for g in gm.geometryObjects:
            base_joint = next((j for j, e in ext_root.items() if e == g.parentJoint), None)
            lc = None if base_joint is None else first[base_joint]
            if lc is None or lc.beam is None:
                out.addGeometryObject(g.copy())
                continue
            tip_lc = last[base_joint]  # type: ignore[index]
            to_tip = tip_lc.placement.inverse()  # joint frame -> the last piece's frame
            root, tip = lc.beam
            shape = g.geometry
            mid = 0.5 * (root + tip)
            axis = (tip - root) / np.linalg.norm(tip - root)
            if isinstance(shape, coal.Cylinder | coal.Capsule) and _along(g.placement, axis, mid):
                h = float(shape.halfLength)
                for half, sign in (("root", -1.0), ("tip", 1.0)):
                    piece = g.copy()
                    piece.name = f"{g.name}/{half}"
                    piece.geometry = type(shape)(float(shape.radius), h)
                    z = np.asarray(g.placement.rotation)[:, 2]
                    s = 0.5 * h * (sign if float(z @ axis) > 0.0 else -sign)
                    M = pin.SE3(g.placement.rotation, g.placement.act(np.array([0.0, 0.0, s])))
                    if half == "tip":
                        piece.parentJoint = tips[base_joint]  # type: ignore[index]
                        M = to_tip * M
                    piece.placement = M
                    out.addGeometryObject(piece)
                continue
            h = g.copy()
            p = np.asarray(g.placement.translation)
            if np.linalg.norm(p - tip) < np.linalg.norm(p - root):  # nearer the tip: carried
                h.parentJoint = tips[base_joint]  # type: ignore[index]
                h.placement = to_tip * g.placement
            out.addGeometryObject(h)
        return out

    return dataclasses.replace(
        em.robot,
        visual_model=split(em.robot.visual_model),
        collision_model=split(em.robot.collision_model),
    )


def _along(M: pin.SE3, axis: np.ndarray, mid: np.ndarray) -> bool:
    """A shape placed at ``M`` lies along the beam: its axis parallel, its centre on the line."""
    z = np.asarray(M.rotation)[:, 2]
    off = np.asarray(M.translation) - mid
    parallel = abs(abs(float(z @ axis)) - 1.0) < 1e-6
    return bool(parallel and np.linalg.norm(np.cross(off, axis)) < 1e-6)


@public
def animate_mode(
    model: ElasticModel,
    result: Modes,
    index: int = 0,
    *,
    amplitude: float | None = None,
    period: float = 2.0,
    cycles: int = 3,
    collision: bool = False,
    serve: bool = False,
) -> Scene:
    """A scene of the robot vibrating in one mode, slowed down and amplified to be seen.

    The robot is the virtual-joint model's (:attr:`ElasticModel.robot`, the one of
    ``result.elastic`` when the modes carry it), its closures satisfied at every frame; the
    compliant links are drawn bending (:func:`display_robot`).

    Args:
        model: The elastic model the modes were computed on.
        result: Modes from :func:`pkdyn.precision.modes.modes` on ``model``.
        index: Mode number, 0 = lowest frequency.
        amplitude: Largest displacement of a joint or of the platform [m] (default 5 % of the
            robot's size).
        period: Displayed period [s].
        cycles: Periods played before the loop restarts.
        collision: Draw the collision geometry.
        serve: Start a live meshcat server (else: save the scene with ``save_html``).

    Returns:
        The scene, playing.

    """
    from pkdyn.inputs import instance

    instance("model", model, ElasticModel, "an ElasticModel (pkdyn.precision.elastic_model)")
    instance("result", result, Modes, "Modes (pkdyn.precision.modes)")
    em = result.elastic if result.elastic is not None else model
    t, Q = mode_trajectory(em, result, index, amplitude, period, cycles)
    scene = Scene(display_robot(em), Q[0], collision=collision, serve=serve)
    scene.animate(t, Q)
    return scene
