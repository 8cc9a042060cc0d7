"""Precision maps and mode spectra (matplotlib Agg figures)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.plotting._save import save_figure
from pkdyn.precision.maps import FIELDS, PrecisionMap
from pkdyn.precision.modes import Modes

__all__ = ["plot_modes", "plot_precision_map"]

_SCALE = {"stiffness_min": (1e-3, "kN/m"), "deflection": (1e6, "um"), "f1": (1.0, "Hz")}


def plot_precision_map(
    pmap: PrecisionMap,
    field: str = "stiffness_min",
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
    reference: float | None = None,
) -> Any:
    """Colour map of a precision field over a workspace slice, the worst pose marked.

    Args:
        pmap: A map from :func:`pkdyn.precision.maps.precision_map`.
        field: ``stiffness_min``, ``deflection`` or ``f1`` (those the map holds).
        path: Save the figure there (format from the suffix).
        ax: Draw into this matplotlib Axes instead of a new figure.
        title: Figure title (default: robot, field, slice).
        reference: A value to draw as a contour (e.g. a required stiffness or frequency, in the
            field's SI unit).

    Returns:
        The matplotlib Figure.

    Raises:
        InvalidInputError: A field the map does not hold, or nothing evaluated.

    """
    from matplotlib.figure import Figure

    from pkdyn.inputs import instance, positive

    instance("pmap", pmap, PrecisionMap, "a PrecisionMap (pkdyn.precision.precision_map)")
    if reference is not None:
        reference = positive("reference", reference)
    if not isinstance(field, str) or field not in pmap.values:
        raise InvalidInputError(
            "field", f"'{field}': this map holds {', '.join(pmap.values) or 'nothing'}"
        )
    z = np.asarray(pmap.values[field], dtype=float)
    if not np.isfinite(z).any():
        raise InvalidInputError("field", f"'{field}': no pose of the map was evaluated")
    scale, unit = _SCALE[field]
    if ax is None:
        fig = Figure(figsize=(6.0, 5.0), layout="constrained")
        ax = fig.add_subplot(1, 1, 1)
    else:
        fig = ax.figure
    extent = (pmap.u[0], pmap.u[-1], pmap.v[0], pmap.v[-1])
    im = ax.imshow(
        np.ma.masked_invalid(z * scale), origin="lower", extent=extent, aspect="equal",
        cmap="viridis_r" if field == "deflection" else "viridis",
    )  # fmt: skip
    fig.colorbar(im, ax=ax, label=f"{FIELDS[field][1]} [{unit}]")
    worst = np.nanargmax(z) if field == "deflection" else np.nanargmin(z)
    iv, iu = np.unravel_index(worst, z.shape)
    ax.plot(
        pmap.u[iu], pmap.v[iv], "rx", ms=9, mew=2, label=f"worst: {z[iv, iu] * scale:.4g} {unit}"
    )
    if reference is not None and np.nanmin(z) < reference < np.nanmax(z):
        ax.contour(pmap.u, pmap.v, z, levels=[reference], colors="red", linewidths=1.2)
    ax.legend(loc="upper right", fontsize=8)
    iv_all, iu_all = np.nonzero(np.isfinite(z))
    du, dv = pmap.u[1] - pmap.u[0], pmap.v[1] - pmap.v[0]
    ax.set_xlim(pmap.u[iu_all.min()] - du, pmap.u[iu_all.max()] + du)
    ax.set_ylim(pmap.v[iv_all.min()] - dv, pmap.v[iv_all.max()] + dv)
    ax.set_xlabel(f"{pmap.axes[0]} [m]")
    ax.set_ylabel(f"{pmap.axes[1]} [m]")
    fixed = ", ".join(f"{k} = {v:.4g}" for k, v in pmap.fixed.items() if k in "xyz")
    ax.set_title(title if title is not None else f"{pmap.robot}: {FIELDS[field][1]} ({fixed})")
    if path is not None:
        save_figure(fig, path, dpi=120)
    return fig


def plot_modes(
    result: Modes,
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
    band: tuple[float, float] | None = None,
    length: float = 0.1,
) -> Any:
    """Natural frequencies, each drawn as high as it moves the platform.

    Args:
        result: Modes from :func:`pkdyn.precision.modes.modes`.
        path: Save the figure there.
        ax: Draw into this Axes.
        title: Figure title.
        band: A frequency band [Hz] to shade (e.g. measured values to compare with).
        length: Lever that makes rotations commensurate with translations [m].

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    from pkdyn.inputs import instance, positive, vector

    instance("result", result, Modes, "Modes (pkdyn.precision.modes)")
    length = positive("length", length, "m")
    if band is not None:
        band = tuple(vector("band", band, 2, "Hz"))

    if ax is None:
        fig = Figure(figsize=(7.0, 3.5), layout="constrained")
        ax = fig.add_subplot(1, 1, 1)
    else:
        fig = ax.figure
    f = result.frequencies
    P = result.platform  # mass-normalised shapes: platform motion per unit modal amplitude
    move = np.linalg.norm(P[:, :3], axis=1) + length * np.linalg.norm(P[:, 3:], axis=1)
    height = move / max(float(move.max()), 1e-300)
    if band is not None:
        ax.axvspan(band[0], band[1], color="0.88", label=f"{band[0]:g}-{band[1]:g} Hz")
    ax.vlines(f, 0.0, height, colors="C0", linewidth=1.5)
    ax.plot(f, height, "o", color="C0", ms=4)
    ax.axvline(f[0], color="C3", linestyle="--", linewidth=1, label=f"f1 = {f[0]:.4g} Hz")
    ax.set_xscale("log")
    ax.set_ylim(0.0, 1.08)
    ax.set_xlabel("natural frequency [Hz]")
    ax.set_ylabel("platform motion (relative)")
    ax.set_title(title if title is not None else f"{len(f)} modes")
    ax.legend(loc="upper right", fontsize=8)
    if path is not None:
        save_figure(fig, path, dpi=120)
    return fig
