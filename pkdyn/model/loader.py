"""``pkdyn.load``: a library robot or a description file -> :class:`pkdyn.model.robot.Robot`.

Files are told apart by their root element, whatever their name: ``<robot>`` is a URDF (with
pkdyn's extension elements, Drake's ``drake:ball_constraint``, onshape-to-robot's ``closing_``
frames, a Gepetto YAML sidecar), ``<mujoco>`` an MJCF model
(:mod:`~pkdyn.model.formats.mjcf_import`), ``<sdf>`` an SDFormat model
(:mod:`~pkdyn.model.formats.sdf`). Anything else is refused with one
:class:`~pkdyn.exceptions.DescriptionError`.

The home configuration is then assembled by :func:`pkdyn.model.home.find_home` from the
description's own pose (or ``home=``), within the assembly tolerance ``tol``.
"""

from __future__ import annotations

import dataclasses
import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.parsers import expat

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError, InvalidInputError, ParameterError, UnknownRobotError
from pkdyn.model.arguments import public
from pkdyn.model.assembly import check_actuator_limits
from pkdyn.model.build import (
    build_tree,
    check_model_size,
    constraint_models,
    constraint_set,
    geometry_models,
    resolve_frame,
)
from pkdyn.model.description import (
    TASK_COMPONENTS,
    ActuatorSpec,
    ClosureSpec,
    Description,
    parse_description,
)
from pkdyn.model.families import FAMILIES, from_description
from pkdyn.model.home import ASSEMBLY_TOL, HomeResult, find_home
from pkdyn.model.passive import passive_forces
from pkdyn.model.robot import Robot
from pkdyn.model.warn import warn, warn_missing_meshes

if TYPE_CHECKING:
    from pkdyn.model.formats.gepetto import Sidecar
    from pkdyn.model.formats.xmldoc import XmlDoc

# The readers of other formats (MJCF, SDFormat, sidecars: yaml, Drake, onshape) are imported
# where they are used: a library robot or a URDF loads without them (the CLI starts quicker).

__all__ = ["FORMATS", "detect_format", "home_result", "load", "load_string"]

FORMATS = {"robot": "urdf", "mujoco": "mjcf", "sdf": "sdf"}
"""Root element -> description format."""


class _RootFoundError(Exception):
    def __init__(self, tag: str) -> None:
        self.tag = tag


def detect_format(text: str, source: str) -> str:
    """Format of a description from its root element: ``urdf``, ``mjcf`` or ``sdf``.

    Args:
        text: The document.
        source: File or name, for messages.

    Returns:
        The format.

    Raises:
        DescriptionError: Not XML, or a root element of none of the three formats.

    """
    parser = expat.ParserCreate()

    def start(tag: str, _: dict[str, str]) -> None:
        raise _RootFoundError(tag)

    parser.StartElementHandler = start
    try:
        parser.Parse(text, True)
    except _RootFoundError as root:
        tag = root.tag.split(":")[-1]
        if tag in FORMATS:
            return FORMATS[tag]
        raise DescriptionError(
            source,
            f"<{root.tag}>",
            "cannot tell the format from this root element: pkdyn reads URDF (<robot>), MJCF "
            "(<mujoco>) and SDFormat (<sdf>) descriptions",
        ) from None
    except expat.ExpatError as err:
        raise DescriptionError(
            source,
            "file",
            f"is not an XML document ({expat.errors.messages[err.code]}, line {err.lineno}): "
            "pkdyn reads URDF, MJCF and SDFormat descriptions",
        ) from None
    raise DescriptionError(source, "file", "is empty: no XML element")


def _package_dirs(path: Path | None) -> list[str]:
    """The file's directory and its ancestors: where ``package://`` meshes usually resolve."""
    dirs: list[str] = []
    if path is not None:
        p = path.resolve().parent
        for _ in range(5):
            dirs.append(str(p))
            p = p.parent
    return dirs


@public
def load(
    name_or_path: str | os.PathLike[str],
    sidecar: str | os.PathLike[str] | None = None,
    geometry: bool = True,
    package_dirs: list[str] | None = None,
    *,
    home: Sequence[float] | np.ndarray | None = None,
    tol: float = ASSEMBLY_TOL,
    xacro_args: dict[str, Any] | None = None,
    ignore_elements: Sequence[str] = (),
    repair_inertias: bool = False,
    **params: Any,
) -> Robot:
    """Load a robot: a library family name (``delta``, ``gough_stewart``...) or a file.

    Args:
        name_or_path: Library family name, or path to a URDF (pkdyn or plain), MJCF or SDFormat
            file (the format is read from the root element).
        sidecar: Gepetto-style YAML sidecar (``closed_loop``, ``type``, ``name_mot``,
            ``joint_name``/``joint_type``, ``free_flyer``, ``platform``); by default
            ``<file>.yaml`` or ``robot.yaml`` next to the file when present.
        geometry: Build the visual and collision geometry models.
        package_dirs: Extra directories for mesh look-up.
        home: Home configuration to assemble: actuator coordinates (n_a,) [rad or m], the
            passive ones solved, or a full configuration (nq,) used as the starting guess.
        tol: Assembly tolerance [m or rad]: closures a description misses by at most this much
            (CAD rounding) are closed with a warning; beyond it, an error.
        xacro_args: Arguments of a ``.xacro`` file (``<xacro:arg>`` name -> value); the file
            is expanded by the ``xacro`` package (``pip install "pkdyn[xacro]"``).
        ignore_elements: Names of elements to leave out of the file (``"loop"``,
            ``"drake:ball_constraint"``...), wherever they are: an element pkdyn does not
            read whose name says it closes a loop or couples joints is otherwise an error
            (:mod:`~pkdyn.model.formats.unread`).
        repair_inertias: Replace the physically invalid inertia tensors of the file by the
            nearest valid ones (:mod:`~pkdyn.model.inertia`), with a warning naming the links;
            without it they are reported (plain URDF) or refused (pkdyn, MJCF, SDFormat).
        **params: Builder parameters of a library family (SI units).

    Returns:
        The loaded robot, assembled at its home configuration.

    Raises:
        UnknownRobotError: Neither a family nor an existing file.
        ParameterError: Unknown or invalid builder parameter, or parameters given for a file.
        InvalidInputError: Malformed ``home`` or ``tol``.
        DescriptionError: Malformed description, or a format that cannot be told apart.
        LoopClosureError: No assembled home configuration found (names the closure; also an
            ``AssemblyError`` and a ``DescriptionError``).

    """
    from pkdyn.inputs import instance

    instance("name_or_path", name_or_path, str | os.PathLike, "a library robot name or a file")
    if sidecar is not None:
        instance("sidecar", sidecar, str | os.PathLike, "a YAML file name")
    package_dirs = _directories(package_dirs)
    name = str(name_or_path)
    if name in FAMILIES and xacro_args:
        raise ParameterError(name, "xacro_args", "apply to .xacro files only")
    if name in FAMILIES and (ignore_elements or repair_inertias):
        what = "ignore_elements" if ignore_elements else "repair_inertias"
        raise ParameterError(name, what, "applies to description files only")
    if name in FAMILIES:
        fam = FAMILIES[name]
        p = fam.make_params(params)
        xml = fam.build_urdf(p)
        return load_string(
            xml,
            name,
            geometry=geometry,
            params=p,
            home=fam.home(p) if home is None else home,
            tol=tol,
            user_home=home is not None,
        )
    path = Path(name)
    if not path.exists() or path.is_dir():
        raise UnknownRobotError(name, list(FAMILIES))
    if params:
        first = next(iter(params))
        raise ParameterError(path.name, first, "builder parameters apply to library robots only")
    from pkdyn.model.formats.xacro_files import expand_xacro, is_xacro

    if is_xacro(path):
        text = expand_xacro(path, xacro_args)
    elif xacro_args:
        raise ParameterError(path.name, "xacro_args", "apply to .xacro files only")
    else:
        from pkdyn.model.formats.xmldoc import read_text

        text = read_text(path, "description file")
    side = Path(sidecar) if sidecar is not None else None
    if side is None:
        for cand in (path.with_suffix(".yaml"), path.parent / "robot.yaml"):
            if cand.is_file():
                side = cand
                break
    dirs = _package_dirs(path) + list(package_dirs or [])
    return load_string(
        text,
        name,
        geometry=geometry,
        package_dirs=dirs,
        sidecar=side,
        home=home,
        tol=tol,
        path=path,
        ignore_elements=ignore_elements,
        repair_inertias=repair_inertias,
    )


def _directories(value: Any) -> list[str]:
    """``package_dirs``: existing directories (mesh look-up), or ``None`` for none."""
    if value is None:
        return []
    from pkdyn.inputs import names

    if isinstance(value, list | tuple):
        value = list(dict.fromkeys(value)) if all(isinstance(v, str) for v in value) else value
    dirs = list(names("package_dirs", value, what="directory", empty=True))
    for d in dirs:
        if not Path(d).is_dir():
            raise InvalidInputError("package_dirs", f"'{d}' is not a directory")
    return dirs


@dataclasses.dataclass(frozen=True)
class _Options:
    """What the user asked of an import: elements to leave out, inertias to repair."""

    ignore: frozenset[str] = frozenset()
    repair_inertias: bool = False


@dataclasses.dataclass(eq=False)
class _Parts:
    """A description turned into Pinocchio objects, before assembly."""

    model: pin.Model
    desc: Description
    visual: pin.GeometryModel
    collision: pin.GeometryModel
    q_ref: np.ndarray
    missing_meshes: tuple[str, ...] = ()
    preload: bool = False  # spring rests outside the joint limits accepted (MJCF springref)
    declared: dict[str, bool] | None = None  # URDF+ independent flags the actuators came from
    dropped: tuple[str, ...] = ()  # collision elements left out (malformed)


@public
def load_string(
    xml: str,
    source: str,
    geometry: bool = True,
    package_dirs: list[str] | None = None,
    sidecar: Path | None = None,
    params: Any = None,
    home: Sequence[float] | np.ndarray | None = None,
    tol: float = ASSEMBLY_TOL,
    path: Path | None = None,
    user_home: bool | None = None,
    ignore_elements: Sequence[str] = (),
    repair_inertias: bool = False,
) -> Robot:
    """Load a robot from the text of its description (URDF, MJCF or SDFormat).

    Args:
        xml: The description.
        source: Name used in messages and as ``Robot.source``.
        geometry: Build the visual and collision geometry models.
        package_dirs: Directories for mesh look-up.
        sidecar: Optional Gepetto YAML sidecar.
        params: Builder parameters to keep on the robot.
        home: Home configuration: actuator coordinates (n_a,) or a full configuration (nq,).
        tol: Assembly tolerance [m or rad] (see :func:`load`).
        path: File the text came from (relative includes and meshes).
        user_home: ``home`` came from the user (default: whenever it is given).
        ignore_elements: Element names to leave out (see :func:`load`).
        repair_inertias: Repair invalid inertia tensors (see :func:`load`).

    Returns:
        The loaded robot.

    """
    from pkdyn.inputs import instance
    from pkdyn.model.formats.unread import ignored_names
    from pkdyn.model.formats.xmldoc import lenient

    instance("xml", xml, str, "the text of a description (str)")
    instance("source", source, str, "a name for messages (str)")
    if sidecar is not None:
        instance("sidecar", sidecar, str | os.PathLike, "a YAML file name")
        sidecar = Path(sidecar)
    package_dirs = _directories(package_dirs)
    opts = _Options(ignored_names(ignore_elements), bool(repair_inertias))

    xml = lenient(xml)  # Drake's and Gazebo's leniencies: comments with --, drake: undeclared
    fmt = detect_format(xml, source)
    side = None
    if sidecar is not None:
        from pkdyn.model.formats.gepetto import read_sidecar

        side = read_sidecar(sidecar)
    dirs = list(package_dirs or [])
    if fmt == "urdf":
        parts = _urdf(xml, source, geometry, dirs, side, opts)
    else:
        from pkdyn.model.formats.graph import build
        from pkdyn.model.formats.mjcf_import import read_mjcf
        from pkdyn.model.formats.sdf import read_sdf

        reader = read_mjcf if fmt == "mjcf" else read_sdf
        mech = reader(
            xml,
            source,
            path,
            geometry=geometry,
            ignore=opts.ignore,
            repair_inertias=opts.repair_inertias,
        )
        if side is not None and side.joint_types:
            raise DescriptionError(
                str(sidecar), "joint_name", "joint upgrades apply to URDF descriptions only"
            )
        built = build(mech)
        check_model_size(built.model, source)  # before any createData
        q_ref = built.q_ref
        if "home" in mech.home:
            q_ref = built.configuration(mech.home["home"], q_ref)
        desc = Description(
            mech.name,
            tuple(built.closures),
            (),
            tuple(mech.actuators),
            None,
            tuple(b for b, body in mech.bodies.items() if not body.virtual),
            tuple(j.name for j in mech.joints),
            passive=tuple(built.passive),
            couplings=tuple(built.couplings),
        )
        parts = _Parts(
            built.model,
            desc,
            built.visual,
            built.collision,
            q_ref,
            tuple(mech.missing_meshes),
            preload=fmt == "mjcf",
            dropped=tuple(mech.dropped_collisions),
        )
        if not geometry:
            parts.visual, parts.collision = pin.GeometryModel(), pin.GeometryModel()
    parts = _with_sidecar(parts, side, source)
    parts = _with_onshape(parts)
    if parts.desc.family is not None and params is None:  # a file of pkdyn urdf FAMILY
        params, family_home = from_description(parts.desc, parts.model, source)
        if home is None:
            home, user_home = family_home, False
    if parts.desc.home is not None and home is None:  # <pkdyn:home>: the described home
        home, user_home = parts.desc.home, False
    robot = _robot(parts, source, params)
    if parts.declared is not None and home is None:  # assembled, with or without actuators
        robot = _independent_actuation(robot, parts, params, tol)
    else:
        robot = _assembled(
            robot, parts, home, tol, user_home if user_home is not None else home is not None
        )
    _check_massless(robot)
    return robot


def _check_massless(robot: Robot) -> None:
    """Warn when massless bodies leave motions without inertia (undefined accelerations).

    A body with neither mass nor rotational inertia moves nothing when its joint turns, unless
    bodies with mass hang below it or a coupling ties its joint to one. The mass matrix reduced
    to the motions the constraints allow (``N^T M N``) is then singular, and forward dynamics
    cannot give those accelerations: the load names the joints (rotors with inertia and no
    mass, and massless links carrying others, are fine).
    """
    from solvers.numerics import null_space

    model = robot.model
    if not any(model.inertias[j].mass == 0.0 for j in range(1, model.njoints)):
        return
    data = model.createData()
    M = pin.crba(model, data, robot.q_home)
    M = np.triu(M) + np.triu(M, 1).T
    N = np.eye(robot.nv)
    if robot.constraints.n:
        N = null_space(robot.constraints.jacobian(model.createData(), robot.q_home))
    Mr = N.T @ M @ N
    if Mr.size == 0:
        return
    w, V = np.linalg.eigh(Mr)
    scale = max(float(np.abs(w).max()), 1e-300)
    dead = V[:, w <= 1e-12 * scale]
    if dead.shape[1] == 0:
        return
    motion = np.abs(N @ dead).max(axis=1)
    joints = [
        model.names[j]
        for j in range(1, model.njoints)
        for iv in range(model.joints[j].idx_v, model.joints[j].idx_v + model.joints[j].nv)
        if motion[iv] > 1e-6 * float(motion.max())
    ]
    names = ", ".join(f"'{n}'" for n in dict.fromkeys(joints))
    warn(
        f"{robot.source}: {dead.shape[1]} motion(s) of joint(s) {names} move no mass or "
        "inertia (massless links): their accelerations are undefined and forward dynamics "
        "cannot run; give the links an <inertial> or make the joints fixed"
    )


def _independent_ranks(
    robot: Robot, declared: dict[str, bool], actuated: list[str]
) -> tuple[int, int, int, int]:
    """Ranks of a declared independent set at the robot's (assembled) home.

    Returns ``(chosen, r, r_others, others)``: ``chosen`` the coordinates of the ``actuated``
    joints and of the multi-DoF joints (a floating base) not declared dependent; ``r`` the rank
    of the constraint Jacobian; ``r_others`` its rank on the other coordinates (``others`` of
    them).
    """
    from solvers.numerics import rank

    model = robot.model
    ids = [model.getJointId(n) for n in actuated]
    free = [
        jid
        for jid in range(1, model.njoints)
        if model.joints[jid].nv > 1 and declared.get(model.names[jid], True)
    ]
    chosen = np.array(
        sorted(
            iv
            for jid in ids + free
            for iv in range(model.joints[jid].idx_v, model.joints[jid].idx_v + model.joints[jid].nv)
        ),
        dtype=int,
    )
    others = np.setdiff1d(np.arange(robot.nv), chosen)
    r = r_others = 0
    if robot.constraints.n:  # closures and couplings
        _, J = robot.constraints.residual_and_jacobian(robot.data, robot.q_home)
        r = rank(J, 1e-9, scale=1.0)
        r_others = rank(J[:, others], 1e-9, scale=1.0) if others.size else 0
    return chosen.size, r, r_others, others.size


def _independent_actuation(robot: Robot, parts: _Parts, params: Any, tol: float) -> Robot:
    """The robot with URDF+'s independent joints as actuators, or without when they conflict.

    The mechanism is assembled without actuators first; at that home, the independent
    coordinates are consistent when the constraints leave them free (the Jacobian has the same
    rank on the other coordinates as on all: no relation among them); the other coordinates
    are then determined when that rank is their number, else the mechanism has motions no
    declared coordinate drives (said; the file's choice is kept). Independent coordinates the
    constraints relate cannot all be driven: the actuators are left out, with a warning, rather
    than assembled in conflict. The home is the one assembled without them: consistent
    actuators do not make it singular (the test :func:`~pkdyn.model.home.find_home` would
    make is the one above), so it is not searched again.

    Returns:
        The robot, assembled.

    """
    assert parts.declared is not None
    actuators = parts.desc.actuators
    parts.desc = dataclasses.replace(parts.desc, actuators=())
    bare = _assembled(_robot(parts, robot.source, params), parts, None, tol, False)
    parts.q_ref = bare.q_home
    names = [a.joint for a in actuators]
    chosen, r, r_others, n_others = _independent_ranks(bare, parts.declared, names)
    shown = ", ".join(names[:4]) + (" ..." if len(names) > 4 else "")
    what = f"{robot.source}: the joints URDF+ declares independent (the actuators {shown})"
    if r_others < r:
        warn(
            f"{what} are related by the file's loops and couplings: {chosen} coordinates for a "
            f"mobility of {robot.nv - r}; they are not made actuators (give the actuators "
            "<transmission> elements, or correct the independent attributes)"
        )
        return bare
    if r_others < n_others:
        warn(
            f"{what} leave {n_others - r_others} mobility(ies) undriven: {chosen} coordinates "
            f"for a mobility of {robot.nv - r}"
        )
    parts.desc = dataclasses.replace(parts.desc, actuators=actuators)
    jids, iq, iv = _actuation(bare.model, list(actuators), robot.source)
    passive = np.ones(bare.nv, dtype=bool)
    passive[iv] = False
    return dataclasses.replace(  # the same model and constraints: no second Pinocchio data
        bare,
        description=parts.desc,
        actuators=tuple(actuators),
        actuated_joints=jids,
        actuated_q=iq,
        actuated_v=iv,
        passive_v=np.flatnonzero(passive),
    )


_URDF_JOINTS = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


def _check_urdf_joints(doc: XmlDoc) -> None:
    """Name the joint and its line when its type is not a URDF joint type.

    Only the URDF's own joints: a ``<gazebo><joint>`` is SDFormat (``ball``...), read by
    :mod:`~pkdyn.model.formats.gazebo`.
    """
    for el in doc.root.findall("joint"):
        if el.get("type") is not None and el.get("type") not in _URDF_JOINTS:
            raise doc.error(
                el,
                f"unknown joint type '{el.get('type')}'; URDF joints are "
                f"{', '.join(_URDF_JOINTS)} (ball and universal joints: pkdyn:joint, see "
                "urdf/README.md)",
            )


def _drop_malformed_geometry(doc: XmlDoc) -> tuple[int, list[str]]:
    """Remove the visual and collision elements with malformed numbers, one warning each.

    A typo in a shape (a radius written ``0.1"``) costs that shape, not the robot: the element
    is left out, as a missing mesh is. Returns how many were removed, and how the dropped
    collision elements are named (collision checks refuse to run without them).
    """
    from pkdyn.model.validate import geometry_problems

    found = geometry_problems(doc.source, doc.root)
    dropped = []
    for link, el, problem in found:
        link.remove(el)
        what = f"link '{link.get('name', '?')}' {doc.where(el)}"
        warn(f"{doc.source}: {what}: {problem}; this {el.tag} shape is left out")
        if el.tag == "collision":
            dropped.append(what)
    return len(found), dropped


def _urdf(
    xml: str,
    source: str,
    geometry: bool,
    dirs: list[str],
    side: Sidecar | None,
    opts: _Options | None = None,
) -> _Parts:
    from pkdyn.model.formats import drake, unread, urdfplus
    from pkdyn.model.formats.xmldoc import parse_xml
    from pkdyn.model.inertia import report
    from pkdyn.model.validate import repair_inertias

    opts = opts or _Options()
    doc = parse_xml(xml, source)  # lines for messages; entities refused
    if doc.root.tag != "robot":
        raise DescriptionError(source, f"<{doc.root.tag}>", "the root element must be <robot>")
    _check_urdf_joints(doc)
    unread.check(doc, "urdf", opts.ignore)
    changed = unread.prune(doc, opts.ignore) > 0
    n_dropped, dropped = _drop_malformed_geometry(doc)
    changed = changed or n_dropped > 0
    if opts.repair_inertias:
        repaired = repair_inertias(source, doc.root)
        report(source, [], repaired, [])
        changed = changed or bool(repaired)
    plus = urdfplus.read_urdfplus(doc)
    if changed:  # what Pinocchio's parser and the description reader read
        xml = ET.tostring(doc.root, encoding="unicode")
    root = ET.fromstring(xml)
    xml = drake.implicit_world(xml, root)  # Drake's implicit world link
    desc = parse_description(xml, source)
    root = ET.fromstring(xml)
    extra = drake.urdf_constraints(root, source)
    model = build_tree(xml, desc.joints, source)
    if root.find("gazebo/joint") is not None:
        from pkdyn.model.formats.gazebo import gazebo_closures

        extra += gazebo_closures(root, model, source)
    check_model_size(model, source)  # before any createData
    if side is not None:
        from pkdyn.model.formats.gepetto import apply_joint_types

        model = apply_joint_types(model, side, source)
    if side is not None and side.free_flyer:
        model = _with_free_flyer(model)
    extra += list(plus.closures)
    if side is None and not desc.closures and not extra:
        from pkdyn.model.formats.gepetto import loop_frames

        pairs = loop_frames(model)
        if pairs:
            warn(
                f"{source}: frames {', '.join(pairs[:3])}{' ...' if len(pairs) > 3 else ''} "
                "look like Gepetto loop frames, but there is no robot.yaml sidecar: the "
                "loops are left open"
            )
    actuators = urdfplus.independent_actuators(root, plus, desc.actuators)
    from_independent = bool(actuators) and not desc.actuators
    model = _one_coordinate(model, [a.joint for a in actuators])
    missing: list[str] = []
    if geometry:
        visual, collision, missing = geometry_models(model, xml, dirs, source)
        if missing:
            warn_missing_meshes(source, missing)
    else:
        visual, collision = pin.GeometryModel(), pin.GeometryModel()
    desc = dataclasses.replace(
        desc,
        closures=desc.closures + tuple(extra),
        couplings=desc.couplings + plus.couplings,
        actuators=actuators,
    )
    parts = _Parts(model, desc, visual, collision, _guess(model), tuple(missing))
    parts.dropped = tuple(dropped)
    if from_independent:
        parts.declared = plus.independent
    return parts


def _revolute_axis(jm: pin.JointModel) -> np.ndarray:
    """Axis (3,) of a 1-DoF revolute joint model, in its own frame (motion subspace)."""
    single = pin.Model()
    single.addJoint(0, jm, pin.SE3.Identity(), "j")
    data = single.createData()
    pin.computeJointJacobians(single, data, pin.neutral(single))
    J = pin.getJointJacobian(single, data, 1, pin.ReferenceFrame.LOCAL)
    return np.reshape(np.asarray(J, dtype=float), (6, -1))[3:, 0]  # a (6,) array when nv = 1


def _one_coordinate(model: pin.Model, joints: list[str]) -> pin.Model:
    """Actuated ``continuous`` joints as revolute joints of one coordinate (no cos/sin pair).

    An actuator drives one coordinate: Pinocchio's unbounded revolute joint has two
    (``cos, sin``). The joint keeps its axis, placement, effort and velocity limits; its
    position is unbounded. The model is unchanged when no actuated joint is unbounded.
    """
    from pkdyn.model.build import replace_joints

    new: dict[str, pin.JointModel | None] = {}
    for name in joints:
        if not model.existJointName(name):
            continue  # _actuation names it
        jm = model.joints[model.getJointId(name)]
        kind = jm.shortname()
        if jm.nq == 2 and jm.nv == 1 and ("RUB" in kind or "Unbounded" in kind):
            if kind[-1] in "XYZ" and kind.startswith("JointModelRUB"):
                new[name] = getattr(pin, f"JointModelR{kind[-1]}")()
            else:
                new[name] = pin.JointModelRevoluteUnaligned(_revolute_axis(jm))
    if not new:
        return model
    out = replace_joints(model, new)
    out.inertias[0] = model.inertias[0]  # the links welded to the world (no dynamics)
    for name in new:
        old, jid = model.joints[model.getJointId(name)], out.getJointId(name)
        iq, iv = out.joints[jid].idx_q, out.joints[jid].idx_v
        out.lowerPositionLimit[iq] = -np.inf
        out.upperPositionLimit[iq] = np.inf
        out.effortLimit[iv] = model.effortLimit[old.idx_v]
        out.velocityLimit[iv] = model.velocityLimit[old.idx_v]
        for attr in ("damping", "friction", "armature"):
            getattr(out, attr)[iv] = getattr(model, attr)[old.idx_v]
    return out


def _with_free_flyer(model: pin.Model) -> pin.Model:
    """The model with a free-flyer root joint (Gepetto's ``free_flyer`` option)."""
    new = pin.Model()
    new.name = model.name
    new.gravity = model.gravity
    ff = new.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root_joint")
    new.addFrame(pin.Frame("root_joint", ff, pin.SE3.Identity(), pin.JOINT), False)
    ids = {0: ff}
    for jid in range(1, model.njoints):
        jm = model.joints[jid]
        sl_q = slice(jm.idx_q, jm.idx_q + jm.nq)
        sl_v = slice(jm.idx_v, jm.idx_v + jm.nv)
        ids[jid] = new.addJoint(
            ids[model.parents[jid]],
            jm,
            model.jointPlacements[jid],
            model.names[jid],
            model.effortLimit[sl_v],
            model.velocityLimit[sl_v],
            model.lowerPositionLimit[sl_q],
            model.upperPositionLimit[sl_q],
        )
        new.appendBodyToJoint(ids[jid], model.inertias[jid], pin.SE3.Identity())
    for f in model.frames:
        if f.name == "universe":
            continue
        fr = pin.Frame(f)
        fr.parentJoint = ids[f.parentJoint]
        new.addFrame(fr, False)
    new.appendBodyToJoint(ff, model.inertias[0], pin.SE3.Identity())
    return new


def _with_sidecar(parts: _Parts, side: Sidecar | None, source: str) -> _Parts:
    if side is None:
        return parts
    model, desc = parts.model, parts.desc
    closures = list(desc.closures) + side.closures
    actuators = list(desc.actuators)
    moving = {model.names[j] for j in range(1, model.njoints)}
    for a in side.actuators:
        if a.joint not in moving:
            raise DescriptionError(
                side.source,
                f"name_mot '{a.joint}'",
                "matches no joint (a moving joint of the model)",
            )
        if a.joint in [b.joint for b in actuators]:
            continue
        iv = model.joints[model.getJointId(a.joint)].idx_v
        eff, vel = float(model.effortLimit[iv]), float(model.velocityLimit[iv])
        actuators.append(dataclasses.replace(a, effort=eff, velocity=vel))
    platform = desc.platform if side.platform is None else side.platform
    parts.desc = dataclasses.replace(
        desc,
        closures=tuple(closures),
        actuators=tuple(actuators),
        platform=platform,
        couplings=desc.couplings + tuple(side.couplings),
    )
    return parts


def _with_onshape(parts: _Parts) -> _Parts:
    """Closures of onshape-to-robot ``closing_`` frame pairs, each loop closed once.

    A pair already closed by another closure (the ``<connect>`` equality an MJCF export writes
    between the two sites, a sidecar or pkdyn closure on the same frames) is not closed again:
    the same two joints, the same points (1e-9 m).
    """
    from pkdyn.model.formats import onshape

    found = onshape.closing_closures(parts.model)
    if not found:
        return parts
    model = parts.model

    def ends(c: ClosureSpec) -> list[tuple[int, np.ndarray]] | None:
        try:
            out = [resolve_frame(model, f, "", "") for f in (c.frame1, c.frame2)]
        except DescriptionError:
            return None
        return sorted(((j, M.translation) for j, M in out), key=lambda e: e[0])

    def same(a: list[tuple[int, np.ndarray]] | None, b: list[tuple[int, np.ndarray]]) -> bool:
        return a is not None and all(
            ja == jb and float(np.linalg.norm(pa - pb)) < 1e-9
            for (ja, pa), (jb, pb) in zip(a, b, strict=True)
        )

    used = {f.link for c in parts.desc.closures for f in (c.frame1, c.frame2)}
    closed = [ends(c) for c in parts.desc.closures]
    extra = []
    for c in found:
        e = ends(c)
        if c.frame1.link in used or (e is not None and any(same(k, e) for k in closed)):
            continue
        extra.append(c)
    if extra:
        parts.desc = dataclasses.replace(parts.desc, closures=parts.desc.closures + tuple(extra))
    return parts


def _robot(parts: _Parts, source: str, params: Any) -> Robot:
    model, desc = parts.model, parts.desc
    names = [c.name for c in desc.closures]
    for n in names:
        if names.count(n) > 1:
            raise DescriptionError(source, f"closure '{n}'", "closure names must be unique")
    cms, owner = constraint_models(model, desc.closures, source)
    constraints = constraint_set(model, desc.closures, desc.couplings, source)
    actuated_joints, actuated_q, actuated_v = _actuation(model, list(desc.actuators), source)
    desc = dataclasses.replace(desc, actuators=_reflected(model, desc.actuators, actuated_v))
    platform_frame = None
    task_rows = np.arange(6)
    if desc.platform is not None:
        j, M = resolve_frame(model, desc.platform.frame, source, "platform")
        fname = "platform" if not model.existFrame("platform") else "pkdyn_platform"
        platform_frame = model.addFrame(pin.Frame(fname, j, M, pin.FrameType.OP_FRAME), False)
        task_rows = np.array([TASK_COMPONENTS.index(t) for t in desc.platform.task])
    vec = pin.StdVec_RigidConstraintModel()
    for cm in cms:
        vec.append(cm)
    is_passive = np.ones(model.nv, dtype=bool)
    is_passive[actuated_v] = False
    passive = np.flatnonzero(is_passive)  # (not setdiff1d: it imports numpy.ma, 10 ms)
    elements = passive_forces(
        model,
        desc.passive,
        desc.springs,
        source,
        desc.joint_names,
        desc.joints,
        preload=parts.preload,
    )
    return Robot(
        name=desc.name,
        source=source,
        model=model,
        data=model.createData(),
        visual_model=parts.visual,
        collision_model=parts.collision,
        description=desc,
        constraint_models=vec,
        constraint_owner=owner,
        constraints=constraints,
        actuators=tuple(desc.actuators),
        actuated_joints=actuated_joints,
        actuated_q=actuated_q,
        actuated_v=actuated_v,
        passive_v=passive,
        platform_frame=platform_frame,
        task_rows=task_rows,
        q_home=pin.neutral(model),
        params=params,
        passive=elements,
        missing_meshes=parts.missing_meshes,
        dropped_collisions=parts.dropped,
    )


def _reflected(
    model: pin.Model, actuators: tuple[ActuatorSpec, ...], actuated_v: np.ndarray
) -> tuple[ActuatorSpec, ...]:
    """Rotor inertias into the model's armature (``N^2 J``), or out of it.

    A described rotor inertia is added to the armature of its coordinate; a format that gives
    the reflected inertia itself (MJCF ``armature``) sets the actuator's rotor inertia to
    ``armature / N^2``, so that the drive model and the model agree.
    """
    out = []
    for a, iv in zip(actuators, actuated_v, strict=True):
        existing = float(model.armature[iv])
        if a.rotor_inertia:
            model.armature[iv] = existing + a.reduction**2 * a.rotor_inertia
        elif existing > 0.0:
            a = dataclasses.replace(a, rotor_inertia=existing / a.reduction**2)
        out.append(a)
    return tuple(out)


def _assembled(
    robot: Robot,
    parts: _Parts,
    home: Sequence[float] | np.ndarray | None,
    tol: float,
    user: bool,
) -> Robot:
    res = home_result(robot, parts.q_ref, home, tol, user)
    if res.moved:
        parts.desc = dataclasses.replace(parts.desc, closures=tuple(res.closures))
        if res.couplings is not None:
            parts.desc = dataclasses.replace(parts.desc, couplings=tuple(res.couplings))
        robot = _robot(parts, robot.source, robot.params)
    robot.q_home = res.q
    return robot


def home_result(
    robot: Robot,
    q_ref: np.ndarray,
    home: Sequence[float] | np.ndarray | None,
    tol: float,
    user: bool,
) -> HomeResult:
    """The home :func:`load` assembles: ``home`` checked, then :func:`find_home` from it.

    Args:
        robot: The robot before assembly.
        q_ref: The description's own configuration (nq,).
        home: Actuator coordinates (n_a,), a full configuration (nq,), or ``None``.
        tol: Assembly tolerance [m or rad].
        user: ``home`` came from the user (its actuator limits are checked).

    Returns:
        :func:`find_home`'s result.

    Raises:
        InvalidInputError: A malformed ``home``.
        JointLimitError: A user's home outside the actuator limits.
        LoopClosureError: No assembled configuration.

    """
    q0 = np.array(q_ref, dtype=float)
    qa = None
    if home is not None:
        try:
            h = np.asarray(home, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InvalidInputError("home", f"expected numbers, got {home!r}") from None
        if not np.all(np.isfinite(h)):
            raise InvalidInputError("home", "NaN and infinite values are not allowed")
        n_a = len(robot.actuators)
        if h.size == n_a and n_a > 0:
            qa = h
            if user:  # the limits forward_geometry holds the same values to
                q_check = q0.copy()
                q_check[robot.actuated_q] = qa
                check_actuator_limits(robot, q_check)
        elif h.size == robot.nq:
            _check_quaternions(robot.model, h)
            q0 = pin.normalize(robot.model, h)
            if user:
                check_actuator_limits(robot, q0)
        else:
            raise InvalidInputError(
                "home",
                f"{h.size} values; give the {n_a} actuator coordinates "
                f"({', '.join(a.name for a in robot.actuators) or 'none'}) or a full "
                f"configuration of {robot.nq} values",
            )
    return find_home(robot, q0, qa, tol, user=user)


def _check_quaternions(model: pin.Model, q: np.ndarray) -> None:
    """Refuse a configuration whose ball or free joint has a zero (or tiny) quaternion."""
    for jid in range(1, model.njoints):
        jm = model.joints[jid]
        if jm.nq in (4, 7) and jm.nv in (3, 6):
            quat = q[jm.idx_q + jm.nq - 4 : jm.idx_q + jm.nq]
            if float(np.linalg.norm(quat)) < 1e-9:
                raise InvalidInputError(
                    "home",
                    f"joint '{model.names[jid]}': the quaternion {quat.tolist()} has no "
                    "orientation (norm 0); give a unit quaternion x y z w",
                )


def _actuation(
    model: pin.Model, actuators: list[ActuatorSpec], source: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    jids, iq, iv = [], [], []
    for a in actuators:
        if not model.existJointName(a.joint):
            raise DescriptionError(
                source,
                f"transmission of '{a.name}'",
                f"names joint '{a.joint}', which is not a moving joint",
            )
        jid = model.getJointId(a.joint)
        jm = model.joints[jid]
        if jm.nv != 1 or jm.nq != 1:
            raise DescriptionError(
                source,
                f"transmission of '{a.name}'",
                f"joint '{a.joint}' must be revolute or prismatic (1 coordinate) to be actuated",
            )
        jids.append(jid)
        iq.append(jm.idx_q)
        iv.append(jm.idx_v)
    return np.array(jids, dtype=int), np.array(iq, dtype=int), np.array(iv, dtype=int)


def _guess(model: pin.Model) -> np.ndarray:
    """Neutral configuration moved inside finite joint limits (mid-range when outside)."""
    q = pin.neutral(model)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    for jid in range(1, model.njoints):
        jm = model.joints[jid]
        if jm.nq != 1:
            continue
        i = jm.idx_q
        if (
            math.isfinite(lo[i])
            and math.isfinite(hi[i])
            and lo[i] < hi[i]
            and not lo[i] <= q[i] <= hi[i]
        ):
            q[i] = 0.5 * (lo[i] + hi[i])
    return q
