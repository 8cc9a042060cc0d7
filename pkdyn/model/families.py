"""The registry of robot families that ``pkdyn.load(name)`` resolves.

The model layer owns the registry; :mod:`pkdyn.library` registers its families into it when
:mod:`pkdyn` is imported, so the loader never imports the library (layering).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from pkdyn.exceptions import ParameterError, UnknownRobotError, close_match
from pkdyn.inputs import MAX_MAGNITUDE

__all__ = ["FAMILIES", "Family", "export_urdf", "family", "from_description", "register"]


@dataclass(frozen=True)
class Family:
    """A robot family of the library.

    The family's module is imported on first use (``import pkdyn`` stays light): it defines
    ``NAME``, ``SUMMARY``, a frozen ``Params`` dataclass, ``build_urdf(params) -> str`` and
    ``home(params) -> list[float]`` (actuated coordinates of the home configuration).

    Attributes:
        name: Family name (also the URDF file stem).
        module: Dotted name of the module that builds it.

    """

    name: str
    module: str

    def _module(self) -> ModuleType:
        return importlib.import_module(self.module)

    @property
    def summary(self) -> str:
        """One-line description."""
        return str(self._module().SUMMARY)

    @property
    def params(self) -> type:
        """Frozen dataclass of parameters (SI units, documented defaults)."""
        return self._module().Params  # type: ignore[no-any-return]

    def build_urdf(self, params: Any) -> str:
        """URDF text of the robot with these parameters."""
        return str(self._module().build_urdf(params))

    def layout(self, params: Any) -> Any:
        """The builder's elements with these parameters, before any text, or ``None``.

        A :class:`~pkdyn.model.formats.urdf_writer.UrdfWriter` holding the
        :class:`~pkdyn.model.formats.urdf_writer.Record` s that :meth:`build_urdf` renders
        (the module's optional ``layout(params)``); :mod:`pkdyn.model.candidate` writes their
        numbers into an existing model. ``None``: the family writes text only.
        """
        fn = getattr(self._module(), "layout", None)
        return None if fn is None else fn(params)

    def home(self, params: Any) -> list[float]:
        """Actuated coordinates of the home configuration."""
        return list(self._module().home(params))

    @property
    def has_forward_position(self) -> bool:
        """Whether the family has a closed-form direct model (:meth:`forward_position`)."""
        return _has(self.module, "forward_position")

    def forward_position(self, params: Any, qa: Any, reference: Any = None) -> Any:
        """Platform position (3,) [m] from actuated coordinates, in a chosen assembly mode.

        The family's closed-form direct geometric model (its optional
        ``forward_position(params, qa, reference)``): in the assembly mode of ``reference``
        (``(qa_ref, position_ref)``, an assembled configuration's actuators and platform
        position) or, without one, of the home configuration. The Delta always keeps the nacelle
        below the base. ``None``: no closed form, or not assemblable.
        """
        fn = getattr(self._module(), "forward_position", None)
        return None if fn is None else fn(params, qa, reference)

    def configuration(self, robot: Any, qa: Any, position: Any) -> Any:
        """A configuration (nq,) with actuators ``qa`` and the platform at ``position``.

        Built by the family (its optional ``configuration(robot, qa, position)``), or ``None``.
        """
        fn = getattr(self._module(), "configuration", None)
        return None if fn is None else fn(robot, qa, position)

    def inverse_actuators(self, params: Any, pose: Any) -> Any:
        """Actuated coordinates (n_a,) reaching a platform pose in the family's working mode.

        The closed-form inverse geometric model (optional ``inverse_actuators(params, pose)``,
        ``pose`` a ``pin.SE3``) in the working mode of the home configuration, or ``None``.
        """
        fn = getattr(self._module(), "inverse_actuators", None)
        return None if fn is None else fn(params, pose)

    def make_params(self, overrides: dict[str, Any]) -> Any:
        """Parameters with ``overrides`` applied; strings are converted to the field type.

        Args:
            overrides: ``{name: value}``.

        Returns:
            The parameter dataclass instance.

        Raises:
            ParameterError: Unknown name or value that does not convert / validate.

        """
        if not overrides:
            return self.params()
        fields = {f.name: f for f in dataclasses.fields(self.params)}
        kwargs: dict[str, Any] = {}
        for key, value in overrides.items():
            if key not in fields:
                raise ParameterError(
                    self.name,
                    key,
                    f"unknown; valid parameters: {', '.join(sorted(fields))}"
                    + close_match(key, sorted(fields)),
                )
            f = fields[key]  # the field's default, without building (validating) an instance
            factory: Any = f.default_factory
            default = f.default if f.default is not dataclasses.MISSING else factory()
            try:
                if default is None:  # derived unless given (a length or angle)
                    text = str(value).strip().lower()
                    kwargs[key] = None if text in ("none", "auto", "") else float(value)
                elif isinstance(default, bool):
                    kwargs[key] = (
                        value
                        if isinstance(value, bool)
                        else str(value).lower()
                        in (
                            "1",
                            "true",
                            "yes",
                        )
                    )
                elif isinstance(default, tuple):
                    import ast  # (not at import time: 5 ms of every command's start)

                    parsed = ast.literal_eval(value) if isinstance(value, str) else value
                    kwargs[key] = tuple(
                        tuple(float(x) for x in row)
                        if isinstance(row, list | tuple)
                        else float(row)
                        for row in parsed
                    )
                elif isinstance(default, int | float):
                    kwargs[key] = type(default)(float(value))
                else:
                    kwargs[key] = type(default)(value)
            except (TypeError, ValueError, SyntaxError):
                kind = "float" if default is None else type(default).__name__
                raise ParameterError(
                    self.name, key, f"cannot use {value!r} (expected {kind})"
                ) from None
            _check_magnitude(self.name, key, kwargs[key])
        return self.params(**kwargs)


def _check_magnitude(family: str, name: str, value: Any) -> None:
    """Refuse a numeric parameter beyond :data:`pkdyn.inputs.MAX_MAGNITUDE` (SI units).

    Such a value is a typing or unit error, and the builders' arithmetic on it (squares of
    lengths, inertias) would overflow before any check of the geometry could name it.
    """
    values = value if isinstance(value, tuple) else (value,)
    for v in values:
        if isinstance(v, tuple):
            _check_magnitude(family, name, v)
        elif isinstance(v, int | float) and not isinstance(v, bool) and abs(v) > MAX_MAGNITUDE:
            raise ParameterError(
                family,
                name,
                f"{v:g} is beyond any plausible value (at most {MAX_MAGNITUDE:g} in SI units)",
            )


FAMILIES: dict[str, Family] = {}
"""Registered families by name, in registration (documentation) order; fill with
:func:`register`."""


def register(fam: Family) -> None:
    """Add a family to the registry (done by :mod:`pkdyn.library`).

    Args:
        fam: The family; its name must be new.

    Raises:
        ValueError: A family of that name is already registered (a programming error).

    """
    if fam.name in FAMILIES and FAMILIES[fam.name] != fam:
        raise ValueError(f"family {fam.name!r} registered twice")
    FAMILIES[fam.name] = fam


def family(name: str) -> Family:
    """The family called ``name``.

    Raises:
        UnknownRobotError: No such family.

    """
    if not isinstance(name, str):
        raise UnknownRobotError(repr(name), list(FAMILIES))
    try:
        return FAMILIES[name]
    except KeyError:
        raise UnknownRobotError(name, list(FAMILIES)) from None


def _text(value: Any) -> str:
    """A parameter value as :meth:`Family.make_params` reads it back."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, tuple):
        return repr(tuple(tuple(float(x) for x in v) if isinstance(v, tuple) else v for v in value))
    return str(value)


def export_urdf(name: str, params: Any) -> str:
    """The family's URDF with a ``<pkdyn:family>`` element recording its parameters.

    Derived parameters (``None``: computed from the others) are written as computed, so the
    file keeps its geometry whatever later versions derive. Loading the file gives the robot
    the family name gives (:func:`from_description` checks it).

    Args:
        name: Family name.
        params: Its parameters.

    Returns:
        URDF text (what ``pkdyn urdf NAME`` writes and ``urdf/NAME.urdf`` holds).

    """
    fam = family(name)
    module = fam._module()
    resolved = module.resolved(params) if hasattr(module, "resolved") else params
    xml = fam.build_urdf(params)
    lines = [f'  <pkdyn:family name="{name}">']
    for f in dataclasses.fields(resolved):
        value = getattr(resolved, f.name)
        if value is None:
            continue
        text = _text(value).replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")
        lines.append(f'    <pkdyn:param name="{f.name}" value="{text}"/>')
    lines.append("  </pkdyn:family>")
    head, sep, tail = xml.rpartition("</robot>")
    return head + "\n".join(lines) + "\n" + sep + tail


def from_description(desc: Any, model: Any, source: str) -> tuple[Any, list[float]]:
    """Parameters and home of a file carrying a ``<pkdyn:family>`` element, checked.

    The family's builder is run with the recorded parameters and its model compared with the
    file's (joints, placements, inertias, limits, closures, pkdyn joints, actuators, platform):
    a file edited since it was written is refused rather than given parameters (and closed
    forms) that no longer describe it.

    Args:
        desc: The file's parsed description.
        model: The file's Pinocchio tree (from :func:`pkdyn.model.build.build_tree`).
        source: File name, for messages.

    Returns:
        ``(params, home)``: the family's parameter instance and home actuator coordinates.

    Raises:
        DescriptionError: Unknown family, unusable parameters, or a file that differs from what
            the builder writes with them.

    """
    from pkdyn.exceptions import DescriptionError
    from pkdyn.model.build import build_tree
    from pkdyn.model.description import parse_description

    spec = desc.family
    where = f"<pkdyn:family name='{spec.name}'>"
    if spec.name not in FAMILIES:
        raise DescriptionError(
            source, where, f"unknown family; the library has {', '.join(FAMILIES)}"
        )
    fam = FAMILIES[spec.name]
    try:
        params = fam.make_params(dict(spec.params))
    except ParameterError as err:
        raise DescriptionError(source, where, str(err)) from None
    xml = fam.build_urdf(params)
    ref_desc = parse_description(xml, spec.name)
    ref = build_tree(xml, ref_desc.joints, spec.name)
    diff = _difference(desc, model, ref_desc, ref)
    if diff:
        raise DescriptionError(
            source,
            where,
            f"the file is not what the {spec.name} builder writes with these parameters "
            f"({diff}); regenerate it (pkdyn urdf {spec.name} --param ... -o FILE) or remove "
            "the element to load it as a robot of its own",
        )
    return params, fam.home(params)


def _difference(desc: Any, model: Any, ref_desc: Any, ref: Any, tol: float = 1e-9) -> str:
    """First difference between two models and their pkdyn elements ('' if none)."""
    import numpy as np

    if list(model.names) != list(ref.names):
        return "joint names"
    for j in range(1, model.njoints):
        name = model.names[j]
        if model.joints[j].shortname() != ref.joints[j].shortname():
            return f"joint '{name}' type"
        if not model.jointPlacements[j].isApprox(ref.jointPlacements[j], tol):
            return f"joint '{name}' origin"
        if not model.inertias[j].isApprox(ref.inertias[j], tol):
            return f"inertia of the body of joint '{name}'"
    for a, b in (
        (model.lowerPositionLimit, ref.lowerPositionLimit),
        (model.upperPositionLimit, ref.upperPositionLimit),
        (model.effortLimit, ref.effortLimit),
        (model.velocityLimit, ref.velocityLimit),
    ):
        if a.shape != b.shape or not np.allclose(a, b, rtol=tol, atol=tol):
            return "joint limits"
    if len(desc.closures) != len(ref_desc.closures):
        return "number of closures"
    for c, r in zip(desc.closures, ref_desc.closures, strict=True):
        same = (c.name, c.kind, c.frame1.link, c.frame2.link) == (
            r.name,
            r.kind,
            r.frame1.link,
            r.frame2.link,
        )
        if not (
            same
            and c.frame1.placement.isApprox(r.frame1.placement, tol)
            and c.frame2.placement.isApprox(r.frame2.placement, tol)
            and np.allclose(c.axis, r.axis, atol=tol)
        ):
            return f"closure '{c.name}'"
    if [(j.name, j.kind) for j in desc.joints] != [(j.name, j.kind) for j in ref_desc.joints]:
        return "pkdyn joints"
    key = [(a.name, a.joint, a.reduction, a.effort, a.velocity) for a in desc.actuators]
    if key != [(a.name, a.joint, a.reduction, a.effort, a.velocity) for a in ref_desc.actuators]:
        return "actuators"
    p, r = desc.platform, ref_desc.platform
    if (p is None) != (r is None) or (
        p is not None
        and r is not None
        and (
            p.frame.link != r.frame.link
            or p.task != r.task
            or not p.frame.placement.isApprox(r.frame.placement, tol)
        )
    ):
        return "platform"
    return ""


@functools.cache
def _has(module: str, name: str) -> bool:
    """Whether a family module defines ``name`` (modules do not change at run time)."""
    return getattr(importlib.import_module(module), name, None) is not None
