"""A design study: a family, ranges, metrics, constraints, objectives, a runner; its study file.

:class:`Study` is the whole definition of a study, reproducible from its YAML form
(:meth:`Study.to_yaml`, :meth:`Study.load`)::

    family: delta
    ranges: {la: [0.15, 0.35], lb: [0.3, 0.6]}
    fixed: {z_home: -0.35}
    metrics: [clavel, sizing, required, moving_mass]
    requirement: {kind: cylinder, D: 0.4, H: 0.1, center: [0, 0, -0.35]}
    trajectory: adept
    trajectory_options: {cycle_time: 0.5}
    payload: 1.0
    constraints: ["inv_cond_min>=0.2", "interference_margin>=0"]
    objectives: ["min:peak_effort", "max:inv_cond_min"]
    sampler: sobol          # grid | lhs | sobol | random | nsga2
    n: 256                  # designs; grid: values per variable; nsga2: population
    seed: 0

A required workspace adds the constraint ``contains >= 1`` (every required pose reached).
Metrics named by constraints and objectives are computed even if not listed.
"""

from __future__ import annotations

import hashlib
import json
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, cast

import numpy as np

from pkdyn.design import fields
from pkdyn.design.context import Conditions
from pkdyn.design.goals import Constraint, Objective
from pkdyn.design.metrics import (
    METRICS,
    PRECISION_METRICS,
    VIBRATION_METRICS,
    WORKSPACE_METRICS,
    Metric,
    check_precision,
    resolve_metrics,
)
from pkdyn.design.requirement import Requirement
from pkdyn.design.samplers import SAMPLERS, check_count, unit_points
from pkdyn.design.space import DesignSpace, Range
from pkdyn.dynamics.trajectory import TRAJECTORIES, task_at_home
from pkdyn.exceptions import InvalidInputError, StudyError
from pkdyn.files import read_text

__all__ = ["MAX_CLOSED_FORM_WORK", "MAX_SEED", "MAX_STUDY_FILE", "MAX_STUDY_WORK", "Study"]

MAX_SEED = 2**32 - 1
"""Largest seed (the samplers' and NSGA-II's generators take 32-bit seeds)."""

MAX_STUDY_FILE = 1_000_000
"""Largest study file read [bytes]."""

MAX_STUDY_WORK = 20_000_000
"""Most pose checks, duty-cycle samples or workspace grid points a study may ask for, over all
its designs (each is microseconds in closed form, up to a millisecond on the numeric path)."""

MAX_CLOSED_FORM_WORK = 200_000_000
"""Most required poses or duty-cycle samples a study may ask for, over all its designs, where
every design takes the library Delta's closed forms (a pose and its figures about 12 us, a
duty-cycle sample 3 us, ``bench/design.py``: 40 min of CPU at most; the worked study at 100,000
designs asks for 4.25e7 poses and 5.01e7 samples)."""

_CONDITION_KEYS = (
    "limits",
    "length",
    "gamma_max",
    "ab_min",
    "workspace_samples",
    "clavel_rays",
    "actuator_stiffness",
    "material",
    "damping_ratio",
    "band",
    "dwell",
)


def _ranges(value: Any) -> tuple[Range, ...]:
    """Ranges from ``{name: [low, high]}``, or a list of :class:`Range` s or ``NAME=LOW:HIGH``."""
    if isinstance(value, Mapping):
        items = []
        for k, v in value.items():
            if not isinstance(k, str):
                raise InvalidInputError("ranges", f"names are strings, got {k!r}")
            if isinstance(v, str) or not isinstance(v, Sequence) or len(v) != 2:
                raise InvalidInputError(f"range '{k}'", f"expected [low, high], got {v!r}")
            lo = fields.number(f"range '{k}' low", v[0])
            hi = fields.number(f"range '{k}' high", v[1])
            items.append(Range(k, lo, hi))
        return tuple(items)
    rs = fields.names("ranges", value, (Range,), "NAME: [LOW, HIGH] entries or NAME=LOW:HIGH")
    return tuple(r if isinstance(r, Range) else Range.parse(r) for r in rs)


@dataclass(frozen=True)
class Study:
    """The definition of a design study (see the module docstring for its file form).

    Attributes:
        family: Registered family name.
        ranges: Design variables: ``{name: (low, high)}`` or :class:`Range` s.
        fixed: Fixed builder (or parametrisation) values.
        metrics: Metric names, group names or :class:`Metric` objects.
        constraints: ``"NAME>=VALUE"`` / ``"NAME<=VALUE"`` or :class:`Constraint` s.
        objectives: ``"min:NAME"`` / ``"max:NAME"`` or :class:`Objective` s; the first chooses.
        requirement: Required workspace (``"cylinder:D=0.4,H=0.1,z=-0.35"``, a dict or a
            :class:`Requirement`), or ``None``.
        trajectory: Duty cycle name (``adept``, ``sine``, ``p2p``).
        trajectory_options: Its options (``cycle_time`` [s], ``depth`` [m], ``dt`` [s]...).
        payload: Payload during the duty cycle [kg].
        sampler: ``grid``, ``lhs``, ``sobol``, ``random`` or ``nsga2``.
        n: Designs (``lhs``, ``sobol``, ``random``), values per variable (``grid``), or the
            population (``nsga2``).
        generations: NSGA-II generations.
        seed: Seed of the sampler or of NSGA-II.
        parametrisation: Name of a parametrisation (:mod:`pkdyn.design.parametrisations`).
        settings: Other conditions: ``limits``, ``length`` [m], ``gamma_max``, ``ab_min`` [rad],
            ``workspace_samples``, ``clavel_rays``, ``actuator_stiffness``, ``material``,
            ``damping_ratio``, ``band``, ``dwell`` (see :class:`pkdyn.design.Conditions`).
        name: A label for reports.

    Raises:
        PkdynError: Any bad input (:class:`~pkdyn.exceptions.InvalidInputError`,
            :class:`~pkdyn.exceptions.ParameterError`, ...), named.

    """

    family: str
    ranges: Any
    fixed: Mapping[str, Any] = field(default_factory=dict)
    metrics: Sequence[str | Metric] = ()
    constraints: Sequence[str | Constraint] = ()
    objectives: Sequence[str | Objective] = ()
    requirement: Any = None
    trajectory: str = "adept"
    trajectory_options: Mapping[str, Any] = field(default_factory=dict)
    payload: float = 0.0
    sampler: str = "lhs"
    n: int = 64
    generations: int = 10
    seed: int = 0
    parametrisation: str | None = None
    settings: Mapping[str, Any] = field(default_factory=dict)
    name: str = ""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "family", fields.text("family", self.family))
        set_(self, "ranges", _ranges(self.ranges))
        set_(self, "fixed", fields.mapping("fixed", self.fixed))
        set_(self, "metrics", fields.names("metrics", self.metrics, (Metric,), "metric names"))
        set_(
            self,
            "constraints",
            tuple(
                c if isinstance(c, Constraint) else Constraint.parse(c)
                for c in fields.names("constraints", self.constraints, (Constraint,), "NAME>=VALUE")
            ),
        )
        set_(
            self,
            "objectives",
            tuple(
                o if isinstance(o, Objective) else Objective.parse(o)
                for o in fields.names(
                    "objectives", self.objectives, (Objective,), "min:NAME or max:NAME"
                )
            ),
        )
        req = self.requirement
        if req is not None and not isinstance(req, Requirement):
            if isinstance(req, str):
                req = Requirement.parse(req)
            else:
                req = Requirement.from_dict(fields.mapping("requirement", req))
        set_(self, "requirement", req)
        set_(self, "trajectory", fields.text("trajectory", self.trajectory, TRAJECTORIES))
        opts = fields.mapping("trajectory_options", self.trajectory_options)
        set_(self, "trajectory_options", opts)
        set_(self, "settings", fields.mapping("settings", self.settings))
        bad = [k for k in self.settings if k not in _CONDITION_KEYS]
        if bad:
            raise InvalidInputError(
                "settings", f"unknown '{bad[0]}' (use {', '.join(_CONDITION_KEYS)})"
            )
        set_(self, "payload", fields.number("payload", self.payload, 0.0, unit="kg"))
        set_(self, "sampler", fields.text("sampler", self.sampler, SAMPLERS))
        set_(self, "n", fields.integer("n", self.n, 1))
        set_(self, "generations", fields.integer("generations", self.generations, 1))
        set_(self, "seed", fields.integer("seed", self.seed, 0, MAX_SEED))
        if self.parametrisation is not None:
            fields.text("parametrisation", self.parametrisation)
        set_(self, "name", fields.text("name", self.name))
        # validate now: bad input fails before any design is evaluated
        _ = self.space, self.conditions, self.metric_list
        self._check_precision()
        set_(self, "fixed", dict(self.space.fixed))  # text values converted by the space
        _ = self.total
        if self.sampler == "nsga2" and not self.objectives:
            raise InvalidInputError("objectives", "nsga2 needs at least one objective")
        self._check_work(self._check_duty_cycle())

    def _check_precision(self) -> None:
        """Refuse precision options no design could turn into a metric (on the middle design)."""
        if not any(m.name in PRECISION_METRICS for m in self.metric_list):
            return
        from pkdyn.exceptions import PkdynError
        from pkdyn.model.candidate import CandidateBuilder

        middle = self.space.values(np.full((1, self.space.dimension), 0.5))[0]
        try:
            params = self.space.family_obj.make_params(self.space.overrides(middle))
            robot = CandidateBuilder(self.space.family, collision=self.geometry).robot(params)
        except PkdynError:
            return  # (the middle design does not build: each design says why)
        check_precision(self.metric_list, self.conditions, robot)

    def _check_duty_cycle(self) -> int:
        """Build the duty cycle about a stand-in home: its options fail now, not per design.

        Returns:
            Its number of samples.

        """
        with warnings.catch_warnings():
            if not self.uses_duty:  # options checked; a coarse dt matters only when used
                warnings.simplefilter("ignore")
            task = task_at_home(np.zeros(6), range(6), self.trajectory, **self.trajectory_options)
        return int(task.t.size)

    def _check_work(self, duty_samples: int) -> None:
        """Refuse a study whose pose checks or duty-cycle samples exceed the budgets."""
        designs = self.total
        budgets = []
        if self.requirement is not None:
            budgets.append(("required poses", self.requirement.count, "--require samples"))
        closed = self._closed_form()
        if self.uses_duty:
            budgets.append(("duty-cycle samples", duty_samples, "--dt or the cycles"))
        if any(m.name in ("workspace_volume", "gci") for m in self.metric_list):
            s = self.conditions.workspace_samples
            budgets.append(("workspace grid points", s**3, "workspace_samples"))
        for what, per_design, fix in budgets:
            work = designs * per_design
            cap = (
                MAX_CLOSED_FORM_WORK
                if closed and what != "workspace grid points"
                else MAX_STUDY_WORK
            )
            if work > cap:
                how = " in closed form" if cap == MAX_CLOSED_FORM_WORK else ""
                raise InvalidInputError(
                    "study",
                    f"{designs} designs x {per_design} {what} = {work:.3g} evaluations, more "
                    f"than the {cap:.0e} a study may ask{how} (hours of computing); "
                    f"lower the designs or {fix}",
                )

    def _closed_form(self) -> bool:
        """Whether every design takes the library Delta's closed forms (poses, duty cycle).

        The family ``delta`` with three arms of ball-jointed bars, without a parametrisation
        (:class:`pkdyn.workspace.delta.DeltaEvaluator` and
        :func:`pkdyn.dynamics.delta.delta_inverse_dynamics` take every such design).
        """
        space = self.space
        if space.family != "delta" or space.parametrisation is not None:
            return False
        from types import SimpleNamespace

        from pkdyn.dynamics.delta import delta_closed_form_params

        names = ("arms", "parallelogram", "bar_joint")
        fixed = {n: space.fixed.get(n, getattr(space._defaults, n, None)) for n in names}
        ranged = {r.name for r in space.ranges}
        return "arms" not in ranged and delta_closed_form_params(
            SimpleNamespace(**{n: v for n, v in fixed.items() if v is not None})
        )

    # ------------------------------------------------------------------ derived

    @cached_property
    def space(self) -> DesignSpace:
        """The design space."""
        return DesignSpace(self.family, self.ranges, self.fixed, self.parametrisation)

    @cached_property
    def conditions(self) -> Conditions:
        """What the designs are evaluated against."""
        return Conditions(
            requirement=self.requirement,
            trajectory=self.trajectory,
            trajectory_options=self.trajectory_options,
            payload=float(self.payload),
            **self.settings,
        )

    @property
    def objective_list(self) -> tuple[Objective, ...]:
        """The objectives (parsed)."""
        return cast("tuple[Objective, ...]", self.objectives)

    @cached_property
    def all_constraints(self) -> tuple[Constraint, ...]:
        """The constraints, with ``contains >= 1`` when a workspace is required."""
        given = cast("tuple[Constraint, ...]", self.constraints)
        extra: tuple[Constraint, ...] = ()
        if self.requirement is not None and not any(c.metric == "contains" for c in given):
            extra = (Constraint("contains", ">=", 1.0),)
        return extra + given

    @cached_property
    def metric_list(self) -> list[Metric]:
        """Every metric computed, in column order (listed, then those goals name)."""
        names: list[str | Metric] = list(self.metrics)
        names += [c.metric for c in self.all_constraints]
        names += [o.metric for o in self.objective_list]
        if not names:
            raise InvalidInputError("metrics", "a study needs at least one metric (--metric)")
        metrics = resolve_metrics(names)
        needs = {"contains", "inv_cond_min", "inv_cond_mean", "interference_margin"}
        needs |= set(WORKSPACE_METRICS)
        if self.requirement is None:
            used = sorted(needs & {m.name for m in metrics})
            if used:
                raise InvalidInputError(
                    f"metric '{used[0]}'", "needs a required workspace (--require KIND:...)"
                )
        vib = [m.name for m in metrics if m.name in VIBRATION_METRICS]
        if vib:
            self._check_vibration(vib[0])
        return metrics

    def _check_vibration(self, name: str) -> None:
        """Refuse up front the settings a vibration metric cannot be computed with.

        The duty cycle must run from rest to rest (the settling follows a stop); the actuators'
        stiffness is checked with the precision metrics' (:func:`check_precision`).
        """
        if self.trajectory == "sine":
            raise InvalidInputError(
                f"metric '{name}'",
                "needs a duty cycle from rest to rest (adept or p2p), not sine (it ends in motion)",
            )

    @property
    def metric_names(self) -> list[str]:
        """Column names of the metrics."""
        return [m.name for m in self.metric_list]

    @cached_property
    def units(self) -> dict[str, str]:
        """Unit of each metric; efforts and speeds resolved for the family's actuators.

        ``N m or N`` becomes ``N m`` when every actuator of the family's default robot is
        rotary (``N`` when every one is linear), and likewise for speeds.
        """
        units = {m.name: m.unit for m in self.metric_list}
        if not any(" or " in u for u in units.values()):
            return units
        import pkdyn

        try:
            robot = pkdyn.load(self.family, geometry=False)
        except Exception:  # the defaults do not build: keep the generic units
            return units
        kinds = {robot.model.joints[int(j)].shortname() for j in robot.actuated_joints}
        rotary = all("Revolute" in k or k.startswith("JointModelR") for k in kinds)
        linear = all("Prismatic" in k or k.startswith("JointModelP") for k in kinds)
        pick = 0 if rotary else 1 if linear else None
        if pick is None:
            return units
        return {k: u.split(" or ")[pick] if " or " in u else u for k, u in units.items()}

    @property
    def uses_duty(self) -> bool:
        """Whether a metric runs the duty cycle (the sizing metrics)."""
        duty = {"peak_effort", "rms_effort", "peak_speed", "peak_power"}
        duty |= {"effort_margin", "speed_margin", *VIBRATION_METRICS}
        return any(m.name in duty or m.name.rsplit("_", 1)[0] in duty for m in self.metric_list)

    @property
    def geometry(self) -> bool:
        """Whether designs are built with collision geometry."""
        return any(m.geometry for m in self.metric_list) or any(
            m.name in ("workspace_volume", "gci") for m in self.metric_list
        )

    @cached_property
    def total(self) -> int:
        """Number of designs the runner evaluates (NSGA-II: at most)."""
        return check_count(self.sampler, self.n, self.space.dimension, self.generations)

    def designs(self) -> np.ndarray:
        """Design variables (N, d) of a sweep (grid, lhs, sobol, random), in index order."""
        u = unit_points(self.sampler, self.n, self.space.dimension, self.seed)
        return self.space.values(u)

    # ------------------------------------------------------------------ file form

    def as_dict(self) -> dict[str, Any]:
        """The study-file form (YAML-ready; user metric objects by name)."""
        out: dict[str, Any] = self.space.as_dict()
        out.update(
            {
                "metrics": [m if isinstance(m, str) else m.name for m in self.metrics],
                "constraints": [str(c) for c in self.constraints],
                "objectives": [str(o) for o in self.objectives],
                "requirement": None if self.requirement is None else self.requirement.as_dict(),
                "trajectory": self.trajectory,
                "trajectory_options": dict(self.trajectory_options),
                "payload": float(self.payload),
                "sampler": self.sampler,
                "n": self.n,
                "seed": self.seed,
            }
        )
        if self.sampler == "nsga2":
            out["generations"] = self.generations
        if self.settings:
            out["settings"] = dict(self.settings)
        if self.name:
            out["name"] = self.name
        return out

    def to_yaml(self) -> str:
        """The study file text."""
        import yaml

        return str(yaml.safe_dump(self.as_dict(), sort_keys=False, default_flow_style=None))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "study") -> Study:
        """A study from its file form.

        A ``results`` entry (the summary :func:`pkdyn.design.run_study` appends to the study
        file it writes) is ignored.

        Raises:
            StudyError: Not a mapping, or unknown keys.

        """
        if not isinstance(source, str):
            raise InvalidInputError("source", f"expected a name for messages, got {source!r:.40}")
        if not isinstance(data, Mapping):
            raise StudyError(source, "a study file is a mapping (family, ranges, metrics...)")
        known = set(cls.__dataclass_fields__)
        data = {k: v for k, v in data.items() if k != "results"}  # a written study's summary
        bad = [k for k in data if k not in known]
        if bad:
            raise StudyError(source, f"unknown key '{bad[0]}' (use {', '.join(sorted(known))})")
        if "family" not in data or "ranges" not in data:
            raise StudyError(source, "a study needs 'family' and 'ranges'")
        return cls(**data)

    @classmethod
    def load(cls, path: str | Path) -> Study:
        """Read a YAML study file.

        Raises:
            StudyError: Missing, unreadable or malformed file.

        """
        import yaml

        text = read_text(path, MAX_STUDY_FILE, lambda msg: StudyError(str(path), msg))
        try:
            data = yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
        except yaml.YAMLError as err:
            raise StudyError(str(path), f"not valid YAML ({err})".replace("\n", " ")) from None
        except RecursionError:
            raise StudyError(str(path), "nested too deeply to be a study file") from None
        return cls.from_dict(data, str(path))

    def digest(self) -> str:
        """Fingerprint of everything that determines the results (16 hex digits).

        Covers the study-file form, the metrics' units and the code of user metrics
        (by module and name).
        """
        described = []
        for m in self.metric_list:
            builtin = METRICS.get(m.name) is m
            where = "" if builtin else f"{getattr(m.fn, '__module__', '')}.{m.fn.__qualname__}"
            described.append([m.name, m.unit, where])
        text = json.dumps([self.as_dict(), described], sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]
