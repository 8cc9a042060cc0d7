"""pkdyn's meshcat viewer: robot scenes, trajectory animation, overlays, static HTML export.

The core never imports this package. Entry points take plain arrays::

    from pkdyn.viewer import Scene, animate

    scene = animate(robot, t, Q, singular=True)   # t (N,) [s], Q (N, nq)
    scene.add_points("workspace", P)              # (N, 3) [m]
    scene.save_html("delta.html")                 # opens without a server or network

    scene = animate_mode(model, modes(model, q), index=0)   # a natural mode, slowed down
    scene = animate_vibration(pkdyn.precision.vibration(robot, "adept", ...))  # exaggerated
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.viewer.animation import chain, check_trajectory
from pkdyn.viewer.camera import Camera, bounding_box, frame_box, project
from pkdyn.viewer.highlight import closest_pair, singularity_labels
from pkdyn.viewer.html import static_html
from pkdyn.viewer.modes import animate_mode
from pkdyn.viewer.scene import Scene
from pkdyn.viewer.vibration import animate_vibration
from pkdyn.viewer.window import OfflineWindow

__all__ = [
    "Camera",
    "OfflineWindow",
    "Scene",
    "animate",
    "animate_mode",
    "animate_vibration",
    "bounding_box",
    "chain",
    "closest_pair",
    "export_html",
    "frame_box",
    "project",
    "singularity_labels",
    "static_html",
]


@public
def animate(
    robot: Robot,
    t: np.ndarray,
    Q: np.ndarray,
    *,
    singular: bool = False,
    closest: bool = False,
    collision: bool = False,
) -> Scene:
    """A scene of ``robot`` playing the trajectory ``(t, Q)`` in a loop.

    Args:
        robot: Robot loaded with its geometry.
        t: Sample times (N,) [s].
        Q: Assembled configurations (N, nq).
        singular: Colour singular (red) and near-singular (pink) samples.
        closest: Colour the two collision objects closest to each other.
        collision: Draw the collision geometry.

    Returns:
        The scene (``save_html`` it, or add overlays first).

    """
    tt, QQ = check_trajectory(t, Q, robot.nq)
    scene = Scene(robot, QQ[0], collision=collision)
    scene.animate(tt, QQ, singular=singular, closest=closest)
    return scene


def export_html(scene: Scene, path: str | Path) -> Path:
    """Write the scene as one self-contained HTML file (see :meth:`Scene.save_html`)."""
    from pkdyn.inputs import instance

    instance("scene", scene, Scene, "a Scene (pkdyn.viewer.Scene)")
    return scene.save_html(path)
