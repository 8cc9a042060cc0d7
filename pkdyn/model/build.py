"""Build the Pinocchio model of a description: URDF tree, upgraded joints, constraint models."""

from __future__ import annotations

import contextlib
import math
import os
import re
import sys
from collections.abc import Iterator, Sequence

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.description import (
    ClosureSpec,
    CouplingSpec,
    FrameRef,
    JointSpec,
    LinearCouplingSpec,
)
from pkdyn.model.validate import check_data_size
from solvers.closure import HINGE_ARM, Closure
from solvers.constraints import ConstraintSet
from solvers.coupling import MAX_COEFFICIENTS, Coupling, JointCoupling, LinearCoupling

__all__ = [
    "HINGE_ARM",
    "build_tree",
    "build_geometry",
    "geometry_models",
    "check_model_size",
    "replace_joints",
    "resolve_frame",
    "find_frame",
    "closures",
    "constraint_models",
    "constraint_set",
    "joint_couplings",
]


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    """Silence the C++ parser's own messages on stderr; pkdyn reports errors itself."""
    try:
        fd = sys.stderr.fileno()
    except (AttributeError, ValueError, OSError):
        yield
        return
    saved = os.dup(fd)
    with open(os.devnull, "w") as devnull:
        os.dup2(devnull.fileno(), fd)
        try:
            yield
        finally:
            os.dup2(saved, fd)
            os.close(saved)


def build_tree(xml: str, joints: Sequence[JointSpec], source: str) -> pin.Model:
    """Parse the URDF tree and upgrade placeholder joints to spherical / universal.

    Args:
        xml: URDF document.
        joints: Joint upgrades from the extension elements.
        source: File or robot name, for error messages.

    Returns:
        The Pinocchio model. Without upgrades it is exactly ``pin.buildModelFromXML(xml)``.

    Raises:
        DescriptionError: The URDF is rejected, or an upgrade names a missing or unsuitable joint.

    """
    try:
        with _quiet_stderr():
            model = pin.buildModelFromXML(xml)
    except (RuntimeError, ValueError) as err:
        raise DescriptionError(source, "URDF", f"rejected by the URDF parser: {err}") from None
    if not joints:
        return model
    specs = {j.name: j for j in joints}
    for name in specs:
        if not model.existJointName(name):
            raise DescriptionError(
                source, f"pkdyn:joint '{name}'", "no moving URDF joint of that name"
            )
        jm = model.joints[model.getJointId(name)]
        # revolute shortnames: JointModelR{X,Y,Z}, JointModelRUB{X,Y,Z}, JointModelRevolute*
        if jm.nv != 1 or not jm.shortname().startswith("JointModelR"):
            raise DescriptionError(
                source,
                f"pkdyn:joint '{name}'",
                "the placeholder must be a 'continuous' or 'revolute' URDF joint",
            )
        axis2 = specs[name].axis2
        if axis2 is not None and abs(float(_axis_of(jm) @ axis2)) > 1e-9:
            raise DescriptionError(
                source,
                f"pkdyn:joint '{name}' axis2",
                "must be orthogonal to the placeholder joint's <axis>",
            )
    return _rebuild(model, specs)


def _axis_of(jm: pin.JointModel) -> np.ndarray:
    """Axis of a 1-DOF revolute joint model (aligned or not, bounded or not).

    Read from the joint's motion subspace at its neutral configuration, computed on a copy of
    the joint in a one-joint model: ``jm`` indexes its own model's configuration (its
    ``idx_q``), and its ``calc`` on a one-element vector read memory past it (a crash, at
    times).
    """
    single = _single_joint_model(jm)
    own = single.joints[1]
    jd = own.createData()
    own.calc(jd, pin.neutral(single))
    S = np.reshape(np.asarray(jd.S), (6, -1))
    axis = S[3:, 0]
    return axis / np.linalg.norm(axis)


def _single_joint_model(jm: pin.JointModel) -> pin.Model:
    m = pin.Model()
    m.addJoint(0, jm, pin.SE3.Identity(), "j")
    return m


def _rebuild(model: pin.Model, specs: dict[str, JointSpec]) -> pin.Model:
    joints: dict[str, pin.JointModel | None] = {}
    for name, spec in specs.items():
        if spec.kind == "spherical":
            joints[name] = pin.JointModelSpherical()
        else:
            assert spec.axis2 is not None
            jm = model.joints[model.getJointId(name)]
            joints[name] = pin.JointModelUniversal(_axis_of(jm), spec.axis2)
    return replace_joints(model, joints)


def replace_joints(model: pin.Model, joints: dict[str, pin.JointModel | None]) -> pin.Model:
    """A copy of ``model`` with the named joints replaced (ball and universal joints, welds).

    The other joints keep their models and limits; a new joint gets effort and velocity limits
    of 1e3 and position bounds of -1..1 (quaternion) or -pi..pi (universal angles); ``None``
    welds the joint's body to its parent (a fixed joint: later joints and frames move onto the
    parent with the placement). Bodies and frames follow.

    Args:
        model: The tree (unchanged).
        joints: Joint name -> new joint model, or ``None`` to weld.

    Returns:
        The new model.

    """
    new = pin.Model()
    new.name = model.name
    new.gravity = model.gravity
    image: dict[int, tuple[int, pin.SE3]] = {0: (0, pin.SE3.Identity())}
    for jid in range(1, model.njoints):
        name = model.names[jid]
        jm = model.joints[jid]
        pj, off = image[model.parents[jid]]
        placement = off * model.jointPlacements[jid]
        if name in joints and joints[name] is None:
            image[jid] = (pj, placement)
            new.appendBodyToJoint(pj, model.inertias[jid], placement)
            continue
        njm = joints.get(name)
        if njm is None:
            sl_q = slice(jm.idx_q, jm.idx_q + jm.nq)
            sl_v = slice(jm.idx_v, jm.idx_v + jm.nv)
            nid = new.addJoint(
                pj,
                jm,
                placement,
                name,
                model.effortLimit[sl_v],
                model.velocityLimit[sl_v],
                model.lowerPositionLimit[sl_q],
                model.upperPositionLimit[sl_q],
            )
        else:
            big = np.full(njm.nv, 1e3)
            lo = np.full(njm.nq, -np.pi if njm.nq == 2 else -1.0)
            nid = new.addJoint(pj, njm, placement, name, big, big, lo, -lo)
        image[jid] = (nid, pin.SE3.Identity())
        new.appendBodyToJoint(nid, model.inertias[jid], pin.SE3.Identity())
    welded = {name for name, jm in joints.items() if jm is None}
    for f in model.frames:
        if f.name == "universe" and f.parentJoint == 0 and f.type == pin.FrameType.FIXED_JOINT:
            continue
        pj, off = image[f.parentJoint]
        ftype = f.type
        if ftype == pin.FrameType.JOINT and f.name in welded:
            ftype = pin.FrameType.FIXED_JOINT
        if new.existFrame(f.name, ftype):
            continue
        if not welded:  # the same tree: the frame as it is
            new.addFrame(pin.Frame(f), False)
        else:
            new.addFrame(pin.Frame(f.name, pj, off * f.placement, ftype), False)
    return new


def build_geometry(
    model: pin.Model, xml: str, kind: pin.GeometryType, package_dirs: Sequence[str], source: str
) -> pin.GeometryModel:
    """Visual or collision geometry of the URDF, attached to ``model``.

    Args:
        model: Model built by :func:`build_tree`.
        xml: URDF document (every mesh file must be found: see :func:`geometry_models`).
        kind: ``pin.VISUAL`` or ``pin.COLLISION``.
        package_dirs: Directories searched for ``package://`` and relative mesh paths.
        source: File or robot name, for error messages.

    Returns:
        The geometry model (coal shapes).

    Raises:
        DescriptionError: A geometry cannot be parsed or a mesh file is missing.

    """
    try:
        with _quiet_stderr():
            return pin.buildGeomFromUrdfString(model, xml, kind, None, list(package_dirs))
    except (RuntimeError, ValueError, IndexError) as err:
        first = str(err).splitlines()[0] if str(err).strip() else type(err).__name__
        missing = re.match(r"Mesh (.*) could not be found", first)
        if missing:
            raise _missing_mesh(source, xml, missing[1], package_dirs) from None
        raise DescriptionError(source, f"{kind} geometry", first) from None


def _found(filename: str, package_dirs: Sequence[str]) -> bool:
    """Whether Pinocchio's resource look-up finds a mesh file (``package://``, ``file://``...)."""
    name = filename
    if name.startswith("file://"):
        name = name[len("file://") :]
    elif name.startswith("package://"):
        rest = name[len("package://") :]
        dirs = list(package_dirs) + os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep)
        return any(d and os.path.isfile(os.path.join(d, rest)) for d in dirs)
    if os.path.isabs(name):
        return os.path.isfile(name)
    return os.path.isfile(name) or any(os.path.isfile(os.path.join(d, name)) for d in package_dirs)


def geometry_models(
    model: pin.Model, xml: str, package_dirs: Sequence[str], source: str
) -> tuple[pin.GeometryModel, pin.GeometryModel, list[str]]:
    """Visual and collision geometry of the URDF; shapes whose mesh file is missing left out.

    People often have a URDF without its meshes and need its kinematics and dynamics: the
    ``<visual>`` and ``<collision>`` elements whose mesh file cannot be found are dropped (the
    caller warns once, naming the files; collision checks and the viewer refuse or warn).

    Args:
        model: Model built by :func:`build_tree`.
        xml: URDF document.
        package_dirs: Directories searched for ``package://`` and relative mesh paths.
        source: File or robot name, for error messages.

    Returns:
        ``(visual, collision, missing)``: the geometry models and the mesh files not found.

    Raises:
        DescriptionError: A geometry cannot be parsed.

    """
    import xml.etree.ElementTree as ET

    if "<mesh" not in xml:
        kinds = (pin.GeometryType.VISUAL, pin.GeometryType.COLLISION)
        vis, col = (build_geometry(model, xml, k, package_dirs, source) for k in kinds)
        return vis, col, []
    root = ET.fromstring(xml)
    missing: list[str] = []
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                files = [m.get("filename", "") for m in el.iter("mesh")]
                lost = [f for f in files if not _found(f, package_dirs)]
                if lost:
                    missing.extend(lost)
                    link.remove(el)
    text = ET.tostring(root, encoding="unicode") if missing else xml
    out = []
    for kind in (pin.GeometryType.VISUAL, pin.GeometryType.COLLISION):
        for _ in range(1000):  # a mesh Pinocchio does not find after all: drop it too
            try:
                out.append(build_geometry(model, text, kind, package_dirs, source))
                break
            except DescriptionError as err:
                m = re.search(r"<mesh filename='(.*)'>", err.culprit)
                if m is None or "mesh file not found" not in str(err):
                    raise
                missing.append(m[1])
                text = _without_mesh(text, m[1])
    return out[0], out[1], sorted(set(missing))


def _without_mesh(xml: str, filename: str) -> str:
    """The URDF without the visual and collision elements of one mesh file."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(xml)
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                if any(m.get("filename") == filename for m in el.iter("mesh")):
                    link.remove(el)
    return ET.tostring(root, encoding="unicode")


def _missing_mesh(
    source: str, xml: str, filename: str, package_dirs: Sequence[str]
) -> DescriptionError:
    """The error for a mesh file that cannot be found: the link, the file, where it looked."""
    import xml.etree.ElementTree as ET

    link = "?"
    for el in ET.fromstring(xml).findall("link"):
        if any(m.get("filename") == filename for m in el.iter("mesh")):
            link = el.get("name", "?")
            break
    where = ", ".join(package_dirs) if package_dirs else "no package directories given"
    return DescriptionError(
        source,
        f"link '{link}' <mesh filename='{filename}'>",
        f"mesh file not found (searched: {where}); pass package_dirs= or fix the path",
    )


def check_model_size(model: pin.Model, source: str) -> None:
    """Refuse, before ``model.createData()``, a model whose Pinocchio data would not fit.

    Args:
        model: The model.
        source: File or robot name, for messages.

    Raises:
        DescriptionError: The estimated ``Data`` size exceeds
            :data:`pkdyn.model.validate.MAX_DATA_BYTES` or half of the memory available.

    """
    check_data_size(source, int(model.nv), model.njoints - 1)


def resolve_frame(model: pin.Model, ref: FrameRef, source: str, what: str) -> tuple[int, pin.SE3]:
    """Joint id and placement in that joint's frame of a frame attached to a link.

    Args:
        model: The model.
        ref: Link (or frame) name and placement in it.
        source: File or robot name, for error messages.
        what: Element that refers to the frame, for error messages.

    Returns:
        ``(joint_id, jMf)``.

    Raises:
        DescriptionError: No link or frame of that name.

    """
    fid = find_frame(model, ref.link)
    if fid is None:
        raise DescriptionError(source, what, f"names link '{ref.link}', which does not exist")
    f = model.frames[fid]
    return f.parentJoint, f.placement * ref.placement


def find_frame(model: pin.Model, link: str) -> int | None:
    """The id of the frame a :class:`FrameRef` names: its link's body frame, else any frame.

    Args:
        model: The model.
        link: Link (or frame) name.

    Returns:
        The frame id, or ``None`` if the model has no frame of that name.

    """
    for ftype in (pin.FrameType.BODY, None):
        if ftype is None:
            if model.existFrame(link):
                return int(model.getFrameId(link))
        elif model.existFrame(link, ftype):
            return int(model.getFrameId(link, ftype))
    return None


def _closure_frames(
    model: pin.Model, c: ClosureSpec, source: str
) -> tuple[int, pin.SE3, int, pin.SE3]:
    """The joints and placements of a closure's two frames, on two different bodies.

    Raises:
        DescriptionError: A frame names a missing link, or both frames are on one body.

    """
    j1, M1 = resolve_frame(model, c.frame1, source, f"closure '{c.name}'")
    j2, M2 = resolve_frame(model, c.frame2, source, f"closure '{c.name}'")
    if j1 == j2:
        raise DescriptionError(
            source, f"closure '{c.name}'", "both frames are on the same body; nothing to close"
        )
    return j1, M1, j2, M2


def constraint_models(
    model: pin.Model, closures: Sequence[ClosureSpec], source: str
) -> tuple[list[pin.RigidConstraintModel], list[str]]:
    """Pinocchio rigid constraint models of the closures.

    ``point`` gives one CONTACT_3D, ``weld`` one CONTACT_6D, ``hinge`` two CONTACT_3D: the frame
    origins, and points :data:`HINGE_ARM` along the axis (6 equations of rank 5).

    Args:
        model: The model.
        closures: Closure specifications.
        source: File or robot name, for error messages.

    Returns:
        The constraint models and, for each, the name of its closure.

    Raises:
        DescriptionError: A closure names a missing link, or both frames are on one body.

    """
    out: list[pin.RigidConstraintModel] = []
    owner: list[str] = []
    local = pin.ReferenceFrame.LOCAL
    for c in closures:
        j1, M1, j2, M2 = _closure_frames(model, c, source)
        if c.kind == "weld":
            cm = pin.RigidConstraintModel(pin.ContactType.CONTACT_6D, model, j1, M1, j2, M2, local)
            cm.name = c.name
            out.append(cm)
            owner.append(c.name)
            continue
        cm = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, j1, M1, j2, M2, local)
        cm.name = c.name
        out.append(cm)
        owner.append(c.name)
        if c.kind == "hinge":
            off = pin.SE3(np.eye(3), HINGE_ARM * c.axis)
            cm2 = pin.RigidConstraintModel(
                pin.ContactType.CONTACT_3D, model, j1, M1 * off, j2, M2 * off, local
            )
            cm2.name = c.name + "/axis"
            out.append(cm2)
            owner.append(c.name)
    return out, owner


def _coupled_joint(model: pin.Model, name: str, source: str, what: str) -> int:
    """Joint id of a 1-DoF joint named by a coupling, or a :class:`DescriptionError`."""
    if not model.existJointName(name):
        raise DescriptionError(source, what, f"names joint '{name}', which is not a moving joint")
    jid = model.getJointId(name)
    jm = model.joints[jid]
    if jm.nv != 1:
        raise DescriptionError(
            source,
            what,
            f"joint '{name}' has {jm.nv} degrees of freedom; couplings relate revolute, "
            "continuous or prismatic joints (1 coordinate)",
        )
    return int(jid)


def _finite(value: object) -> bool:
    try:
        return math.isfinite(float(value))  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False


def _linear_coupling(model: pin.Model, c: LinearCouplingSpec, source: str) -> LinearCoupling:
    what = f"coupling '{c.name}'"
    if not c.terms:
        raise DescriptionError(source, what, "no terms: give at least one joint and coefficient")
    seen: set[str] = set()
    terms = []
    for joint, coef in c.terms:
        if joint in seen:
            raise DescriptionError(
                source, what, f"joint '{joint}' appears twice; give each joint once"
            )
        seen.add(joint)
        if not _finite(coef) or float(coef) == 0.0:
            raise DescriptionError(
                source,
                what,
                f"coefficient {coef!r} of joint '{joint}': give a finite, non-zero number",
            )
        terms.append((_coupled_joint(model, joint, source, what), float(coef)))
    if not _finite(c.offset):
        raise DescriptionError(source, what, f"offset {c.offset!r} is not a finite number")
    return LinearCoupling(c.name, tuple(terms), float(c.offset))


def _polynomial_coupling(model: pin.Model, c: CouplingSpec, source: str) -> JointCoupling:
    what = f"coupling '{c.name}'"
    n = len(c.coefficients)
    if not 1 <= n <= MAX_COEFFICIENTS:
        raise DescriptionError(
            source, what, f"{n} polynomial coefficients; give 1 to {MAX_COEFFICIENTS}"
        )
    values = (*c.coefficients, c.joint_ref, c.source_ref)
    if not all(_finite(x) for x in values):
        raise DescriptionError(
            source, what, "coefficients and reference positions must be finite numbers"
        )
    jid = _coupled_joint(model, c.joint, source, what)
    sid = None if c.source is None else _coupled_joint(model, c.source, source, what)
    if sid == jid:
        raise DescriptionError(source, what, f"joint '{c.joint}' cannot drive itself")
    return JointCoupling(
        c.name, jid, sid, tuple(float(x) for x in c.coefficients), c.joint_ref, c.source_ref
    )


def joint_couplings(
    model: pin.Model, couplings: Sequence[CouplingSpec | LinearCouplingSpec], source: str
) -> list[Coupling]:
    """The solver couplings (:mod:`solvers.coupling`) of coupling specs.

    A :class:`~pkdyn.model.description.LinearCouplingSpec` gives a
    :class:`solvers.coupling.LinearCoupling`, a :class:`~pkdyn.model.description.CouplingSpec`
    a :class:`solvers.coupling.JointCoupling`.

    Args:
        model: The model.
        couplings: Coupling specifications (either kind).
        source: File or robot name, for error messages.

    Returns:
        One coupling per spec, joints resolved to Pinocchio joint ids.

    Raises:
        DescriptionError: Naming the coupling: a missing joint or one that is not 1-DoF, a
            joint coupled to itself or named twice, no terms, a zero coefficient, no or more
            than 5 polynomial coefficients, non-finite numbers, or two couplings of one name.

    """
    out: list[Coupling] = []
    names: set[str] = set()
    for c in couplings:
        what = f"coupling '{c.name}'"
        if c.name in names:
            raise DescriptionError(source, what, "coupling names must be unique")
        names.add(c.name)
        if isinstance(c, LinearCouplingSpec):
            out.append(_linear_coupling(model, c, source))
        else:
            out.append(_polynomial_coupling(model, c, source))
    return out


def closures(model: pin.Model, specs: Sequence[ClosureSpec], source: str) -> list[Closure]:
    """The solver closures (:class:`solvers.closure.Closure`) of closure specs.

    Args:
        model: The model.
        specs: Closure specifications.
        source: File or robot name, for error messages.

    Returns:
        One closure per spec, frames resolved to joint ids and placements.

    Raises:
        DescriptionError: A closure names a missing link, or both frames are on one body.

    """
    out: list[Closure] = []
    for c in specs:
        j1, M1, j2, M2 = _closure_frames(model, c, source)
        axis = tuple(float(x) for x in np.asarray(c.axis, dtype=float).reshape(3))
        out.append(Closure(c.name, c.kind, int(j1), M1, int(j2), M2, axis))  # type: ignore[arg-type]
    return out


def constraint_set(
    model: pin.Model,
    closure_specs: Sequence[ClosureSpec],
    coupling_specs: Sequence[CouplingSpec | LinearCouplingSpec],
    source: str,
) -> ConstraintSet:
    """The constraint layer of a description: its closures, then its couplings.

    Args:
        model: The model.
        closure_specs: Closure specifications.
        coupling_specs: Coupling specifications (either kind).
        source: File or robot name, for error messages.

    Returns:
        The :class:`solvers.ConstraintSet`.

    Raises:
        DescriptionError: A bad closure or coupling (:func:`closures`, :func:`joint_couplings`),
            or a coupling named as a closure.

    """
    cl = closures(model, closure_specs, source)
    cp = joint_couplings(model, coupling_specs, source)
    clash = {c.name for c in coupling_specs} & {c.name for c in closure_specs}
    if clash:
        raise DescriptionError(
            source, f"coupling '{sorted(clash)[0]}'", "a closure has the same name"
        )
    try:
        return ConstraintSet(model, cl, cp)
    except ValueError as err:  # checked above: a model the specs do not describe
        raise DescriptionError(source, "constraints", str(err)) from None
