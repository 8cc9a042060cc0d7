"""The robot library: one module per family, each a frozen parameter dataclass and a builder.

``FAMILIES`` maps a family name to its :class:`Family`; the committed ``urdf/<name>.urdf`` files
are the builders' output on the default parameters (a test keeps them in sync).
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pkdyn.exceptions import ParameterError

__all__ = ["Family", "FAMILIES", "URDF_DIR", "family_names"]

URDF_DIR = Path(__file__).resolve().parents[2] / "urdf"
"""Directory of the committed descriptions (source checkout)."""


@dataclass(frozen=True)
class Family:
    """A robot family of the library.

    Attributes:
        name: Family name (also the URDF file stem).
        summary: One-line description.
        params: Frozen dataclass of parameters (SI units, documented defaults).
        build_urdf: ``params -> URDF text``.
        home: ``params -> actuated coordinates`` of the home configuration.

    """

    name: str
    summary: str
    params: type
    build_urdf: Callable[[Any], str]
    home: Callable[[Any], list[float]]

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
        kwargs: dict[str, Any] = {}
        for key, value in overrides.items():
            if key not in fields:
                raise ParameterError(
                    self.name, key, f"unknown; valid parameters: {', '.join(sorted(fields))}"
                )
            default = getattr(self.params(), key)
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


MODULES = ("delta", "gough_stewart", "planar_3rrr", "five_bar", "tripod")
"""Family modules of ``pkdyn.library``, in documentation order."""


def _family(module: str) -> Family:
    m = importlib.import_module(f"pkdyn.library.{module}")
    return Family(m.NAME, m.SUMMARY, m.Params, m.build_urdf, m.home)


FAMILIES: dict[str, Family] = {
    f.name: f
    for f in (
        _family(m) for m in MODULES if importlib.util.find_spec(f"pkdyn.library.{m}") is not None
    )
}


def family_names() -> list[str]:
    """Names of the library families, sorted."""
    return sorted(FAMILIES)
