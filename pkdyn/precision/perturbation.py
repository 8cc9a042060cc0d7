"""A robot with its placements moved: the nonlinear model of geometric errors.

:func:`perturbed` applies parameters of a :class:`~pkdyn.precision.parameters.ParameterModel`
exactly (``M -> M exp(xi)`` for every placement); :func:`with_placements` puts given placements
(e.g. those a family builder gives for other dimensions). Both return a new
:class:`pkdyn.Robot` (copies of the model, its closures and description; the original is left
alone) assembled near the original's home, with ``params`` dropped: the family's closed forms no
longer describe it. The actuator gains of a model are returned beside it (:class:`Perturbed`):
the joint coordinate of an actuator reading ``qa`` is ``(1 + gain) qa``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.model.assembly import forward_geometry
from pkdyn.model.build import constraint_set, find_frame
from pkdyn.model.description import ClosureSpec, FrameRef
from pkdyn.model.reuse import kept, kept_data
from pkdyn.model.robot import Robot, length_scale_at
from pkdyn.precision.parameters import ParameterModel, Placement, local_placement
from solvers.closure import Closure
from solvers.constraints import ConstraintSet

__all__ = ["Perturbed", "perturbed", "with_placements"]


@dataclass(eq=False)
class Perturbed:
    """A robot with geometric errors, and the relative gains of its actuators.

    Attributes:
        robot: The robot with the moved placements.
        gains: Relative actuator gains (n_a,): joint coordinate = ``(1 + gains) * reading``.

    """

    robot: Robot
    gains: np.ndarray

    def joint_coordinates(self, readings: Sequence[float] | np.ndarray) -> np.ndarray:
        """Actuated joint coordinates from actuator readings (..., n_a) [rad or m]."""
        return (1.0 + self.gains) * np.asarray(readings, dtype=float)


def perturbed(
    robot: Robot,
    model: ParameterModel,
    p: Sequence[float] | np.ndarray,
    assemble: bool = True,
    *,
    shared: bool = False,
) -> Perturbed:
    """The robot with parameters ``p`` of ``model`` applied (nonlinear: ``M exp(E p)``).

    Args:
        robot: The nominal robot (the model's).
        model: The parameter model.
        p: Parameter values (n_par,) [m, rad, -]: errors from the nominal robot.

        assemble: Assemble its home near the original's (``False``: ``q_home`` is the
            original's, for a caller that solves its own configurations, as the Monte Carlo).
        shared: Write into one working copy of the model kept for ``robot`` (the Monte
            Carlo's robots, one at a time): the robot returned is valid until the next call.

    Returns:
        The perturbed robot and its actuator gains.

    """
    p = np.asarray(p, dtype=float)
    xi = model.twists(p)
    moved = np.any(xi != 0.0, axis=1).tolist()
    nominal = _nominal(robot, model, shared)
    new = [  # (a placement not moved is left as it is: M exp(0) = M)
        M * pin.exp6(x) if m else M for M, x, m in zip(nominal, xi, moved, strict=True)
    ]
    out = _rebuilt(robot, model.placements, new, moved, assemble, shared)
    return Perturbed(out, model.gains(p))


def _nominal(robot: Robot, model: ParameterModel, shared: bool) -> list[pin.SE3]:
    """The model's placements' nominal values (:func:`local_placement`), kept if ``shared``.

    Kept per robot and parameter model (the model by identity: hashing its placements costs
    more than the rest of a robot's placements).
    """

    def make() -> list[pin.SE3]:
        return [local_placement(robot, pl) for pl in model.placements]

    return kept(robot, ("nominal placements", model), make) if shared else make()


def with_placements(
    robot: Robot, where: Sequence[Placement], values: Sequence[pin.SE3], assemble: bool = True
) -> Robot:
    """The robot with the given placements replaced.

    Args:
        robot: The robot.
        where: Placements (:func:`pkdyn.precision.parameters.placements`).
        values: Their new values (in the parent joint frame for joints, in the joint frame of
            the placed frame for closure frames and the platform).
        assemble: Assemble its home near ``robot``'s (see :func:`perturbed`).

    Returns:
        The new robot, assembled near ``robot``'s home.

    """
    moved = [
        not local_placement(robot, pl).isApprox(M, 0.0) for pl, M in zip(where, values, strict=True)
    ]
    return _rebuilt(robot, list(where), list(values), moved, assemble)


def _rebuilt(
    robot: Robot,
    where: Sequence[Placement],
    values: Sequence[pin.SE3],
    moved: Sequence[bool],
    assemble: bool = True,
    shared: bool = False,
) -> Robot:
    work = _shared(robot) if shared else None
    if work is not None:  # one working copy per robot, every placement written (Monte Carlo)
        model = work.model
        nominal = robot.model
        for pl in where:
            if pl.kind == "joint":
                model.jointPlacements[pl.joint] = nominal.jointPlacements[pl.joint]
        if robot.platform_frame is not None:
            pf = robot.platform_frame
            model.frames[pf].placement = nominal.frames[pf].placement
        first, arms = work.first, work.arms
    else:
        model = pin.Model(robot.model)
        first, arms = _closure_frames(robot)
    desc = robot.description
    platform = desc.platform
    frames: dict[tuple[str, int], pin.SE3] = {}
    for pl, M, m in zip(where, values, moved, strict=True):
        if not m:
            continue
        if pl.kind == "joint":
            model.jointPlacements[pl.joint] = M
        elif pl.kind == "closure":
            frames[(pl.closure, pl.side)] = M
        else:
            assert robot.platform_frame is not None
            old = model.frames[robot.platform_frame].placement
            model.frames[robot.platform_frame].placement = M
            if platform is not None:  # the link-frame placement moves by the same right factor
                fr = platform.frame
                delta = old.actInv(M)
                platform = dataclasses.replace(
                    platform, frame=FrameRef(fr.link, fr.placement * delta)
                )
    layer = work.constraints if work is not None else None  # (moved in place, if not None)
    cms = work.cms if work is not None and layer is not None else pin.StdVec_RigidConstraintModel()
    for k, (cm, owner, (off1, off2)) in enumerate(
        zip(robot.constraint_models, robot.constraint_owner, arms, strict=True)
    ):
        f1, f2 = first[owner]  # a hinge's arm models are offsets of these
        new1 = frames.get((owner, 1), f1) * off1
        new2 = frames.get((owner, 2), f2) * off2
        if layer is not None:  # (the working copies: the same numbers written in place)
            cms[k].joint1_placement = new1
            cms[k].joint2_placement = new2
            continue
        c = pin.RigidConstraintModel(
            cm.type, model, cm.joint1_id, new1, cm.joint2_id, new2, cm.reference_frame
        )
        c.name = cm.name
        cms.append(c)
    new_closures = []
    for c in desc.closures:
        ref = []
        for side, fr in ((1, c.frame1), (2, c.frame2)):
            if (c.name, side) in frames:
                f_old = first[c.name][side - 1]
                fr = FrameRef(fr.link, fr.placement * f_old.actInv(frames[(c.name, side)]))
            ref.append(fr)
        new_closures.append(dataclasses.replace(c, frame1=ref[0], frame2=ref[1]))
    desc = dataclasses.replace(desc, closures=tuple(new_closures), platform=platform)
    # the constraint layer of the perturbed description (couplings depend on no placement)
    if layer is not None:
        assert work is not None
        constraints = layer
        constraints.move_closures(work.resolved(desc.closures))
    else:
        constraints = constraint_set(model, desc.closures, desc.couplings, robot.name)
    out = dataclasses.replace(
        robot,
        model=model,
        data=model.createData() if work is None else work.data,
        description=desc,
        constraint_models=cms,
        constraints=constraints,
        params=None,
    )
    if work is not None:  # (the same joints: which actuators are prismatic)
        out.__dict__["_actuator_prismatic"] = work.prismatic
    if assemble:
        out.q_home = forward_geometry(
            out, robot.q_home[robot.actuated_q], q_init=robot.q_home, check_limits=False
        ).q
    else:  # (its length scale computed in the kept data, not a new one)
        out.__dict__["length_scale"] = length_scale_at(model, out.data, out.q_home)
    return out


@dataclass(eq=False)
class _Shared:
    """The working copy :func:`perturbed` writes each robot into when ``shared`` (per robot).

    Attributes:
        model: A copy of the robot's model, its placements written for each robot.
        data: A data of it.
        first: The two frames of each closure (:func:`_closure_frames`).
        arms: Each constraint model's offsets from them.
        prismatic: Which actuators are prismatic (the robot's).
        cms: Copies of the constraint models on ``model``, written for each robot.
        constraints: A constraint layer on ``model`` whose closures are moved in place
            (:meth:`solvers.constraints.ConstraintSet.move_closures`), or ``None`` where its
            rows depend on the placements (each robot then gets a layer of its own).
        frame_ids: Per closure of the description, the ids of the frames its two sides name.

    """

    model: pin.Model
    data: pin.Data
    first: dict[str, tuple[pin.SE3, pin.SE3]]
    arms: list[tuple[pin.SE3, pin.SE3]]
    prismatic: np.ndarray
    cms: pin.StdVec_RigidConstraintModel
    constraints: ConstraintSet | None
    frame_ids: list[tuple[int, int]]

    def resolved(self, specs: Sequence[ClosureSpec]) -> list[Closure]:
        """The solver closures of closure specs on :attr:`model` (as :func:`closures`).

        The frames found once (:attr:`frame_ids`): the same products as
        :func:`pkdyn.model.build.resolve_frame`, without its look-ups by name.
        """
        assert self.constraints is not None
        frames = self.model.frames
        return [
            Closure(
                c.name,
                c.kind,
                c.joint1,
                frames[f1].placement * spec.frame1.placement,
                c.joint2,
                frames[f2].placement * spec.frame2.placement,
                c.axis,
            )
            for c, spec, (f1, f2) in zip(
                self.constraints.closure_specs, specs, self.frame_ids, strict=True
            )
        ]


def _shared(robot: Robot) -> _Shared:
    """The working copy of :func:`perturbed` for ``robot`` (kept per robot and thread)."""

    def make() -> _Shared:
        model = pin.Model(robot.model)
        desc = robot.description
        constraints: ConstraintSet | None = constraint_set(
            model, desc.closures, desc.couplings, robot.name
        )
        cms = pin.StdVec_RigidConstraintModel()
        for cm in robot.constraint_models:
            c = pin.RigidConstraintModel(
                cm.type,
                model,
                cm.joint1_id,
                cm.joint1_placement,
                cm.joint2_id,
                cm.joint2_placement,
                cm.reference_frame,
            )
            c.name = cm.name
            cms.append(c)
        ids: list[tuple[int, int]] = []
        for c in desc.closures:
            f1, f2 = find_frame(model, c.frame1.link), find_frame(model, c.frame2.link)
            if f1 is None or f2 is None:  # (a description the robot was not built from)
                constraints = None
                break
            ids.append((f1, f2))
        if constraints is not None and not constraints.movable:
            constraints = None
        first, arms = _closure_frames(robot)
        return _Shared(
            model,
            kept_data(robot, "perturbed robots"),
            first,
            arms,
            robot.actuator_prismatic,
            cms,
            constraints,
            ids,
        )

    return kept(robot, "perturbed robots", make)


def _closure_frames(
    robot: Robot,
) -> tuple[dict[str, tuple[pin.SE3, pin.SE3]], list[tuple[pin.SE3, pin.SE3]]]:
    """The two frames of each closure, and each constraint model's offsets from them."""
    first = {owner: _first_frames(robot, owner) for owner in robot.constraint_owner}
    arms = []
    for cm, owner in zip(robot.constraint_models, robot.constraint_owner, strict=True):
        f1, f2 = first[owner]
        arms.append((f1.actInv(cm.joint1_placement), f2.actInv(cm.joint2_placement)))
    return first, arms


def _first_frames(robot: Robot, closure: str) -> tuple[pin.SE3, pin.SE3]:
    """The two frames of a closure (placements of its first constraint model)."""
    k = robot.constraint_owner.index(closure)
    cm = robot.constraint_models[k]
    return pin.SE3(cm.joint1_placement), pin.SE3(cm.joint2_placement)
