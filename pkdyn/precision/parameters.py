"""Geometric parameters of a robot: the placements manufacturing errors move, and models of them.

A **placement** is a rigid transform of the description that a manufacturing error changes:

- the placement of every tree joint in its parent body (the URDF joint ``<origin>``), except the
  free-flyer and planar joints that only place a platform or a floating base (modelling devices,
  :data:`pkdyn.model.robot.MODELLING_JOINTS`: their placement is absorbed by their motion);
- the placement of each closure frame in its body (the two ``<pkdyn:frame>`` of a closure);
- the platform frame in its body (``<pkdyn:platform xyz rpy>``: the tool, the measured frame).

An error of a placement ``M`` is a twist ``xi = (v, w)`` (6,) [m, rad] in the frame it places:
``M -> M exp(xi)`` (right perturbation). For a joint it is the error of its URDF ``<origin>``
(``origin exp(xi)``); its component along a 1-DOF joint's motion axis shifts that joint's zero:
for an actuated joint, the actuator's **offset** [rad or m].

A **parameter model** (:class:`ParameterModel`) maps parameters ``p`` (n_par,) to placement
twists and actuator gains, linearly: ``xi = E p`` (6 n_placements,) and ``g = G p`` (n_a,), the
actuated joint coordinate being ``(1 + g) qa`` for an actuator reading ``qa``. Three models:

- :func:`placement_parameters`: 6 parameters per placement (its twist components ``tx ty tz rx
  ry rz`` in the placed frame), an actuated joint's axis component named ``<actuator>.offset``;
  optionally one gain per actuator (``<actuator>.gain``);
- :func:`family_shortcuts`: the dimensions people calibrate on a library family: per-chain
  Clavel parameters of a Delta (``ra, rb, la, lb``, the arm plane angle, the arm height and the
  arm offset of each chain), the base and platform joint centres ``A_i``, ``B_i`` and the leg
  offsets of a Gough-Stewart platform;
- :func:`family_parameters`: the family builder's own parameters (``la``, ``A``...), whose
  placement derivatives are taken by central differences of the builder (placements are affine
  or smooth in them).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.build import build_tree, constraint_models, resolve_frame
from pkdyn.model.description import parse_description
from pkdyn.model.families import FAMILIES
from pkdyn.model.robot import MODELLING_JOINTS, Robot

__all__ = [
    "COMPONENTS",
    "Placement",
    "ParameterModel",
    "family_parameters",
    "family_shortcuts",
    "family_values",
    "parameter_model",
    "placement_frames",
    "placement_parameters",
    "placements",
]

COMPONENTS = ("tx", "ty", "tz", "rx", "ry", "rz")
"""Names of a placement twist's components (translation [m], rotation [rad], placed frame)."""


@dataclass(frozen=True)
class Placement:
    """A placement of the description that a manufacturing error moves.

    Attributes:
        kind: ``joint`` (a tree joint's origin), ``closure`` (a closure frame) or ``platform``.
        name: Joint name, ``<closure>/1`` or ``<closure>/2``, or ``platform``.
        joint: Pinocchio id of the joint the placed frame moves with (for a joint placement,
            that joint; 0 for a frame on the ground).
        closure: Closure name (closure frames), else ``""``.
        side: 1 or 2 for a closure frame (its first or second ``<pkdyn:frame>``), else 0.

    """

    kind: str
    name: str
    joint: int
    closure: str = ""
    side: int = 0


def placements(robot: Robot) -> tuple[Placement, ...]:
    """The placements of a robot a manufacturing error moves, in a fixed order.

    Joints (model order, modelling joints excluded), then the closure frames (closure order,
    frame 1 then frame 2), then the platform frame.

    Args:
        robot: The robot.

    Returns:
        The placements.

    """
    model = robot.model
    out = [
        Placement("joint", str(model.names[j]), j)
        for j in range(1, model.njoints)
        if model.joints[j].shortname() not in MODELLING_JOINTS
    ]
    first = _first_constraint(robot)
    for c in robot.closures:
        cm = robot.constraint_models[first[c.name]]
        out.append(Placement("closure", f"{c.name}/1", int(cm.joint1_id), c.name, 1))
        out.append(Placement("closure", f"{c.name}/2", int(cm.joint2_id), c.name, 2))
    if robot.platform_frame is not None:
        out.append(
            Placement("platform", "platform", int(model.frames[robot.platform_frame].parentJoint))
        )
    return tuple(out)


def _first_constraint(robot: Robot) -> dict[str, int]:
    """Index of the first constraint model of each closure (its frames, before hinge arms)."""
    first: dict[str, int] = {}
    for k, owner in enumerate(robot.constraint_owner):
        first.setdefault(owner, k)
    return first


def placement_frames(robot: Robot, data: pin.Data, where: tuple[Placement, ...]) -> list[pin.SE3]:
    """World placement of each placed frame, from the joint placements in ``data``.

    For a joint, the frame just after its origin (before its motion); for a closure frame, the
    frame of its ``<pkdyn:frame>``; for the platform, the platform frame.

    Args:
        robot: The robot.
        data: Pinocchio data after ``forwardKinematics`` at the configuration.
        where: The placements (:func:`placements`).

    Returns:
        One world placement per placement.

    """
    model = robot.model
    first = _first_constraint(robot)
    out = []
    for pl in where:
        if pl.kind == "joint":
            out.append(data.oMi[model.parents[pl.joint]] * model.jointPlacements[pl.joint])
        elif pl.kind == "closure":
            cm = robot.constraint_models[first[pl.closure]]
            M = cm.joint1_placement if pl.side == 1 else cm.joint2_placement
            out.append(data.oMi[pl.joint] * M)
        else:
            assert robot.platform_frame is not None
            f = model.frames[robot.platform_frame]
            out.append(data.oMi[f.parentJoint] * f.placement)
    return out


def local_placement(robot: Robot, pl: Placement) -> pin.SE3:
    """The placement itself: in the parent joint frame (joints) or in the frame's joint frame.

    Args:
        robot: The robot.
        pl: One of its placements.

    Returns:
        ``M`` such that an error ``xi`` makes it ``M exp(xi)``.

    """
    model = robot.model
    if pl.kind == "joint":
        return pin.SE3(model.jointPlacements[pl.joint])
    if pl.kind == "closure":
        cm = robot.constraint_models[_first_constraint(robot)[pl.closure]]
        return pin.SE3(cm.joint1_placement if pl.side == 1 else cm.joint2_placement)
    assert robot.platform_frame is not None
    return pin.SE3(model.frames[robot.platform_frame].placement)


@dataclass(frozen=True, eq=False)  # numpy fields: no boolean ==
class ParameterModel:
    """A linear model of geometric errors: ``xi = E p`` (placement twists), ``g = G p`` (gains).

    Attributes:
        kind: ``placements``, ``family shortcuts`` or ``family parameters``.
        names: Parameter names (n_par,).
        units: Their units (``m``, ``rad``, ``-`` for gains).
        placements: The robot's placements (n_pl,).
        E: Twist of every placement per unit parameter (6 n_pl, n_par) [m or rad per unit]:
            rows ``6 k .. 6 k + 5`` are placement ``k``'s twist (translation, rotation) in the
            frame it places.
        G: Relative actuator gain per unit parameter (n_a, n_par).
        nominal: Nominal values of the parameters when they have one (family parameters),
            else zeros (errors).

    """

    kind: str
    names: tuple[str, ...]
    units: tuple[str, ...]
    placements: tuple[Placement, ...]
    E: np.ndarray
    G: np.ndarray
    nominal: np.ndarray

    @property
    def size(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def index(self, name: str) -> int:
        """Position of a parameter by name.

        Raises:
            InvalidInputError: No parameter of that name.

        """
        try:
            return self.names.index(name)
        except ValueError:
            close = [n for n in self.names if n.split(".")[0] == name.split(".")[0]][:6]
            hint = f" (e.g. {', '.join(close)})" if close else ""
            raise InvalidInputError(
                "parameter", f"'{name}' is not a parameter of this model{hint}"
            ) from None

    def twists(self, p: np.ndarray) -> np.ndarray:
        """Placement twists (n_pl, 6) [m, rad] of parameters ``p`` (n_par,)."""
        return (self.E @ np.asarray(p, dtype=float)).reshape(-1, 6)

    def gains(self, p: np.ndarray) -> np.ndarray:
        """Relative actuator gains (n_a,) of parameters ``p`` (n_par,)."""
        return self.G @ np.asarray(p, dtype=float)

    def tolerances(self, length: float, angle: float, gain: float = 0.0) -> np.ndarray:
        """A tolerance per parameter from its unit: ``length`` [m], ``angle`` [rad], ``gain`` [-].

        Args:
            length: Tolerance of lengths [m].
            angle: Tolerance of angles [rad].
            gain: Tolerance of relative gains [-].

        Returns:
            Tolerances (n_par,).

        """
        table = {"m": length, "rad": angle, "-": gain}
        return np.array([table.get(u, 0.0) for u in self.units])

    def subset(self, keep: np.ndarray) -> ParameterModel:
        """The model restricted to some parameters (indices or a boolean mask)."""
        idx = np.arange(self.size)[np.asarray(keep)]
        return dataclasses.replace(
            self,
            names=tuple(self.names[i] for i in idx),
            units=tuple(self.units[i] for i in idx),
            E=self.E[:, idx],
            G=self.G[:, idx],
            nominal=self.nominal[idx],
        )


def _motion_axis(robot: Robot, joint: int) -> np.ndarray:
    """Motion subspace (6,) of a 1-DOF joint in its frame (translation, rotation)."""
    jm = robot.model.joints[joint]
    jd = jm.createData()
    jm.calc(jd, robot.q_home)
    return np.asarray(jd.S, dtype=float).reshape(6)


def _basis(axis: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """An orthonormal basis of twists whose first vector is ``axis``, with component names.

    The other five are the coordinate directions, minus the one ``axis`` is closest to, made
    orthogonal to it: exactly the five other coordinate twists when ``axis`` is one.
    """
    axis = axis / np.linalg.norm(axis)
    drop = int(np.argmax(np.abs(axis)))
    vecs, names = [axis], ["offset"]
    for k in range(6):
        if k == drop:
            continue
        v = np.eye(6)[k] - axis[k] * axis
        for w in vecs[1:]:
            v -= (w @ v) * w
        n = float(np.linalg.norm(v))
        vecs.append(v / n)
        aligned = abs(n - 1.0) < 1e-12
        names.append(COMPONENTS[k] if aligned else f"d{len(vecs) - 1}")
    return np.column_stack(vecs), names


def placement_parameters(robot: Robot, gains: bool = False) -> ParameterModel:
    """Every placement's 6 twist components, plus actuator gains if asked.

    An actuated joint's component along its motion axis is named ``<actuator>.offset`` (its other
    five keep the names ``tx ... rz`` when the axis is a coordinate axis of the joint frame).

    Args:
        robot: The robot.
        gains: Add one relative gain per actuator (``<actuator>.gain``).

    Returns:
        The parameter model (6 per placement, plus ``n_a`` gains).

    """
    where = placements(robot)
    actuated = {int(j): a for j, a in zip(robot.actuated_joints, robot.actuators, strict=True)}
    cols: list[np.ndarray] = []
    names: list[str] = []
    units: list[str] = []
    n_pl = len(where)
    for k, pl in enumerate(where):
        if pl.kind == "joint" and pl.joint in actuated:
            S = _motion_axis(robot, pl.joint)
            basis, comp = _basis(S)
            prismatic = bool(np.linalg.norm(S[:3]) > 0.5)
            act = actuated[pl.joint].name
            for b, c in zip(basis.T, comp, strict=True):
                col = np.zeros(6 * n_pl)
                col[6 * k : 6 * k + 6] = b
                cols.append(col)
                if c == "offset":
                    names.append(f"{act}.offset")
                    units.append("m" if prismatic else "rad")
                else:
                    names.append(f"{pl.name}.{c}")
                    units.append("m" if np.linalg.norm(b[:3]) > 0.5 else "rad")
            continue
        for i in range(6):
            col = np.zeros(6 * n_pl)
            col[6 * k + i] = 1.0
            cols.append(col)
            names.append(f"{pl.name}.{COMPONENTS[i]}")
            units.append("m" if i < 3 else "rad")
    E = np.column_stack(cols)
    n_a = len(robot.actuators)
    G = np.zeros((n_a, E.shape[1]))
    if gains:
        E, G = _with_gains(robot, E, G, names, units)
    return ParameterModel(
        "placements", tuple(names), tuple(units), where, E, G, np.zeros(len(names))
    )


def _with_gains(
    robot: Robot, E: np.ndarray, G: np.ndarray, names: list[str], units: list[str]
) -> tuple[np.ndarray, np.ndarray]:
    n_a = len(robot.actuators)
    E = np.hstack([E, np.zeros((E.shape[0], n_a))])
    G = np.hstack([G, np.eye(n_a)])
    names += [f"{a.name}.gain" for a in robot.actuators]
    units += ["-"] * n_a
    return E, G


class _Columns:
    """Builder of a shortcut model: named columns of placement twists."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.where = placements(robot)
        self.index = {pl.name: k for k, pl in enumerate(self.where)}
        self.cols: list[np.ndarray] = []
        self.names: list[str] = []
        self.units: list[str] = []

    def add(self, name: str, unit: str, terms: list[tuple[str, np.ndarray]]) -> None:
        col = np.zeros(6 * len(self.where))
        for pl_name, xi in terms:
            k = self.index[pl_name]
            col[6 * k : 6 * k + 6] += xi
        self.cols.append(col)
        self.names.append(name)
        self.units.append(unit)

    def translation(self, pl_name: str, d: np.ndarray) -> np.ndarray:
        """Twist translating a placement along ``d`` given in its parent (joint/link) frame."""
        M = local_placement(self.robot, self.where[self.index[pl_name]])
        return np.concatenate([M.rotation.T @ np.asarray(d, dtype=float), np.zeros(3)])

    def offset(self, joint: str) -> np.ndarray:
        return _motion_axis(self.robot, self.robot.model.getJointId(joint))

    def model(self, kind: str, gains: bool) -> ParameterModel:
        E = np.column_stack(self.cols)
        G = np.zeros((len(self.robot.actuators), E.shape[1]))
        if gains:
            E, G = _with_gains(self.robot, E, G, self.names, self.units)
        return ParameterModel(
            kind,
            tuple(self.names),
            tuple(self.units),
            self.where,
            E,
            G,
            np.zeros(len(self.names)),
        )


def _delta_shortcuts(robot: Robot, c: _Columns) -> None:
    p = robot.params
    if p.parallelogram != "ball":
        raise InvalidInputError(
            "parameters",
            "the Delta shortcuts describe ball-jointed parallelograms; this Delta has "
            "parallelogram='hinge': use the placement parameters",
        )
    ez = np.array([0.0, 0.0, 1.0])
    for i, theta in enumerate(p.theta, start=1):
        u = np.array([np.cos(theta), np.sin(theta), 0.0])
        arm, motor = f"arm{i}", robot.actuators[i - 1].name
        M = local_placement(robot, c.where[c.index[arm]])
        spin = M.inverse().toActionMatrix() @ np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
        bars = [f"bar{i}{s}_upper" for s in "ab"]
        tips = [f"loop{i}{s}/1" for s in "ab"]
        seats = [f"loop{i}{s}/2" for s in "ab"]
        c.add(f"ra{i}", "m", [(arm, c.translation(arm, u))])
        c.add(f"rb{i}", "m", [(s, c.translation(s, u)) for s in seats])
        c.add(f"la{i}", "m", [(b, c.translation(b, np.array([1.0, 0.0, 0.0]))) for b in bars])
        c.add(f"lb{i}", "m", [(s, c.translation(s, ez)) for s in tips])
        c.add(f"theta{i}", "rad", [(arm, spin)])
        c.add(f"z{i}", "m", [(arm, c.translation(arm, ez))])
        c.add(f"{motor}.offset", "rad", [(arm, c.offset(arm))])


def _gough_stewart_shortcuts(robot: Robot, c: _Columns) -> None:
    joint = "U" if robot.params.base_joint == "universal" else "S"
    for i in range(1, 7):
        for k, axis in enumerate("xyz"):
            d = np.eye(3)[k]
            c.add(f"A{i}{axis}", "m", [(f"leg{i}_{joint}", c.translation(f"leg{i}_{joint}", d))])
        for k, axis in enumerate("xyz"):
            d = np.eye(3)[k]
            c.add(f"B{i}{axis}", "m", [(f"S{i}/2", c.translation(f"S{i}/2", d))])
        motor = robot.actuators[i - 1].name
        c.add(f"{motor}.offset", "m", [(f"leg{i}", c.offset(f"leg{i}"))])


SHORTCUTS = {"delta": _delta_shortcuts, "gough_stewart": _gough_stewart_shortcuts}
"""Families with calibration shortcuts (:func:`family_shortcuts`)."""


def family_shortcuts(robot: Robot, gains: bool = False) -> ParameterModel:
    """The dimensions people calibrate on a library family, as placement twists.

    - Delta (chain ``i``): ``ra<i>`` (arm axis from the base centre, along the arm's radial
      direction), ``rb<i>`` (the chain's two nacelle ball joints, radially), ``la<i>`` (arm
      length: both upper ball joints along the arm), ``lb<i>`` (both bars' length),
      ``theta<i>`` (arm plane angle about the base z axis), ``z<i>`` (arm axis height) [m, rad]
      and the arm's ``<motor>.offset`` [rad];
    - Gough-Stewart (leg ``i``): ``A<i>x A<i>y A<i>z`` (base joint centre, base axes),
      ``B<i>x B<i>y B<i>z`` (platform joint centre, platform axes) [m] and the leg's
      ``<motor>.offset`` [m].

    Args:
        robot: A robot of a family of :data:`SHORTCUTS`.
        gains: Add one relative gain per actuator.

    Returns:
        The parameter model.

    Raises:
        InvalidInputError: The robot is of no family with shortcuts.

    """
    fam = robot.family
    if fam not in SHORTCUTS:
        raise InvalidInputError(
            "parameters",
            f"{robot.name} is {'of family ' + fam if fam else 'of no library family'}; "
            f"family shortcuts exist for {', '.join(SHORTCUTS)}: use the placement parameters",
        )
    c = _Columns(robot)
    SHORTCUTS[fam](robot, c)
    return c.model("family shortcuts", gains)


# ---------------------------------------------------------------------- family parameters


def _units_of(params_cls: type) -> dict[str, str]:
    """``{field: unit}`` read from the ``Attributes:`` section of a Params docstring."""
    doc = params_cls.__doc__ or ""
    out = {}
    for line in doc.split("\n"):
        m = re.match(r"^\s+(\w+):[^\[]*\[([^\],]+)", line)
        if m:
            out[m.group(1)] = m.group(2).strip()
    return out


def _scalar_fields(p: Any) -> list[tuple[str, tuple[int, ...], float]]:
    """Numeric fields of a Params instance: ``(field, index, value)``, tuples element-wise."""
    out: list[tuple[str, tuple[int, ...], float]] = []
    for f in dataclasses.fields(p):
        v = getattr(p, f.name)
        if isinstance(v, bool) or v is None or f.name.endswith("_home"):  # (a pose, not a size)
            continue
        if isinstance(v, float):
            out.append((f.name, (), v))
        elif isinstance(v, tuple):
            arr = np.asarray(v, dtype=object)
            try:
                arr = np.asarray(v, dtype=float)
            except (TypeError, ValueError):
                continue
            for idx in np.ndindex(arr.shape):
                out.append((f.name, idx, float(arr[idx])))
    return out


def _with_value(p: Any, name: str, idx: tuple[int, ...], value: float) -> Any:
    v = getattr(p, name)
    if not idx:
        return dataclasses.replace(p, **{name: value})
    arr = np.array(v, dtype=float)
    arr[idx] = value
    nested = arr.tolist()
    as_tuple = (
        tuple(tuple(r) for r in nested) if arr.ndim == 2 else tuple(nested)  # type: ignore[arg-type]
    )
    return dataclasses.replace(p, **{name: as_tuple})


def _built_placements(robot: Robot, xml: str, where: tuple[Placement, ...]) -> list[pin.SE3]:
    """The placements of a description built from ``xml`` (same structure as ``robot``)."""
    desc = parse_description(xml, robot.name)
    model = build_tree(xml, desc.joints, robot.name)
    cms, owner = constraint_models(model, desc.closures, robot.name)
    first: dict[str, int] = {}
    for k, o in enumerate(owner):
        first.setdefault(o, k)
    out = []
    for pl in where:
        if pl.kind == "joint":
            out.append(pin.SE3(model.jointPlacements[model.getJointId(pl.name)]))
        elif pl.kind == "closure":
            cm = cms[first[pl.closure]]
            out.append(pin.SE3(cm.joint1_placement if pl.side == 1 else cm.joint2_placement))
        else:
            assert desc.platform is not None
            out.append(resolve_frame(model, desc.platform.frame, robot.name, "platform")[1])
    return out


def built_placements(robot: Robot, params: Any) -> list[pin.SE3]:
    """The placements the robot's family builder gives with other parameters.

    Args:
        robot: A library robot.
        params: Parameters of its family.

    Returns:
        One placement per :func:`placements` entry (same order).

    """
    fam = FAMILIES[_family_name(robot)]
    return _built_placements(robot, fam.build_urdf(params), placements(robot))


def _family_name(robot: Robot) -> str:
    name = robot.family
    if name is None:
        raise InvalidInputError(
            "parameters",
            f"{robot.name} is of no library family, so it has no family parameters; use the "
            "placement parameters",
        )
    return name


def family_parameters(robot: Robot, step: float = 1e-6, gains: bool = False) -> ParameterModel:
    """The family builder's numeric parameters, as placement twists (central differences).

    Each parameter (tuples element-wise: ``A[2][0]`` is named ``A3x`` for a 6 x 3 array, else
    ``name[i]``; the home-pose fields ``*_home`` are not dimensions) is moved by ``+-step``
    times its magnitude (at least ``step``), the builder run (description only: no assembly),
    and every placement's change measured as a twist
    ``log6(M0^-1 M)``. Parameters that move no placement (masses, limits, the home pose of a
    free-flyer) are left out.

    Args:
        robot: A library robot.
        step: Relative finite-difference step.
        gains: Add one relative gain per actuator.

    Returns:
        The parameter model (``nominal`` holds the parameter values).

    Raises:
        InvalidInputError: The robot is of no library family.

    """
    fam = FAMILIES[_family_name(robot)]
    p = _resolved(robot)
    where = placements(robot)
    base = _built_placements(robot, fam.build_urdf(p), where)
    units_of = _units_of(type(p))
    cols, names, units, nominal = [], [], [], []
    for field_name, idx, value in _scalar_fields(p):
        h = step * max(abs(value), 1.0)
        twists = []
        try:
            for sgn in (1.0, -1.0):
                q = _with_value(p, field_name, idx, value + sgn * h)
                built = _built_placements(robot, fam.build_urdf(q), where)
                twists.append(
                    np.concatenate(
                        [pin.log6(b0.actInv(b)).vector for b0, b in zip(base, built, strict=True)]
                    )
                )
        except Exception:  # noqa: BLE001 - a value the builder refuses: not a geometric parameter
            continue
        col = (twists[0] - twists[1]) / (2.0 * h)
        if np.max(np.abs(col)) < 1e-9:
            continue
        cols.append(col)
        names.append(_param_name(field_name, idx, p))
        units.append(units_of.get(field_name, "?"))
        nominal.append(value)
    E = np.column_stack(cols) if cols else np.zeros((6 * len(where), 0))
    G = np.zeros((len(robot.actuators), E.shape[1]))
    if gains:
        E, G = _with_gains(robot, E, G, names, units)
        nominal += [0.0] * len(robot.actuators)
    return ParameterModel(
        "family parameters", tuple(names), tuple(units), where, E, G, np.array(nominal)
    )


def _resolved(robot: Robot) -> Any:
    module = FAMILIES[_family_name(robot)]._module()
    return module.resolved(robot.params) if hasattr(module, "resolved") else robot.params


def family_values(robot: Robot, model: ParameterModel, values: np.ndarray) -> Any:
    """The family's parameters with those of a family-parameter model set to ``values``.

    Args:
        robot: The library robot of ``model``.
        model: A :func:`family_parameters` model.
        values: Values of its parameters (n_par,) (gains are ignored).

    Returns:
        The family's parameter dataclass.

    """
    p = _resolved(robot)
    where = {_param_name(f, idx, p): (f, idx) for f, idx, _ in _scalar_fields(p)}
    for name, value in zip(model.names, np.asarray(values, dtype=float), strict=True):
        if name in where:
            f, idx = where[name]
            p = _with_value(p, f, idx, float(value))
    return p


def _param_name(name: str, idx: tuple[int, ...], p: Any) -> str:
    if not idx:
        return name
    shape = np.asarray(getattr(p, name), dtype=float).shape
    if len(idx) == 2 and shape[1] == 3:
        return f"{name}{idx[0] + 1}{'xyz'[idx[1]]}"
    return f"{name}[{']['.join(str(i) for i in idx)}]"


MODELS = ("placements", "shortcuts", "family")
"""Names of the parameter models (:func:`parameter_model`)."""


def parameter_model(robot: Robot, kind: str = "auto", gains: bool = False) -> ParameterModel:
    """A parameter model by name.

    Args:
        robot: The robot.
        kind: ``placements`` (:func:`placement_parameters`), ``shortcuts``
            (:func:`family_shortcuts`), ``family`` (:func:`family_parameters`) or ``auto``
            (shortcuts for the families that have them, else placements).
        gains: Add one relative gain per actuator.

    Returns:
        The model.

    Raises:
        InvalidInputError: Unknown kind, or a kind the robot does not have.

    """
    if kind == "auto":
        kind = "shortcuts" if robot.family in SHORTCUTS else "placements"
    if kind == "placements":
        return placement_parameters(robot, gains)
    if kind == "shortcuts":
        return family_shortcuts(robot, gains)
    if kind == "family":
        return family_parameters(robot, gains=gains)
    raise InvalidInputError(
        "parameters", f"unknown model '{kind}'; use auto or {', '.join(MODELS)}"
    )
