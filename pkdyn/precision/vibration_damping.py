"""Damping of the elastic model in a vibration analysis: the servos' and the links'.

- Each finite **actuator** is a servo, a spring-damper between the commanded and the actual joint
  coordinate: ``c`` [N m s/rad or N s/m] on the error rate, given (``actuator_damping``), or
  ``c = 2 Z k / omega_1`` from a damping ratio ``Z`` (``damping_ratio``, default
  :data:`DEFAULT_DAMPING_RATIO`), ``k`` its stiffness and ``omega_1`` the first undamped
  natural frequency [rad/s] at the **middle pose** of the motion (the commanded pose at half
  its duration; for the Adept cycle, the place point).
- Each **compliant link**'s virtual spring gets the stiffness-proportional (Rayleigh) damping
  ``beta k`` with ``beta = 2 Z / omega_1`` [s], the same ``Z`` and ``omega_1``.

With the ratio alone the damping matrix is ``beta K`` (proportional): mode ``i`` then has the
damping ratio ``Z omega_i / omega_1`` (``Z`` for the first mode at the middle pose, more for
the higher ones) exactly, in both methods. The robot's own dampers (``robot.passive``) act
besides.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.inputs import number_array
from pkdyn.precision.elastic import ElasticModel

__all__ = [
    "DEFAULT_DAMPING_RATIO",
    "MAX_DAMPING_RATIO",
    "Damping",
    "actuator_damping_values",
    "damping",
    "damping_ratio",
]

DEFAULT_DAMPING_RATIO = 0.02
"""Damping ratio of the first mode when none is given (2 %: a lightly damped servo axis and
metal or carbon links)."""

MAX_DAMPING_RATIO = 10.0
"""Largest damping ratio accepted (beyond, the motion is creep, not vibration)."""


@dataclass(frozen=True, eq=False)  # numpy fields
class Damping:
    """The damping of a vibration analysis (see the module docstring).

    Attributes:
        ratio: Damping ratio ``Z`` of the first mode at the middle pose.
        f1: First undamped natural frequency at the middle pose [Hz].
        middle: Time of the middle pose [s].
        beta: Stiffness-proportional coefficient ``2 Z / omega_1`` [s].
        actuator: Servo damping per actuator (n_a,) [N m s/rad or N s/m] (0 for a rigid one).
        given: ``actuator`` was given (else derived from ``ratio``).

    """

    ratio: float
    f1: float
    middle: float
    beta: float
    actuator: np.ndarray
    given: bool

    def coefficients(self, em: ElasticModel) -> np.ndarray:
        """Viscous coefficient per extended velocity coordinate (nv_ext,): servos and links.

        The robot's own dampers are not included (they are in ``em.robot.passive``).
        """
        out = np.zeros(em.nv)
        iv = np.asarray(em.robot.actuated_v)
        finite = np.isfinite(em.actuator_stiffness)
        out[iv[finite]] = self.actuator[finite]
        if em.links and em.robot.passive is not None:
            d = np.asarray(em.deflection_v).ravel()
            out[d] += self.beta * np.asarray(em.robot.passive.stiffness)[d]
        return out

    def to_json(self) -> dict[str, Any]:
        """JSON-ready description (SI units)."""
        return {
            "damping_ratio": self.ratio,
            "f1_middle": self.f1,
            "middle_time": self.middle,
            "beta": self.beta,
            "actuator_damping": [float(c) for c in self.actuator],
            "actuator_damping_given": self.given,
            "links": "stiffness-proportional beta k on each link's virtual spring",
        }


def damping_ratio(value: Any) -> float:
    """A damping ratio, checked: a finite number in ``[0, MAX_DAMPING_RATIO]``.

    Raises:
        InvalidInputError: Not a number, negative, or beyond :data:`MAX_DAMPING_RATIO`.

    """
    from pkdyn.inputs import real

    z = real("damping_ratio", value)
    if not 0.0 <= z <= MAX_DAMPING_RATIO:
        raise InvalidInputError(
            "damping_ratio", f"{z:g}: a damping ratio is in [0, {MAX_DAMPING_RATIO:g}]"
        )
    return z


def damping(
    em: ElasticModel,
    f1: float,
    middle: float,
    ratio: float | None = None,
    actuator_damping: float | Sequence[float] | np.ndarray | None = None,
) -> Damping:
    """The damping of the analysis (see the module docstring).

    Args:
        em: The elastic model.
        f1: First undamped natural frequency at the middle pose [Hz].
        middle: Time of that pose [s].
        ratio: Damping ratio ``Z`` (default :data:`DEFAULT_DAMPING_RATIO`).
        actuator_damping: Servo damping, one or one per actuator [N m s/rad or N s/m]
            (default: ``2 Z k / omega_1``).

    Returns:
        The damping.

    Raises:
        InvalidInputError: A bad ratio or damping (the value is named).

    """
    z = DEFAULT_DAMPING_RATIO if ratio is None else damping_ratio(ratio)
    omega1 = 2.0 * math.pi * float(f1)
    beta = 2.0 * z / omega1
    k = em.actuator_stiffness
    if actuator_damping is None:
        c = np.where(np.isfinite(k), beta * np.where(np.isfinite(k), k, 0.0), 0.0)
        return Damping(z, float(f1), float(middle), beta, c, False)
    arr = actuator_damping_values(em, actuator_damping)
    arr = np.where(np.isfinite(k), arr, 0.0)
    return Damping(z, float(f1), float(middle), beta, arr, True)


def actuator_damping_values(
    em: ElasticModel, value: float | Sequence[float] | np.ndarray
) -> np.ndarray:
    """Servo damping per actuator (n_a,) [N m s/rad or N s/m], checked.

    One value or one per actuator, each finite, ``>= 0`` and at most 1e12.

    Raises:
        InvalidInputError: Not numbers, a wrong count, or a bad value (the actuator named).

    """
    names = em.base.actuator_names
    actuator_damping = value
    if isinstance(actuator_damping, bool):
        raise InvalidInputError("actuator_damping", f"{actuator_damping!r:.60} is not a number")
    arr = number_array("actuator_damping", actuator_damping, "a number or one per actuator")
    if arr.size not in (1, len(names)):
        raise InvalidInputError(
            "actuator_damping",
            f"{arr.size} values for {len(names)} actuators ({', '.join(names)}): give 1 or "
            f"{len(names)}",
        )
    arr = np.array(np.broadcast_to(arr, (len(names),)))
    for name, c in zip(names, arr, strict=True):
        if not (math.isfinite(c) and 0.0 <= c <= 1e12):
            raise InvalidInputError(
                "actuator_damping",
                f"{c:g} for actuator '{name}': a damping must be finite, >= 0 and at most 1e12 "
                "[N m s/rad or N s/m]",
            )
    return arr
