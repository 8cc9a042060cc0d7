"""Whether a precision figure is defined: the scale-aware rule behind every precision figure.

A figure is reported only where it is defined, judged against the robot's own scale (its size
``L``, :attr:`pkdyn.Robot.length_scale`, and its springs), never against a fixed threshold:

- **Stiffness and compliance.** The task compliance ``C`` is made dimensionless with the robot's
  **reference stiffness** ``k_ref`` (its stiffest spring in rotational units: a revolute
  actuator's or joint spring's ``k`` [N m/rad], a prismatic one's or a link's translational
  ``k L^2``) and its size: ``C' = k_ref S C S``, ``S = diag(1/L, 1)`` on translations and
  rotations. A mechanism that transmits its springs' motion to the platform through levers of
  its own size has eigenvalues of ``C'`` of order one (at least ``1 / (number of springs)``);
  at a serial singularity the transmission folds and the smallest eigenvalue falls like the
  square of the serial margin of :mod:`pkdyn.analysis.singularity`. So, with the singularity
  rule's own thresholds (:data:`pkdyn.analysis.kinematics.SINGULAR_TOL`,
  :data:`~pkdyn.analysis.kinematics.NEAR_SERIAL_TOL`):

  - ``c'_min <= SINGULAR_TOL^2 max(c'_max, 1)``: the stiffness is **unbounded** along a task
    direction (a serial singularity, or nothing compliant moves the platform along it), or its
    figure is round-off (the cut-off sits a hundred times above the double precision of
    ``C'``): refused, :class:`pkdyn.exceptions.SingularConfigurationError` naming the pose
    and the direction;
  - ``c'_min <= NEAR_SERIAL_TOL^2``: **near** a serial singularity (within about 1e-4 of the
    robot's size of one): reported, flagged with a warning (the stiffness there grows without
    bound towards the singularity and depends on the pose to the last digit).

  Rigid actuators (``inf``) hold their directions by declaration: the rule is applied with them
  freed (given the reference stiffness), so that a direction only they hold is reported as
  **rigid** (infinite stiffness, zero compliance), not as a singularity. Every actuator rigid
  and nothing else compliant: the whole platform is rigid. A motion of the platform without
  any spring deforming (a parallel singularity) makes the stiffness undefined
  (:func:`pkdyn.precision.condensation.compliance` refuses it).
- **Frequencies.** Modes exist about any stable equilibrium; at a pose where the stiffness is
  unbounded the platform does not move to first order in the modes (they are the mechanism's
  own): the result is flagged not valid (``valid`` false, a warning), its frequencies kept.
- **Error budgets.** First-order sensitivities are unbounded at a parallel singularity
  (refused) and vanish along the folded direction at a serial one, where the error is of second
  order: flagged not valid there, with a warning near either (the singularity margins of
  :func:`pkdyn.analysis.kinematics.kinematic_models`, the same thresholds).

Every precision result carries ``valid`` and ``warnings`` (:class:`Validity`), in its JSON and its
table, and issues one :class:`PrecisionWarning` per warning.
"""

from __future__ import annotations

import dataclasses
import warnings as _warnings
import weakref
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pkdyn.analysis.kinematics import (
    NEAR_SERIAL_TOL,
    NEAR_SINGULAR_TOL,
    SINGULAR_TOL,
    NearSingularityWarning,
    kinematic_models,
)
from pkdyn.exceptions import SingularConfigurationError
from pkdyn.model.robot import Robot
from pkdyn.precision.elastic import ElasticModel
from pkdyn.units import vector

__all__ = [
    "NEAR_COMPLIANCE",
    "UNBOUNDED_COMPLIANCE",
    "Flagged",
    "PrecisionWarning",
    "Validity",
    "budget_validity",
    "check_stiffness",
    "coordinate_scales",
    "freed",
    "pose_text",
    "reference_stiffness",
    "scaled_compliance",
    "stiffness_check",
]

UNBOUNDED_COMPLIANCE = SINGULAR_TOL**2
"""Smallest scaled compliance (relative to ``max(c'_max, 1)``) of a bounded stiffness."""

NEAR_COMPLIANCE = NEAR_SERIAL_TOL**2
"""Scaled compliance below which a pose is flagged near a serial singularity."""


class PrecisionWarning(UserWarning):
    """A precision figure is reported but flagged (near a singularity, degenerate, ...)."""


@dataclass(frozen=True)
class Validity:
    """Whether a figure is defined, and what to know about it.

    Attributes:
        valid: The figure means what it says (``False``: reported, but degenerate here).
        warnings: One line per thing to know (near a singularity, a degenerate mode...).

    """

    valid: bool = True
    warnings: tuple[str, ...] = ()

    def __add__(self, other: Validity) -> Validity:
        """Both at once: valid when both are, the warnings of both."""
        return Validity(self.valid and other.valid, self.warnings + other.warnings)

    def warn(self, stacklevel: int = 3) -> None:
        """Issue one :class:`PrecisionWarning` per warning."""
        from pkdyn.inputs import count

        stacklevel = count("stacklevel", stacklevel, 1, 100)
        for text in self.warnings:
            _warnings.warn(text, PrecisionWarning, stacklevel=stacklevel)

    def to_json(self) -> dict[str, object]:
        """``{"valid": bool, "warnings": [str, ...]}``."""
        return {"valid": self.valid, "warnings": list(self.warnings)}

    def lines(self) -> list[str]:
        """The table lines: ``not valid: ...`` and ``warning: ...``."""
        out = [] if self.valid else ["NOT VALID here (see the warnings)"]
        return out + [f"warning: {w}" for w in self.warnings]


class Flagged:
    """Mixin of the results that carry a ``validity`` field: ``valid`` and ``warnings``."""

    validity: Validity

    @property
    def valid(self) -> bool:
        """The figures mean what they say here (:mod:`pkdyn.precision.validity`)."""
        return self.validity.valid

    @property
    def warnings(self) -> tuple[str, ...]:
        """What to know about the figures (near a singularity...)."""
        return self.validity.warnings


def pose_text(robot: Robot, q: np.ndarray) -> str:
    """The platform pose of ``q`` for messages: ``at x y = [0, 0.49] m`` (task components)."""
    if robot.platform_frame is None:
        return "at this configuration"
    M = robot.platform_placement(np.asarray(q, dtype=float))
    xyz = np.where(np.abs(M.translation) > 1e-9 * robot.length_scale, M.translation, 0.0)
    rows = [int(i) for i in robot.task_rows]
    t = [i for i in rows if i < 3]
    r = [i for i in rows if i >= 3]
    parts = []
    if t:
        parts.append(f"{' '.join('xyz'[i] for i in t)} = {vector(xyz[t], 'm')}")
    if r:
        import pinocchio as pin

        rpy = pin.rpy.matrixToRpy(M.rotation)
        names = ("roll", "pitch", "yaw")
        parts.append(
            f"{' '.join(names[i - 3] for i in r)} = {vector(rpy[[i - 3 for i in r]], 'rad')}"
        )
    return "at " + ", ".join(parts)


def coordinate_scales(robot: Robot) -> np.ndarray:
    """Length scale of each velocity coordinate (nv,): ``L`` for translations, 1 for rotations.

    Prismatic joints, the translations of free-flyer, planar and translation joints (the link
    deflections of the virtual-joint model are free-flyers) are lengths; everything else turns.
    """
    L = robot.length_scale
    out = np.ones(robot.nv)
    for j in range(1, robot.model.njoints):
        jm = robot.model.joints[j]
        name = str(jm.shortname())
        i = jm.idx_v
        if name.startswith(("JointModelP", "JointModelTranslation")):
            out[i : i + jm.nv] = L
        elif name == "JointModelFreeFlyer":
            out[i : i + 3] = L
        elif name == "JointModelPlanar":
            out[i : i + 2] = L
    return out


def reference_stiffness(robot: Robot, spring_stiffness: np.ndarray) -> float:
    """The robot's stiffest spring in rotational units [N m/rad] (0 without any).

    Args:
        robot: The (extended) robot the springs act on.
        spring_stiffness: Diagonal stiffness per velocity coordinate (nv,) [N m/rad or N/m],
            finite entries only counted.

    Returns:
        ``max_i k_i s_i^2`` with ``s_i`` = :func:`coordinate_scales`, two-frame springs
        included (their stiffness times ``L^2``).

    """
    k = np.asarray(spring_stiffness, dtype=float)
    s = coordinate_scales(robot)
    finite = np.isfinite(k)
    ref = float(np.max(k[finite] * s[finite] ** 2, initial=0.0))
    P = robot.passive
    if P is not None:
        for sp in P.springs:
            ref = max(ref, float(sp.stiffness) * robot.length_scale**2)
    return ref


def scaled_compliance(C: np.ndarray, rows: Sequence[int], L: float, k_ref: float) -> np.ndarray:
    """``C' = k_ref S C S`` on the task rows (module docstring), symmetrised.

    Args:
        C: Compliance (6, 6) [m/N, m/(N m), rad/N, rad/(N m)].
        rows: Task rows (indices 0..5).
        L: The robot's size [m].
        k_ref: Reference stiffness [N m/rad].

    Returns:
        The dimensionless task compliance (m, m).

    """
    idx = list(rows)
    S = np.array([1.0 / L if i < 3 else 1.0 for i in idx])
    Ct = np.asarray(C)[np.ix_(idx, idx)]
    Cs = k_ref * (S[:, None] * Ct * S[None, :])
    return np.asarray(0.5 * (Cs + Cs.T))


def direction_text(d: np.ndarray, rows: Sequence[int]) -> str:
    """A task direction for messages: ``[0.71, 0.71] (x y)``."""
    names = " ".join(("x", "y", "z", "rx", "ry", "rz")[i] for i in rows)
    return f"{vector(d, '', 2)} ({names})"


def check_stiffness(
    robot: Robot,
    q: np.ndarray,
    C: np.ndarray,
    rows: Sequence[int],
    k_ref: float,
    freed: np.ndarray | None = None,
) -> tuple[Validity, np.ndarray]:
    """The stiffness rule (module docstring) on a compliance.

    Args:
        robot: The robot (as loaded), for names, size and pose.
        q: Its configuration (nq,).
        C: Compliance (6, 6) with the actuators as given (rigid ones held).
        rows: Task rows.
        k_ref: Reference stiffness [N m/rad] (> 0).
        freed: The compliance with the rigid actuators freed (given ``k_ref``), when some are
            rigid; ``None``: none is.

    Returns:
        ``(validity, rigid)``: the flags, and unit task directions (k, m) held rigidly by rigid
        actuators (none: (0, m)).

    Raises:
        SingularConfigurationError: The stiffness is unbounded along a task direction, or round
            off.

    """
    L = robot.length_scale
    m = len(rows)
    test = C if freed is None else freed
    w, V = np.linalg.eigh(scaled_compliance(test, rows, L, k_ref))
    if w[0] <= UNBOUNDED_COMPLIANCE * max(float(w[-1]), 1.0):
        d = V[:, 0] * np.array([L if i < 3 else 1.0 for i in rows])
        d /= np.linalg.norm(d)
        raise SingularConfigurationError(
            "serial",
            f"{robot.name} {pose_text(robot, q)}: the platform cannot move along "
            f"{direction_text(d, rows)} even when every spring deforms (scaled compliance "
            f"{max(w[0], 0.0):.2g}, a serial singularity or nothing compliant along it): the "
            "stiffness is unbounded here, no figure is given",
        )
    warnings: list[str] = []
    rigid = np.zeros((0, m))
    if freed is not None:
        wa, Va = np.linalg.eigh(scaled_compliance(C, rows, L, k_ref))
        held = wa <= UNBOUNDED_COMPLIANCE * max(float(wa[-1]), 1.0)
        rigid = Va[:, held].T
        w = wa[~held] if (~held).any() else np.array([np.inf])
    if w[0] <= NEAR_COMPLIANCE:
        warnings.append(
            f"{robot.name} {pose_text(robot, q)} is near a serial singularity: the platform is "
            f"{1.0 / max(w[0], 1e-300):.3g} times stiffer than its springs through levers of its "
            "size, and the figure grows without bound towards the singularity"
        )
    return Validity(True, tuple(warnings)), rigid


def freed(em: ElasticModel) -> tuple[ElasticModel, float]:
    """The model with its rigid actuators given the reference stiffness, and that stiffness.

    The rule of :mod:`pkdyn.precision.validity` judges whether a direction is unbounded with
    the rigid actuators freed: what only they hold is rigid by declaration.
    """
    cached = _FREED.get(em)
    if cached is None:
        other, k_ref = _freed(em)
        cached = (None if other is em else other, k_ref)  # (no reference back to the key)
        _FREED[em] = cached
    return (em if cached[0] is None else cached[0]), cached[1]


_FREED: weakref.WeakKeyDictionary[ElasticModel, tuple[ElasticModel | None, float]] = (
    weakref.WeakKeyDictionary()
)


def _freed(em: ElasticModel) -> tuple[ElasticModel, float]:
    k_ref = reference_stiffness(em.robot, em.spring_stiffness())
    k = em.actuator_stiffness
    if np.all(np.isfinite(k)):
        return em, k_ref
    ref = k_ref if k_ref > 0.0 else 1.0
    s = coordinate_scales(em.robot)[np.asarray(em.robot.actuated_v)]
    k_free = np.where(np.isfinite(k), k, ref / s**2)
    return dataclasses.replace(em, actuator_stiffness=k_free), ref


def stiffness_check(
    em: ElasticModel, q_ext: np.ndarray, point: np.ndarray, C6: np.ndarray, q: np.ndarray
) -> tuple[Validity, np.ndarray, float]:
    """The stiffness rule on a condensed compliance, the rigid actuators freed if any.

    Args:
        em: The elastic model.
        q_ext: Its configuration (nq_ext,) the compliance was condensed at.
        point: Reference point, platform frame [m].
        C6: The compliance (6, 6) with the actuators as given.
        q: The robot's configuration (nq,) (for the messages).

    Returns:
        ``(validity, rigid directions (k, m), k_ref)`` (:func:`check_stiffness`).

    Raises:
        SingularConfigurationError: The stiffness is unbounded along a task direction.

    """
    from pkdyn.precision.condensation import compliance, reduce

    rows = [int(i) for i in em.base.task_rows]
    em_free, k_ref = freed(em)
    C_free = None
    if em_free is not em:
        C_free, _ = compliance(em_free, reduce(em_free, q_ext, point))
    validity, rigid = check_stiffness(em.base, q, C6, rows, k_ref, C_free)
    return validity, rigid, k_ref


def budget_validity(robot: Robot, q: np.ndarray) -> Validity:
    """The error-budget rule (module docstring): flags at and near singularities.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).

    Returns:
        Not valid at a serial singularity (first order vanishes), warnings near either kind.

    Raises:
        SingularConfigurationError: A parallel singularity (the errors are unbounded).

    """
    with _warnings.catch_warnings():
        _warnings.simplefilter("ignore", NearSingularityWarning)
        km = kinematic_models(robot, q)
    where = f"{robot.name} {pose_text(robot, q)}"
    if km.margin_A < SINGULAR_TOL:
        raise SingularConfigurationError(
            "parallel",
            f"{where}: parallel singularity (margin {km.margin_A:.2g}): the platform moves with "
            "the actuators held, the sensitivities are unbounded here, no budget is given",
        )
    if km.margin_B < SINGULAR_TOL:
        return Validity(
            False,
            (
                f"{where} is at a serial singularity (margin {km.margin_B:.2g}): the first-order "
                "error vanishes along the folded direction, where the error is of second order: "
                "the budget underestimates it",
            ),
        )
    out: list[str] = []
    if km.margin_A < NEAR_SINGULAR_TOL:
        out.append(
            f"{where} is near a parallel singularity (margin {km.margin_A:.2g}): errors are "
            "amplified and the first order holds only for small errors"
        )
    if km.margin_B < NEAR_SERIAL_TOL:
        out.append(
            f"{where} is near a serial singularity (margin {km.margin_B:.2g}): the first order "
            "holds only for small errors"
        )
    return Validity(True, tuple(out))
