"""Constraints and objectives of a study, on metric values.

A :class:`Constraint` bounds a metric (``inv_cond_min >= 0.2``); a design that breaks one is
infeasible (its metrics are still recorded). An :class:`Objective` is a metric to minimise or
maximise; the first objective chooses the design (:meth:`pkdyn.design.StudyResult.best`), all of
them span the Pareto front.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = ["Constraint", "Objective"]


def _metric_name(what: str, name: Any) -> str:
    """A metric's name: a non-empty string (checked against the metrics by the study)."""
    if not isinstance(name, str) or not name.strip():
        raise InvalidInputError(what, f"expected a metric name, got {name!r:.40}")
    return name


@dataclass(frozen=True)
class Constraint:
    """``metric >= bound`` or ``metric <= bound``.

    Attributes:
        metric: Metric name.
        op: ``>=`` or ``<=``.
        bound: The bound (the metric's unit).

    """

    metric: str
    op: str
    bound: float

    def __post_init__(self) -> None:
        from pkdyn.inputs import real

        _metric_name("constraint", self.metric)
        if self.op not in (">=", "<="):
            raise InvalidInputError("constraint", f"operator must be >= or <=, got '{self.op}'")
        object.__setattr__(self, "bound", real(f"constraint {self.metric}: bound", self.bound))

    @classmethod
    def parse(cls, text: str) -> Constraint:
        """``NAME>=VALUE`` or ``NAME<=VALUE`` (spaces allowed)."""
        if not isinstance(text, str):
            raise InvalidInputError("constraint", f"expected NAME>=VALUE, got {text!r:.40}")
        m = re.fullmatch(r"\s*([A-Za-z_][A-Za-z0-9_:.]*)\s*(>=|<=)\s*(\S+)\s*", text)
        if m is None:
            raise InvalidInputError("constraint", f"'{text}': expected NAME>=VALUE or NAME<=VALUE")
        try:
            bound = float(m.group(3))
        except ValueError:
            raise InvalidInputError("constraint", f"'{text}': the bound is not a number") from None
        return cls(m.group(1), m.group(2), bound)

    def violation(self, value: float) -> float:
        """How far ``value`` is on the wrong side (0 when satisfied; ``inf`` for NaN)."""
        if isinstance(value, bool) or not isinstance(value, int | float | np.floating):
            raise InvalidInputError("value", f"expected a number, got {value!r:.40}")
        if not math.isfinite(value):
            return math.inf
        return max(0.0, self.bound - value if self.op == ">=" else value - self.bound)

    def __str__(self) -> str:
        return f"{self.metric}{self.op}{self.bound:g}"


@dataclass(frozen=True)
class Objective:
    """A metric to minimise or maximise.

    Attributes:
        metric: Metric name.
        sense: ``min`` or ``max``.

    """

    metric: str
    sense: str = "min"

    def __post_init__(self) -> None:
        _metric_name("objective", self.metric)
        if self.sense not in ("min", "max"):
            raise InvalidInputError("objective", f"sense must be min or max, got '{self.sense}'")

    @classmethod
    def parse(cls, text: str) -> Objective:
        """``min:NAME`` / ``max:NAME`` (or a bare ``NAME``, minimised)."""
        if not isinstance(text, str):
            raise InvalidInputError("objective", f"expected [min:|max:]NAME, got {text!r:.40}")
        sense, sep, name = text.partition(":")
        if not sep:
            return cls(text.strip())
        return cls(name.strip(), sense.strip())

    def sign(self) -> float:
        """+1 to minimise, -1 to maximise (minimise ``sign * value``)."""
        return 1.0 if self.sense == "min" else -1.0

    def __str__(self) -> str:
        return f"{self.sense}:{self.metric}"
