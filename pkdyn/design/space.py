"""The design space of a study: a family, ranges of some parameters, the others fixed.

A design is a point of the box spanned by the :class:`Range` s; :class:`DesignSpace` turns it
into the family's builder parameters: the fixed values, the design variables, and, when the
study names a *parametrisation* (:mod:`pkdyn.design.parametrisations`), the builder parameters
it derives from variables that are not builder parameters themselves (Clavel's normalised
``r, b``; the scale factors of a MEL-like hexapod).
"""

from __future__ import annotations

import ast
import dataclasses
import math
import numbers
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from pkdyn.design.parametrisations import Parametrisation, parametrisation
from pkdyn.exceptions import InvalidInputError, ParameterError
from pkdyn.model.families import Family, family

__all__ = ["DesignSpace", "Range"]


@dataclass(frozen=True)
class Range:
    """The interval a design variable takes.

    Attributes:
        name: Builder parameter (or parametrisation input) name.
        low: Lower bound (SI units of the parameter).
        high: Upper bound, strictly above ``low``.

    """

    name: str
    low: float
    high: float

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidInputError("range", f"a range needs a parameter name, got {self.name!r}")
        for bound in (self.low, self.high):
            if isinstance(bound, bool) or not isinstance(bound, numbers.Real):
                raise InvalidInputError(
                    f"range '{self.name}'", f"bounds must be numbers, got {bound!r}"
                )
        if not (math.isfinite(self.low) and math.isfinite(self.high)):
            raise InvalidInputError(
                f"range '{self.name}'", f"bounds must be finite, got {self.low}:{self.high}"
            )
        from pkdyn.inputs import MAX_MAGNITUDE

        if max(abs(self.low), abs(self.high)) > MAX_MAGNITUDE:
            raise InvalidInputError(
                f"range '{self.name}'",
                f"{self.low:g}:{self.high:g} is beyond any plausible value (at most "
                f"{MAX_MAGNITUDE:g} in SI units)",
            )
        if self.high == self.low:
            raise InvalidInputError(
                f"range '{self.name}'",
                f"empty ({self.low}:{self.high}); give low < high, or fix the parameter",
            )
        if self.high < self.low:
            raise InvalidInputError(
                f"range '{self.name}'",
                f"inverted ({self.low}:{self.high}); write it {self.high}:{self.low}",
            )

    @classmethod
    def parse(cls, text: str) -> Range:
        """``NAME=LOW:HIGH`` (e.g. ``la=0.15:0.35``).

        Raises:
            InvalidInputError: Not of that form, or bounds that are not numbers.

        """
        if not isinstance(text, str):
            raise InvalidInputError("--range", f"expected NAME=LOW:HIGH, got {text!r:.40}")
        name, sep, span = text.partition("=")
        low, sep2, high = span.partition(":")
        if not (sep and sep2 and name.strip()):
            raise InvalidInputError("--range", f"'{text}': expected NAME=LOW:HIGH")
        try:
            return cls(name.strip(), float(low), float(high))
        except ValueError:
            raise InvalidInputError("--range", f"'{text}': bounds must be numbers") from None

    def at(self, u: np.ndarray) -> np.ndarray:
        """Values at fractions ``u`` in [0, 1] of the interval."""
        from pkdyn.inputs import vector

        u = vector("u", u)
        if u.size == 0 or np.any((u < 0.0) | (u > 1.0)):
            raise InvalidInputError("u", "expected fractions in [0, 1] (at least one)")
        return self.low + u * (self.high - self.low)

    def fraction(self, x: np.ndarray) -> np.ndarray:
        """Fractions in [0, 1] of values ``x`` (inverse of :meth:`at`)."""
        from pkdyn.inputs import vector

        x = vector("x", x)
        if x.size == 0:
            raise InvalidInputError("x", "no value")
        return (x - self.low) / (self.high - self.low)


def _numbers(x: Any) -> Any:
    """``x`` as an array when it can be one (else as given: its check refuses it)."""
    try:
        return np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        return x


@dataclass(frozen=True)
class DesignSpace:
    """A family, the ranges of its design variables and its fixed parameters.

    Attributes:
        family: Registered family name (:data:`pkdyn.model.families.FAMILIES`).
        ranges: The design variables.
        fixed: Fixed builder (or parametrisation) values, SI units.
        parametrisation: Name (or ``module:function``) of a parametrisation, or ``None``.

    Raises:
        UnknownRobotError: Unknown family.
        ParameterError: A variable or fixed value that is not a parameter of the family (nor
            an input of the parametrisation), a range on a non-numeric parameter, or a
            parameter both ranged and fixed.
        InvalidInputError: No range at all.

    """

    family: str
    ranges: tuple[Range, ...]
    fixed: Mapping[str, Any] = field(default_factory=dict)
    parametrisation: str | None = None

    def __post_init__(self) -> None:
        if isinstance(self.ranges, str | bytes | Mapping) or not isinstance(self.ranges, Iterable):
            raise InvalidInputError("ranges", f"expected Range objects, got {self.ranges!r:.60}")
        if not all(isinstance(r, Range) for r in self.ranges):
            raise InvalidInputError("ranges", "expected Range objects (pkdyn.design.Range)")
        if not isinstance(self.fixed, Mapping):
            raise InvalidInputError(
                "fixed", f"expected a mapping NAME: VALUE, got {self.fixed!r:.60}"
            )
        if not isinstance(self.family, str):
            raise InvalidInputError("family", f"expected a family name, got {self.family!r:.40}")
        object.__setattr__(self, "ranges", tuple(self.ranges))
        object.__setattr__(self, "fixed", dict(self.fixed))
        fam = self.family_obj
        if not self.ranges:
            raise InvalidInputError("ranges", "a study needs at least one --range NAME=LOW:HIGH")
        fields = {f.name: f for f in dataclasses.fields(fam.params)}
        inputs = set(self._mapping.names) if self._mapping else set()
        names = [r.name for r in self.ranges]
        for name in names + list(self.fixed):
            if name not in fields and name not in inputs:
                known = sorted(set(fields) | inputs)
                raise ParameterError(
                    fam.name, name, f"unknown; valid parameters: {', '.join(known)}"
                )
        dup = sorted({n for n in names if names.count(n) > 1} | (set(names) & set(self.fixed)))
        if dup:
            raise ParameterError(fam.name, dup[0], "given twice (ranged and/or fixed)")
        default = fam.params()
        object.__setattr__(
            self,
            "fixed",
            {k: _coerce(fam.name, k, v, getattr(default, k, 0.0)) for k, v in self.fixed.items()},
        )
        from pkdyn.model.families import _check_magnitude

        for k, v in self.fixed.items():
            bad = _not_finite(v)
            if bad is not None:
                raise ParameterError(fam.name, k, f"fixed at {bad}: give a finite number")
            _check_magnitude(fam.name, k, v)
        if self._mapping is not None:
            missing = [n for n in self._mapping.inputs if n not in names and n not in self.fixed]
            if missing:
                raise ParameterError(
                    fam.name,
                    missing[0],
                    f"the parametrisation '{self._mapping.name}' needs it: give it a range or a "
                    f"fixed value (it reads {', '.join(self._mapping.inputs)})",
                )
        for name in names:
            if name in fields and not isinstance(getattr(default, name), int | float):
                raise ParameterError(fam.name, name, "not a number: it cannot take a range")
            if isinstance(getattr(default, name, 0.0), bool):
                raise ParameterError(fam.name, name, "a flag: it cannot take a range")

    @property
    def family_obj(self) -> Family:
        """The registered family."""
        return family(self.family)

    @cached_property
    def _mapping(self) -> Parametrisation | None:
        """The parametrisation, resolved once (and shipped resolved to the workers)."""
        return None if self.parametrisation is None else parametrisation(self.parametrisation)

    @cached_property
    def integral(self) -> tuple[bool, ...]:
        """Per design variable: whether it is a whole number (an integer parameter)."""
        return tuple(isinstance(getattr(self._defaults, r.name, 0.0), int) for r in self.ranges)

    @cached_property
    def _defaults(self) -> Any:
        """The family's default parameters (built once)."""
        return self.family_obj.params()

    @property
    def names(self) -> list[str]:
        """Design variable names, in range order."""
        return [r.name for r in self.ranges]

    @property
    def dimension(self) -> int:
        """Number of design variables."""
        return len(self.ranges)

    def values(self, u: np.ndarray) -> np.ndarray:
        """Design variables (n, d) from unit-cube points (n, d); integer parameters rounded."""
        from pkdyn.inputs import matrix

        pts = _numbers(u)
        if isinstance(pts, np.ndarray) and pts.ndim == 1:
            pts = pts[None, :]
        u = matrix("u", pts, None, self.dimension)
        if np.any((u < 0.0) | (u > 1.0)):
            raise InvalidInputError("u", "expected points of the unit cube (fractions in [0, 1])")
        x = np.column_stack([r.at(u[:, k]) for k, r in enumerate(self.ranges)])
        for k, whole in enumerate(self.integral):
            if whole:
                x[:, k] = np.round(x[:, k])
        return x

    def overrides(self, x: Sequence[float] | np.ndarray) -> dict[str, Any]:
        """Builder parameter overrides of the design with variables ``x`` (d,).

        Args:
            x: One value per range [SI].

        Returns:
            ``{parameter: value}`` for :meth:`pkdyn.model.families.Family.make_params`.

        """
        from pkdyn.inputs import vector

        x = vector("x", x, self.dimension)
        vals: dict[str, Any] = dict(self.fixed)
        vals.update({r.name: float(v) for r, v in zip(self.ranges, x, strict=True)})
        mapping = self._mapping
        if mapping is None:
            return vals
        fields = {f.name for f in dataclasses.fields(self.family_obj.params)}
        out = {k: v for k, v in vals.items() if k in fields and k not in mapping.names}
        out.update(mapping(vals, self._defaults))
        return out

    def params(self, x: Sequence[float] | np.ndarray) -> Any:
        """The family's parameter dataclass of the design ``x`` (validated by the family).

        Raises:
            ParameterError: The family rejects the combination (e.g. an unreachable home).

        """
        return self.family_obj.make_params(self.overrides(x))

    def as_dict(self) -> dict[str, Any]:
        """Plain form for study files."""
        out: dict[str, Any] = {
            "family": self.family,
            "ranges": {r.name: [r.low, r.high] for r in self.ranges},
            "fixed": {k: _plain(v) for k, v in self.fixed.items()},
        }
        if self.parametrisation is not None:
            out["parametrisation"] = self.parametrisation
        return out


def _coerce(family: str, name: str, value: Any, default: Any) -> Any:
    """A fixed value given as text (command line) in the type of the parameter's default.

    A number where the default is a number, numbers where it is a tuple (a value of another
    type would fail every design of the study, each on its own).
    """
    if not isinstance(value, str) or isinstance(default, str):
        if value is None or default is None or isinstance(default, str):
            return value
        number = isinstance(default, numbers.Real) and not isinstance(default, bool)
        if number and (isinstance(value, bool) or not isinstance(value, numbers.Real)):
            raise ParameterError(family, name, f"expected a number, got {value!r:.40}")
        if isinstance(default, tuple) and not _numbers_only(value):
            raise ParameterError(family, name, f"expected numbers, got {value!r:.60}")
        return value
    try:
        if isinstance(default, bool):
            return value.strip().lower() in ("1", "true", "yes")
        if isinstance(default, tuple):
            return ast.literal_eval(value)
        if isinstance(default, int):
            return int(float(value))
        return float(value)
    except (ValueError, SyntaxError):
        raise ParameterError(
            family, name, f"cannot use {value!r} (expected {type(default).__name__})"
        ) from None


def _numbers_only(v: Any) -> bool:
    """``v`` is a number or (nested) tuples or lists of numbers."""
    if isinstance(v, tuple | list):
        return all(_numbers_only(x) for x in v)
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def _not_finite(v: Any) -> str | None:
    """The first NaN or infinite number in a fixed value (a number or nested tuples), else None."""
    if isinstance(v, tuple | list):
        return next((b for b in (_not_finite(x) for x in v) if b is not None), None)
    if isinstance(v, numbers.Real) and not isinstance(v, bool) and not math.isfinite(float(v)):
        return str(float(v))
    return None


def _plain(v: Any) -> Any:
    if isinstance(v, tuple | list):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v
