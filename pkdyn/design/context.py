"""What metrics see: the study's conditions and, per design, the built robot and shared results.

:class:`Conditions` holds what every design of a study is judged on (the required workspace,
the duty cycle and payload, Clavel's limits, sampling densities). :class:`DesignContext` is
made for each design: metrics call its methods for the expensive results several of them share
(the required-workspace check, the duty-cycle figures, the translation workspace, Clavel's
figures), computed once per design. A user metric can share its own with :meth:`cached`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from pkdyn.design import fields
from pkdyn.design.duty import DutyFigures, duty_figures
from pkdyn.design.required import RequiredCheck, required_check
from pkdyn.design.requirement import Requirement
from pkdyn.exceptions import InvalidInputError
from pkdyn.model.robot import Robot
from pkdyn.workspace.clavel import AB_MIN, GAMMA_MAX, ClavelFigures
from pkdyn.workspace.limits import check_kinds
from pkdyn.workspace.translation import TranslationWorkspace

__all__ = ["MAX_CLAVEL_RAYS", "MAX_WORKSPACE_SAMPLES", "Conditions", "DesignContext"]

MAX_WORKSPACE_SAMPLES = 100
"""Most grid samples per axis of a design's translation workspace (10^6 poses)."""

MAX_CLAVEL_RAYS = 720
"""Most directions of the numeric Clavel measurement."""

T = TypeVar("T")


_TEXT_OPTIONS = ("profile",)
"""Options of the named trajectories that are not numbers."""


@dataclass(frozen=True)
class Conditions:
    """What every design of a study is evaluated against.

    Attributes:
        requirement: Required workspace, or ``None``.
        limits: Limit kinds a required pose must respect besides reach (``stroke``,
            ``joint``); interference is measured apart (``interference_margin``).
        length: Characteristic length for the angular rows of ``J`` [m] (robots with
            rotations in their task); ``None``: unscaled.
        trajectory: Duty cycle, a :func:`pkdyn.dynamics.trajectory.named_task` name.
        trajectory_options: Its options (``cycle_time`` [s], ``depth`` [m], ``dt`` [s]...).
        payload: Payload on the platform during the duty cycle [kg].
        gamma_max: Clavel's limit 1 [rad].
        ab_min: Clavel's limit 2, (alpha + beta)_min [rad].
        workspace_samples: Grid samples per axis of the translation workspace (volume, GCI).
        clavel_rays: Directions of the numeric Clavel measurement.
        actuator_stiffness: Joint-side actuator stiffness for the precision metrics
            (``stiffness_min``, ``f1_min``), one or one per actuator [N m/rad or N/m];
            ``None``: the description's ``<pkdyn:stiffness>``.
        material: Material of the links for the precision metrics (a preset name of
            :mod:`pkdyn.precision.material`); ``None``: rigid links (or the description's).
        damping_ratio: Damping ratio of the first mode for the vibration metrics
            (``settling_time``, ``residual_amplitude``); ``None``: 0.02.
        band: Settling band of ``settling_time`` [m].
        dwell: Time after the duty cycle within which the tool must settle [s].

    """

    requirement: Requirement | None = None
    limits: tuple[str, ...] = ("stroke", "joint")
    length: float | None = None
    trajectory: str = "adept"
    trajectory_options: Mapping[str, Any] = field(default_factory=dict)
    payload: float = 0.0
    gamma_max: float = GAMMA_MAX
    ab_min: float = AB_MIN
    workspace_samples: int = 21
    clavel_rays: int = 24
    actuator_stiffness: float | tuple[float, ...] | None = None
    material: str | None = None
    damping_ratio: float | None = None
    band: float = 1e-4
    dwell: float = 0.5
    _tasks: dict[Any, Any] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        limits = fields.names("limits", self.limits)
        check_kinds(limits)
        set_(self, "limits", limits)
        set_(
            self,
            "trajectory_options",
            fields.mapping("trajectory_options", self.trajectory_options),
        )
        from pkdyn.dynamics.trajectory import TRAJECTORIES, _check_named, _number

        set_(self, "trajectory", fields.text("trajectory", self.trajectory, TRAJECTORIES))
        _check_named(self.trajectory, self.trajectory_options)
        for key in self.trajectory_options:
            if key not in _TEXT_OPTIONS:  # (their ranges: checked when the cycle is built)
                _number(self.trajectory, dict(self.trajectory_options), key, 0.0)
        set_(self, "payload", fields.number("payload", self.payload, 0.0, unit="kg"))
        if self.length is not None:
            set_(self, "length", fields.number("length", self.length, 0.0, open_low=True, unit="m"))
        for name in ("gamma_max", "ab_min"):
            angle = fields.number(
                name, getattr(self, name), 0.0, math.pi, open_low=True, unit="rad"
            )
            set_(self, name, angle)
        set_(
            self,
            "workspace_samples",
            fields.integer("workspace_samples", self.workspace_samples, 3, MAX_WORKSPACE_SAMPLES),
        )
        set_(
            self, "clavel_rays", fields.integer("clavel_rays", self.clavel_rays, 3, MAX_CLAVEL_RAYS)
        )
        if self.actuator_stiffness is not None:
            from pkdyn.inputs import vector

            k = vector("actuator_stiffness", self.actuator_stiffness, unit="N m/rad or N/m")
            if k.size == 0 or not np.all(k > 0.0):
                raise InvalidInputError(
                    "actuator_stiffness", f"{k.tolist()}: stiffnesses must be > 0 [N m/rad or N/m]"
                )
            value = float(k[0]) if k.size == 1 else tuple(float(x) for x in k)
            object.__setattr__(self, "actuator_stiffness", value)
        if self.material is not None:
            from pkdyn.precision.material import as_material

            as_material(self.material)
        if self.damping_ratio is not None:
            from pkdyn.precision.vibration_damping import MAX_DAMPING_RATIO

            set_(
                self,
                "damping_ratio",
                fields.number("damping_ratio", self.damping_ratio, 0.0, MAX_DAMPING_RATIO),
            )
        set_(self, "band", fields.number("band", self.band, 0.0, 10.0, open_low=True, unit="m"))
        set_(self, "dwell", fields.number("dwell", self.dwell, 0.0, 60.0, open_low=True, unit="s"))

    def as_dict(self) -> dict[str, Any]:
        """Plain form for study files."""
        return {
            "requirement": None if self.requirement is None else self.requirement.as_dict(),
            "limits": list(self.limits),
            "length": self.length,
            "trajectory": self.trajectory,
            "trajectory_options": dict(self.trajectory_options),
            "payload": self.payload,
            "gamma_max": self.gamma_max,
            "ab_min": self.ab_min,
            "workspace_samples": self.workspace_samples,
            "clavel_rays": self.clavel_rays,
            "actuator_stiffness": None
            if self.actuator_stiffness is None
            else (
                self.actuator_stiffness
                if isinstance(self.actuator_stiffness, float)
                else list(self.actuator_stiffness)
            ),
            "material": self.material,
            "damping_ratio": self.damping_ratio,
            "band": self.band,
            "dwell": self.dwell,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Conditions:
        """From the study-file form (see :meth:`as_dict`)."""
        d = fields.mapping("conditions", data)
        req = d.pop("requirement", None)
        known = {k for k in cls.__dataclass_fields__ if not k.startswith("_")}
        bad = [k for k in d if k not in known]
        if bad:
            raise InvalidInputError(
                "conditions", f"unknown key '{bad[0]}' (use {', '.join(sorted(known))})"
            )
        return cls(requirement=None if req is None else Requirement.from_dict(req), **d)


class DesignContext:
    """One design being evaluated: its robot, the study's conditions, shared results.

    Args:
        robot: The built design.
        conditions: The study's conditions.

    """

    def __init__(self, robot: Robot, conditions: Conditions) -> None:
        self.robot = robot
        self.conditions = conditions
        self._memo: dict[str, Any] = {}

    def cached(self, key: str, compute: Callable[[], T]) -> T:
        """``compute()`` once per design under ``key`` (shared between metrics).

        Raises:
            InvalidInputError: ``key`` is not a string or ``compute`` not a function.
            StudyError: ``compute`` raised (or called ``sys.exit``): the cause is kept.

        """
        from pkdyn.exceptions import PkdynError, StudyError
        from pkdyn.inputs import callable_input

        if not isinstance(key, str):
            raise InvalidInputError("key", f"expected a string, got {key!r:.40}")
        callable_input("compute", compute)
        if key not in self._memo:
            try:
                self._memo[key] = compute()
            except (PkdynError, MemoryError):
                raise
            except (Exception, SystemExit) as err:
                raise StudyError(
                    f"cached '{key}'", f"the compute function raised {type(err).__name__}: {err}"
                ) from err
        return self._memo[key]  # type: ignore[no-any-return]

    def requirement(self) -> Requirement:
        """The required workspace.

        Raises:
            InvalidInputError: The study has none.

        """
        if self.conditions.requirement is None:
            raise InvalidInputError(
                "requirement", "this metric needs a required workspace (--require KIND:...)"
            )
        return self.conditions.requirement

    def required(self) -> RequiredCheck:
        """The design on the required workspace (:func:`pkdyn.design.required.required_check`)."""
        c = self.conditions
        return self.cached(
            "required",
            lambda: required_check(self.robot, self.requirement(), c.limits, c.length),
        )

    def duty(self) -> DutyFigures:
        """Actuator figures on the duty cycle (:func:`pkdyn.design.duty.duty_figures`)."""
        c = self.conditions
        return self.cached(
            "duty",
            lambda: duty_figures(
                self.robot, c.trajectory, c.trajectory_options, c.payload, c._tasks
            ),
        )

    def translation(self) -> TranslationWorkspace:
        """Constant-orientation workspace on a grid.

        The robot's own limits, with interference when it has collision geometry.
        """
        from pkdyn.workspace.translation import translation_workspace

        def run() -> TranslationWorkspace:
            kinds = list(self.conditions.limits)
            if len(self.robot.collision_model.geometryObjects):
                kinds.append("interference")
            return translation_workspace(
                self.robot,
                samples=self.conditions.workspace_samples,
                limits=kinds,
                progress=False,
            )

        return self.cached("translation", run)

    def clavel(self) -> ClavelFigures:
        """Clavel's closed-form figures with the study's limits (Delta)."""
        from pkdyn.workspace.clavel import clavel_closed_form

        c = self.conditions
        return self.cached(
            "clavel", lambda: clavel_closed_form(self._delta(), c.gamma_max, c.ab_min)
        )

    def clavel_numeric(self) -> ClavelFigures:
        """Clavel's figures measured on the mechanism (Delta; slower)."""
        from pkdyn.workspace.clavel import clavel_numeric

        c = self.conditions
        return self.cached(
            "clavel_numeric",
            lambda: clavel_numeric(
                self._delta(),
                c.gamma_max,
                c.ab_min,
                rays=c.clavel_rays,
                fractions=5,
                heights=40,
                tol=1e-7,
            )[0],
        )

    def _delta(self) -> Any:
        p = self.robot.params
        if self.robot.family != "delta" or p is None:
            raise InvalidInputError(
                "metric", f"Clavel's figures apply to the delta family, not {self.robot.name}"
            )
        return p

    def gci(self) -> float:
        """Global conditioning index: mean ``1 / cond(J)`` over the translation workspace."""

        def run() -> float:
            ws = self.translation()
            P = ws.points()
            if P.shape[0] == 0:
                return 0.0
            check = required_check(self.robot, P, (), self.conditions.length)
            return float(np.mean(np.nan_to_num(check.inv_cond, nan=0.0)))

        return self.cached("gci", run)
