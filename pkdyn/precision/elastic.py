"""The virtual-joint model (VJM) of a robot: its springs, and a virtual joint per compliant link.

Pashkevich, Chablat and Wenger's virtual-joint method (2009) on the whole tree:

- each **actuator** is a spring on its joint coordinate, of joint-side stiffness ``k_a``
  [N m/rad or N/m] (the motor, its transmission and its servo loop held at a commanded
  position): the description's ``<pkdyn:stiffness>`` or the ``actuator_stiffness`` argument;
  ``inf`` holds the coordinate rigidly;
- **passive joints** carry the robot's own springs (``robot.passive``: joint springs and
  two-frame springs);
- each **compliant link** (:mod:`pkdyn.precision.links`) gets a 6-DOF virtual joint (Pinocchio's
  free-flyer) at its elastic centre, between its root (the body and its parent joint) and
  everything it carries, with a diagonal spring (the link's compliance inverted) about the
  undeformed placement. A beam that springs attach to along its length is cut there: one
  virtual joint per piece, in series, the springs on the section where they attach. A beam's
  mass is lumped on its two halves: the half next to the tip (a uniform half rod or tube of half
  the link's mass) moves with the tip, the rest of the link's inertia with the root (when the
  link's inertia does not contain such a half rod, all of it stays on the root); a described
  compliance keeps the link's inertia on its root. With ``mass="from-material"`` the link's own
  inertia (not that of links merged into it by fixed joints) is its beam's (section, length,
  density); otherwise the links weigh what the URDF says;
- a **prismatic leg**'s rod deflects over its part outside its cylinder, whose length follows
  the leg's stroke: the model is rebuilt at each configuration (:meth:`ElasticModel.at`);
- the constraint layer (``robot.constraints``) stays rigid, re-made on the new tree: the loop
  closures (their frames carried by the tips of compliant links) and the joint couplings (rigid
  relations between the same tree joints, in the same condensation as the closures); redundant
  closures keep their rank deficiency (the analyses use rank-revealing null spaces).

:func:`elastic_model` returns this as an :class:`ElasticModel`: a :class:`pkdyn.Robot` of the
extended tree (the robot itself when no link is compliant) whose ``passive`` holds the joint
springs and the links' virtual springs, plus the actuators' stiffness. The extended robot is an
ordinary robot: the statics, the forward dynamics and the viewer take it unchanged, which the
tests use to check the linear analyses against nonlinear equilibria and simulations.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.inputs import is_complex
from pkdyn.model.arguments import public
from pkdyn.model.reuse import kept
from pkdyn.model.robot import Robot, length_scale_at
from pkdyn.precision.links import LinkCompliance, link_compliances
from pkdyn.precision.material import Material, as_material
from solvers import ConstraintSet, FrameSpring, PassiveForces
from solvers.coupling import Coupling, LinearCoupling

__all__ = ["DEFLECTION_SUFFIX", "ElasticModel", "actuator_stiffness", "elastic_model"]

MAX_STIFFNESS = 1e15
"""Largest finite actuator stiffness accepted [N m/rad or N/m]: beyond it products with the
other springs overflow (``inf`` stands for a rigid actuator)."""

DEFLECTION_SUFFIX = "/deflection"
"""Name suffix of a link's virtual joint (``bar1a_upper/deflection``)."""


@dataclass(eq=False)  # numpy / Pinocchio fields
class ElasticModel:
    """A robot with its sources of compliance (see the module docstring).

    Attributes:
        robot: The extended robot (the loaded robot itself when no link is compliant); its
            ``passive`` holds the joint springs and the virtual link springs, not the actuators.
        base: The robot as loaded.
        actuator_stiffness: Joint-side stiffness of each actuator (n_a,) [N m/rad or N/m];
            ``inf``: held rigidly.
        links: The compliant links.
        q_index: Index in the extended ``q`` of each coordinate of the robot's ``q`` (nq,).
        v_index: Index in the extended ``v`` of each coordinate of the robot's ``v`` (nv,).
        deflection_v: Velocity indices of each link's virtual joint (n_links, 6): translation
            then rotation of the tip part, in the virtual joint's frame [m, rad].
        material: The ``material`` argument it was built with (applies to undescribed links).
        shear: Whether the beams include shear.

    """

    robot: Robot
    base: Robot
    actuator_stiffness: np.ndarray
    links: tuple[LinkCompliance, ...]
    q_index: np.ndarray
    v_index: np.ndarray
    deflection_v: np.ndarray
    material: Material | None = None
    shear: bool = True

    @property
    def material_links(self) -> tuple[str, ...]:
        """Links whose material is the ``material`` argument (undescribed by the description)."""
        return tuple(dict.fromkeys(lc.link for lc in self.links if lc.origin == "argument"))

    def at(self, q: np.ndarray) -> ElasticModel:
        """The model for configuration ``q`` (nq,) of the robot (itself, or rebuilt).

        Rebuilt when a prismatic leg's rod is compliant: its free length follows the stroke.

        Raises:
            InvalidInputError: ``q`` is not nq finite numbers.

        """
        from pkdyn.model.arguments import configuration

        q = configuration(self.base, q)
        if not any(lc.sliding for lc in self.links):
            return self
        found = link_compliances(self.base, self.material, self.shear, q)
        return _build(self.base, self.actuator_stiffness, found, self.material, self.shear)

    @property
    def nv(self) -> int:
        """Size of the extended velocity vector."""
        return self.robot.nv

    @property
    def rigid_v(self) -> np.ndarray:
        """Extended velocity indices held rigidly (actuators of infinite stiffness)."""
        return np.asarray(self.robot.actuated_v)[~np.isfinite(self.actuator_stiffness)]

    def spring_stiffness(self) -> np.ndarray:
        """Diagonal stiffness per extended velocity coordinate (nv,) at rest [N m/rad or N/m].

        The finite actuators, the joint springs and the virtual link springs (about their rest
        positions; the two-frame springs, and springs away from rest, add terms that
        :func:`pkdyn.precision.stiffness.stiffness` evaluates).
        """
        out = np.zeros(self.nv)
        P = self.robot.passive
        if P is not None:
            out += P.stiffness
        k = self.actuator_stiffness
        out[np.asarray(self.robot.actuated_v)] += np.where(np.isfinite(k), k, 0.0)
        return out

    def embed(self, q: np.ndarray) -> np.ndarray:
        """Extended configuration of a configuration of the robot, links undeformed."""
        from pkdyn.inputs import vector

        q = vector("q", q, self.base.nq, "rad or m")
        if self.robot is self.base:
            return q
        out = pin.neutral(self.robot.model)
        out[self.q_index] = q
        return out

    def restrict(self, q: np.ndarray) -> np.ndarray:
        """The robot's coordinates (nq,) of an extended configuration (deflections dropped)."""
        from pkdyn.inputs import vector

        return np.array(vector("q", q, self.robot.nq, "rad or m")[self.q_index])


@public
def actuator_stiffness(
    robot: Robot, value: float | Sequence[float] | np.ndarray | None = None
) -> np.ndarray:
    """Each actuator's joint-side stiffness, given or described.

    Args:
        robot: The robot.
        value: One stiffness for every actuator or one per actuator [N m/rad or N/m] (``inf``:
            rigid); ``None``: the description's ``<pkdyn:stiffness>`` of each transmission.

    Returns:
        Stiffness (n_a,).

    Raises:
        InvalidInputError: A stiffness that is NaN, negative or zero, a wrong count, or (with
            ``value=None``) an actuator whose stiffness is not described.

    """
    names = robot.actuator_names
    n_a = len(names)
    if value is None:
        missing = [a.name for a in robot.actuators if a.stiffness is None]
        if missing:
            raise InvalidInputError(
                "actuator_stiffness",
                f"{robot.name}: no stiffness described for actuator '{missing[0]}': give one "
                "(actuator_stiffness=..., --actuator-stiffness K) or describe "
                "<pkdyn:stiffness value=...> in its transmission",
            )
        return np.array([float(a.stiffness) for a in robot.actuators])  # type: ignore[arg-type]
    if isinstance(value, bool | str | bytes | dict) or is_complex(value):
        raise InvalidInputError("actuator_stiffness", f"{value!r:.60} is not a number")
    try:
        arr = np.atleast_1d(np.asarray(value, dtype=float)).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidInputError("actuator_stiffness", f"{value!r:.60} is not a number") from None
    if arr.size not in (1, n_a):
        raise InvalidInputError(
            "actuator_stiffness",
            f"{arr.size} values for {n_a} actuators ({', '.join(names)}): give 1 or {n_a}",
        )
    arr = np.array(np.broadcast_to(arr, (n_a,)))
    for name, k in zip(names, arr, strict=True):
        if math.isnan(k) or k <= 0.0:
            raise InvalidInputError(
                "actuator_stiffness",
                f"{k:g} for actuator '{name}': a stiffness must be > 0 [N m/rad or N/m] "
                "(inf: rigid)",
            )
        if math.isfinite(k) and k > MAX_STIFFNESS:
            raise InvalidInputError(
                "actuator_stiffness",
                f"{k:g} for actuator '{name}' is beyond any plausible stiffness (at most "
                f"{MAX_STIFFNESS:g} N m/rad or N/m; give inf for a rigid actuator)",
            )
    return arr


@public
def elastic_model(
    robot: Robot,
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    material: str | Material | None = None,
    links: bool = True,
    shear: bool = True,
) -> ElasticModel:
    """The virtual-joint model of a robot (see the module docstring).

    Args:
        robot: The robot (loaded with its geometry when links are modelled as beams).
        actuator_stiffness: One stiffness or one per actuator [N m/rad or N/m], ``inf`` for a
            rigid one; ``None``: the description's ``<pkdyn:stiffness>``.
        material: Material of every slender link (a preset name or a
            :class:`~pkdyn.precision.material.Material`); ``None``: the description's.
        links: Model the links' compliance (``False``: rigid links, the actuators' and the joint
            springs' compliance only: Gosselin's ``K = J^T K_a J``).
        shear: Timoshenko's shear deflection in the beams.

    Returns:
        The elastic model.

    Raises:
        InvalidInputError: A bad stiffness or material (the value is named).

    """
    k_a = _actuator_stiffness(robot, actuator_stiffness)
    mat = as_material(material) if material is not None else None
    key = ("elastic model", k_a.tobytes(), repr(mat), bool(links), bool(shear))

    def make() -> ElasticModel:  # kept without references to the robot (module reuse)
        found = link_compliances(robot, mat, shear) if links else []
        em = _build(robot, k_a, found, mat, shear)
        return dataclasses.replace(
            em,
            robot=None if em.robot is robot else em.robot,  # type: ignore[arg-type]
            base=None if em.base is robot else em.base,  # type: ignore[arg-type]
        )

    kept_em = kept(robot, key, make)
    return dataclasses.replace(
        kept_em,
        robot=robot if kept_em.robot is None else kept_em.robot,
        base=robot if kept_em.base is None else kept_em.base,
    )


def _build(
    robot: Robot,
    k_a: np.ndarray,
    found: Sequence[LinkCompliance],
    material: Material | None,
    shear: bool,
) -> ElasticModel:
    if not found:
        return ElasticModel(
            robot,
            robot,
            k_a,
            (),
            np.arange(robot.nq),
            np.arange(robot.nv),
            np.zeros((0, 6), dtype=int),
            material,
            shear,
        )
    robot = _with_beam_masses(robot, found)  # (the robot as the precision models weigh it)
    ext, q_index, v_index, defl = _extended(robot, found)
    return ElasticModel(ext, robot, k_a, tuple(found), q_index, v_index, defl, material, shear)


def _with_beam_masses(robot: Robot, found: Sequence[LinkCompliance]) -> Robot:
    """The robot whose links asking ``mass="from-material"`` weigh what their beam says.

    A body's own inertia (not that of the links merged into it by fixed joints) is replaced by
    its beam's (:attr:`LinkCompliance.inertia`).
    """
    heavy = {lc.joint: lc.inertia for lc in found if lc.segment == 0 and lc.inertia is not None}
    if not heavy:
        return robot
    model = pin.Model(robot.model)
    for j, beam in heavy.items():
        merged = pin.Inertia.Zero()
        for f in model.frames:
            if f.parentJoint == j and f.type == pin.FrameType.FIXED_JOINT and f.inertia.mass > 0:
                merged = merged + f.placement.act(f.inertia)
        model.inertias[j] = beam + merged
    return dataclasses.replace(robot, model=model, data=model.createData())


_actuator_stiffness = actuator_stiffness


def _extended(
    robot: Robot, links: Sequence[LinkCompliance]
) -> tuple[Robot, np.ndarray, np.ndarray, np.ndarray]:
    """The robot with a free-flyer virtual joint at each compliant link's elastic centre.

    A beam cut in pieces gets one virtual joint per piece, in series (root to tip); the body
    after piece ``k`` is the beam's section at its far end, where the springs attached there
    hang (``pieces``).
    """
    model = robot.model
    comp: dict[int, list[LinkCompliance]] = {}
    for lc in links:
        comp.setdefault(lc.joint, []).append(lc)
    new = pin.Model()
    new.name = model.name
    new.gravity = model.gravity
    jmap = {0: 0}
    carrier: dict[int, tuple[int, pin.SE3]] = {0: (0, pin.SE3.Identity())}
    virtual: dict[int, int] = {}
    pieces: dict[int, list[tuple[LinkCompliance, int]]] = {}
    vids: dict[int, int] = {}  # id(link compliance) -> its virtual joint
    fixed = _fixed_inertias(model) if comp else {}
    # (each read of a model's vector copies all of it: read once)
    effort, velocity = np.asarray(model.effortLimit), np.asarray(model.velocityLimit)
    lower, upper = np.asarray(model.lowerPositionLimit), np.asarray(model.upperPositionLimit)
    parents, names, placements = list(model.parents), list(model.names), model.jointPlacements
    big = np.full(6, 1e3)
    lo = np.concatenate([np.full(3, -1e3), np.full(4, -1.0)])
    for j in range(1, model.njoints):
        jm = model.joints[j]
        pj, off = carrier[parents[j]]
        sq = slice(jm.idx_q, jm.idx_q + jm.nq)
        sv = slice(jm.idx_v, jm.idx_v + jm.nv)
        nid = new.addJoint(
            pj,
            jm,
            off * placements[j],
            names[j],
            effort[sv],
            velocity[sv],
            lower[sq],
            upper[sq],
        )
        chain = comp.get(j, [])
        whole = _whole(chain[-1]) if chain else None
        tip, root = (
            _split(model, j, whole, fixed.get(j, ()))
            if whole is not None
            else (None, model.inertias[j])
        )
        new.appendBodyToJoint(nid, root, pin.SE3.Identity())
        jmap[j] = nid
        carrier[j] = (nid, pin.SE3.Identity())
        prev, prev_at = nid, pin.SE3.Identity()  # the body before the piece, its frame in j's
        for k, lc in enumerate(chain):
            vid = new.addJoint(
                prev,
                pin.JointModelFreeFlyer(),
                prev_at.actInv(lc.placement),
                f"{names[j]}{DEFLECTION_SUFFIX}" + (f"{k}" if len(chain) > 1 else ""),
                big,
                big,
                lo,
                -lo,
            )
            if k == len(chain) - 1 and tip is not None and whole is not None:
                new.appendBodyToJoint(vid, tip, lc.placement.actInv(whole.placement))
            pieces.setdefault(j, []).append((lc, vid))
            vids[id(lc)] = vid
            prev, prev_at = vid, lc.placement
        if chain:
            virtual[j] = prev
            carrier[j] = (prev, chain[-1].placement.inverse())
    q_index = np.zeros(model.nq, dtype=int)
    v_index = np.zeros(model.nv, dtype=int)
    for j in range(1, model.njoints):
        old, nj = model.joints[j], new.joints[jmap[j]]
        q_index[old.idx_q : old.idx_q + old.nq] = np.arange(nj.idx_q, nj.idx_q + nj.nq)
        v_index[old.idx_v : old.idx_v + old.nv] = np.arange(nj.idx_v, nj.idx_v + nj.nv)
    for name in ("armature", "damping", "friction", "rotorInertia", "rotorGearRatio"):
        values = np.array(getattr(new, name))
        values[v_index] = np.asarray(getattr(model, name))
        setattr(new, name, values)
    platform = robot.platform_frame
    for fid, f in enumerate(model.frames):
        if fid == 0:
            continue
        pj, placement = jmap[f.parentJoint], f.placement
        if fid == platform and f.parentJoint in virtual:
            pj, off = carrier[f.parentJoint]
            placement = off * placement
        new.addFrame(pin.Frame(f.name, pj, f.parentFrame, placement, f.type, f.inertia), False)
    cms = pin.StdVec_RigidConstraintModel()
    for cm in robot.constraint_models:
        j1, o1 = carrier[cm.joint1_id]
        j2, o2 = carrier[cm.joint2_id]
        c = pin.RigidConstraintModel(
            cm.type, new, j1, o1 * cm.joint1_placement, j2, o2 * cm.joint2_placement,
            cm.reference_frame,
        )  # fmt: skip
        c.name = cm.name
        cms.append(c)
    defl = np.array(
        [np.arange(new.joints[vids[id(lc)]].idx_v, new.joints[vids[id(lc)]].idx_v + 6)
         for lc in links]
    )  # fmt: skip
    q_home = pin.neutral(new)
    q_home[q_index] = robot.q_home
    # the extended tree's structure is the same at every pose of a sliding leg: its data (nv^3
    # in size) is made once per robot and structure (pkdyn.model.reuse): the robot's tree with
    # the virtual joints of each compliant body (its pieces)
    structure = tuple((j, len(chain)) for j, chain in comp.items())
    data = kept(robot, ("elastic extension", structure), new.createData)
    ext = dataclasses.replace(
        robot,
        model=new,
        data=data,
        visual_model=_geometry(robot.visual_model, jmap),
        collision_model=_geometry(robot.collision_model, jmap),
        constraint_models=cms,
        constraints=_constraints(robot.constraints, new, jmap, carrier),
        actuated_joints=np.array([jmap[int(j)] for j in robot.actuated_joints], dtype=int),
        actuated_q=q_index[np.asarray(robot.actuated_q, dtype=int)],
        actuated_v=v_index[np.asarray(robot.actuated_v, dtype=int)],
        passive_v=np.setdiff1d(np.arange(new.nv), v_index[np.asarray(robot.actuated_v)]),
        q_home=q_home,
        params=None,
        passive=_passive(
            robot, new, q_index, v_index, _spring_carrier(carrier, pieces), links, defl
        ),
    )
    ext.__dict__["length_scale"] = length_scale_at(new, data, q_home)  # (in the kept data)
    return ext, q_index, v_index, defl


def _whole(lc: LinkCompliance) -> LinkCompliance:
    """The whole beam a piece belongs to (for the split of its mass)."""
    if lc.beam is None or lc.segment == 0 and lc.end == lc.beam_length:
        return lc
    return dataclasses.replace(lc, placement=lc.beam_placement, length=lc.beam_length)


def _spring_carrier(
    carrier: dict[int, tuple[int, pin.SE3]],
    pieces: dict[int, list[tuple[LinkCompliance, int]]],
) -> Callable[[int, pin.SE3], tuple[int, pin.SE3]]:
    """Where a spring end at ``placement`` on joint ``j``'s body hangs on the extended tree.

    On a beam cut in pieces, the section nearest the point along the beam (the springs are
    where the cuts are); elsewhere what carries the body's tip (or the body itself).
    """

    def place(j: int, placement: pin.SE3) -> tuple[int, pin.SE3]:
        chain = pieces.get(j)
        if not chain or len(chain) == 1:
            return carrier[j]
        lc0 = chain[0][0]
        assert lc0.beam is not None
        root, tip = lc0.beam
        z = (tip - root) / np.linalg.norm(tip - root)
        s = float((np.asarray(placement.translation) - root) @ z)
        lc, vid = min(chain, key=lambda item: abs(item[0].end - s))
        return vid, lc.placement.inverse()

    return place


def _constraints(
    cs: ConstraintSet,
    new: pin.Model,
    jmap: dict[int, int],
    carrier: dict[int, tuple[int, pin.SE3]],
) -> ConstraintSet:
    """The constraint layer on the extended tree: the same closures and couplings.

    A closure's frames ride on what the link's tip carries (``carrier``); a coupling relates
    the same tree joints (``jmap``). The virtual joints are spatial: a planar closure whose loop
    holds a compliant link keeps its out-of-plane rows (the link deforms out of the plane).
    """
    closures = []
    for c in cs.closure_specs:
        j1, o1 = carrier[c.joint1]
        j2, o2 = carrier[c.joint2]
        closures.append(
            dataclasses.replace(
                c, joint1=j1, placement1=o1 * c.placement1, joint2=j2, placement2=o2 * c.placement2
            )
        )
    couplings: list[Coupling] = []
    for k in cs.coupling_specs:
        if isinstance(k, LinearCoupling):
            couplings.append(dataclasses.replace(k, terms=tuple((jmap[j], a) for j, a in k.terms)))
        else:
            src = None if k.source is None else jmap[k.source]
            couplings.append(dataclasses.replace(k, joint=jmap[k.joint], source=src))
    reduce = cs.closure_rows.reduce if cs.closure_rows is not None else True
    return ConstraintSet(new, closures, couplings, reduce=reduce)


def _fixed_inertias(model: pin.Model) -> dict[int, list[tuple[pin.SE3, pin.Inertia]]]:
    """Per joint, ``(placement, inertia)`` of the links merged into its body by fixed joints."""
    out: dict[int, list[tuple[pin.SE3, pin.Inertia]]] = {}
    for f in model.frames:
        if f.type == pin.FrameType.FIXED_JOINT and f.inertia.mass > 0:
            out.setdefault(int(f.parentJoint), []).append((f.placement, f.inertia))
    return out


def _split(
    model: pin.Model,
    joint: int,
    lc: LinkCompliance,
    fixed: Sequence[tuple[pin.SE3, pin.Inertia]],
) -> tuple[pin.Inertia | None, pin.Inertia]:
    """``(tip part in the virtual joint's frame, root part in the joint frame)`` of a body.

    Links merged into the body by fixed joints (their inertia is on their ``FIXED_JOINT``
    frame) go with the end of the beam they are nearer; the beam link's own inertia is split
    into a uniform half rod (or tube) at its tip and the rest, when the rest is a valid inertia
    (else it stays whole on the root).
    """
    inertia = model.inertias[joint]
    if lc.length is None or lc.section is None or inertia.mass <= 0.0:
        return None, inertia
    h = 0.5 * lc.length
    tip_pt = lc.placement.act(np.array([0.0, 0.0, h]))
    root_pt = lc.placement.act(np.array([0.0, 0.0, -h]))
    main = pin.Inertia(inertia)
    tip = pin.Inertia.Zero()
    for placement, f_inertia in fixed:  # (_fixed_inertias: the joint's, in frame order)
        part = placement.act(f_inertia)
        main = main - part
        o = np.asarray(placement.translation)
        if np.linalg.norm(o - tip_pt) < np.linalg.norm(o - root_pt):
            tip = tip + part
    if main.mass > 0.0:
        m = 0.5 * float(main.mass)
        r2 = lc.section.radius**2 + lc.section.inner_radius**2
        I_t = m * (h * h / 12.0 + r2 / 4.0)
        half = pin.Inertia(m, np.array([0.0, 0.0, 0.5 * h]), np.diag([I_t, I_t, 0.5 * m * r2]))
        if _valid(main - lc.placement.act(half)):
            tip = tip + lc.placement.act(half)
    if tip.mass <= 0.0:
        return None, inertia
    root = inertia - tip
    if not _valid(root):
        return None, inertia
    return lc.placement.actInv(tip), root


def _valid(inertia: pin.Inertia) -> bool:
    """A physical inertia: positive mass, rotational inertia about the centre of mass >= 0."""
    if not inertia.mass > 0.0:
        return False
    I = np.asarray(inertia.inertia)
    scale = max(float(np.trace(I)), 1e-300)
    # Gershgorin: every eigenvalue is at least a diagonal term less its row's other terms
    # (enough for the usual nearly diagonal inertias; the eigenvalues otherwise)
    (a, b, c), (d, e, f), (g, h, i) = I.tolist()
    bd, cg, fh = 0.5 * abs(b + d), 0.5 * abs(c + g), 0.5 * abs(f + h)
    t = -1e-9 * scale
    if a - bd - cg >= t and e - bd - fh >= t and i - cg - fh >= t:  # (NaN: not taken)
        return True
    S = 0.5 * (I + I.T)
    return bool(np.linalg.eigvalsh(S)[0] >= -1e-9 * scale)


def _geometry(gm: pin.GeometryModel, jmap: dict[int, int]) -> pin.GeometryModel:
    out = pin.GeometryModel()
    for g in gm.geometryObjects:
        h = g.copy()
        h.parentJoint = jmap[g.parentJoint]
        out.addGeometryObject(h)
    return out


def _passive(
    robot: Robot,
    new: pin.Model,
    q_index: np.ndarray,
    v_index: np.ndarray,
    carrier: Callable[[int, pin.SE3], tuple[int, pin.SE3]],
    links: Sequence[LinkCompliance],
    defl: np.ndarray,
) -> PassiveForces:
    """The robot's passive elements on the extended tree, plus the virtual link springs."""
    P = robot.passive
    stiffness, damping, friction = np.zeros(new.nv), np.zeros(new.nv), np.zeros(new.nv)
    rest = pin.neutral(new)
    springs: list[FrameSpring] = []
    smoothing = 1e-2
    if P is not None:
        stiffness[v_index] = P.stiffness
        damping[v_index] = P.damping
        friction[v_index] = P.friction
        rest[q_index] = P.rest
        smoothing = P.smoothing
        for s in P.springs:
            j1, o1 = carrier(s.joint1, s.placement1)
            j2, o2 = carrier(s.joint2, s.placement2)
            springs.append(
                dataclasses.replace(
                    s, joint1=j1, placement1=o1 * s.placement1, joint2=j2,
                    placement2=o2 * s.placement2,
                )
            )  # fmt: skip
    for lc, iv in zip(links, defl, strict=True):
        stiffness[iv] = lc.stiffness
    return PassiveForces(
        new,
        stiffness=stiffness,
        rest=rest,
        damping=damping,
        friction=friction,
        smoothing=smoothing,
        springs=springs,
    )
