"""Metrics: small functions of a built design, each with a name and a unit.

A metric is ``fn(robot, ctx) -> float`` (:class:`Metric`): ``robot`` the built design
(:class:`pkdyn.Robot`), ``ctx`` its :class:`pkdyn.design.context.DesignContext`, whose methods
share the expensive results between metrics (the required-workspace check, the duty-cycle
figures...). A metric that cannot be evaluated raises a :class:`pkdyn.PkdynError`: the design is
then recorded as infeasible with that reason.

Adding one is one small function::

    from pkdyn.design import Metric

    def arm_ratio(robot, ctx):
        return robot.params.lb / robot.params.la

    study = Study(..., metrics=["peak_effort", Metric("arm_ratio", "-", arm_ratio)])

or, to make it known by name (``--metric arm_ratio``), decorate it with :func:`metric`.

Built-in metrics (:data:`METRICS`; groups of them: :data:`GROUPS`):

- Clavel's workspace figures of the Delta, closed form with the study's limits:
  ``clavel_D``, ``clavel_S``, ``clavel_H``, ``clavel_Hmax``, ``clavel_V``, ``clavel_zh`` [SI],
  their dimensionless forms ``clavel_d, _s, _h, _hmax, _v, _z_h`` and ``clavel_r``,
  ``clavel_b``; ``clavel_H_numeric`` / ``clavel_h_numeric``: the complete prism's height
  measured on the mechanism;
- ``workspace_volume`` [m^3] of the translation workspace at the identity orientation, ``gci``
  (global conditioning index: mean ``1/cond(J)`` over it);
- on the required workspace: ``contains`` (fraction of the required poses reached within the
  limits; 1 = all), ``inv_cond_min`` and ``inv_cond_mean`` (worst and mean ``1/cond(J)``;
  the mean is the GCI of the required region), ``interference_margin`` [m] (smallest
  clearance between legs, negative when they overlap);
- on the duty cycle: ``peak_effort``, ``rms_effort`` [N m or N], ``peak_speed`` [rad/s or
  m/s], ``peak_power`` [W] (largest over the actuators), ``effort_margin``, ``speed_margin``
  (smallest ``1 - peak / limit``), and per actuator ``peak_effort_<k>``, ``rms_effort_<k>``,
  ``peak_speed_<k>`` (``k`` = 1, 2, ... in actuator order);
- on the required workspace, precision (:mod:`pkdyn.precision`, with the study's
  ``actuator_stiffness`` and ``material``): ``stiffness_min`` [N/m] (smallest principal
  translational stiffness; 0 when a required pose is singular), ``f1_min`` [Hz] (lowest natural
  frequency). Options that cannot give them are refused before the study starts
  (:func:`check_precision`): no actuator stiffness given or described, a count that does not
  match the actuators, rigid actuators (``inf``) with nothing else compliant (the figures would
  be infinite: the robot is rigid), no required workspace;
- on the duty cycle, vibration (:func:`pkdyn.precision.vibration.vibration`, modal method,
  with the study's ``actuator_stiffness``, ``material``, ``damping_ratio``, ``band`` and
  ``dwell``, the payload at the platform): ``settling_time`` [s] (after the motion, until the
  tool stays within the band; a design whose tool does not settle within the window observed is
  infeasible), ``residual_amplitude`` [m] (largest deviation from the end pose's equilibrium over
  0.2 s after the motion), ``motion_settled`` [s] (the duty cycle's duration plus its settling
  time: the real cycle time); the duty cycle must start and end at rest (``adept``, ``p2p``),
  and the actuators' stiffness is checked up front as for the precision metrics;
- on the required workspace: ``error_max`` [m], the largest worst-case platform position error
  of actuator errors of :data:`pkdyn.precision.accuracy.DEFAULT_RESOLUTION` (1e-4 rad, 1e-5 m);
- ``base_radius`` [m]: largest distance of a base joint from the z axis (a footprint);
- ``moving_mass`` [kg]: every body but the base.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.design.context import DesignContext
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.arguments import public
from pkdyn.model.robot import MODELLING_JOINTS, Robot

__all__ = [
    "GROUPS",
    "METRICS",
    "PRECISION_METRICS",
    "VIBRATION_METRICS",
    "WORKSPACE_METRICS",
    "Metric",
    "check_precision",
    "metric",
    "resolve_metrics",
]

MetricFn = Callable[[Robot, DesignContext], float]


@dataclass(frozen=True)
class Metric:
    """A named figure of a design.

    Attributes:
        name: Column name in the results table.
        unit: Unit (SI), ``-`` when dimensionless.
        fn: ``fn(robot, ctx) -> float``.
        summary: One line for listings.
        geometry: The metric needs the robot's collision geometry.

    """

    name: str
    unit: str
    fn: MetricFn
    summary: str = ""
    geometry: bool = False

    def __post_init__(self) -> None:
        _check_metric(self.name, self.unit, self.summary, self.geometry)
        if not callable(self.fn):
            raise InvalidInputError(
                f"metric '{self.name}'", f"fn: expected a function, got {self.fn!r:.40}"
            )

    def __call__(self, robot: Robot, ctx: DesignContext) -> float:
        """The value for one design.

        Raises:
            PkdynError: The design cannot be evaluated (the design is then infeasible).
            InvalidInputError: The function returned something that is not a finite number.

        """
        value = self.fn(robot, ctx)
        try:
            out = float(value)
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"metric '{self.name}'", f"returned {value!r}, not a number"
            ) from None
        if not math.isfinite(out):
            raise InvalidInputError(f"metric '{self.name}'", f"is not finite ({out})")
        return out


METRICS: dict[str, Metric] = {}
"""Metrics known by name (built-ins and those registered with :func:`metric`)."""

_BUILTIN: set[str] = set()
"""The built-in metric and group names (a plug-in may not replace them), filled below."""


@public
def _check_metric(name: Any, unit: Any, summary: Any, geometry: Any) -> None:
    """A metric's name (an identifier), unit and summary (strings) and geometry flag."""
    from pkdyn.inputs import flag

    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise InvalidInputError("metric", f"{name!r:.40}: names are identifiers")
    for what, value in (("unit", unit), ("summary", summary)):
        if not isinstance(value, str):
            raise InvalidInputError(f"metric '{name}'", f"{what}: expected text, got {value!r:.40}")
    flag(f"metric '{name}' geometry", geometry)


def metric(
    name: str, unit: str, summary: str = "", geometry: bool = False
) -> Callable[[MetricFn], MetricFn]:
    """Register a function as a metric known by name (decorator).

    Args:
        name: Column name.
        unit: Unit (SI), ``-`` when dimensionless.
        summary: One line.
        geometry: Needs the collision geometry.

    Returns:
        The decorator (the function is returned unchanged).

    """
    _check_metric(name, unit, summary, geometry)

    def wrap(fn: MetricFn) -> MetricFn:
        if name in _BUILTIN:
            raise InvalidInputError(
                "metric", f"'{name}' is a built-in name: give your metric another one"
            )
        METRICS[name] = Metric(name, unit, fn, summary or (fn.__doc__ or "").strip(), geometry)
        return fn

    return wrap


# ---------------------------------------------------------------------- Clavel's figures

_CLAVEL_SI = {
    "D": ("m", "inscribed cylinder diameter"),
    "S": ("m^2", "hexagon area"),
    "H": ("m", "complete prism height"),
    "Hmax": ("m", "prism top to lowest point"),
    "V": ("m^3", "prism volume S H"),
    "zh": ("m", "prism top height"),
}
_CLAVEL_DIMLESS = {"d": "D", "s": "S", "h": "H", "hmax": "Hmax", "v": "V", "z_h": "zh"}


def _clavel_si(key: str) -> MetricFn:
    return lambda robot, ctx: float(getattr(ctx.clavel(), key))


def _clavel_dimless(key: str) -> MetricFn:
    return lambda robot, ctx: float(ctx.clavel().dimensionless()[key])


for _k, (_u, _s) in _CLAVEL_SI.items():
    METRICS[f"clavel_{_k}"] = Metric(f"clavel_{_k}", _u, _clavel_si(_k), f"Clavel: {_s}")
for _k, _big in _CLAVEL_DIMLESS.items():
    METRICS[f"clavel_{_k}"] = Metric(
        f"clavel_{_k}", "-", _clavel_dimless(_k), f"Clavel: {_CLAVEL_SI[_big][1]} / la^n"
    )


@metric("clavel_r", "-", "Clavel's r = (ra - rb) / la")
def _clavel_r(robot: Robot, ctx: DesignContext) -> float:
    p = ctx._delta()
    return float((p.ra - p.rb) / p.la)


@metric("clavel_b", "-", "Clavel's b = lb / la")
def _clavel_b(robot: Robot, ctx: DesignContext) -> float:
    p = ctx._delta()
    return float(p.lb / p.la)


@metric("clavel_H_numeric", "m", "complete prism height measured on the mechanism")
def _clavel_H_numeric(robot: Robot, ctx: DesignContext) -> float:
    return float(ctx.clavel_numeric().H)


@metric("clavel_h_numeric", "-", "complete prism height measured on the mechanism / la")
def _clavel_h_numeric(robot: Robot, ctx: DesignContext) -> float:
    f = ctx.clavel_numeric()
    return float(f.H / f.la)


# ---------------------------------------------------------------------- workspaces


@metric("workspace_volume", "m^3", "translation workspace volume (grid)")
def _workspace_volume(robot: Robot, ctx: DesignContext) -> float:
    return ctx.translation().volume


@metric("gci", "-", "global conditioning index: mean 1/cond(J) over the translation workspace")
def _gci(robot: Robot, ctx: DesignContext) -> float:
    return ctx.gci()


@metric("contains", "-", "fraction of the required poses reached within the limits")
def _contains(robot: Robot, ctx: DesignContext) -> float:
    return ctx.required().fraction


def _reached_inv_cond(ctx: DesignContext) -> np.ndarray:
    chk = ctx.required()
    v = chk.inv_cond[chk.reached]
    return v if v.size else np.zeros(1)


@metric("inv_cond_min", "-", "worst 1/cond(J) over the reached required poses")
def _inv_cond_min(robot: Robot, ctx: DesignContext) -> float:
    return float(np.min(_reached_inv_cond(ctx)))


@metric("inv_cond_mean", "-", "mean 1/cond(J) over the reached required poses")
def _inv_cond_mean(robot: Robot, ctx: DesignContext) -> float:
    return float(np.mean(_reached_inv_cond(ctx)))


@metric(
    "interference_margin",
    "m",
    "smallest clearance between legs over the reached required poses",
    geometry=True,
)
def _interference_margin(robot: Robot, ctx: DesignContext) -> float:
    chk = ctx.required()
    c = chk.clearance[chk.reached]
    c = c[np.isfinite(c)]
    if c.size == 0:
        raise InvalidInputError("interference_margin", "no required pose reached")
    return float(np.min(c))


# ---------------------------------------------------------------------- duty cycle


@metric("peak_effort", "N m or N", "largest peak actuator effort on the duty cycle")
def _peak_effort(robot: Robot, ctx: DesignContext) -> float:
    return float(np.max(ctx.duty().peak))


@metric("rms_effort", "N m or N", "largest RMS actuator effort on the duty cycle")
def _rms_effort(robot: Robot, ctx: DesignContext) -> float:
    return float(np.max(ctx.duty().rms))


@metric("peak_speed", "rad/s or m/s", "largest peak actuator speed on the duty cycle")
def _peak_speed(robot: Robot, ctx: DesignContext) -> float:
    return float(np.max(ctx.duty().peak_speed))


@metric("peak_power", "W", "largest peak actuator power on the duty cycle")
def _peak_power(robot: Robot, ctx: DesignContext) -> float:
    return float(np.max(ctx.duty().peak_power))


@metric("effort_margin", "-", "smallest 1 - peak effort / effort limit")
def _effort_margin(robot: Robot, ctx: DesignContext) -> float:
    d = ctx.duty()
    with np.errstate(divide="ignore"):
        return float(np.min(np.where(np.isfinite(d.effort_limit), 1 - d.peak / d.effort_limit, 1)))


@metric("speed_margin", "-", "smallest 1 - peak speed / speed limit")
def _speed_margin(robot: Robot, ctx: DesignContext) -> float:
    d = ctx.duty()
    with np.errstate(divide="ignore"):
        return float(
            np.min(np.where(np.isfinite(d.speed_limit), 1 - d.peak_speed / d.speed_limit, 1))
        )


_PER_ACTUATOR = {
    "peak_effort": ("peak", "N m or N"),
    "rms_effort": ("rms", "N m or N"),
    "peak_speed": ("peak_speed", "rad/s or m/s"),
}


def _per_actuator(name: str) -> Metric | None:
    m = re.fullmatch(r"(peak_effort|rms_effort|peak_speed)_([1-9][0-9]*)", name)
    if m is None:
        return None
    attr, unit = _PER_ACTUATOR[m.group(1)]
    k = int(m.group(2))

    def fn(robot: Robot, ctx: DesignContext) -> float:
        values = getattr(ctx.duty(), attr)
        if k > len(values):
            raise InvalidInputError(
                f"metric '{name}'", f"{robot.name} has {len(values)} actuators, not {k}"
            )
        return float(values[k - 1])

    return Metric(name, unit, fn, f"{m.group(1).replace('_', ' ')} of actuator {k}")


# ---------------------------------------------------------------------- precision

VIBRATION_METRICS = ("settling_time", "residual_amplitude", "motion_settled")
"""The metrics of a design's vibration on the duty cycle (checked up front by a study)."""


PRECISION_METRICS = ("stiffness_min", "f1_min", *VIBRATION_METRICS)
"""Metrics of the elastic model (they need the actuators' stiffness)."""

WORKSPACE_METRICS = ("stiffness_min", "f1_min", "error_max")
"""Precision metrics evaluated over the required workspace (they need one)."""


def check_precision(metrics: Sequence[Metric], conditions: Any, robot: Robot) -> None:
    """Refuse, before a study starts, precision options that cannot give a metric.

    Args:
        metrics: The study's metrics.
        conditions: Its :class:`pkdyn.design.context.Conditions`.
        robot: A design of the study (its actuators and description).

    Raises:
        InvalidInputError: No actuator stiffness given nor described, a count that does not
            match the actuators, or every actuator rigid with nothing else compliant (one line,
            naming the option and the fix).

    """
    names = [m.name for m in metrics if m.name in PRECISION_METRICS]
    if not names:
        return
    from pkdyn.precision.elastic import actuator_stiffness

    what = f"metric '{names[0]}'"
    try:
        k = actuator_stiffness(robot, conditions.actuator_stiffness)
    except InvalidInputError as err:
        text = str(err).removeprefix(f"{err.name}: ")
        raise InvalidInputError(
            "actuator_stiffness",
            f"{what} needs each actuator's stiffness: {text} (study setting actuator_stiffness)",
        ) from None
    desc = robot.description
    compliant = (
        conditions.material is not None
        or desc.material is not None
        or any(c.compliance is not None or c.material is not None for c in desc.compliance)
        or (robot.passive is not None and bool(np.any(robot.passive.stiffness > 0.0)))
    )
    if np.all(np.isinf(k)) and not compliant:
        raise InvalidInputError(
            "actuator_stiffness",
            f"{what}: every actuator is rigid (inf) and nothing else is compliant: every design "
            "is rigid (infinite stiffness and frequencies), no metric to compare; give finite "
            "actuator stiffnesses or a material for the links (--material)",
        )


def _precision(ctx: DesignContext, frequency: bool) -> np.ndarray:
    """Stiffness (or lowest frequency) at the reached required poses (0: singular)."""
    from pkdyn.precision.maps import pose_figures

    def run() -> np.ndarray:
        chk = ctx.required()
        ok = chk.reached
        if not ok.any():
            raise InvalidInputError("stiffness_min", "no required pose reached")
        c = ctx.conditions
        fig = pose_figures(
            ctx.robot,
            chk.P[ok],
            chk.R[ok],
            c.actuator_stiffness,
            material=c.material,
            frequency=frequency,
            progress=False,
        )
        values = fig.f1 if frequency else fig.stiffness_min
        return np.where(fig.valid, values, 0.0)

    return ctx.cached("precision_f1" if frequency else "precision_k", run)


@metric(
    "stiffness_min",
    "N/m",
    "smallest translational stiffness over the required workspace",
    geometry=True,  # the links' beams are read from their cylinders
)
def _stiffness_min(robot: Robot, ctx: DesignContext) -> float:
    return float(np.min(_precision(ctx, False)))


@metric("f1_min", "Hz", "lowest natural frequency over the required workspace", geometry=True)
def _f1_min(robot: Robot, ctx: DesignContext) -> float:
    return float(np.min(_precision(ctx, True)))


def _vibration(ctx: DesignContext) -> Any:
    """The vibration of the design on the duty cycle (shared by the vibration metrics)."""
    from pkdyn.dynamics.trajectory import named_task
    from pkdyn.precision.vibration import vibration

    def run() -> Any:
        c = ctx.conditions
        task = named_task(ctx.robot, c.trajectory, **dict(c.trajectory_options))
        return vibration(
            ctx.robot,
            task,
            payload=c.payload,
            actuator_stiffness=c.actuator_stiffness,
            material=c.material,
            damping_ratio=c.damping_ratio,
            band=c.band,
            dwell=c.dwell,
            progress=False,
        )

    return ctx.cached("vibration", run)


@metric(
    "settling_time",
    "s",
    "time after the duty cycle until the tool stays within the band (vibration)",
    geometry=True,  # the links' beams are read from their cylinders
)
def _settling_time(robot: Robot, ctx: DesignContext) -> float:
    r = _vibration(ctx)
    if r.settling_time is None:
        raise PkdynError(
            f"the tool does not settle within {ctx.conditions.band:g} m in the "
            f"{float(r.t[-1] - r.duration):.3g} s observed after the duty cycle"
        )
    return float(r.settling_time)


@metric(
    "residual_amplitude",
    "m",
    "largest deviation from the end equilibrium over 0.2 s after the duty cycle (vibration)",
    geometry=True,
)
def _residual_amplitude(robot: Robot, ctx: DesignContext) -> float:
    return float(_vibration(ctx).residual_amplitude)


@metric(
    "motion_settled",
    "s",
    "duty cycle duration plus its settling time: the cycle time the vibration allows",
    geometry=True,
)
def _motion_settled(robot: Robot, ctx: DesignContext) -> float:
    r = _vibration(ctx)
    return float(r.duration) + _settling_time(robot, ctx)


@metric(
    "error_max",
    "m",
    "largest worst-case position error over the reached required poses (actuator resolution "
    "1e-4 rad or 1e-5 m)",
)
def _error_max(robot: Robot, ctx: DesignContext) -> float:
    from pkdyn.precision.accuracy import largest_position_error

    chk = ctx.required()
    ok = chk.reached
    if not ok.any():
        raise InvalidInputError("error_max", "no required pose reached")
    return largest_position_error(robot, chk.P[ok], chk.R[ok], reached=True)


@metric("base_radius", "m", "largest distance from the z axis of a joint on the base")
def _base_radius(robot: Robot, ctx: DesignContext) -> float:
    model = robot.model
    on_base = [j for j in range(1, model.njoints) if model.parents[j] == 0]
    on_base = [j for j in on_base if model.joints[j].shortname() not in MODELLING_JOINTS]
    if not on_base:
        raise InvalidInputError("base_radius", f"{robot.name} has no joint on its base")
    return float(max(np.hypot(*model.jointPlacements[j].translation[:2]) for j in on_base))


@metric("moving_mass", "kg", "mass of every body but the base")
def _moving_mass(robot: Robot, ctx: DesignContext) -> float:
    return float(sum(robot.model.inertias[j].mass for j in range(1, robot.model.njoints)))


GROUPS: dict[str, tuple[str, ...]] = {
    "clavel": tuple(f"clavel_{k}" for k in _CLAVEL_SI),
    "clavel_chart": (
        "clavel_r",
        "clavel_b",
        "clavel_d",
        "clavel_s",
        "clavel_h",
        "clavel_h_numeric",
        "clavel_hmax",
        "clavel_v",
        "clavel_z_h",
    ),
    "required": ("contains", "inv_cond_min", "inv_cond_mean", "interference_margin"),
    "precision": ("stiffness_min", "f1_min"),
    "vibration": VIBRATION_METRICS,
    "sizing": (
        "peak_effort",
        "rms_effort",
        "peak_speed",
        "peak_power",
        "effort_margin",
        "speed_margin",
    ),
    "workspace": ("workspace_volume", "gci"),
}
"""Names that stand for several metrics (``--metric sizing``)."""

_BUILTIN.update(METRICS, GROUPS)


def resolve_metrics(items: Sequence[str | Metric]) -> list[Metric]:
    """Metrics from names, group names and :class:`Metric` objects, without repeats.

    Args:
        items: Metric names (built-in or registered), group names (:data:`GROUPS`), per-actuator
            names (``peak_effort_2``), ``module:attribute`` of a loaded plug-in
            (:mod:`pkdyn.design.plugins`), or :class:`Metric` objects.

    Returns:
        The metrics, in order of first mention.

    Raises:
        InvalidInputError: An unknown name (the message lists the known ones), or a
            ``module:attribute`` whose module is not a loaded plug-in.

    """
    if isinstance(items, str | bytes | Mapping) or not isinstance(items, Iterable):
        raise InvalidInputError("metric", f"expected metric names, got {items!r:.60}")
    out: dict[str, Metric] = {}
    for item in items:
        if not isinstance(item, str | Metric):
            raise InvalidInputError(
                "metric", f"expected a metric name or a Metric, got {item!r:.40}"
            )
        if isinstance(item, Metric):
            out.setdefault(item.name, item)
            continue
        for name in GROUPS.get(item, (item,)):
            m = METRICS.get(name) or _per_actuator(name) or _imported(name)
            if m is None:
                raise InvalidInputError(
                    "metric",
                    f"unknown metric '{name}'; known: {', '.join(sorted(METRICS))}, groups "
                    f"{', '.join(GROUPS)}, per actuator peak_effort_<k> rms_effort_<k> "
                    "peak_speed_<k>, or module:attribute of a plug-in (--plugin MODULE)",
                )
            out.setdefault(m.name, m)
    return list(out.values())


def _imported(name: str) -> Metric | None:
    """A metric of a plug-in: ``module:attribute``, or a plain name an installed one registers.

    ``module:attribute`` names a :class:`Metric` (or a function registered with
    :func:`metric`) of a loaded plug-in; an unknown plain name is looked for in the installed
    plug-ins (entry points).

    Raises:
        InvalidInputError: A module that is not a loaded plug-in, or an attribute that is not a
            metric.

    """
    from pkdyn.design import plugins

    module, sep, attr = name.partition(":")
    if not sep:
        plugins.load_entry_points()
        return METRICS.get(name)
    obj: Any = plugins.resolve(name, "metric")
    if isinstance(obj, Metric):
        return obj
    for m in METRICS.values():
        if m.fn is obj:
            return m
    raise InvalidInputError(
        "metric", f"'{name}' is neither a Metric nor a function registered with @metric"
    )
