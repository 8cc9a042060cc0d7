"""Parametrisations: design variables that are not builder parameters, mapped onto them.

A study may sweep quantities a family's builder does not take directly: Clavel's normalised
``r = (ra - rb) / la`` and ``b = lb / la`` (seed 000), or scale factors of Merlet's MEL hexapod
(seed 002), whose joint centres are 6 x 3 tables. A :class:`Parametrisation` names its inputs
and returns the builder parameters they set. Built-ins: :data:`PARAMETRISATIONS`; a study may
also name ``module:attribute`` of its own :class:`Parametrisation` in a plug-in the user loaded
(:mod:`pkdyn.design.plugins`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = ["PARAMETRISATIONS", "Parametrisation", "parametrisation"]


@dataclass(frozen=True)
class Parametrisation:
    """Builder parameters derived from design variables.

    Attributes:
        name: Name used in study files.
        inputs: Names of the variables it needs (they are not builder parameters).
        fn: ``fn(values, defaults) -> {builder parameter: value}``; ``values`` holds every
            fixed and ranged value of the design, ``defaults`` the family's default parameters.
        summary: One line for ``--help`` and the docs.
        optional: Names of the variables it reads when given.

    """

    name: str
    inputs: tuple[str, ...]
    fn: Callable[[Mapping[str, Any], Any], dict[str, Any]]
    summary: str = ""
    optional: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        from pkdyn.inputs import callable_input, names

        if not isinstance(self.name, str) or not self.name.strip():
            raise InvalidInputError(
                "parametrisation", f"name: expected text, got {self.name!r:.40}"
            )
        if not isinstance(self.summary, str):
            raise InvalidInputError(
                f"parametrisation '{self.name}'",
                f"summary: expected text, got {self.summary!r:.40}",
            )
        object.__setattr__(self, "inputs", names("inputs", self.inputs, what="variable"))
        object.__setattr__(
            self, "optional", names("optional", self.optional, what="variable", empty=True)
        )
        callable_input("fn", self.fn)

    @property
    def names(self) -> tuple[str, ...]:
        """Every variable name it reads."""
        return self.inputs + self.optional

    def __call__(self, values: Mapping[str, Any], defaults: Any) -> dict[str, Any]:
        """Builder overrides for ``values``."""
        missing = [k for k in self.inputs if k not in values]
        if missing:
            raise InvalidInputError(
                f"parametrisation '{self.name}'", f"needs a range or fixed value for {missing[0]}"
            )
        return self.fn(values, defaults)


def _get(values: Mapping[str, Any], defaults: Any, name: str) -> float:
    return float(values[name]) if name in values else float(getattr(defaults, name))


def _clavel(values: Mapping[str, Any], defaults: Any) -> dict[str, Any]:
    from types import SimpleNamespace

    from pkdyn.workspace.clavel import clavel_closed_form

    la, rb = _get(values, defaults, "la"), _get(values, defaults, "rb")
    out: dict[str, Any] = {"ra": rb + float(values["r"]) * la, "lb": float(values["b"]) * la}
    if "z_home" not in values:  # home in the middle of the complete prism (Clavel's limits)
        g = SimpleNamespace(la=la, rb=rb, ra=out["ra"], lb=out["lb"])
        kw = {k: float(values[k]) for k in ("gamma_max", "ab_min") if k in values}
        f = clavel_closed_form(g, **kw)
        out["z_home"] = f.zh - 0.5 * f.H
    return out


def _mel(values: Mapping[str, Any], defaults: Any) -> dict[str, Any]:
    A = np.array(defaults.A, dtype=float)
    B = np.array(defaults.B, dtype=float)
    A[:, :2] *= float(values["base_scale"])
    B[:, :2] *= float(values["platform_scale"])
    lo = np.array(defaults.rho_min, dtype=float) * float(values["leg_scale"])
    stroke = (np.array(defaults.rho_max) - np.array(defaults.rho_min)) * float(values["leg_scale"])
    hi = lo + stroke * float(values.get("stroke_scale", 1.0))
    return {
        "A": tuple(tuple(float(v) for v in row) for row in A),
        "B": tuple(tuple(float(v) for v in row) for row in B),
        "rho_min": tuple(float(v) for v in lo),
        "rho_max": tuple(float(v) for v in hi),
    }


PARAMETRISATIONS: dict[str, Parametrisation] = {
    "clavel": Parametrisation(
        "clavel",
        ("r", "b"),
        _clavel,
        "Delta by Clavel's normalised r = (ra - rb)/la and b = lb/la (la, rb fixed or default; "
        "z_home, unless fixed, in the middle of Clavel's prism)",
    ),
    "mel": Parametrisation(
        "mel",
        ("base_scale", "platform_scale", "leg_scale"),
        _mel,
        "Gough-Stewart like Merlet's MEL: joint circles scaled (x, y), leg lengths scaled, "
        "stroke scaled (stroke_scale optional, default 1)",
        optional=("stroke_scale",),
    ),
}
"""Built-in parametrisations by name."""


def parametrisation(name: str) -> Parametrisation:
    """A built-in parametrisation, or ``module:attribute`` of a loaded plug-in.

    Raises:
        InvalidInputError: Unknown name, a module that is not a loaded plug-in
            (:mod:`pkdyn.design.plugins`: a study never imports code), or an attribute that is
            not a parametrisation.

    """
    from pkdyn.design import plugins

    if not isinstance(name, str):
        raise InvalidInputError("parametrisation", f"expected a name, got {name!r}")
    if name in PARAMETRISATIONS:
        return PARAMETRISATIONS[name]
    if ":" in name:
        obj = plugins.resolve(name, "parametrisation")
        if isinstance(obj, Parametrisation):
            return obj
        raise InvalidInputError("parametrisation", f"'{name}' is not a Parametrisation")
    raise InvalidInputError(
        "parametrisation",
        f"unknown '{name}' (built-in: {', '.join(PARAMETRISATIONS)}; or module:attribute of a "
        "plug-in loaded with --plugin MODULE)",
    )
