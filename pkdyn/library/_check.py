"""Validation helpers shared by the parameter dataclasses."""

from __future__ import annotations

import math

from pkdyn.exceptions import ParameterError

__all__ = ["positive", "in_range"]


def positive(family: str, **values: float) -> None:
    """Raise :class:`ParameterError` unless every value is finite and > 0."""
    for k, v in values.items():
        if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            raise ParameterError(family, k, f"must be a positive finite number, got {v!r}")


def in_range(family: str, name: str, value: float, lo: float, hi: float) -> None:
    """Raise :class:`ParameterError` unless ``lo <= value <= hi``."""
    if not (math.isfinite(value) and lo <= value <= hi):
        raise ParameterError(family, name, f"must lie in [{lo}, {hi}], got {value!r}")
