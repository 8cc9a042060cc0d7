"""Deterministic writer of pkdyn descriptions (URDF + extension elements) for the builders."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.model.description import NAMESPACE

__all__ = [
    "Record",
    "Shape",
    "UrdfWriter",
    "number_text",
    "rod_inertia",
    "rpy_z_to",
    "segment_origin",
    "vector_text",
]

Vec = Sequence[float] | np.ndarray


def number_text(x: float) -> str:
    """Shortest text that reads back as the same double (no rounding of the geometry).

    ``0`` for both zeros, no trailing ``.0`` (``2``, ``0.1``, ``1e-07``).
    """
    v = float(x)
    if v == 0.0:
        return "0"
    s = repr(v)
    return s[:-2] if s.endswith(".0") else s


def vector_text(v: Vec) -> str:
    """The numbers of ``v`` as :func:`number_text` writes them, separated by spaces."""
    return " ".join(number_text(x) for x in v)


_f, _v = number_text, vector_text  # short names for the element templates below


@dataclass(frozen=True)
class Shape:
    """A primitive shape: ``kind`` is ``cylinder`` (along local z), ``box`` or ``sphere``.

    Attributes:
        kind: Shape kind.
        size: ``(radius, length)``, ``(sx, sy, sz)`` or ``(radius,)`` [m].
        xyz: Origin in the link frame [m].
        rpy: Orientation in the link frame [rad].
        rgba: Display colour.

    """

    kind: str
    size: tuple[float, ...]
    xyz: tuple[float, ...] = (0.0, 0.0, 0.0)
    rpy: tuple[float, ...] = (0.0, 0.0, 0.0)
    rgba: tuple[float, ...] = (0.7, 0.7, 0.7, 1.0)

    def geometry_xml(self) -> str:
        """The ``<geometry>`` element."""
        if self.kind == "cylinder":
            return f'<cylinder radius="{_f(self.size[0])}" length="{_f(self.size[1])}"/>'
        if self.kind == "box":
            return f'<box size="{_v(self.size)}"/>'
        return f'<sphere radius="{_f(self.size[0])}"/>'


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of two 3-vectors, the same arithmetic without its overhead (50 us)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


_X = np.array([1.0, 0.0, 0.0])
_EYE = np.eye(3)
_Y = np.array([0.0, 1.0, 0.0])


def _norm(v: np.ndarray) -> float:
    """``np.linalg.norm`` of a vector, the same arithmetic (``sqrt(v . v)``) without its checks."""
    return math.sqrt(float(v.dot(v)))


_MEMO_SIZE = 256
"""Most entries of each memo of the pure functions below (a builder repeats a few inputs: the
bars of a Delta are one rod; a design study writes thousands of builders' elements)."""

_RPY: dict[Any, tuple[float, float, float]] = {}
_RODS: dict[Any, tuple[Any, ...]] = {}


def _remember(memo: dict[Any, Any], key: Any, value: Any) -> Any:
    if len(memo) >= _MEMO_SIZE:
        memo.clear()
    memo[key] = value
    return value


def rpy_z_to(d: Vec) -> tuple[float, float, float]:
    """Roll-pitch-yaw [rad] of a rotation taking the z axis onto direction ``d``.

    Args:
        d: Direction (3,), not necessarily unit.

    Returns:
        ``(roll, pitch, yaw)``.

    """
    z = np.asarray(d, dtype=float)
    key = (z.shape, z.tobytes())  # (bytes: -0.0 and 0.0 are different inputs)
    found = _RPY.get(key)
    if found is None:
        found = _remember(_RPY, key, _rpy_z_to(z))
    return found


def _rpy_z_to(z: np.ndarray) -> tuple[float, float, float]:
    import pinocchio as pin

    z = z / _norm(z)
    helper = _X if abs(z[0]) < 0.9 else _Y
    x = _cross(helper, z)
    x /= _norm(x)
    y = _cross(z, x)
    rpy = pin.rpy.matrixToRpy(np.array([x, y, z]).T)
    return (float(rpy[0]), float(rpy[1]), float(rpy[2]))


def segment_origin(p0: Vec, p1: Vec) -> tuple[tuple[float, ...], tuple[float, float, float], float]:
    """Origin, orientation and length of a cylinder spanning the segment ``p0 -> p1``.

    Args:
        p0: Segment start (3,) [m].
        p1: Segment end (3,) [m].

    Returns:
        ``(xyz, rpy, length)`` for a :class:`Shape` of kind ``cylinder``.

    """
    a = np.asarray(p0, dtype=float)
    b = np.asarray(p1, dtype=float)
    mid = 0.5 * (a + b)
    return tuple(mid.tolist()), rpy_z_to(b - a), _norm(b - a)


def rod_inertia(
    mass: float, radius: float, p0: Vec, p1: Vec
) -> tuple[tuple[float, ...], np.ndarray]:
    """Centre of mass and inertia (about the COM, link axes) of a solid rod ``p0 -> p1``.

    Args:
        mass: Rod mass [kg].
        radius: Rod radius [m].
        p0: Rod start in the link frame [m].
        p1: Rod end in the link frame [m].

    Returns:
        ``(com, I)`` with ``I`` a 3x3 inertia tensor [kg m^2].

    """
    a = np.asarray(p0, dtype=float)
    b = np.asarray(p1, dtype=float)
    L = _norm(b - a)
    d = (b - a) / L
    i_ax = 0.5 * mass * radius**2
    i_tr = mass * (3 * radius**2 + L**2) / 12.0
    dd = d[:, None] * d[None, :]  # (np.outer's products)
    inertia = i_tr * (_EYE - dd) + i_ax * dd
    return tuple((0.5 * (a + b)).tolist()), inertia


@dataclass(frozen=True)
class Record:
    """One element a builder wrote, as its numbers (the text is rendered from it).

    Attributes:
        kind: The :class:`UrdfWriter` method that wrote it: ``link``, ``joint``,
            ``transmission`` (URDF elements), ``pkdyn_joint``, ``closure``, ``coupling``,
            ``linear_coupling``, ``platform`` (pkdyn elements).
        args: Its arguments, by name, as the builder gave them.

    """

    kind: str
    args: dict[str, Any]


_URDF_KINDS = ("link", "joint", "transmission")


class UrdfWriter:
    """Accumulates links, joints and pkdyn extension elements; writes a stable document.

    The elements are kept as :class:`Record` s (:attr:`records`, in the order written) and
    rendered by :meth:`to_string`: the family candidates of a design study
    (:mod:`pkdyn.model.candidate`) read the numbers from the records without any text.

    Args:
        name: Robot name.

    Attributes:
        name: Robot name.
        records: The elements written, in order.

    """

    def __init__(self, name: str) -> None:
        self.name = name
        self.records: list[Record] = []

    def _add(self, _kind: str, **args: Any) -> None:
        self.records.append(Record(_kind, args))

    def link(
        self,
        name: str,
        mass: float = 0.0,
        com: Vec = (0.0, 0.0, 0.0),
        inertia: np.ndarray | None = None,
        visuals: Sequence[Shape] = (),
        collisions: Sequence[Shape] = (),
    ) -> None:
        """Add a link.

        Args:
            name: Link name.
            mass: Mass [kg]; 0 writes no inertial element.
            com: Centre of mass in the link frame [m].
            inertia: 3x3 inertia about the COM in link axes [kg m^2] (default all zero: a
                point mass, which loads from a plain URDF only; a description with pkdyn
                elements refuses it, see :func:`pkdyn.model.validate.inertia_problem`).
            visuals: Visual shapes.
            collisions: Collision shapes.

        """
        self._add(
            "link",
            name=name,
            mass=mass,
            com=com,
            inertia=inertia,
            visuals=tuple(visuals),
            collisions=tuple(collisions),
        )

    @staticmethod
    def _render_link(
        name: str,
        mass: float,
        com: Vec,
        inertia: np.ndarray | None,
        visuals: Sequence[Shape],
        collisions: Sequence[Shape],
    ) -> str:
        out = [f'  <link name="{name}">']
        if mass > 0:
            I = np.zeros((3, 3)) if inertia is None else np.asarray(inertia)
            out.append(
                f'    <inertial><origin xyz="{_v(com)}" rpy="0 0 0"/><mass value="{_f(mass)}"/>'
                f'<inertia ixx="{_f(I[0, 0])}" ixy="{_f(I[0, 1])}" ixz="{_f(I[0, 2])}" '
                f'iyy="{_f(I[1, 1])}" iyz="{_f(I[1, 2])}" izz="{_f(I[2, 2])}"/></inertial>'
            )
        for s in visuals:
            out.append(
                f'    <visual><origin xyz="{_v(s.xyz)}" rpy="{_v(s.rpy)}"/>'
                f"<geometry>{s.geometry_xml()}</geometry>"
                f'<material name="{name}_mat"><color rgba="{_v(s.rgba)}"/></material></visual>'
            )
        for s in collisions:
            out.append(
                f'    <collision><origin xyz="{_v(s.xyz)}" rpy="{_v(s.rpy)}"/>'
                f"<geometry>{s.geometry_xml()}</geometry></collision>"
            )
        out.append("  </link>")
        return "\n".join(out)

    def rod(
        self,
        name: str,
        mass: float,
        radius: float,
        p0: Vec,
        p1: Vec,
        rgba: tuple[float, ...] = (0.7, 0.7, 0.7, 1.0),
        extra_visuals: Sequence[Shape] = (),
    ) -> None:
        """Add a link that is a solid rod ``p0 -> p1``: inertia, visual and collision cylinder.

        Args:
            name: Link name.
            mass: Rod mass [kg].
            radius: Rod radius [m].
            p0: Rod start in the link frame [m].
            p1: Rod end in the link frame [m].
            rgba: Display colour.
            extra_visuals: More visual shapes (e.g. an elbow).

        """
        a, b = np.asarray(p0, dtype=float), np.asarray(p1, dtype=float)
        key = (np.array([mass, radius], dtype=float).tobytes(), a.shape, a.tobytes(), b.tobytes())
        found = _RODS.get(key)
        if found is None:  # (the same numbers as computing them again: pure functions)
            found = _remember(_RODS, key, (*rod_inertia(mass, radius, a, b), *segment_origin(a, b)))
        com, inertia, xyz, rpy, length = found
        inertia = inertia.copy()
        self.link(
            name,
            mass,
            com,
            inertia,
            visuals=[Shape("cylinder", (radius, length), xyz, rpy, rgba), *extra_visuals],
            collisions=[Shape("cylinder", (radius, length), xyz, rpy)],
        )

    def joint(
        self,
        name: str,
        kind: str,
        parent: str,
        child: str,
        xyz: Vec = (0.0, 0.0, 0.0),
        rpy: Vec = (0.0, 0.0, 0.0),
        axis: Vec | None = None,
        limit: tuple[float, float, float, float] | None = None,
    ) -> None:
        """Add a URDF joint.

        Args:
            name: Joint name.
            kind: URDF type (revolute, continuous, prismatic, fixed, floating, planar).
            parent: Parent link.
            child: Child link.
            xyz: Joint origin in the parent link frame [m].
            rpy: Joint orientation in the parent link frame [rad].
            axis: Joint axis in the joint frame.
            limit: ``(lower, upper, effort, velocity)`` [rad or m, N m or N, rad/s or m/s].

        """
        self._add(
            "joint",
            name=name,
            kind=kind,
            parent=parent,
            child=child,
            xyz=xyz,
            rpy=rpy,
            axis=axis,
            limit=limit,
        )

    @staticmethod
    def _render_joint(
        name: str,
        kind: str,
        parent: str,
        child: str,
        xyz: Vec,
        rpy: Vec,
        axis: Vec | None,
        limit: tuple[float, float, float, float] | None,
    ) -> str:
        out = [
            f'  <joint name="{name}" type="{kind}">',
            f'    <parent link="{parent}"/><child link="{child}"/>',
            f'    <origin xyz="{_v(xyz)}" rpy="{_v(rpy)}"/>',
        ]
        if axis is not None:
            out.append(f'    <axis xyz="{_v(axis)}"/>')
        if limit is not None:
            lo, hi, eff, vel = limit
            out.append(
                f'    <limit lower="{_f(lo)}" upper="{_f(hi)}" effort="{_f(eff)}" '
                f'velocity="{_f(vel)}"/>'
            )
        out.append("  </joint>")
        return "\n".join(out)

    def spherical(
        self,
        name: str,
        parent: str,
        child: str,
        xyz: Vec,
        rpy: Vec = (0.0, 0.0, 0.0),
        cone: tuple[Vec, float] | None = None,
        pyramid: tuple[Vec, Vec, tuple[float, float]] | None = None,
    ) -> None:
        """Add a spherical joint: a ``continuous`` placeholder plus a ``pkdyn:joint``.

        Args:
            name: Joint name.
            parent: Parent link.
            child: Child link.
            xyz: Joint centre in the parent link frame [m].
            rpy: Joint frame orientation [rad].
            cone: Optional ``(axis, half_angle)`` limit.
            pyramid: Optional ``(axis, ref, (half_angle_1, half_angle_2))`` limit.

        """
        self.joint(name, "continuous", parent, child, xyz, rpy, axis=(0.0, 0.0, 1.0))
        self._add(
            "pkdyn_joint", name=name, kind="spherical", axis2=None, cone=cone, pyramid=pyramid
        )

    def universal(
        self,
        name: str,
        parent: str,
        child: str,
        xyz: Vec,
        rpy: Vec,
        axis1: Vec,
        axis2: Vec,
        cone: tuple[Vec, float] | None = None,
        pyramid: tuple[Vec, Vec, tuple[float, float]] | None = None,
    ) -> None:
        """Add a universal joint: a ``continuous`` placeholder about ``axis1`` + ``pkdyn:joint``.

        Args:
            name: Joint name.
            parent: Parent link.
            child: Child link.
            xyz: Joint centre in the parent link frame [m].
            rpy: Joint frame orientation [rad].
            axis1: First axis (joint frame).
            axis2: Second axis (frame after the first rotation).
            cone: Optional ``(axis, half_angle)`` limit.
            pyramid: Optional ``(axis, ref, (half_angle_1, half_angle_2))`` limit.

        """
        self.joint(name, "continuous", parent, child, xyz, rpy, axis=axis1)
        self._add(
            "pkdyn_joint", name=name, kind="universal", axis2=axis2, cone=cone, pyramid=pyramid
        )

    @staticmethod
    def _render_pkdyn_joint(
        name: str,
        kind: str,
        axis2: Vec | None,
        cone: tuple[Vec, float] | None,
        pyramid: tuple[Vec, Vec, tuple[float, float]] | None,
    ) -> str:
        extra = f' axis2="{_v(axis2)}"' if axis2 is not None else ""
        head = f'  <pkdyn:joint name="{name}" type="{kind}"{extra}'
        if cone is None and pyramid is None:
            return head + "/>"
        if cone is not None:
            body = f'<pkdyn:cone axis="{_v(cone[0])}" half_angle="{_f(cone[1])}"/>'
        else:
            assert pyramid is not None
            body = (
                f'<pkdyn:pyramid axis="{_v(pyramid[0])}" ref="{_v(pyramid[1])}" '
                f'half_angles="{_v(pyramid[2])}"/>'
            )
        return f"{head}>{body}</pkdyn:joint>"

    def closure(
        self,
        name: str,
        kind: str,
        frame1: tuple[str, Vec, Vec],
        frame2: tuple[str, Vec, Vec],
        axis: Vec | None = None,
    ) -> None:
        """Add a loop closure.

        Args:
            name: Closure name.
            kind: ``point``, ``hinge`` or ``weld``.
            frame1: ``(link, xyz, rpy)`` of the first frame.
            frame2: ``(link, xyz, rpy)`` of the second frame.
            axis: Hinge axis in each frame's coordinates.

        """
        self._add("closure", name=name, kind=kind, frame1=frame1, frame2=frame2, axis=axis)

    @staticmethod
    def _render_closure(
        name: str,
        kind: str,
        frame1: tuple[str, Vec, Vec],
        frame2: tuple[str, Vec, Vec],
        axis: Vec | None,
    ) -> str:
        extra = f' axis="{_v(axis)}"' if axis is not None else ""
        frames = "".join(
            f'<pkdyn:frame link="{link}" xyz="{_v(xyz)}" rpy="{_v(rpy)}"/>'
            for link, xyz, rpy in (frame1, frame2)
        )
        return f'  <pkdyn:closure name="{name}" type="{kind}"{extra}>{frames}</pkdyn:closure>'

    def coupling(
        self,
        name: str,
        joint: str,
        source: str | None,
        coefficients: Sequence[float],
        joint_ref: float = 0.0,
        source_ref: float = 0.0,
    ) -> None:
        """Add a joint coupling (``pkdyn:coupling``, see urdf/README.md).

        Written with ``multiplier`` / ``offset`` when the polynomial is affine, else with
        ``polycoef``; the references only when non-zero.

        Args:
            name: Coupling name.
            joint: Driven joint.
            source: Source joint, or ``None`` (the joint is locked at ``joint_ref +
                coefficients[0]``).
            coefficients: Polynomial coefficients, constant term first (1 to 5).
            joint_ref: Reference position of ``joint`` [rad or m].
            source_ref: Reference position of ``source`` [rad or m].

        """
        self._add(
            "coupling",
            name=name,
            joint=joint,
            source=source,
            coefficients=tuple(coefficients),
            joint_ref=joint_ref,
            source_ref=source_ref,
        )

    @staticmethod
    def _render_coupling(
        name: str,
        joint: str,
        source: str | None,
        coefficients: Sequence[float],
        joint_ref: float,
        source_ref: float,
    ) -> str:
        attrs = f'name="{name}" joint="{joint}"'
        c = [float(x) for x in coefficients]
        if source is not None:
            attrs += f' source="{source}"'
            if len(c) <= 2 or not any(c[2:]):
                c = (c + [0.0])[:2]
                attrs += f' multiplier="{_f(c[1])}" offset="{_f(c[0])}"'
            else:
                attrs += f' polycoef="{_v(c)}"'
        else:
            attrs += f' offset="{_f(c[0])}"'
        if joint_ref:
            attrs += f' joint_ref="{_f(joint_ref)}"'
        if source_ref and source is not None:
            attrs += f' source_ref="{_f(source_ref)}"'
        return f"  <pkdyn:coupling {attrs}/>"

    def linear_coupling(
        self, name: str, terms: Sequence[tuple[str, float]], offset: float = 0.0
    ) -> None:
        """Add a linear coupling ``sum_i coefficient_i joint_i = offset`` (see urdf/README.md).

        Args:
            name: Coupling name.
            terms: ``(joint, coefficient)`` pairs.
            offset: Right-hand side [rad or m].

        """
        self._add("linear_coupling", name=name, terms=tuple(terms), offset=offset)

    @staticmethod
    def _render_linear_coupling(
        name: str, terms: Sequence[tuple[str, float]], offset: float
    ) -> str:
        body = "".join(f'<pkdyn:term joint="{j}" coefficient="{_f(float(a))}"/>' for j, a in terms)
        return (
            f'  <pkdyn:coupling name="{name}" offset="{_f(float(offset))}">{body}</pkdyn:coupling>'
        )

    def transmission(
        self,
        joint: str,
        actuator: str,
        reduction: float,
        rotor_inertia: float = 0.0,
        efficiency: float = 1.0,
    ) -> None:
        """Add a SimpleTransmission driving ``joint``.

        Args:
            joint: Actuated joint name.
            actuator: Actuator (motor) name.
            reduction: Mechanical reduction (motor speed / joint speed).
            rotor_inertia: Motor-side rotor inertia [kg m^2] (``pkdyn:rotor_inertia``, written
                when non-zero).
            efficiency: Gearbox efficiency (``pkdyn:efficiency``, written when below 1).

        """
        self._add(
            "transmission",
            joint=joint,
            actuator=actuator,
            reduction=reduction,
            rotor_inertia=rotor_inertia,
            efficiency=efficiency,
        )

    @staticmethod
    def _render_transmission(
        joint: str, actuator: str, reduction: float, rotor_inertia: float, efficiency: float
    ) -> str:
        drive = ""
        if rotor_inertia:
            drive += f'<pkdyn:rotor_inertia value="{_f(rotor_inertia)}"/>'
        if efficiency != 1.0:
            drive += f'<pkdyn:efficiency value="{_f(efficiency)}"/>'
        return (
            f'  <transmission name="{joint}_transmission">\n'
            "    <type>transmission_interface/SimpleTransmission</type>\n"
            f'    <joint name="{joint}"><hardwareInterface>'
            "hardware_interface/EffortJointInterface</hardwareInterface></joint>\n"
            f'    <actuator name="{actuator}"><mechanicalReduction>{_f(reduction)}'
            f"</mechanicalReduction>{drive}</actuator>\n"
            "  </transmission>"
        )

    def platform(
        self, link: str, task: Sequence[str], xyz: Vec = (0, 0, 0), rpy: Vec = (0, 0, 0)
    ) -> None:
        """Declare the platform / end-effector frame.

        Args:
            link: Link carrying the frame.
            task: Controlled pose components among x y z rx ry rz.
            xyz: Frame origin in the link frame [m].
            rpy: Frame orientation in the link frame [rad].

        """
        self._add("platform", link=link, task=tuple(task), xyz=xyz, rpy=rpy)

    @staticmethod
    def _render_platform(link: str, task: Sequence[str], xyz: Vec, rpy: Vec) -> str:
        return (
            f'  <pkdyn:platform link="{link}" xyz="{_v(xyz)}" rpy="{_v(rpy)}" '
            f'task="{" ".join(task)}"/>'
        )

    def to_string(self, comment: str = "") -> str:
        """The whole document.

        Args:
            comment: Text of a leading XML comment (e.g. the generating parameters).

        Returns:
            The URDF text, ending with a newline.

        """
        head = ['<?xml version="1.0"?>']
        if comment:
            head.append(f"<!-- {comment} -->")
        head.append(f'<robot name="{self.name}" xmlns:pkdyn="{NAMESPACE}">')
        parts = [self._render(r) for r in self.records if r.kind in _URDF_KINDS]
        ext = [self._render(r) for r in self.records if r.kind not in _URDF_KINDS]
        return "\n".join(head + parts + ext + ["</robot>", ""])

    def _render(self, record: Record) -> str:
        render: Any = getattr(self, f"_render_{record.kind}")
        return str(render(**record.args))
