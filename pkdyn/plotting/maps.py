"""Conditioning and singularity maps (matplotlib Agg figures).

Figures are :class:`matplotlib.figure.Figure` objects drawn with the Agg canvas, so they can be
saved headless (``path=...``) or shown in a notebook (a Figure displays itself in Jupyter).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.analysis.maps import ConditioningMap
from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.plotting._save import finish_figure
from pkdyn.results import register_plot

__all__ = ["plot_conditioning_map"]

_LABELS = {
    "lci": "local conditioning index 1/cond(J)",
    "cond_J": "cond(J)",
    "cond_A": "cond(A)",
    "cond_B": "cond(B)",
    "manipulability": "manipulability sqrt(det(J J^T))",
}


@register_plot(ConditioningMap)
@public
def plot_conditioning_map(
    cmap: ConditioningMap,
    field: str = "lci",
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
    singular_loci: bool = True,
) -> Any:
    """Colour map of a conditioning indicator with the singularity loci overlaid.

    Args:
        cmap: A map from :func:`pkdyn.analysis.maps.delta_map` or ``planar_3rrr_map``.
        field: ``lci``, ``cond_J``, ``cond_A``, ``cond_B`` or ``manipulability`` (condition
            numbers are drawn on a log scale).
        path: Save the figure there (format from the suffix, e.g. ``.png``).
        ax: Draw into this matplotlib Axes instead of a new figure.
        title: Figure title (default: robot and slice).
        singular_loci: Overlay the zero levels of ``det A`` (parallel, red) and ``det B``
            (serial, blue).

    Returns:
        The matplotlib Figure.

    Raises:
        InvalidInputError: Unknown field, or a map without data.

    """
    from matplotlib import colors
    from matplotlib.figure import Figure

    from pkdyn.inputs import instance

    instance("cmap", cmap, ConditioningMap, "a ConditioningMap (pkdyn.analysis.maps)")
    if not isinstance(field, str) or field not in _LABELS:
        raise InvalidInputError("field", f"must be one of {', '.join(_LABELS)}, got {field!r}")
    if cmap.data is None:
        raise InvalidInputError("cmap", "the map holds no data (no sample was computed)")
    d = cmap.data
    values = np.ma.masked_invalid(np.asarray(getattr(d, field), dtype=float))
    if ax is None:
        fig = Figure(figsize=(6.0, 5.0))
        ax = fig.add_subplot(1, 1, 1)
    else:
        fig = ax.figure
    norm = colors.LogNorm() if field.startswith("cond") else None
    extent = (cmap.u[0], cmap.u[-1], cmap.v[0], cmap.v[-1])
    im = ax.imshow(values, origin="lower", extent=extent, aspect="equal", norm=norm, cmap="viridis")
    fig.colorbar(im, ax=ax, label=_LABELS[field])
    if singular_loci:
        for det, colour, label in ((d.det_A, "red", "parallel"), (d.det_B, "blue", "serial")):
            z = np.asarray(det, dtype=float)
            if np.isfinite(z).any() and np.nanmin(z) < 0.0 < np.nanmax(z):
                cs = ax.contour(cmap.u, cmap.v, z, levels=[0.0], colors=colour, linewidths=1.2)
                cs.set_label(f"{label} singularity")
    ax.set_xlabel(f"{cmap.axes[0]} [{'rad' if cmap.axes[0] == 'phi' else 'm'}]")
    ax.set_ylabel(f"{cmap.axes[1]} [{'rad' if cmap.axes[1] == 'phi' else 'm'}]")
    fixed = ", ".join(f"{k} = {v:.4g}" for k, v in cmap.fixed.items())
    ax.set_title(title if title is not None else f"{cmap.robot}: {field} ({fixed})")
    return finish_figure(fig, path, tight=False)
