"""Saving figures: the format from the file name's extension, written atomically."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from pkdyn.exceptions import OutputError
from pkdyn.files import atomic_path

__all__ = ["finish_figure", "save_figure"]


def save_figure(fig: Any, path: str | os.PathLike[str], dpi: int) -> None:
    """Write a matplotlib figure to ``path`` in the format its extension names.

    The figure goes to a temporary file beside ``path``, renamed when complete
    (:func:`pkdyn.files.atomic_path`): an interrupted run leaves a previous file intact.

    Args:
        fig: The figure.
        path: Output file; its extension (``.png``, ``.pdf``, ``.svg``...) is the format.
        dpi: Resolution of raster formats [dots per inch].

    Raises:
        OutputError: No or unknown extension, missing directory, or the file cannot be written.

    """
    if not isinstance(path, str | os.PathLike):
        raise OutputError(repr(path)[:80], "expected a file name (str or Path)")
    target = Path(path)
    fmt = target.suffix.lower().lstrip(".")
    supported = fig.canvas.get_supported_filetypes()
    if fmt not in supported:
        known = ", ".join(f".{k}" for k in sorted(supported))
        what = f"unknown figure format '{target.suffix}'" if fmt else "no file extension"
        raise OutputError(str(path), f"{what}: name the file with one of {known}")
    with atomic_path(path) as tmp:  # (the name as given: a trailing slash is refused)
        try:
            fig.savefig(tmp, dpi=dpi, format=fmt)
        except (OSError, ValueError) as err:
            raise OutputError(str(path), str(err)) from None


def finish_figure(
    fig: Any, path: str | os.PathLike[str] | None, dpi: int = 120, tight: bool = True
) -> Any:
    """Lay a finished figure out, save it when a path is given, and return it.

    Args:
        fig: The figure.
        path: Output file (its extension is the format), or ``None`` to only return it.
        dpi: Resolution of raster formats [dots per inch].
        tight: Tighten the layout first (``fig.tight_layout()``).

    Returns:
        The figure.

    Raises:
        OutputError: The file cannot be written (see :func:`save_figure`).

    """
    if tight:
        fig.tight_layout()
    if path is not None:
        save_figure(fig, path, dpi=dpi)
    return fig
