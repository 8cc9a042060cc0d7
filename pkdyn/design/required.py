"""A robot against a required workspace: reach and limits, conditioning, interference clearance.

:func:`required_check` picks the fastest exact path the robot allows:

- the library Delta (ball-jointed parallelograms): Clavel's closed forms
  (:class:`pkdyn.workspace.delta.DeltaEvaluator`, :func:`pkdyn.analysis.maps.delta_conditioning`),
  vectorised; clearance between bars and arms as cylinders (analytic segment distances, which
  agree with coal: see the tests);
- leg robots (Gough-Stewart kind): leg vectors (:class:`pkdyn.workspace.legs.HexapodLegs`) and
  reciprocal screws (:func:`pkdyn.analysis.screws.gough_stewart_AB`), vectorised;
- any other robot: pose by pose, the general inverse geometric model, the limits of
  :func:`pkdyn.workspace.numeric.configuration_violation`, :func:`pkdyn.analysis.dexterity` and
  coal distances (:class:`pkdyn.analysis.collisions.CollisionChecker`).

Each gives, per required pose, the first limit broken (codes of
:data:`pkdyn.workspace.limits.LIMIT_KINDS`, -1 when reached), ``1 / cond(J)`` (the local
conditioning index) and the interference clearance [m], NaN where the pose is not reached.
"""

from __future__ import annotations

import warnings
from abc import ABC, abstractmethod
from functools import cached_property

import numpy as np
import pinocchio as pin

from pkdyn.analysis.collisions import CollisionChecker
from pkdyn.analysis.dexterity import dexterity
from pkdyn.analysis.kinematics import COND_MAX
from pkdyn.analysis.maps import conditioning
from pkdyn.analysis.screws import delta_AB, gough_stewart_AB
from pkdyn.closed_form import delta as delta_cf
from pkdyn.design.requirement import Requirement
from pkdyn.exceptions import AssemblyError, PkdynError
from pkdyn.model.assembly import inverse_geometry
from pkdyn.model.robot import Robot
from pkdyn.workspace.delta import DeltaEvaluator
from pkdyn.workspace.legs import HexapodLegs
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE, check_kinds
from pkdyn.workspace.numeric import configuration_violation

__all__ = ["RequiredCheck", "required_check"]

_TASK = ("x", "y", "z", "rx", "ry", "rz")


class RequiredCheck(ABC):
    """Per-pose figures of a robot on a required workspace (computed on first use).

    Attributes:
        robot: The robot.
        P: Platform positions (N, 3) [m].
        R: Platform orientations (N, 3, 3).
        kinds: Limit kinds checked besides reach.
        length: Characteristic length for the angular rows of ``J`` [m] (``None``: none).
        method: How the poses are checked.

    """

    method = ""

    def __init__(
        self,
        robot: Robot,
        P: np.ndarray,
        R: np.ndarray,
        kinds: tuple[str, ...],
        length: float | None,
    ) -> None:
        self.robot = robot
        self.P = np.asarray(P, dtype=float)
        self.R = np.asarray(R, dtype=float)
        self.kinds = check_kinds(kinds)
        self.length = length

    @property
    @abstractmethod
    def codes(self) -> np.ndarray:
        """First limit broken per pose (N,) (-1: reached within the limits)."""

    @property
    @abstractmethod
    def inv_cond(self) -> np.ndarray:
        """``1 / cond(J)`` per pose (N,), NaN where not reached."""

    @property
    @abstractmethod
    def clearance(self) -> np.ndarray:
        """Interference clearance per pose (N,) [m] (negative: overlap), NaN where not reached."""

    @property
    def reached(self) -> np.ndarray:
        """(N,) True where the pose is reached within the limits."""
        return self.codes == REACHABLE

    @property
    def fraction(self) -> float:
        """Fraction of the required poses reached within the limits."""
        return float(np.mean(self.reached))


class _DeltaCheck(RequiredCheck):
    method = "closed form (Clavel's models)"

    @cached_property
    def _evaluator(self) -> DeltaEvaluator:
        return DeltaEvaluator(self.robot)

    @cached_property
    def _solved(self) -> tuple[np.ndarray, np.ndarray]:
        """Clavel's inverse model at the poses, shared by the checks."""
        return delta_cf.inverse(self.robot.params, self.P)

    @cached_property
    def _checked(self) -> tuple[np.ndarray, tuple[np.ndarray, list[np.ndarray], np.ndarray] | None]:
        """The limits' codes, and the elbows of the poses within them (when made)."""
        return self._evaluator._violations(self.P, self.kinds, 0.0, self._solved)

    @property
    def codes(self) -> np.ndarray:
        return self._checked[0]

    @cached_property
    def inv_cond(self) -> np.ndarray:
        """``1 / cond(J)`` from Clavel's ``J^-1 = B^-1 A`` (rows ``d_i / B_ii``), one SVD."""
        ok = self.reached
        out = np.full(ok.size, np.nan)
        if ok.any():
            P = self.P[ok]
            alpha = self._solved[0][ok]
            A, B = delta_AB(self.robot.params, P, alpha)
            with np.errstate(divide="ignore", invalid="ignore"):
                Jinv = A / np.einsum("nii->ni", B)[..., None]
                s = np.linalg.svd(np.nan_to_num(Jinv, posinf=0.0, neginf=0.0), compute_uv=False)
                lci = np.where(s[:, 0] > 0, s[:, -1] / s[:, 0], 0.0)
            out[ok] = np.where(lci * COND_MAX > 1.0, lci, 0.0)
        return out

    @cached_property
    def clearance(self) -> np.ndarray:
        ok = self.reached
        out = np.full(ok.size, np.nan)
        if ok.any():
            made = self._checked[1]
            if made is None:
                out[ok] = self._evaluator.clearance(self.P[ok], self._solved[0][ok])
            else:  # the limits' elbows of the reached poses (the same numbers, made once)
                todo, E, tip = made
                out[todo] = self._evaluator._clearance(self.P[todo], E, tip)
        return out


class _LegCheck(RequiredCheck):
    method = "closed form (leg vectors, reciprocal screws)"

    @cached_property
    def _legs(self) -> HexapodLegs:
        return HexapodLegs.from_robot(self.robot, "the required workspace")

    @cached_property
    def _v(self) -> np.ndarray:
        return self._legs.leg_vectors(self.P, self.R)

    @cached_property
    def codes(self) -> np.ndarray:
        legs, v = self._legs, self._v
        out = np.full(v.shape[0], REACHABLE, dtype=np.int8)
        for kind, test in (("stroke", legs.stroke_bad), ("joint", legs.joint_bad)):
            if kind in self.kinds:
                todo = np.flatnonzero(out == REACHABLE)
                out[todo[test(v[todo])]] = LIMIT_KINDS.index(kind)
        return out

    @cached_property
    def inv_cond(self) -> np.ndarray:
        ok = self.reached
        out = np.full(ok.size, np.nan)
        if ok.any():
            P = self.P[ok]
            R = self.R[ok]
            Bw = P[:, None, :] + np.einsum("nij,kj->nki", R, self._legs.B)
            A, B = gough_stewart_AB(self._legs.A, Bw, P, R)
            task = tuple(_TASK[int(i)] for i in self.robot.task_rows)
            out[ok] = conditioning(A, B, np.ones(len(P), dtype=bool), task, self.length).lci
        return out

    @cached_property
    def clearance(self) -> np.ndarray:
        ok = self.reached
        out = np.full(ok.size, np.nan)
        if ok.any() and self._legs.n > 1:
            out[ok] = np.min(self._legs.pair_distances(self._v[ok]), axis=1)
        return out


class _NumericCheck(RequiredCheck):
    method = "numeric (inverse geometric model, dexterity, coal)"

    @cached_property
    def _solved(self) -> tuple[np.ndarray, list[np.ndarray | None]]:
        """First limit broken and configuration (``None`` unless reached) per pose.

        Each pose is solved from the previous solution, then from ``q_home`` if that fails or
        breaks a limit (as :class:`pkdyn.workspace.numeric.NumericEvaluator` does).
        """
        robot = self.robot
        codes = np.full(len(self.P), LIMIT_KINDS.index("reach"), dtype=np.int8)
        qs: list[np.ndarray | None] = []
        q = robot.q_home
        for k, (P, R) in enumerate(zip(self.P, self.R, strict=True)):
            found = None
            for q0 in (q, robot.q_home):
                try:
                    sol = inverse_geometry(robot, pin.SE3(R, P), q_init=q0, check_limits=False).q
                except AssemblyError:
                    continue
                codes[k] = configuration_violation(robot, sol, self.kinds, 0.0)
                if codes[k] == REACHABLE:
                    found = q = sol
                    break
            qs.append(found)
        return codes, qs

    @property
    def codes(self) -> np.ndarray:
        return self._solved[0]

    @cached_property
    def inv_cond(self) -> np.ndarray:
        out = np.full(len(self._solved[1]), np.nan)
        for k, q in enumerate(self._solved[1]):
            if q is not None:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    out[k] = dexterity(self.robot, q, self.length).lci
        return out

    @cached_property
    def clearance(self) -> np.ndarray:
        out = np.full(len(self._solved[1]), np.nan)
        if any(q is not None for q in self._solved[1]):
            checker = CollisionChecker(self.robot)
            for k, q in enumerate(self._solved[1]):
                if q is not None:
                    out[k] = float(np.min(checker.distances(q)))
        return out


def _leg_robot(robot: Robot) -> bool:
    try:
        legs = HexapodLegs.from_robot(robot)
    except PkdynError:
        return False
    return legs.n == 6 and len(robot.task_rows) == 6


def required_check(
    robot: Robot,
    requirement: Requirement | np.ndarray,
    kinds: tuple[str, ...] = ("stroke", "joint"),
    length: float | None = None,
    rotations: np.ndarray | None = None,
) -> RequiredCheck:
    """The figures of ``robot`` at required poses, by the fastest exact path it allows.

    Args:
        robot: The robot (with geometry for the clearance).
        requirement: The required workspace, or platform positions (N, 3) [m].
        kinds: Limit kinds checked besides reach (``stroke``, ``joint``; interference is the
            clearance, a separate figure).
        length: Characteristic length for the angular rows of ``J`` [m].
        rotations: Platform orientations (N, 3, 3) with positions (default: identity).

    Returns:
        The check (its figures are computed on first use).

    """
    if isinstance(requirement, Requirement):
        P, R = requirement.positions, requirement.rotations
    else:
        P = np.atleast_2d(np.asarray(requirement, dtype=float))
        R = np.broadcast_to(np.eye(3), (len(P), 3, 3)) if rotations is None else rotations
    if DeltaEvaluator.accepts(robot):
        return _DeltaCheck(robot, P, R, kinds, length)
    if _leg_robot(robot):
        return _LegCheck(robot, P, R, kinds, length)
    return _NumericCheck(robot, P, R, kinds, length)
