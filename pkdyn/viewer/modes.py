"""A natural mode of vibration played slowly in a meshcat scene."""

from __future__ import annotations

from pkdyn.model.arguments import public
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.modes import Modes, mode_trajectory
from pkdyn.viewer.scene import Scene

__all__ = ["animate_mode"]


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

    The robot is the virtual-joint model's (:attr:`ElasticModel.robot`): with compliant links,
    their deflection shows as the tip part of each link moving off its root.

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
    t, Q = mode_trajectory(model, result, index, amplitude, period, cycles)
    scene = Scene(model.robot, Q[0], collision=collision, serve=serve)
    scene.animate(t, Q)
    return scene
