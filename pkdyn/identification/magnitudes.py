"""What size a dynamic parameter plausibly has, and how strongly the nominal values hold it.

- :func:`parameter_scales`: the size of each standard parameter: its nominal value, at least a
  hundredth of the largest of its kind (a first moment or product of inertia of 1e-19 from
  rounding is zero, not a scale); a kind whose nominal values are all zero (friction and rotor
  inertia of a description without drives) takes the largest nominal value of all;
- :func:`base_references`: the plausible magnitude of each base parameter, ``sum_j |K_kj|
  scale_j``: the estimator (:mod:`~pkdyn.identification.estimation`) calls a base parameter
  excited when the data determine it better than that;
- :func:`prior_weights`: the metric ``D`` of the physically consistent fit's pull to the
  nominal values (:mod:`~pkdyn.identification.physical`).
"""

from __future__ import annotations

import numpy as np

from pkdyn.identifiability import Identifiability

__all__ = ["base_references", "parameter_scales", "prior_weights"]


def parameter_scales(names: tuple[str, ...] | list[str], nominal: np.ndarray) -> np.ndarray:
    """The size of each standard parameter (module docstring), > 0.

    Args:
        names: Parameter names (p,) (``<body>.<field>``: the field is the kind).
        nominal: Their nominal values (p,).

    Returns:
        Sizes (p,) in the parameters' units.

    """
    kind = np.array([n.rsplit(".", 1)[-1] for n in names])
    mag = np.abs(np.asarray(nominal, dtype=float))
    floor = np.array([mag[kind == k].max() for k in kind]) if kind.size else np.zeros(0)
    floor = np.where(floor > 0.0, 1e-2 * floor, mag.max(initial=1.0) or 1.0)
    return np.maximum(mag, floor)


def base_references(base: Identifiability, nominal: np.ndarray) -> np.ndarray:
    """Plausible magnitude of each base parameter: ``sum_j |K_kj| scale_j`` (module docstring).

    Args:
        base: The base parameters of the identified standard parameters.
        nominal: Nominal values of those standard parameters (p,).

    Returns:
        Magnitudes (p_b,) > 0.

    """
    return np.abs(base.K) @ parameter_scales(base.names, nominal)


def prior_weights(
    effect: np.ndarray,
    nominal: np.ndarray,
    base: Identifiability,
    unseen: np.ndarray | None = None,
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
    scale = parameter_scales(base.names, nominal)
    out[hidden] = typical / scale[hidden]
    tiny = out <= 0.0
    out[tiny] = 1e-12 * max(float(out.max(initial=0.0)), 1.0)
    return out
