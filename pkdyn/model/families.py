"""The registry of robot families that ``pkdyn.load(name)`` resolves.

The model layer owns the registry; :mod:`pkdyn.library` registers its families into it when
:mod:`pkdyn` is imported, so the loader never imports the library (layering).
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from pkdyn.exceptions import ParameterError, UnknownRobotError

__all__ = ["FAMILIES", "Family", "family", "register"]


@dataclass(frozen=True)
class Family:
    """A robot family of the library.

    The family's module is imported on first use (``import pkdyn`` stays light): it defines
    ``NAME``, ``SUMMARY``, a frozen ``Params`` dataclass, ``build_urdf(params) -> str`` and
    ``home(params) -> list[float]`` (actuated coordinates of the home configuration).

    Attributes:
        name: Family name (also the URDF file stem).
        module: Dotted name of the module that builds it.

    """

    name: str
    module: str

    def _module(self) -> ModuleType:
        return importlib.import_module(self.module)

    @property
    def summary(self) -> str:
        """One-line description."""
        return str(self._module().SUMMARY)

    @property
    def params(self) -> type:
        """Frozen dataclass of parameters (SI units, documented defaults)."""
        return self._module().Params  # type: ignore[no-any-return]

    def build_urdf(self, params: Any) -> str:
        """URDF text of the robot with these parameters."""
        return str(self._module().build_urdf(params))

    def home(self, params: Any) -> list[float]:
        """Actuated coordinates of the home configuration."""
        return list(self._module().home(params))

    def make_params(self, overrides: dict[str, Any]) -> Any:
        """Parameters with ``overrides`` applied; strings are converted to the field type.

        Args:
            overrides: ``{name: value}``.

        Returns:
            The parameter dataclass instance.

        Raises:
            ParameterError: Unknown name or value that does not convert / validate.

        """
        fields = {f.name: f for f in dataclasses.fields(self.params)}
        defaults = self.params()  # once: a family's defaults may be costly to validate
        kwargs: dict[str, Any] = {}
        for key, value in overrides.items():
            if key not in fields:
                raise ParameterError(
                    self.name, key, f"unknown; valid parameters: {', '.join(sorted(fields))}"
                )
            default = getattr(defaults, key)
            try:
                if isinstance(default, bool):
                    kwargs[key] = (
                        value
                        if isinstance(value, bool)
                        else str(value).lower()
                        in (
                            "1",
                            "true",
                            "yes",
                        )
                    )
                elif isinstance(default, tuple):
                    parsed = ast.literal_eval(value) if isinstance(value, str) else value
                    kwargs[key] = tuple(
                        tuple(float(x) for x in row)
                        if isinstance(row, list | tuple)
                        else float(row)
                        for row in parsed
                    )
                elif isinstance(default, int | float):
                    kwargs[key] = type(default)(float(value))
                else:
                    kwargs[key] = type(default)(value)
            except (TypeError, ValueError, SyntaxError):
                raise ParameterError(
                    self.name, key, f"cannot use {value!r} (expected {type(default).__name__})"
                ) from None
        return self.params(**kwargs)


FAMILIES: dict[str, Family] = {}
"""Registered families by name, in registration (documentation) order; fill with
:func:`register`."""


def register(fam: Family) -> None:
    """Add a family to the registry (done by :mod:`pkdyn.library`).

    Args:
        fam: The family; its name must be new.

    Raises:
        ValueError: A family of that name is already registered (a programming error).

    """
    if fam.name in FAMILIES and FAMILIES[fam.name] != fam:
        raise ValueError(f"family {fam.name!r} registered twice")
    FAMILIES[fam.name] = fam


def family(name: str) -> Family:
    """The family called ``name``.

    Raises:
        UnknownRobotError: No such family.

    """
    try:
        return FAMILIES[name]
    except KeyError:
        raise UnknownRobotError(name, list(FAMILIES)) from None
