"""Warnings from the model layer, attributed to the caller's line (not to pkdyn's internals)."""

from __future__ import annotations

import os
import sys
import warnings

__all__ = ["warn"]

_PKDYN = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def warn(message: str) -> None:
    """Issue a ``UserWarning`` whose location is the first frame outside pkdyn.

    Args:
        message: One line, naming the culprit and the amount.

    """
    level = 2
    frame = sys._getframe(1)
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PKDYN):
        frame = frame.f_back  # type: ignore[assignment]
        level += 1
    warnings.warn(message, UserWarning, stacklevel=level)
