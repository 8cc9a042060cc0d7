"""A vibrating robot along its motion, the deviation exaggerated and the time slowed down."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.precision.equilibrium import reassembled
from pkdyn.precision.vibration_result import VibrationResult
from pkdyn.viewer.scene import Scene

__all__ = ["animate_vibration", "exaggerated"]


def exaggerated(
    result: VibrationResult, scale: float | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """The commanded motion with the deformation multiplied by ``scale``, assembled.

    Args:
        result: A vibration result (it keeps its elastic model, command and deformation).
        scale: Exaggeration factor (default: the peak deviation shown as 5 % of the robot's
            size).

    Returns:
        ``(t, Q, scale)``: times (K,) [s], configurations of the elastic model's robot
        (K, nq_ext) and the factor used.

    Raises:
        InvalidInputError: A result without its deformation, or a non-positive scale.

    """
    from pkdyn.inputs import instance

    instance("result", result, VibrationResult, "a VibrationResult (pkdyn.precision.vibration)")
    em = result.elastic
    shown = result.animation()
    if em is None or shown is None:
        raise InvalidInputError("result", "this result keeps no deformation to animate")
    t_coarse, command, deformation = shown
    r = em.robot
    if scale is None:
        top = max(float(result.peak_deviation), float(np.max(result.deviation_norm)), 1e-300)
        scale = 0.05 * r.length_scale / top
    from pkdyn.inputs import positive

    scale = positive("scale", scale, bound=1e12)
    Q = np.empty_like(command)
    q = command[0]
    for k, (qc, u) in enumerate(zip(command, deformation, strict=True)):
        q = pin.integrate(r.model, qc, scale * u)
        if r.constraints.nc:
            q = reassembled(em, q).q
        Q[k] = q
    return np.asarray(t_coarse), Q, float(scale)


@public
def animate_vibration(
    result: VibrationResult,
    *,
    scale: float | None = None,
    slow: float = 20.0,
    collision: bool = False,
    serve: bool = False,
) -> Scene:
    """A scene of the robot moving along the command, its deformation exaggerated.

    Args:
        result: A vibration result (from a robot loaded with its geometry).
        scale: Exaggeration of the deformation (default: the peak deviation shown as 5 % of
            the robot's size).
        slow: Slow-motion factor of the playback (a 100 Hz vibration slowed 20 times is seen).
        collision: Draw the collision geometry.
        serve: Start a live meshcat server (else: save the scene with ``save_html``).

    Returns:
        The scene, playing in a loop.

    """
    from pkdyn.inputs import positive

    slow = positive("slow", slow, bound=1e6)
    t, Q, _ = exaggerated(result, scale)
    assert result.elastic is not None
    scene = Scene(result.elastic.robot, Q[0], collision=collision, serve=serve)
    scene.animate(t * slow, Q)
    return scene
