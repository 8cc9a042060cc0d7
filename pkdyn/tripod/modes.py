"""Operating modes of the walking tripod (seed 003): PP (payload platform), BE (branch extremity).

A *stance* gives the foot frames ``R_Ai`` on the support (three for the tripod, four for the
four-branch walker, ``branches=4`` of :mod:`pkdyn.library.tripod`); a *mode* says which feet are
clamped and which passive joints are locked:

- **PP**: the three feet are welded at their footholds, no lock; the robot is a 6-DOF parallel
  machine and the platform is the spindle tip (the library model's ``platform``).
- **BE** (branch ``i`` swinging): foot ``i`` is free (its weld is removed), the paper's
  ``q1, q2, q3, q6`` of branch ``i`` and ``q1`` of the two support branches ``j, k`` are locked
  (the paper's ``b_i``); the platform is the extremity of branch ``i`` (its foot frame, origin
  ``A_i``). The six actuators then control the 6-DOF foot: the support branches with ``q1``
  locked hold the nacelle with four actuators (4 DOF), the swinging branch's triangle adds 2.

The **four-branch walker** in mode BE keeps the paper's locks of the swinging branch (``q1, q2,
q3, q6``): they make the branch a rigid body from the foot to its triangle, whose two actuators
give the foot 2 DOF with respect to the nacelle. The paper locks ``q1`` of the support branches
only because two of them, with four actuators, cannot hold a 6-DOF nacelle; three support branches
(six actuators) can, exactly as in mode PP, so the walker locks nothing on its support branches
(locking their ``q1`` would leave the nacelle 3 DOF and the foot 5: it could not follow a 6-DOF
path). The nacelle keeps its 6 DOF, the foot takes 6 of the mechanism's 8: the paper's
"connectivity of eight", two degrees of freedom left to the nacelle while the foot follows its path
(:mod:`pkdyn.tripod.redundancy` chooses them). In mode PP the walker's eight actuators drive a
6-DOF nacelle: redundant actuation (the inverse dynamics distributes the forces, see
:func:`pkdyn.dynamics.inverse_dynamics`).

Locks are rigid constraint models (:mod:`pkdyn.tripod.locks`) added to the closures: the
swinging branch's universal joint (``q1`` and ``q2``) is welded, ``q3`` (the knuckle on rod
``L``, joint ``branch{i}_a``, see :func:`pkdyn.library.tripod_cf.lockable_coordinates`) and ``q6``
(joint ``branch{i}_q6``) are point locks, and ``q1`` of a support branch is the point lock of the
universal joint's second coordinate. :func:`mode_robot` returns a :class:`pkdyn.Robot` with this
constraint set and platform, so the general machinery (assembly, inverse geometry, kinematic
models, singularities, inverse and forward dynamics) applies to either mode unchanged.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.library import tripod
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.tripod.locks import Lock, lock_constraint, lock_values
from solvers import Closure

__all__ = [
    "BRANCHES",
    "LOCKABLE",
    "Mode",
    "Stance",
    "be_mode",
    "branch_numbers",
    "foot_frame",
    "foot_placement",
    "locked_names",
    "mode_robot",
    "pp_mode",
    "support_branches",
]

BRANCHES = (1, 2, 3)
"""Branch numbers of the tripod (the paper's ``i``); :func:`branch_numbers` for the walker."""

LOCKABLE: dict[str, tuple[str, int]] = {
    "q1": ("q2q1", 1),
    "q2": ("q2q1", 0),
    "q3": ("a", 0),
    "q6": ("q6", 0),
}
"""The paper's lockable joints -> (model joint suffix, coordinate) in branch ``i``
(joint ``branch{i}_<suffix>``)."""

_FOOT_TURN = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, np.pi), np.zeros(3))
"""The foot link frame is ``R_A`` turned half a turn about ``w_a`` (see the library module)."""


def branch_numbers(source: Robot | tripod.Params | int) -> tuple[int, ...]:
    """Branch numbers ``1 .. n`` of a tripod or walker (its robot, its parameters or ``n``)."""
    if isinstance(source, Robot | tripod.Params):
        p = source.params if isinstance(source, Robot) else source
        n = tripod_cf.branch_count(p)
    elif (
        isinstance(source, bool) or not isinstance(source, int | np.integer) or source not in (3, 4)
    ):
        raise InvalidInputError(
            "branches", f"expected 3 (tripod) or 4 (walker), or the robot, got {source!r:.40}"
        )
    else:
        n = int(source)
    return tuple(range(1, n + 1))


def support_branches(branch: int, branches: int = 3) -> tuple[int, ...]:
    """The support branches while branch ``i`` swings.

    The paper's ``(j, k)`` for the tripod ((1: 2, 3), (2: 1, 3), (3: 1, 2)); the three others for
    the walker (``branches=4``).
    """
    _check_branch(branch, branches)
    return tuple(b for b in branch_numbers(branches) if b != branch)


def locked_names(branch: int, branches: int = 3) -> list[str]:
    """The locked joints of mode BE(i), named ``branch{n}_q{m}`` in the paper's order.

    The tripod's are the paper's ``b_i``: ``q1, q2, q3, q6`` of branch ``i``, ``q1`` of ``j``
    and ``k``; the walker's (``branches=4``) are ``q1, q2, q3, q6`` of branch ``i`` only (see the
    module docstring).

    Args:
        branch: Swinging branch ``i``.
        branches: Number of branches (3 or 4).

    Returns:
        The names.

    """
    supports = support_branches(branch, branches)
    own = [f"branch{branch}_{n}" for n in ("q1", "q2", "q3", "q6")]
    return own + ([f"branch{b}_q1" for b in supports] if branches == 3 else [])


def _site(branch: int, name: str) -> tuple[str, list[int]]:
    """Model joint and coordinate of the paper's lockable joint ``name`` of a branch."""
    suffix, coord = LOCKABLE[name]
    return f"branch{branch}_{suffix}", [coord]


def _check_branch(branch: int, branches: int = 3) -> None:
    if (
        isinstance(branch, bool)
        or not isinstance(branch, int | np.integer)
        or branch not in branch_numbers(branches)
    ):
        raise InvalidInputError(
            "branch", f"expected 1 to {branches} ({branches} branches), got {branch!r}"
        )


@dataclass(frozen=True, eq=False)
class Stance:
    """Foot frames ``R_Ai`` of the branches (3 or 4), in the support frame ``R_B``.

    Origin ``A_i`` at the universal-joint centre, ``w_a`` normal to the support.

    Attributes:
        footholds: One placement per branch.

    """

    footholds: tuple[pin.SE3, ...]

    def __post_init__(self) -> None:
        if (
            not isinstance(self.footholds, tuple | list)
            or len(self.footholds) not in (3, 4)
            or not all(isinstance(f, pin.SE3) for f in self.footholds)
        ):
            raise InvalidInputError(
                "stance", "expected three (tripod) or four (walker) pin.SE3 foot frames"
            )

    @classmethod
    def default(cls, p: tripod.Params) -> Stance:
        """The library model's footholds (:func:`pkdyn.closed_form.tripod.foothold_frames`)."""
        if not isinstance(p, tripod.Params):
            raise InvalidInputError(
                "p", f"expected the tripod's parameters (robot.params), got {p!r:.40}"
            )
        return cls(tuple(tripod_cf.foothold_frames(p)))

    @property
    def branches(self) -> int:
        """Number of feet."""
        return len(self.footholds)

    def moved(self, branch: int, foothold: pin.SE3) -> Stance:
        """The same stance with foot ``branch`` on a new foothold."""
        _check_branch(branch, self.branches)
        if not isinstance(foothold, pin.SE3):
            raise InvalidInputError("foothold", f"expected a pin.SE3, got {foothold!r:.40}")
        f = list(self.footholds)
        f[branch - 1] = pin.SE3(foothold)
        return Stance(tuple(f))

    def centroid(self) -> np.ndarray:
        """Mean of the foot-frame origins [m]."""
        return np.mean([np.array(f.translation) for f in self.footholds], axis=0)


@dataclass(frozen=True)
class Mode:
    """Which feet are clamped and which joints locked.

    Attributes:
        kind: ``"PP"`` or ``"BE"``.
        branch: Swinging branch (BE), ``None`` for PP.
        locks: Model-level locks (the swinging branch's ``q1`` and ``q2`` form one).
        locked: The paper's names of the locked joints (:func:`locked_names`).

    """

    kind: str
    branch: int | None = None
    locks: tuple[Lock, ...] = ()
    locked: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.kind not in ("PP", "BE"):
            raise InvalidInputError("kind", f"expected 'PP' or 'BE', got {self.kind!r:.40}")
        if self.branch is not None:
            _check_branch(self.branch, 4)
        if self.kind == "BE" and self.branch is None:
            raise InvalidInputError("branch", "mode BE needs its swinging branch")

    def lock_vector(self, robot: Robot, q: np.ndarray) -> np.ndarray:
        """Current values of the locked coordinates at ``q``, in the order of ``locks``.

        Args:
            robot: The tripod.
            q: Configuration (nq,).

        Returns:
            The values [rad], one per locked coordinate.

        """
        from pkdyn.model.arguments import check_robot, configuration

        q = configuration(check_robot(robot), q)
        out: list[float] = []
        for lk in self.locks:
            out.extend(lock_values(robot.model, q, lk.joint, lk.coordinates))
        return np.array(out)

    def lock_targets(self) -> np.ndarray:
        """Locked values [rad], in the order of :meth:`lock_vector`."""
        return np.array([v for lk in self.locks for v in lk.values])


def pp_mode() -> Mode:
    """Mode PP: all feet clamped, no lock."""
    return Mode("PP")


@public
def be_mode(
    robot: Robot, q: np.ndarray, branch: int, values: Sequence[float] | None = None
) -> Mode:
    """Mode BE for swinging branch ``i``: the joints of :func:`locked_names` locked.

    Args:
        robot: The tripod or the walker.
        q: Configuration (nq,) whose joint values are locked (unless ``values`` is given).
        branch: Swinging branch ``i``.
        values: Model coordinates of ``[q1_i, q2_i, q3_i, q6_i, q1_j, q1_k]`` (tripod) or
            ``[q1_i, q2_i, q3_i, q6_i]`` (walker) [rad] (e.g. from
            :func:`pkdyn.tripod.xfkmb.bikmx`); default: their values at ``q``.

    Returns:
        The mode, with one lock per model joint.

    """
    n = len(branch_numbers(robot)) if robot.params is not None else 3
    supports = support_branches(branch, n)
    names = locked_names(branch, n)
    held = supports if n == 3 else ()
    if values is None:
        sites = [(branch, "q1"), (branch, "q2"), (branch, "q3"), (branch, "q6")]
        sites += [(s, "q1") for s in held]
        vals = [lock_values(robot.model, q, *_site(b, m))[0] for b, m in sites]
    else:
        from pkdyn.inputs import vector

        vals = [float(v) for v in vector("values", values, len(names), "rad")]
    b = f"branch{branch}"
    locks = (
        Lock(f"{b}_q2q1", (0, 1), (vals[1], vals[0]), f"{b}_q1,{b}_q2"),
        Lock(f"{b}_a", (0,), (vals[2],), f"{b}_q3"),
        Lock(f"{b}_q6", (0,), (vals[3],), f"{b}_q6"),
    ) + tuple(
        Lock(f"branch{s}_q2q1", (1,), (vals[4 + m],), f"branch{s}_q1") for m, s in enumerate(held)
    )
    return Mode("BE", branch, locks, tuple(names))


def foot_frame(foothold: pin.SE3) -> pin.SE3:
    """Placement of a foot link frame (the BE platform) clamped on foot frame ``R_A``."""
    if not isinstance(foothold, pin.SE3):
        raise InvalidInputError("foothold", f"expected a pin.SE3, got {foothold!r:.40}")
    return pin.SE3(foothold) * _FOOT_TURN


@public
def foot_placement(robot: Robot, q: np.ndarray, branch: int) -> pin.SE3:
    """Foot frame ``R_A`` of branch ``i`` at ``q`` (origin ``A_i``, ``w_a`` the sole normal).

    Args:
        robot: The tripod or the walker.
        q: Configuration (nq,).
        branch: Branch number.

    Returns:
        The placement in ``R_B``.

    """
    _check_branch(branch, len(branch_numbers(robot)) if robot.params is not None else 3)
    fid = robot.model.getFrameId(f"branch{branch}_foot")
    pin.framesForwardKinematics(robot.model, robot.data, q)
    return pin.SE3(robot.data.oMf[fid]) * _FOOT_TURN.inverse()


@public
def mode_robot(robot: Robot, stance: Stance, mode: Mode, q: np.ndarray | None = None) -> Robot:
    """The tripod with the constraint set and platform of a mode on a stance.

    Args:
        robot: The library tripod (``pkdyn.load("tripod")``) or walker
            (``pkdyn.load("tripod", branches=4)``).
        stance: Foot frames.
        mode: :func:`pp_mode` or :func:`be_mode`.
        q: Reference configuration kept as ``q_home`` of the result (default: the robot's).

    Returns:
        A :class:`pkdyn.Robot` sharing the model and geometry: closures = the ``A``
        hinges, the welds of the clamped feet at the stance's footholds, the locks; platform =
        the spindle tip (PP) or the swinging foot frame (BE), all six pose components.

    Raises:
        PkdynError: ``robot`` is not the library tripod.

    """
    if robot.family != "tripod":
        raise PkdynError(
            f"{robot.name}: tripod modes need the library tripod (pkdyn.load('tripod')) "
            "to know its footholds"
        )
    from pkdyn.inputs import instance

    instance("stance", stance, Stance, "a Stance (pkdyn.tripod.Stance.default)")
    instance("mode", mode, Mode, "a Mode (pkdyn.tripod.pp_mode, be_mode)")
    p: tripod.Params = robot.params
    model = robot.model
    default = tripod_cf.foothold_frames(p)
    if len(stance.footholds) != len(default):
        raise InvalidInputError(
            "stance",
            f"{len(stance.footholds)} footholds for a robot of {len(default)} branches",
        )
    cms: list[pin.RigidConstraintModel] = []
    owner: list[str] = []
    for cm, name in zip(robot.constraint_models, robot.constraint_owner, strict=True):
        if name.endswith("_foothold"):
            b = int(name[len("branch")])
            if mode.kind == "BE" and b == mode.branch:
                continue
            M2 = stance.footholds[b - 1] * default[b - 1].inverse() * cm.joint2_placement
            cm = pin.RigidConstraintModel(
                cm.type,
                model,
                cm.joint1_id,
                cm.joint1_placement,
                cm.joint2_id,
                M2,
                pin.ReferenceFrame.LOCAL,
            )
            cm.name = name
        cms.append(cm)
        owner.append(name)
    closures: list[Closure] = []
    for c in robot.constraints.closure_specs:
        if c.name.endswith("_foothold"):
            b = int(c.name[len("branch")])
            if mode.kind == "BE" and b == mode.branch:
                continue
            M2 = stance.footholds[b - 1] * default[b - 1].inverse() * c.placement2
            c = dataclasses.replace(c, placement2=M2)
        closures.append(c)
    for lk in mode.locks:
        cms.append(lock_constraint(model, lk))
        owner.append(lk.name)
        closures.append(Closure.of(cms[-1]))
    vec = pin.StdVec_RigidConstraintModel()
    for cm in cms:
        vec.append(cm)
    if mode.kind == "BE":
        assert mode.branch is not None
        platform = model.getFrameId(f"branch{mode.branch}_foot")
    else:
        platform = robot.platform_frame
    return dataclasses.replace(
        robot,
        name=f"{robot.name}[{mode.kind}{'' if mode.branch is None else mode.branch}]",
        constraint_models=vec,
        constraint_owner=owner,
        constraints=robot.constraints.rebuilt(closures=closures),
        platform_frame=platform,
        task_rows=np.arange(6),
        q_home=np.array(robot.q_home if q is None else q, dtype=float),
    )
