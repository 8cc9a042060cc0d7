"""What size a dynamic parameter plausibly has, and how strongly the nominal values hold it.

- :func:`parameter_scales`: the size of each standard parameter: its nominal value, at least a
  hundredth of the largest of its kind (a first moment or product of inertia of 1e-19 from
  rounding is zero, not a scale); a kind whose nominal values are all zero (products of inertia
  of symmetric bodies, the rotor inertia and friction of a description without drives) takes a
  hundredth of the largest nominal value in the same unit (a rotor inertia: of the bodies'
  inertias), else a hundredth of a scale of its unit the caller gives (friction: the motor
  torque that holds the robot's weight at its size);
- :func:`base_references`: the plausible magnitude of each base parameter, ``sum_j |K_kj|
  scale_j``: the estimator (:mod:`~pkdyn.identification.estimation`) calls a base parameter
  excited when the data determine it better than that;
- :func:`prior_weights`: the metric ``D`` of the physically consistent fit's pull to the
  nominal values (:mod:`~pkdyn.identification.physical`).
"""

from __future__ import annotations

import numpy as np

from pkdyn.identifiability import Identifiability
from pkdyn.model.robot import Robot

__all__ = ["base_references", "drive_scales", "parameter_scales", "prior_weights"]


def parameter_scales(
    names: tuple[str, ...] | list[str],
    nominal: np.ndarray,
    units: tuple[str, ...] | list[str] = (),
    unit_scales: dict[str, float] | None = None,
) -> np.ndarray:
    """The size of each standard parameter (module docstring), > 0.

    Args:
        names: Parameter names (p,) (``<body>.<field>``: the field is the kind).
        nominal: Their nominal values (p,).
        units: Their units (p,) (the second fallback), or empty.
        unit_scales: A scale per unit for kinds and units without any nominal value (the third
            fallback; then 1).

    Returns:
        Sizes (p,) in the parameters' units.

    """
    kind = np.array([n.rsplit(".", 1)[-1] for n in names])
    unit = np.array(list(units) if len(units) == len(names) else [""] * len(names))
    mag = np.abs(np.asarray(nominal, dtype=float))
    floor = np.zeros(mag.size)
    extra = unit_scales or {}
    for k in range(mag.size):
        same_kind = mag[kind == kind[k]].max()
        same_unit = mag[unit == unit[k]].max() if unit[k] else 0.0
        if same_kind > 0.0:
            floor[k] = 1e-2 * same_kind
        elif same_unit > 0.0:
            floor[k] = 1e-2 * same_unit
        else:
            floor[k] = 1e-2 * float(extra.get(str(unit[k]), 100.0))
    return np.maximum(mag, floor)


def drive_scales(robot: Robot) -> dict[str, float]:
    """Scales of the drive parameters' units from the robot's weight and size (motor side).

    ``N m``: the torque that holds the robot's weight at its size, per actuator, through the
    mean reduction; ``N m s/rad``: that torque per joint speed of 1 rad/s on the motor (times
    the reduction).

    """
    mass = float(sum(I.mass for I in robot.model.inertias))
    n_a = max(len(robot.actuators), 1)
    red = float(np.mean([abs(a.reduction) for a in robot.actuators])) if robot.actuators else 1.0
    torque = 9.81 * mass * robot.length_scale / n_a / max(red, 1e-12)
    return {"N m": torque, "N m s/rad": torque / max(red, 1e-12)}


def base_references(
    base: Identifiability, nominal: np.ndarray, unit_scales: dict[str, float] | None = None
) -> np.ndarray:
    """Plausible magnitude of each base parameter: ``sum_j |K_kj| scale_j`` (module docstring).

    Args:
        base: The base parameters of the identified standard parameters.
        nominal: Nominal values of those standard parameters (p,).
        unit_scales: Scales of units without nominal values (:func:`drive_scales`).

    Returns:
        Magnitudes (p_b,) > 0.

    """
    return np.abs(base.K) @ parameter_scales(base.names, nominal, base.units, unit_scales)


def prior_weights(
    effect: np.ndarray,
    nominal: np.ndarray,
    base: Identifiability,
    unseen: np.ndarray | None = None,
    unit_scales: dict[str, float] | None = None,
) -> np.ndarray:
    """Metric ``D`` of the pull to the nominal values (:mod:`~.physical`), per parameter.

    A parameter the efforts see weighs its effect on them (its column norm in noise units). One
    the efforts do not see (no effect, or only in base parameters the motion does not excite)
    would weigh nothing and could drift anywhere when its body needs a change to be physical; it
    weighs instead what a change of the same relative size costs a typical seen parameter: it
    moves no more than its body's consistency needs, and the data still decide everything they
    can see.

    Args:
        effect: Column norms (p,) of the identified parameters, in noise units.
        nominal: Their nominal values (p,).
        base: Their base parameters.
        unseen: Parameters the data do not see beyond those without effect (p,) bool.
        unit_scales: Scales of units without nominal values (:func:`drive_scales`).

    Returns:
        Weights (p,), > 0.

    """
    out = effect.copy()
    hidden = np.zeros(effect.size, dtype=bool) if unseen is None else unseen.copy()
    names = list(base.names)
    for n in base.no_effect:
        hidden[names.index(n)] = True
    seen = ~hidden & (effect > 0.0) & (nominal != 0.0)
    typical = float(np.median(effect[seen] * np.abs(nominal[seen]))) if seen.any() else 1.0
    scale = parameter_scales(base.names, nominal, base.units, unit_scales)
    out[hidden] = typical / scale[hidden]
    tiny = out <= 0.0
    out[tiny] = 1e-12 * max(float(out.max(initial=0.0)), 1.0)
    return out
