"""Precision figures: maps over a plane, mode spectra, Monte Carlo spreads, tolerance rankings.

Registered with :func:`pkdyn.results.register_plot`, so that ``result.plot(path)`` draws any
precision result: a :class:`~pkdyn.precision.grid.GridMap` (stiffness, deflection, frequency
and pose-error maps) as an image with its axes and units, unreachable cells grey, singular cells
red, near-singular ones dotted, the worst cell marked; :class:`~pkdyn.precision.modes.Modes` as
a spectrum; a :class:`~pkdyn.precision.monte_carlo.MonteCarlo` as the histogram of its position
errors; a :class:`~pkdyn.precision.budgets.ToleranceRanking` as bars.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.plotting._save import finish_figure
from pkdyn.precision.budgets import ToleranceRanking
from pkdyn.precision.grid import SINGULAR, UNREACHABLE, GridMap
from pkdyn.precision.maps import PrecisionMap
from pkdyn.precision.modes import Modes
from pkdyn.precision.monte_carlo import MonteCarlo
from pkdyn.results import register_plot

__all__ = [
    "plot_grid_map",
    "plot_modes",
    "plot_monte_carlo",
    "plot_precision_map",
    "plot_ranking",
]

_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "u"), (1e-9, "n"))
_NO_PREFIX = {"Hz", "rad", ""}


def _display(values: np.ndarray, unit: str) -> tuple[float, str]:
    """A scale and unit label for values (an SI prefix that keeps them between 1 and 1000)."""
    finite = np.abs(values[np.isfinite(values)])
    if unit in _NO_PREFIX or finite.size == 0 or float(finite.max()) == 0.0:
        return 1.0, unit
    top = float(finite.max())
    scale, prefix = next(((s, p) for s, p in _PREFIXES if top >= s), _PREFIXES[-1])
    return 1.0 / scale, f"{prefix}{unit}"


def _axes(ax: Any, size: tuple[float, float]) -> tuple[Any, Any]:
    """``(figure, axes)``: a new figure of ``size`` [in], or the one ``ax`` is drawn in."""
    if ax is not None:
        return ax.figure, ax
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    return fig, fig.add_subplot(1, 1, 1)


def _edges(x: np.ndarray) -> tuple[float, float]:
    d = (x[-1] - x[0]) / max(x.size - 1, 1) if x.size > 1 else 1.0
    return float(x[0] - d / 2), float(x[-1] + d / 2)


@register_plot(GridMap)
def plot_grid_map(
    result: GridMap,
    field: str | None = None,
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
    reference: float | None = None,
) -> Any:
    """A map's field as an image over its plane (module docstring).

    Args:
        result: The map.
        field: One of its fields (default: the first).
        path: Save the figure there (format from the suffix).
        ax: Draw into this matplotlib Axes instead of a new figure.
        title: Figure title (default: robot, field, plane).
        reference: A value to draw as a contour (e.g. a required stiffness, in the field's SI
            unit).

    Returns:
        The matplotlib Figure.

    Raises:
        InvalidInputError: A field the map does not hold, or no cell evaluated.

    """
    from matplotlib.colors import ListedColormap

    name = field if field is not None else next(iter(result.values), None)
    if not isinstance(name, str) or name not in result.values:
        raise InvalidInputError(
            "field", f"'{name}': this map holds {', '.join(result.values) or 'nothing'}"
        )
    z = np.asarray(result.values[name], dtype=float)
    if not np.isfinite(z).any():
        raise InvalidInputError(
            "field",
            f"'{name}': no cell of the map was evaluated (none is reachable and regular): give "
            "a center and extent inside the workspace",
        )
    fig, ax = _axes(ax, (6.2, 5.0))
    unit = result.units.get(name, "")
    scale, shown = _display(z, unit)
    extent = (*_edges(result.u), *_edges(result.v))
    status = result.status.T
    ax.imshow(
        np.where(status == UNREACHABLE, 1.0, np.where(status == SINGULAR, 0.0, np.nan)),
        origin="lower", extent=extent, aspect="equal", interpolation="nearest",
        cmap=ListedColormap(["#d62728", "#d9d9d9"]), vmin=0.0, vmax=1.0,
    )  # fmt: skip
    worst_is_max = result.worst.get(name) == "max"
    im = ax.imshow(
        np.ma.masked_invalid(z.T * scale), origin="lower", extent=extent, aspect="equal",
        interpolation="nearest", cmap="viridis_r" if worst_is_max else "viridis",
    )  # fmt: skip
    label = result.labels.get(name, name)
    fig.colorbar(im, ax=ax, label=f"{label} [{shown}]" if shown else label)
    if reference is not None and np.nanmin(z) < reference < np.nanmax(z):
        ax.contour(result.u, result.v, z.T, levels=[reference], colors="red", linewidths=1.2)
    iu, iv = np.nonzero(result.near & result.evaluated)
    if iu.size:
        ax.plot(result.u[iu], result.v[iv], ".", color="orange", ms=3, label="near singular")
    at = result.where(name)
    if at is not None:
        ax.plot(*at, "rx", ms=9, mew=2,
                label=f"worst: {result.extreme(name) * scale:.4g} {shown}".rstrip())  # fmt: skip
    ax.legend(loc="upper right", fontsize=8)
    a, b = result.axes
    ax.set_xlabel(f"{a} [m]")
    ax.set_ylabel(f"{b} [m]")
    c = result.counts()
    ax.set_title(
        title
        if title is not None
        else f"{result.robot}: {label} ({result.grid.third} = {result.grid.fixed:.4g} m; "
        f"{c['unreachable']} unreachable grey, {c['singular']} singular red)",
        fontsize=9,
    )
    return finish_figure(fig, path, tight=False)


def plot_precision_map(
    pmap: PrecisionMap,
    field: str = "stiffness_min",
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
    reference: float | None = None,
) -> Any:
    """Colour map of a precision field over a workspace slice (:func:`plot_grid_map`).

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

    """
    from pkdyn.inputs import instance, positive

    instance("pmap", pmap, PrecisionMap, "a PrecisionMap (pkdyn.precision.precision_map)")
    if reference is not None:
        reference = positive("reference", reference)
    return plot_grid_map(pmap, field, path=path, ax=ax, title=title, reference=reference)


@register_plot(Modes)
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

    Raises:
        InvalidInputError: A rigid robot (no mode to draw).

    """
    from pkdyn.inputs import instance, positive, vector

    instance("result", result, Modes, "Modes (pkdyn.precision.modes)")
    length = positive("length", length, "m")
    if band is not None:
        band = tuple(vector("band", band, 2, "Hz"))
    if result.frequencies.size == 0:
        raise InvalidInputError("modes", "the robot is rigid: there is no mode to draw")
    fig, ax = _axes(ax, (7.0, 3.5))
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
    default = f"{result.robot + ': ' if result.robot else ''}{len(f)} modes"
    if not result.valid:
        default += " (NOT VALID here: see the warnings)"
    ax.set_title(title if title is not None else default)
    ax.legend(loc="upper right", fontsize=8)
    return finish_figure(fig, path, tight=False)


@register_plot(MonteCarlo)
def plot_monte_carlo(
    result: MonteCarlo,
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
    bins: int = 30,
) -> Any:
    """Histogram of the sampled position errors, with the RMS (and the first order's).

    Args:
        result: A Monte Carlo.
        path: Save the figure there.
        ax: Draw into this Axes.
        title: Figure title.
        bins: Histogram bins.

    Returns:
        The matplotlib Figure.

    Raises:
        InvalidInputError: No sample assembled.

    """
    if len(result.errors) == 0:
        raise InvalidInputError("monte_carlo", "no sampled robot assembled: nothing to draw")
    fig, ax = _axes(ax, (6.0, 3.8))
    e = np.linalg.norm(result.errors[:, :3], axis=1)
    scale, shown = _display(e, "m")
    ax.hist(e * scale, bins=bins, color="C0", alpha=0.8)
    ax.axvline(
        result.position_rms * scale,
        color="C3",
        label=f"RMS {result.position_rms * scale:.4g} {shown}",
    )
    if result.first_order_rms is not None and math.isfinite(result.first_order_rms):
        r = result.first_order_rms * scale
        ax.axvline(r, color="k", linestyle="--", label=f"first order {r:.4g} {shown}")
    ax.set_xlabel(f"position error [{shown}]")
    ax.set_ylabel("robots")
    ax.set_title(title if title is not None else f"Monte Carlo: {len(e)} robots")
    ax.legend(fontsize=8)
    return finish_figure(fig, path, tight=False)


@register_plot(ToleranceRanking)
def plot_ranking(
    result: ToleranceRanking,
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
) -> Any:
    """The tolerances' shares of the position variance, as horizontal bars.

    Args:
        result: A ranking (:meth:`pkdyn.precision.budgets.GeometricAccuracy.ranked`).
        path: Save the figure there.
        ax: Draw into this Axes.
        title: Figure title.

    Returns:
        The matplotlib Figure.

    """
    fig, ax = _axes(ax, (6.0, 0.8 + 0.3 * max(len(result.entries), 1)))
    names = [e["name"] for e in result.entries][::-1]
    share = [100.0 * e["share"] for e in result.entries][::-1]
    ax.barh(names, share, color="C0")
    ax.set_xlabel("share of the position variance [%]")
    ax.set_title(title if title is not None else f"tolerances ({result.total} parameters)")
    return finish_figure(fig, path, tight=False)
