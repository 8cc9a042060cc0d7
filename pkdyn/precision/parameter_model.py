"""A parameter model: a linear map from geometric parameters to placement twists and gains.

A :class:`ParameterModel` maps parameters ``p`` (n_par,) to placement twists and actuator
gains, linearly: ``xi = E p`` (6 n_placements,) and ``g = G p`` (n_a,), the actuated joint
coordinate being ``(1 + g) qa`` for an actuator reading ``qa``. Three models build one
(:mod:`pkdyn.precision.parameters`): every placement's twist
(:mod:`~pkdyn.precision.placement_parameters`), the shortcuts of a library family
(:mod:`~pkdyn.precision.shortcuts`), the family builder's own parameters
(:mod:`~pkdyn.precision.family_parameters`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.robot import Robot
from pkdyn.precision.placements import Placement

__all__ = ["ParameterModel", "with_gains"]


@dataclass(frozen=True, eq=False)  # numpy fields: no boolean ==
class ParameterModel:
    """A linear model of geometric errors: ``xi = E p`` (placement twists), ``g = G p`` (gains).

    Attributes:
        kind: ``placements``, ``family shortcuts`` or ``family parameters``.
        names: Parameter names (n_par,).
        units: Their units (``m``, ``rad``, ``-`` for gains).
        placements: The robot's placements (n_pl,).
        E: Twist of every placement per unit parameter (6 n_pl, n_par) [m or rad per unit]:
            rows ``6 k .. 6 k + 5`` are placement ``k``'s twist (translation, rotation) in the
            frame it places.
        G: Relative actuator gain per unit parameter (n_a, n_par).
        nominal: Nominal values of the parameters when they have one (family parameters),
            else zeros (errors).

    """

    kind: str
    names: tuple[str, ...]
    units: tuple[str, ...]
    placements: tuple[Placement, ...]
    E: np.ndarray
    G: np.ndarray
    nominal: np.ndarray

    @property
    def size(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def index(self, name: str) -> int:
        """Position of a parameter by name.

        Raises:
            InvalidInputError: No parameter of that name.

        """
        try:
            return self.names.index(name)
        except ValueError:
            close = [n for n in self.names if n.split(".")[0] == name.split(".")[0]][:6]
            hint = f" (e.g. {', '.join(close)})" if close else ""
            raise InvalidInputError(
                "parameter", f"'{name}' is not a parameter of this model{hint}"
            ) from None

    def twists(self, p: np.ndarray) -> np.ndarray:
        """Placement twists (n_pl, 6) [m, rad] of parameters ``p`` (n_par,)."""
        return (self.E @ np.asarray(p, dtype=float)).reshape(-1, 6)

    def gains(self, p: np.ndarray) -> np.ndarray:
        """Relative actuator gains (n_a,) of parameters ``p`` (n_par,)."""
        return self.G @ np.asarray(p, dtype=float)

    def tolerances(self, length: float, angle: float, gain: float = 0.0) -> np.ndarray:
        """A tolerance per parameter from its unit: ``length`` [m], ``angle`` [rad], ``gain`` [-].

        Args:
            length: Tolerance of lengths [m].
            angle: Tolerance of angles [rad].
            gain: Tolerance of relative gains [-].

        Returns:
            Tolerances (n_par,).

        """
        table = {"m": length, "rad": angle, "-": gain}
        return np.array([table.get(u, 0.0) for u in self.units])

    def subset(self, keep: np.ndarray) -> ParameterModel:
        """The model restricted to some parameters (indices or a boolean mask)."""
        idx = np.arange(self.size)[np.asarray(keep)]
        return dataclasses.replace(
            self,
            names=tuple(self.names[i] for i in idx),
            units=tuple(self.units[i] for i in idx),
            E=self.E[:, idx],
            G=self.G[:, idx],
            nominal=self.nominal[idx],
        )


def with_gains(
    robot: Robot, E: np.ndarray, G: np.ndarray, names: list[str], units: list[str]
) -> tuple[np.ndarray, np.ndarray]:
    """``E`` and ``G`` with one relative gain per actuator appended (``names``, ``units`` too)."""
    n_a = len(robot.actuators)
    E = np.hstack([E, np.zeros((E.shape[0], n_a))])
    G = np.hstack([G, np.eye(n_a)])
    names += [f"{a.name}.gain" for a in robot.actuators]
    units += ["-"] * n_a
    return E, G
