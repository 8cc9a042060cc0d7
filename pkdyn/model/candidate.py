"""Family candidates: a family's robot built once, each new candidate written into it.

A design study evaluates thousands of robots of one family that differ only in numbers: joint
placements, inertias, limits, collision shapes, closure frames. :func:`pkdyn.load` builds each
from its URDF text: the builder writes the text, which is parsed twice (the extension elements,
then Pinocchio's URDF parser), validated, and turned into a Pinocchio model, its geometry and
its constraint models before the home is assembled. :class:`CandidateBuilder` does that once for
the first candidate of each *skeleton* (the builder's elements with their kinds, names,
parents and shape kinds: what stays when only the numbers change), and writes the numbers of
each next candidate's elements (:class:`~pkdyn.model.formats.urdf_writer.Record`, no text) into
that Pinocchio model, its collision geometry, constraint models and description, with the
arithmetic of the URDF path: the candidate is the robot ``pkdyn.load(family, **params)`` builds,
bit for bit (``tests/test_candidate.py`` checks every family over random parameters; each
skeleton is checked against its own URDF build when it is first met, and a skeleton whose
in-place copy would differ is built by the URDF path every time).
The constraint layer is the template's, its closures moved in place
(:meth:`solvers.constraints.ConstraintSet.move_closures`) where its rows do not depend on the
placements (points and welds on ball or free joints: the Delta, the Gough-Stewart), else made
anew for each candidate.

Validation: a description pkdyn generated itself is not validated again for each candidate (the
first build of its skeleton was, and the builder's ``Params`` validate the parameters); a user's
file always is (:func:`pkdyn.load`). The home is assembled for each candidate as
:func:`pkdyn.load` assembles it (:func:`pkdyn.model.home.find_home`, the same start and
tolerance); a candidate whose closures :func:`~pkdyn.model.home.find_home` would move (a
description inconsistent within the assembly tolerance) is built by the URDF path.

The robot returned shares its model, data and geometry with the builder: it stays valid until
the builder's next candidate (one candidate at a time, as a worker evaluates its designs).
"""

from __future__ import annotations

import dataclasses
import math
from collections import OrderedDict
from collections.abc import Hashable, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.model.build import HINGE_ARM, build_geometry, constraint_set
from pkdyn.model.description import (
    ActuatorSpec,
    ClosureSpec,
    ConeLimit,
    Description,
    FrameRef,
    JointSpec,
    PlatformSpec,
    PyramidLimit,
)
from pkdyn.model.families import Family, family
from pkdyn.model.formats.urdf_writer import Record, UrdfWriter
from pkdyn.model.home import ASSEMBLY_TOL
from pkdyn.model.passive import passive_forces
from pkdyn.model.robot import Robot
from pkdyn.model.validate import unit_vector
from solvers.closure import FREE_SCALE, Closure, size_bound
from solvers.constraints import ConstraintSet

__all__ = ["CandidateBuilder", "difference", "urdf_pose"]

_IDENTITY = pin.SE3.Identity()
_HERE = _IDENTITY * _IDENTITY
"""A joint's body in its joint frame, as the parser places it (the identity; never changed)."""
_ZERO = pin.Inertia.Zero()
_MAX_TEMPLATES = 4
"""Skeletons a builder keeps (a study whose parameters change the structure cycles a few)."""

_MOVING = ("revolute", "continuous", "prismatic", "floating", "planar")


def _num(x: Any) -> float:
    """A number as the URDF text carries it (the writer writes ``-0.0`` as ``0``)."""
    return float(x) + 0.0  # (-0.0 + 0.0 is +0.0; any other number is unchanged)


def _vec(v: Any) -> np.ndarray:
    return np.array(v, dtype=float).reshape(-1) + 0.0


_ROTATIONS: dict[tuple[str, float, float, float], np.ndarray] = {}
"""Rotation matrices of the roll-pitch-yaw triples met (builders reuse a few), by reader."""


def _rotation(reader: str, rpy: Any) -> np.ndarray:
    key = (reader, _num(rpy[0]), _num(rpy[1]), _num(rpy[2]))
    R = _ROTATIONS.get(key)
    if R is None:
        if len(_ROTATIONS) > 4096:
            _ROTATIONS.clear()
        R = _urdf_rotation(*key[1:]) if reader == "urdf" else pin.rpy.rpyToMatrix(*key[1:])
        R.flags.writeable = False
        _ROTATIONS[key] = R
    return R


def _urdf_rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """The rotation of urdfdom's ``Rotation::setFromRPY`` quaternion, by Eigen."""
    phi, the, psi = roll / 2.0, pitch / 2.0, yaw / 2.0
    sp, cp = math.sin(phi), math.cos(phi)
    st, ct = math.sin(the), math.cos(the)
    ss, cs = math.sin(psi), math.cos(psi)
    x = sp * ct * cs - cp * st * ss
    y = cp * st * cs + sp * ct * ss
    z = cp * ct * ss - sp * st * cs
    w = cp * ct * cs + sp * st * ss
    s = math.sqrt(x * x + y * y + z * z + w * w)
    if s == 0.0:
        x, y, z, w = 0.0, 0.0, 0.0, 1.0
    else:
        x, y, z, w = x / s, y / s, z / s, w / s
    return np.asarray(pin.Quaternion(w, x, y, z).matrix())


def urdf_pose(xyz: Any, rpy: Any) -> pin.SE3:
    """The placement Pinocchio's URDF parser makes of an ``<origin xyz rpy>``, bit for bit.

    urdfdom turns roll, pitch and yaw into a normalised quaternion (``Rotation::setFromRPY``);
    Pinocchio makes the rotation matrix of that quaternion (Eigen).

    Args:
        xyz: Translation (3,) [m].
        rpy: Roll, pitch, yaw (3,) [rad].

    Returns:
        The placement.

    """
    return pin.SE3(_rotation("urdf", rpy), _vec(xyz))


_AXES: dict[tuple[float, ...], str] = {}


def _axis_class(axis: Any) -> str:
    """Which joint model Pinocchio's URDF parser picks for an axis: x, y, z or unaligned.

    Eigen's ``isApprox`` with its default precision (1e-12), as the parser tests it.
    """
    key = tuple(float(x) for x in axis)
    found = _AXES.get(key)
    if found is not None:
        return found
    a = np.array(key)
    na = float(a @ a)
    found = "u"
    for name, e in (("x", (1.0, 0.0, 0.0)), ("y", (0.0, 1.0, 0.0)), ("z", (0.0, 0.0, 1.0))):
        d = a - np.asarray(e)
        if float(d @ d) <= 1e-24 * min(na, 1.0):
            found = name
            break
    if len(_AXES) > 4096:
        _AXES.clear()
    _AXES[key] = found
    return found


def _frame_pose(xyz: Any, rpy: Any) -> pin.SE3:
    """A pkdyn frame's placement as the description reader makes it."""
    return pin.SE3(_rotation("pkdyn", rpy), _vec(xyz))


_UNITS: dict[tuple[float, ...], np.ndarray] = {}


def _unit(v: Any) -> np.ndarray:
    """A unit axis as the description reader makes it (cached: builders reuse a few)."""
    key = tuple(_vec(v).tolist())
    u = _UNITS.get(key)
    if u is None:
        if len(_UNITS) > 4096:
            _UNITS.clear()
        u = _UNITS[key] = np.asarray(unit_vector(np.array(key)))
    return u.copy()


def _total(v: Any) -> float:
    """The sum of the numbers of a vector (NaN or infinite when one is)."""
    return float(sum(v.ravel().tolist())) if isinstance(v, np.ndarray) else float(sum(v))


def _skeleton(records: Sequence[Record]) -> tuple[Hashable, ...] | None:
    """What a candidate shares with every robot it can be written into; ``None``: unsupported.

    Names, kinds, parents, shape kinds and which optional numbers are written (an inertial, a
    limit, a rotor inertia...), and the joint model an axis makes Pinocchio pick; not the
    numbers. ``None`` also when a number is not finite (the URDF path names it).
    """
    out: list[Hashable] = []
    total = 0.0  # NaN or infinite as soon as one number is (the magnitudes cannot overflow)
    for r in records:
        a = r.args
        kind = r.kind
        if kind == "link":
            shapes = (*a["visuals"], *a["collisions"])
            total += a["mass"] + _total(a["com"])
            if a["inertia"] is not None:
                total += _total(a["inertia"])
            for sh in shapes:
                total += _total(sh.size) + _total(sh.xyz) + _total(sh.rpy)
            out.append(
                (
                    "link",
                    a["name"],
                    float(a["mass"]) > 0.0,
                    a["inertia"] is None,
                    tuple(sh.kind for sh in a["visuals"]),
                    tuple(sh.kind for sh in a["collisions"]),
                )
            )
        elif kind == "joint":
            axis = a["axis"]
            cls = None if axis is None else _axis_class(axis)
            if a["kind"] in ("revolute", "prismatic", "continuous") and cls == "u":
                return None  # an unaligned axis: the joint model carries numbers (URDF path)
            total += _total(a["xyz"]) + _total(a["rpy"])
            if a["limit"] is not None:
                total += _total(a["limit"])
            out.append(
                (
                    "joint",
                    a["name"],
                    a["kind"],
                    a["parent"],
                    a["child"],
                    cls,
                    a["limit"] is None,
                )
            )
        elif kind == "transmission":
            total += a["reduction"] + a["rotor_inertia"] + a["efficiency"]
            out.append(
                (
                    "transmission",
                    a["joint"],
                    a["actuator"],
                    bool(a["rotor_inertia"]),
                    a["efficiency"] != 1.0,
                )
            )
        elif kind == "pkdyn_joint":
            # a universal joint's second axis is a number of its joint model (its first, of the
            # placeholder's: aligned, above): part of the skeleton
            axis2 = None if a["axis2"] is None else tuple(_vec(a["axis2"]).tolist())
            if a["cone"] is not None:
                total += _total(a["cone"][0]) + a["cone"][1]
            if a["pyramid"] is not None:
                total += sum(_total(v) for v in a["pyramid"])
            out.append(
                (
                    "pkdyn_joint",
                    a["name"],
                    a["kind"],
                    axis2,
                    a["cone"] is None,
                    a["pyramid"] is None,
                )
            )
        elif kind == "closure":
            f1, f2 = a["frame1"], a["frame2"]
            total += _total(f1[1]) + _total(f1[2]) + _total(f2[1]) + _total(f2[2])
            if a["axis"] is not None:
                total += _total(a["axis"])
            out.append(("closure", a["name"], a["kind"], f1[0], f2[0], a["axis"] is None))
        elif kind == "platform":
            total += _total(a["xyz"]) + _total(a["rpy"])
            out.append(("platform", a["link"], tuple(a["task"])))
        else:
            return None  # couplings: the URDF path
    if not math.isfinite(total):
        return None
    return tuple(out)


@dataclasses.dataclass(eq=False)
class _Template:
    """A skeleton's robot, built by the URDF path, and where each element's numbers go."""

    robot: Robot
    rebuilds: int  # times the tree was rebuilt after parsing (pkdyn joint upgrades)
    links: dict[str, int]  # link -> parent joint record index (-1: the root)
    joints: dict[int, int]  # joint record index -> Pinocchio joint id (moving joints)
    fixed: dict[int, tuple[int, int]]  # fixed joint record -> (joint frame, body frame)
    geometry: dict[str, list[int]]  # link -> geometry object ids of its collision shapes
    body_frames: dict[str, int]  # link -> body frame id
    actuated: dict[str, int]  # actuated joint name -> velocity index
    signs: dict[int, tuple[float, float]]  # joint id -> signs of its lower effort, speed limits


class CandidateBuilder:
    """Robots of one library family, built once per skeleton and written in place.

    Args:
        name: Family name.
        collision: Build the collision geometry (metrics that look at the shapes); the visual
            geometry is never built.
        tol: Assembly tolerance [m or rad] (:func:`pkdyn.load`'s ``tol``).

    Attributes:
        family: The family.
        built: Candidates built by the URDF path (the first of each skeleton, and those that
            cannot be written in place).
        written: Candidates written in place.

    """

    def __init__(self, name: str, collision: bool = False, tol: float = ASSEMBLY_TOL) -> None:
        self.family: Family = family(name)
        self.collision = bool(collision)
        self.tol = tol
        self._templates: OrderedDict[Hashable, _Template | None] = OrderedDict()
        self.built = 0
        self.written = 0

    # ------------------------------------------------------------------ public

    def robot(self, params: Any) -> Robot:
        """The family's robot with these parameters, as ``pkdyn.load`` builds it.

        Args:
            params: The family's parameter dataclass (validated by its constructor).

        Returns:
            The robot, assembled at its home; it shares its model, data and geometry with the
            builder and is valid until the next call.

        Raises:
            PkdynError: What :func:`pkdyn.load` raises for these parameters (an unassemblable
                home, ...).

        """
        layout = self.family.layout(params)
        key = None if layout is None else _skeleton(layout.records)
        if layout is None or key is None:
            return self._urdf_robot(params, None)
        if key not in self._templates:
            template = self._make_template(params, layout)
            self._templates[key] = template
            while len(self._templates) > _MAX_TEMPLATES:
                self._templates.popitem(last=False)
            if template is not None:
                self.built += 1
                return template.robot
        self._templates.move_to_end(key)
        template = self._templates[key]
        if template is None:
            return self._urdf_robot(params, layout)
        out = self._write(template, params, layout.records)
        if out is None:
            return self._urdf_robot(params, layout)
        self.written += 1
        return out

    # ------------------------------------------------------------------ the URDF path

    def _urdf_robot(self, params: Any, layout: UrdfWriter | None) -> Robot:
        from pkdyn.model.loader import load_string

        fam = self.family
        xml = fam.build_urdf(params) if layout is None else layout.to_string()
        robot = load_string(
            xml, fam.name, geometry=False, params=params, home=fam.home(params), tol=self.tol
        )
        if self.collision:
            kind = pin.GeometryType.COLLISION
            robot.collision_model = build_geometry(robot.model, xml, kind, [], fam.name)
        self.built += 1
        return robot

    def _make_template(self, params: Any, layout: UrdfWriter) -> _Template | None:
        """The skeleton's robot and its maps; ``None`` when an in-place copy would differ."""
        robot = self._urdf_robot(params, layout)
        self.built -= 1  # (counted by the caller)
        records = layout.records
        model = robot.model
        links: dict[str, int] = {}
        joints: dict[int, int] = {}
        fixed: dict[int, tuple[int, int]] = {}
        continuous_actuated = False
        actuated_names = {a.joint for a in robot.actuators}
        for k, r in enumerate(records):
            a = r.args
            if r.kind != "joint":
                continue
            links[a["child"]] = k
            if a["kind"] == "fixed":
                fixed[k] = (
                    model.getFrameId(a["name"], pin.FrameType.FIXED_JOINT),
                    model.getFrameId(a["child"], pin.FrameType.BODY),
                )
            elif a["kind"] in _MOVING:
                joints[k] = model.getJointId(a["name"])
                if a["kind"] == "continuous" and a["name"] in actuated_names:
                    continuous_actuated = True
        body_frames: dict[str, int] = {}
        geometry: dict[str, list[int]] = {}
        for r in records:
            if r.kind != "link":
                continue
            name = r.args["name"]
            links.setdefault(name, -1)
            body_frames[name] = model.getFrameId(name, pin.FrameType.BODY)
            if self.collision:
                cm = robot.collision_model
                geometry[name] = [
                    cm.getGeometryId(f"{name}_{i}") for i in range(len(r.args["collisions"]))
                ]
        framed = [f.link for c in robot.closures for f in (c.frame1, c.frame2)]
        if robot.description.platform is not None:
            framed.append(robot.description.platform.frame.link)
        if any(link not in body_frames for link in framed):
            return None  # a frame on something else than a link: the URDF path
        rebuilds = int(bool(robot.description.joints)) + int(continuous_actuated)
        actuated = {
            a.joint: int(iv) for a, iv in zip(robot.actuators, robot.actuated_v, strict=True)
        }
        signs = {}  # (the parser writes -limit, a rebuilt tree +limit as the lower speed limit)
        for jid in joints.values():
            iv = model.joints[jid].idx_v
            signs[jid] = (
                -1.0 if model.lowerEffortLimit[iv] < 0.0 else 1.0,
                -1.0 if model.lowerVelocityLimit[iv] < 0.0 else 1.0,
            )
        template = _Template(
            robot, rebuilds, links, joints, fixed, geometry, body_frames, actuated, signs
        )
        # the skeleton's own numbers written into a second build must give the first, exactly
        probe = self._urdf_robot(params, layout)
        self.built -= 1
        probe_template = dataclasses.replace(template, robot=probe)
        _scramble(probe)
        copy = self._write(probe_template, params, records)
        if copy is None or difference(copy, robot):
            return None
        return template

    # ------------------------------------------------------------------ in place

    def unassembled(self, params: Any) -> Robot:
        """The family's model, geometry, constraint models and description with these parameters.

        What :meth:`robot` writes, without the constraint layer and the home assembly: for a
        caller that reads placements, inertias or shapes only (the family parameters of
        :mod:`pkdyn.precision`). ``q_home`` and ``constraints`` are the previous candidate's
        (or, where the structure takes the URDF path, those of an assembled robot). Valid until
        the next call.

        Args:
            params: The family's parameter dataclass.

        Returns:
            The robot (shared with the builder).

        """
        layout = self.family.layout(params)
        key = None if layout is None else _skeleton(layout.records)
        if layout is None or key is None:
            return self._urdf_robot(params, None)
        if key not in self._templates:
            return self.robot(params)
        template = self._templates[key]
        if template is None:
            return self._urdf_robot(params, layout)
        out = self._write(template, params, layout.records, assemble=False)
        assert out is not None
        return out

    def _write(
        self, t: _Template, params: Any, records: Sequence[Record], assemble: bool = True
    ) -> Robot | None:
        """Write a candidate's numbers into the template; ``None``: take the URDF path."""
        robot = t.robot
        model = robot.model
        by_link: dict[str, dict[str, Any]] = {}
        joint_rec: dict[str, dict[str, Any]] = {}
        for r in records:
            if r.kind == "link":
                by_link[r.args["name"]] = r.args
            elif r.kind == "joint":
                joint_rec[r.args["name"]] = r.args
        body: dict[str, pin.SE3] = {}

        def body_of(link: str) -> pin.SE3:
            M = body.get(link)
            if M is None:
                k = t.links[link]
                a = records[k].args if k >= 0 else None
                if a is None or a["kind"] != "fixed":
                    M = _IDENTITY
                else:
                    M = body_of(a["parent"]) * urdf_pose(a["xyz"], a["rpy"])
                body[link] = M
            return M

        model.armature[:] = 0.0
        inertia: dict[int, list[tuple[pin.SE3, pin.Inertia]]] = {}  # joint id -> bodies
        for k, r in enumerate(records):
            a = r.args
            if r.kind == "joint":
                child = by_link[a["child"]]
                massive = float(child["mass"]) > 0.0
                if k in t.fixed:
                    fid, bid = t.fixed[k]
                    M = body_of(a["child"])
                    model.frames[fid].placement = M
                    model.frames[bid].placement = M
                    # the parser adds the fixed joint's frame (with the link's inertia) and
                    # the link's body frame (none) to the joint that carries them
                    bodies = inertia.setdefault(self._carrier(t, records, k), [])
                    if massive:
                        Y = _link_inertia(child)
                        model.frames[fid].inertia = Y
                        bodies.append((M, Y))
                    bodies.append((M, _ZERO))
                    continue
                jid = t.joints.get(k)
                if jid is None:
                    continue
                M = body_of(a["parent"]) * urdf_pose(a["xyz"], a["rpy"])
                for _ in range(t.rebuilds):
                    M = _IDENTITY * M
                model.jointPlacements[jid] = M
                lim = a["limit"]
                if lim is not None and model.joints[jid].nq == 1:
                    lo, hi, eff, vel = (_num(x) for x in lim)
                    iq, iv = model.joints[jid].idx_q, model.joints[jid].idx_v
                    model.lowerPositionLimit[iq] = lo
                    model.upperPositionLimit[iq] = hi
                    model.effortLimit[iv] = eff
                    model.velocityLimit[iv] = vel
                    se, sv = t.signs[jid]
                    model.lowerEffortLimit[iv] = eff if se > 0.0 else -eff
                    model.upperEffortLimit[iv] = eff
                    model.lowerVelocityLimit[iv] = vel if sv > 0.0 else -vel
                    model.upperVelocityLimit[iv] = vel
                # its body (when it has mass), then its body frame (no inertia), first
                here = _HERE
                own = [(here, _link_inertia(child))] if massive else []
                inertia.setdefault(jid, [])[:0] = [*own, (here, _ZERO)]
            elif r.kind == "link" and t.geometry:
                M0 = body_of(a["name"])
                cm = robot.collision_model
                for gid, s in zip(t.geometry[a["name"]], a["collisions"], strict=True):
                    go = cm.geometryObjects[gid]
                    go.placement = M0 * urdf_pose(s.xyz, s.rpy)
                    go.geometry = _shape(s.kind, s.size)
        # Pinocchio sums inertias with +=, whose centre of mass is m c (1/m) (rounded): each
        # frame the parser adds to a joint rounds it again, so the sums are replayed in order
        for jid, bodies in inertia.items():
            acc = pin.Inertia.Zero()
            for M, Y in bodies:
                acc += M.act(Y)
            for _ in range(t.rebuilds):
                again = pin.Inertia.Zero()
                again += _IDENTITY.act(acc)
                acc = again
            model.inertias[jid] = acc
        desc = self._description(t, records, joint_rec)
        for act in desc.actuators:
            if act.rotor_inertia:
                iv = t.actuated[act.joint]
                existing = float(model.armature[iv])
                model.armature[iv] = existing + act.reduction**2 * act.rotor_inertia
        if robot.platform_frame is not None and desc.platform is not None:
            ref = desc.platform.frame
            f = model.frames[t.body_frames[ref.link]]
            model.frames[robot.platform_frame].placement = f.placement * ref.placement
        source = robot.source
        vec = robot.constraint_models  # written in place, as constraint_models makes them
        k = 0
        placed: list[tuple[int, pin.SE3, int, pin.SE3]] = []  # (as build.closures resolves them)
        for c in desc.closures:
            f1 = model.frames[t.body_frames[c.frame1.link]]
            f2 = model.frames[t.body_frames[c.frame2.link]]
            M1, M2 = f1.placement * c.frame1.placement, f2.placement * c.frame2.placement
            placed.append((int(f1.parentJoint), M1, int(f2.parentJoint), M2))
            vec[k].joint1_placement, vec[k].joint2_placement = M1, M2
            k += 1
            if c.kind == "hinge":
                off = pin.SE3(np.eye(3), HINGE_ARM * c.axis)
                vec[k].joint1_placement, vec[k].joint2_placement = M1 * off, M2 * off
                k += 1
        if not assemble:
            return dataclasses.replace(
                robot, description=desc, actuators=desc.actuators, params=params
            )
        passive = robot.passive
        if passive is not None:
            passive = passive_forces(
                model, desc.passive, desc.springs, source, desc.joint_names, desc.joints
            )
        out = dataclasses.replace(
            robot,
            description=desc,
            constraint_models=vec,
            constraints=self._layer(t, desc, placed),
            actuators=desc.actuators,
            q_home=pin.neutral(model),
            params=params,
            passive=passive,
        )
        from pkdyn.model.loader import _guess, home_result

        # as pkdyn.load assembles a family's home (load_string's: a home given, as the user's)
        res = home_result(out, _guess(model), self.family.home(params), self.tol, True)
        if res.moved:
            return None
        out.q_home = res.q
        return out

    @staticmethod
    def _layer(
        t: _Template, desc: Description, placed: Sequence[tuple[int, pin.SE3, int, pin.SE3]]
    ) -> ConstraintSet:
        """The candidate's constraint layer: the template's, its closures moved in place.

        Where the rows do not depend on the placements (points and welds on ball or free
        joints, no coupling: :attr:`solvers.constraints.ConstraintSet.movable`) and the
        candidate's joints stay within the size that keeps it so, the template's set gets the
        candidate's placements (:meth:`~solvers.constraints.ConstraintSet.move_closures`): the
        rows a new set would have, bit for bit, without making it (0.45 ms for a Delta).
        Otherwise a new set, as :func:`pkdyn.model.build.constraint_set` makes it. The set is
        shared with the previous candidates, like the model.
        """
        model = t.robot.model
        layer = t.robot.constraints
        if not desc.couplings and layer.nk == 0 and layer.movable:
            if size_bound(model) < 0.5 * FREE_SCALE:  # (the bound movable holds the template to)
                closures = [
                    Closure(
                        c.name,
                        c.kind,
                        j1,
                        M1,
                        j2,
                        M2,
                        tuple(float(x) for x in np.asarray(c.axis, dtype=float).reshape(3)),  # type: ignore[arg-type]
                    )
                    for c, (j1, M1, j2, M2) in zip(desc.closures, placed, strict=True)
                ]
                layer.move_closures(closures)
                return layer
        return constraint_set(model, desc.closures, desc.couplings, t.robot.source)

    @staticmethod
    def _carrier(t: _Template, records: Sequence[Record], k: int) -> int:
        """The Pinocchio joint that carries the body of fixed joint record ``k``."""
        while k in t.fixed:
            k = t.links[records[k].args["parent"]]
        return t.joints.get(k, 0)

    def _description(
        self, t: _Template, records: Sequence[Record], joint_rec: dict[str, dict[str, Any]]
    ) -> Description:
        """The description with the candidate's numbers (as the description reader reads them)."""
        closures: list[ClosureSpec] = []
        joints: list[JointSpec] = []
        actuators: list[ActuatorSpec] = []
        platform = None
        for r in records:
            a = r.args
            if r.kind == "closure":
                (l1, x1, r1), (l2, x2, r2) = a["frame1"], a["frame2"]
                axis = _unit(a["axis"] if a["axis"] is not None else (0.0, 0.0, 1.0))
                closures.append(
                    ClosureSpec(
                        a["name"],
                        a["kind"],
                        FrameRef(l1, _frame_pose(x1, r1)),
                        FrameRef(l2, _frame_pose(x2, r2)),
                        axis,
                    )
                )
            elif r.kind == "pkdyn_joint":
                limit: ConeLimit | PyramidLimit | None = None
                if a["cone"] is not None:
                    limit = ConeLimit(_unit(a["cone"][0]), _num(a["cone"][1]))
                elif a["pyramid"] is not None:
                    axis, ref, half = a["pyramid"]
                    axis, ref = _unit(axis), _vec(ref)
                    ref = _unit(ref - (ref @ axis) * axis)
                    limit = PyramidLimit(axis, ref, (_num(half[0]), _num(half[1])))
                axis2 = None if a["axis2"] is None else _unit(a["axis2"])
                joints.append(JointSpec(a["name"], a["kind"], axis2, limit))
            elif r.kind == "transmission":
                lim = joint_rec[a["joint"]]["limit"]
                effort, velocity = (
                    (math.inf, math.inf) if lim is None else (_num(lim[2]), _num(lim[3]))
                )
                drive: dict[str, float] = {}
                if a["rotor_inertia"]:
                    drive["rotor_inertia"] = _num(a["rotor_inertia"])
                if a["efficiency"] != 1.0:
                    drive["efficiency"] = _num(a["efficiency"])
                actuators.append(
                    ActuatorSpec(
                        a["actuator"], a["joint"], _num(a["reduction"]), effort, velocity, **drive
                    )
                )
            elif r.kind == "platform":
                frame = FrameRef(a["link"], _frame_pose(a["xyz"], a["rpy"]))
                platform = PlatformSpec(frame, tuple(a["task"]))
        return dataclasses.replace(
            t.robot.description,
            closures=tuple(closures),
            joints=tuple(joints),
            actuators=tuple(actuators),
            platform=platform,
        )


_INERTIAS: dict[tuple[Any, ...], pin.Inertia] = {}
"""The inertias made, by their numbers' bytes (a Delta's six bars are one; never changed)."""


def _link_inertia(link: dict[str, Any]) -> pin.Inertia:
    """The inertia Pinocchio's URDF parser makes of a link's ``<inertial>`` (origin rpy 0).

    Remembered by the bytes of the mass, centre of mass and inertia (the same numbers as
    making it again: the callers only read it).
    """
    raw = link["inertia"]
    key = (
        np.asarray(link["mass"], dtype=float).tobytes(),
        np.asarray(link["com"], dtype=float).tobytes(),
        None if raw is None else np.asarray(raw, dtype=float).tobytes(),
    )
    found = _INERTIAS.get(key)
    if found is None:
        if len(_INERTIAS) >= 256:
            _INERTIAS.clear()
        found = _INERTIAS[key] = _make_link_inertia(link)
    return found


def _make_link_inertia(link: dict[str, Any]) -> pin.Inertia:
    I = np.zeros((3, 3)) if link["inertia"] is None else np.asarray(link["inertia"], dtype=float)
    sym = np.array(
        [
            [_num(I[0, 0]), _num(I[0, 1]), _num(I[0, 2])],
            [_num(I[0, 1]), _num(I[1, 1]), _num(I[1, 2])],
            [_num(I[0, 2]), _num(I[1, 2]), _num(I[2, 2])],
        ]
    )
    return pin.Inertia(_num(link["mass"]), _vec(link["com"]), sym)


def _shape(kind: str, size: Sequence[float]) -> Any:
    """A fresh coal shape, as Pinocchio's URDF geometry parser makes it."""
    import coal

    if kind == "cylinder":
        return coal.Cylinder(_num(size[0]), _num(size[1]))
    if kind == "box":
        return coal.Box(_num(size[0]), _num(size[1]), _num(size[2]))
    return coal.Sphere(_num(size[0]))


def _scramble(robot: Robot) -> None:
    """Overwrite the numbers an in-place write must set (so that the self-check proves it)."""
    model = robot.model
    for j in range(1, model.njoints):
        model.jointPlacements[j] = pin.SE3.Random()
        if model.inertias[j].mass > 0.0:
            model.inertias[j] = pin.Inertia.Random()
    for go in robot.collision_model.geometryObjects:
        go.placement = pin.SE3.Random()


# ---------------------------------------------------------------------- comparison


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, pin.SE3):
        return isinstance(b, pin.SE3) and _same(a.homogeneous, b.homogeneous)
    if isinstance(a, pin.Inertia):
        return isinstance(b, pin.Inertia) and _same(
            a.toDynamicParameters(), b.toDynamicParameters()
        )
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        x, y = np.asarray(a), np.asarray(b)
        return x.shape == y.shape and bool(np.array_equal(x, y, equal_nan=True))
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(
            _same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a)
        )
    if isinstance(a, tuple | list):
        return (
            isinstance(b, tuple | list)
            and len(a) == len(b)
            and all(_same(x, y) for x, y in zip(a, b, strict=True))
        )
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return bool(a == b)


_MODEL_VECTORS = (
    "lowerPositionLimit",
    "upperPositionLimit",
    "effortLimit",
    "velocityLimit",
    "lowerEffortLimit",
    "upperEffortLimit",
    "lowerVelocityLimit",
    "upperVelocityLimit",
    "lowerDryFrictionLimit",
    "upperDryFrictionLimit",
    "damping",
    "friction",
    "armature",
    "rotorInertia",
    "rotorGearRatio",
    "positionLimitMargin",
)


def difference(a: Robot, b: Robot) -> str:
    """The first difference between two robots' numbers, bit for bit ('' if none).

    Compares the Pinocchio models (joint models, placements, inertias, frames, limit
    vectors), the collision geometry (placements, shape kinds and sizes), the constraint
    models' placements, the description, the actuation, the platform frame and the home.

    Args:
        a: A robot.
        b: Another robot.

    Returns:
        What differs first, or ``''``.

    """
    ma, mb = a.model, b.model
    if list(ma.names) != list(mb.names) or ma.nframes != mb.nframes:
        return "joint or frame names"
    for j in range(ma.njoints):
        if ma.joints[j] != mb.joints[j]:
            return f"joint model of '{ma.names[j]}'"
        if not _same(ma.jointPlacements[j], mb.jointPlacements[j]):
            return f"placement of joint '{ma.names[j]}'"
        if not _same(ma.inertias[j], mb.inertias[j]):
            return f"inertia of the body of joint '{ma.names[j]}'"
    for i in range(ma.nframes):
        fa, fb = ma.frames[i], mb.frames[i]
        if (fa.name, fa.parentJoint, fa.parentFrame, fa.type) != (
            fb.name,
            fb.parentJoint,
            fb.parentFrame,
            fb.type,
        ):
            return f"frame {i} ('{fa.name}')"
        if not (_same(fa.placement, fb.placement) and _same(fa.inertia, fb.inertia)):
            return f"placement or inertia of frame '{fa.name}'"
    for attr in _MODEL_VECTORS:
        if not _same(getattr(ma, attr), getattr(mb, attr)):
            return f"model.{attr}"
    for ga, gb in (
        (a.collision_model, b.collision_model),
        (a.visual_model, b.visual_model),
    ):
        if ga.ngeoms != gb.ngeoms:
            return "number of geometry objects"
        for oa, ob in zip(ga.geometryObjects, gb.geometryObjects, strict=True):
            if (oa.name, oa.parentJoint, oa.parentFrame) != (
                ob.name,
                ob.parentJoint,
                ob.parentFrame,
            ):
                return f"geometry object '{oa.name}'"
            if not (_same(oa.placement, ob.placement) and _same(oa.meshScale, ob.meshScale)):
                return f"placement of geometry object '{oa.name}'"
            sa, sb = oa.geometry, ob.geometry
            if type(sa) is not type(sb):
                return f"shape of geometry object '{oa.name}'"
            for attr in ("radius", "halfLength", "halfSide"):
                if hasattr(sa, attr) and not _same(
                    np.asarray(getattr(sa, attr)), np.asarray(getattr(sb, attr))
                ):
                    return f"size of geometry object '{oa.name}'"
    if len(a.constraint_models) != len(b.constraint_models):
        return "number of constraint models"
    for ca, cb in zip(a.constraint_models, b.constraint_models, strict=True):
        if (ca.name, ca.joint1_id, ca.joint2_id, ca.type) != (
            cb.name,
            cb.joint1_id,
            cb.joint2_id,
            cb.type,
        ):
            return f"constraint model '{ca.name}'"
        if not (
            _same(ca.joint1_placement, cb.joint1_placement)
            and _same(ca.joint2_placement, cb.joint2_placement)
        ):
            return f"placements of constraint model '{ca.name}'"
    if list(a.constraints.names) != list(b.constraints.names):
        return "constraint rows"
    if not _same(a.description, b.description):
        return "description"
    for attr in ("actuated_joints", "actuated_q", "actuated_v", "passive_v", "task_rows"):
        if not _same(getattr(a, attr), getattr(b, attr)):
            return attr
    if a.platform_frame != b.platform_frame:
        return "platform frame"
    if not _same(a.q_home, b.q_home):
        return "home configuration"
    return ""
