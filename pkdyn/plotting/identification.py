"""The fit of an identification per actuator: measured and predicted efforts, the residual."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.identification.result import IdentificationResult
from pkdyn.plotting._save import finish_figure
from pkdyn.results import register_plot

__all__ = ["plot_identification"]


@register_plot(IdentificationResult)
def plot_identification(
    result: IdentificationResult, path: str | Path | None = None, title: str | None = None
) -> Any:
    """Per actuator: the measured efforts and those of the identified model, and the residual.

    The identified model is the physically consistent one (what the written description gives),
    at the samples of the identification motion the result keeps (evenly spaced).

    Args:
        result: The identification.
        path: Save the figure there (format from the suffix).
        title: Figure title.

    Returns:
        The matplotlib Figure.

    Raises:
        InvalidInputError: The result keeps no samples of its motion.

    """
    from matplotlib.figure import Figure

    fit = result.fit
    if fit is None or fit.t.size == 0:
        raise InvalidInputError("result", "keeps no samples of its motion to plot")
    names = result.robot.actuator_names
    units = ["N" if p else "N m" for p in result.robot.actuator_prismatic]
    n = len(names)
    fig = Figure(figsize=(9.0, 1.0 + 2.6 * n))
    axes = fig.subplots(2 * n, 1, sharex=True, gridspec_kw={"height_ratios": [2, 1] * n})
    for i, (name, unit) in enumerate(zip(names, units, strict=True)):
        top, bottom = axes[2 * i], axes[2 * i + 1]
        top.plot(fit.t, fit.measured[:, i], color="0.4", lw=0.8, label="measured")
        top.plot(fit.t, fit.physical[:, i], color="C1", lw=1.0, label="identified model")
        top.set_ylabel(f"{name} [{unit}]")
        res = fit.measured[:, i] - fit.physical[:, i]
        bottom.plot(fit.t, res, color="C3", lw=0.6)
        bottom.axhline(0.0, color="k", lw=0.5)
        rms = float(np.sqrt(np.mean(res**2)))
        bottom.set_ylabel(f"residual [{unit}]")
        bottom.set_title(f"RMS {rms:.3g} {unit}", fontsize="small", loc="right")
    axes[0].legend(loc="upper right", fontsize="small", ncol=2)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(title if title is not None else f"{result.robot.name}: identification fit")
    return finish_figure(fig, path)
