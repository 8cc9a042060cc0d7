"""Warnings from the model layer, attributed to the caller's line (not to pkdyn's internals)."""

from __future__ import annotations

import os
import sys
import warnings

__all__ = ["missing_list", "warn", "warn_missing_meshes"]

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


def missing_list(files: list[str] | tuple[str, ...], shown: int = 5) -> str:
    """``a, b, c and 4 more``: file names for a one-line message (sorted, unique)."""
    names = sorted(set(files))
    more = f" and {len(names) - shown} more" if len(names) > shown else ""
    return ", ".join(names[:shown]) + more


def warn_missing_meshes(
    source: str, files: list[str] | tuple[str, ...], lost_inertia: list[str] | None = None
) -> None:
    """The one warning of a load whose mesh files are missing (every format says the same).

    Args:
        source: File or robot name.
        files: The mesh files not found.
        lost_inertia: Bodies whose inertia would come from those meshes (MJCF bodies without
            ``<inertial>``): their dynamics are incomplete, and the warning says so.

    """
    n = len(set(files))
    if lost_inertia:
        dynamics = (
            f"the mass and inertia of {len(lost_inertia)} body(ies) inferred from them are left "
            f"out, so the dynamics are incomplete: {missing_list(lost_inertia, 3)}"
        )
    else:
        dynamics = "kinematics and dynamics are complete"
    warn(
        f"{source}: {n} mesh file(s) not found, their geometry is left out ({dynamics}; "
        f"collision checks and the viewer need them): {missing_list(files)}"
    )
