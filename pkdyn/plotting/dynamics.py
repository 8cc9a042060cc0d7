"""Efforts, speeds and powers of the actuators against time (matplotlib Agg figures)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.dynamics.fastest_grid import FastestGrid
from pkdyn.dynamics.simulation_result import SimulationResult
from pkdyn.dynamics.sizing import SizingResult
from pkdyn.dynamics.sizing_grid import SizingGrid
from pkdyn.plotting._save import finish_figure
from pkdyn.results import register_plot
from solvers.conditioning import NEAR_SINGULAR, THROUGH

__all__ = ["plot_efforts", "plot_fastest_grid", "plot_simulation", "plot_sizing_grid"]


@register_plot(SizingResult)
def plot_efforts(
    result: SizingResult,
    path: str | Path | None = None,
    title: str | None = None,
    limits: bool = True,
) -> Any:
    """Effort, speed and power of each actuator against time, with the effort limits.

    Args:
        result: A sizing result (:func:`pkdyn.dynamics.sizing.size`).
        path: Save the figure there (format from the suffix, e.g. ``.png``).
        title: Figure title (default: robot, trajectory and payload).
        limits: Draw the effort limits as dashed lines (when finite and within 3x the peak).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    ef = result.efforts
    t = ef.t
    qd = ef.trajectory.qa_dot
    fig = Figure(figsize=(8.0, 7.5))
    axes = fig.subplots(3, 1, sharex=True)
    for i, act in enumerate(result.actuators):
        (line,) = axes[0].plot(t, ef.tau[:, i], label=act.name)
        colour = line.get_color()
        axes[1].plot(t, qd[:, i], color=colour)
        axes[2].plot(t, ef.tau[:, i] * qd[:, i], color=colour)
        if limits and math.isfinite(act.limit) and act.limit < 3.0 * max(act.peak, 1e-12):
            for s in (-1.0, 1.0):
                axes[0].axhline(s * act.limit, color=colour, linestyle="--", linewidth=0.8)
    axes[0].set_ylabel("effort [N m or N]")
    axes[1].set_ylabel("speed [rad/s or m/s]")
    axes[2].set_ylabel("power [W]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", fontsize="small", ncol=min(6, len(result.actuators)))
    peak = max((a.peak for a in result.actuators), default=0.0)
    fig.suptitle(
        title
        if title is not None
        else f"{result.robot}: {result.trajectory}, payload {result.payload:g} kg "
        f"(peak {peak:.3g}, {np.round(result.duration, 4):g} s)"
    )
    return finish_figure(fig, path)


@register_plot(SimulationResult)
def _plot_simulation_result(
    result: SimulationResult, path: str | Path | None = None, title: str | None = None
) -> Any:
    """:func:`plot_simulation` of a result that names its actuators (``result.plot()``)."""
    return plot_simulation(result.layout, result, path=path, title=title)


def plot_simulation(
    robot: Any, result: Any, path: str | Path | None = None, title: str | None = None
) -> Any:
    """Actuator positions and speeds, energies, closure residual and conditioning of a simulation.

    The conditioning of the closure forces is drawn with the thresholds of a passage near
    (1e-4) and through (1e-5) a singularity; each singular passage (``result.events``) is a
    vertical line on every panel.

    Args:
        robot: The simulated robot (or ``result.layout``: its names and indices).
        result: Its :func:`pkdyn.dynamics.simulate` result.
        path: Save the figure there (format from the suffix, e.g. ``.png``).
        title: Figure title (default: robot and duration).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    from pkdyn.dynamics.simulation_output import simulation_columns
    from pkdyn.exceptions import InvalidInputError
    from pkdyn.inputs import instance
    from solvers import ForwardResult

    instance("result", result, ForwardResult, "a simulation (pkdyn.dynamics.simulate)")
    if not hasattr(robot, "actuator_names"):
        raise InvalidInputError("robot", f"expected the simulated Robot, got {robot!r:.40}")
    cols = simulation_columns(robot, result, readings=False)  # (joint coordinates)
    t = cols["t"]
    fig = Figure(figsize=(8.0, 11.0))
    axes = fig.subplots(5, 1, sharex=True)
    for name in robot.actuator_names:
        (line,) = axes[0].plot(t, cols[f"qa_{name}"], label=name)
        axes[1].plot(t, cols[f"qa_dot_{name}"], color=line.get_color())
    for key in ("kinetic", "potential", "work", "dissipated", "energy_balance"):
        axes[2].plot(t, cols[key], label=key.replace("_", " "))
    axes[3].semilogy(t, np.maximum(cols["closure_residual"], 1e-17))
    axes[4].semilogy(t, np.maximum(cols["conditioning"], 1e-17), color="black")
    for level, what in ((NEAR_SINGULAR, "near"), (THROUGH, "through")):
        axes[4].axhline(level, color="tab:red", lw=0.8, ls="--" if what == "near" else ":")
    for ev in getattr(result, "events", []):
        for ax in axes:
            ax.axvline(ev.time, color="tab:red", lw=0.8, alpha=0.6)
    axes[0].set_ylabel("actuators [rad or m]")
    axes[1].set_ylabel("speeds [rad/s or m/s]")
    axes[2].set_ylabel("energy [J]")
    axes[3].set_ylabel("closure residual")
    axes[4].set_ylabel("conditioning")
    axes[4].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    if robot.actuator_names:
        axes[0].legend(loc="upper right", fontsize="small", ncol=min(6, len(robot.actuator_names)))
    axes[2].legend(loc="upper right", fontsize="small", ncol=3)
    fig.suptitle(
        title if title is not None else f"{robot.name}: {float(t[-1] - t[0]):g} s simulated"
    )
    return finish_figure(fig, path)


@register_plot(SizingGrid)
def plot_sizing_grid(
    result: SizingGrid, path: str | Path | None = None, title: str | None = None
) -> Any:
    """The peak effort of each cell of a sizing grid, cells beyond a limit hatched.

    Args:
        result: A sizing grid (:func:`pkdyn.dynamics.sizing_grid.sizing_grid`).
        path: Save the figure there (format from the suffix, e.g. ``.png``).
        title: Figure title (default: robot and motion).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    peak = result.peak
    feasible = result.feasible
    fig = Figure(figsize=(1.6 + 1.3 * len(result.payloads), 1.4 + 0.7 * len(result.cycle_times)))
    ax = fig.subplots()
    image = ax.imshow(peak, cmap="viridis", aspect="auto")
    for i in range(peak.shape[0]):
        for j in range(peak.shape[1]):
            mark = "" if feasible[i, j] else "\nlimit!"
            ax.text(
                j,
                i,
                f"{peak[i, j]:.3g}{mark}",
                ha="center",
                va="center",
                bbox={"facecolor": "white", "alpha": 0.7, "linewidth": 0},
            )
            if not feasible[i, j]:
                ax.add_patch(_hatch(i, j))
    ax.set_xticks(range(len(result.payloads)), [f"{m:g}" for m in result.payloads])
    ax.set_yticks(range(len(result.cycle_times)), [f"{T:g}" for T in result.cycle_times])
    ax.set_xlabel("payload [kg]")
    ax.set_ylabel("cycle time [s]")
    fig.colorbar(image, ax=ax, label=f"peak effort [{result.effort_unit}]")
    ax.set_title(title if title is not None else f"{result.robot}: {result.trajectory}")
    return finish_figure(fig, path)


def _hatch(i: int, j: int) -> Any:
    """A hatched square over cell ``(i, j)``: a limit is exceeded there."""
    from matplotlib.patches import Rectangle

    return Rectangle((j - 0.5, i - 0.5), 1.0, 1.0, fill=False, hatch="//", edgecolor="red")


@register_plot(FastestGrid)
def plot_fastest_grid(
    result: FastestGrid, path: str | Path | None = None, title: str | None = None
) -> Any:
    """Cycle time and RMS effort of the fastest cycles against the payload, per rotor inertia.

    Args:
        result: A grid of fastest cycles (:func:`pkdyn.dynamics.fastest_grid.fastest_grid`).
        path: Save the figure there (format from the suffix, e.g. ``.png``).
        title: Figure title (default: robot and path).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.0, 6.0))
    axes = fig.subplots(2, 1, sharex=True)
    m = np.asarray(result.payloads)
    T, rms = result.cycle_time, result.rms
    for k, J in enumerate(result.rotor_inertias):
        label = "the robot's drives" if J is None else f"rotor {J:g} kg m^2"
        axes[0].plot(m, T[:, k], "o-", label=label)
        axes[1].plot(m, rms[:, k], "o-")
    axes[0].set_ylabel("cycle time [s]")
    axes[1].set_ylabel(f"RMS effort [{result.effort_unit}]")
    axes[1].set_xlabel("payload [kg]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize="small")
    fig.suptitle(title if title is not None else f"{result.robot}: fastest {result.path}")
    return finish_figure(fig, path)
