"""The home configuration of a loaded robot: assembled, non-singular, found or explained.

:func:`find_home` turns the configuration a description gives (its zero pose, MuJoCo's
``qpos0`` or ``home`` keyframe, a library family's actuator values, or the user's ``home``)
into an assembled one:

1. Levenberg-Marquardt from that configuration (only the passive coordinates move when the
   actuator values are imposed). Converged and not singular: done.
2. **CAD-rounded descriptions.** When the closures cannot be closed exactly but the best
   configuration misses them by at most the assembly tolerance ``tol`` (default
   :data:`ASSEMBLY_TOL`), the description is inconsistent by a rounding error (an
   overconstrained loop exported with six significant digits, say): the second frame of each
   such closure is moved onto the first at that configuration, and one warning says by how
   much. A description whose own pose misses the closures by less than ``tol`` but that
   assembles exactly is assembled with a warning that gives the amount too.
3. **Search.** Otherwise, and when the configuration reached is singular (a four-bar whose
   zero pose is the straight line, where Levenberg-Marquardt cannot leave the line), seeded
   random restarts within the joint limits look for an assembled configuration, then for a
   non-singular one near it.
4. Nothing found: :class:`~pkdyn.exceptions.LoopClosureError` (a ``DescriptionError`` and an
   ``AssemblyError``) naming the closure that keeps the
   largest residual at the best configuration, and what to try.

**Singular** means: the rank of the closure Jacobian is below the rank found at nearby
assembled configurations (moving along its null space), or, with actuators, the passive
coordinates cannot absorb the closures (``rank J_passive < rank J``: the actuators do not
determine the configuration). Ranks follow the project's one rule (:mod:`solvers.numerics`): a
singular value counts when it exceeds ``RTOL * max(s_max, 1)`` (scale 1: closure Jacobians are
in SI units with entries of order one), as :meth:`Robot.dof` decides.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError, LoopClosureError
from pkdyn.model.description import ClosureSpec, CouplingSpec, FrameRef, LinearCouplingSpec
from pkdyn.model.robot import Robot
from pkdyn.model.warn import warn
from solvers import SolveResult, numerics, solve_lm

__all__ = [
    "ASSEMBLY_TOL",
    "EXACT_TOL",
    "NEAR_DEAD_CENTRE",
    "RANK_RTOL",
    "HomeResult",
    "dead_centre_distance",
    "find_home",
    "rank",
]

ASSEMBLY_TOL = 1e-4
"""Default assembly tolerance [m or rad]: the largest closure error of a description pkdyn
absorbs (with a warning) instead of refusing it."""

EXACT_TOL = 1e-9
"""Closure residual [m or rad] below which a description's own pose counts as assembled."""

RANK_RTOL = numerics.RTOL
"""Relative tolerance of the rank decisions: :data:`solvers.numerics.RTOL` (the project's rule,
with scale 1 as :meth:`Robot.dof` uses it)."""

_SOLVE_TOL = 1e-12
_RESTARTS = 48
_SEARCH_SECONDS = 20.0


def rank(J: np.ndarray) -> int:
    """Rank of a closure Jacobian (:func:`solvers.numerics.rank`, scale 1)."""
    return numerics.rank(J, RANK_RTOL, 1.0)


@dataclass(eq=False)  # numpy fields: no boolean ==
class HomeResult:
    """Outcome of :func:`find_home`.

    Attributes:
        q: The assembled home configuration (nq,).
        closures: The closures, with second frames moved when CAD rounding was absorbed.
        moved: Closures whose frame was moved (couplings whose constant term was adjusted),
            with the distance [m or rad].
        searched: Whether the configuration came from the search (step 3).
        couplings: The joint couplings, constant terms adjusted when CAD rounding was
            absorbed (``None``: unchanged).

    """

    q: np.ndarray
    closures: list[ClosureSpec]
    moved: dict[str, float]
    searched: bool
    couplings: list[CouplingSpec | LinearCouplingSpec] | None = None


def _solve(
    robot: Robot,
    q0: np.ndarray,
    free: np.ndarray | None,
    max_iter: int,
    r0: np.ndarray | None = None,
) -> SolveResult:
    """Levenberg-Marquardt from ``q0``; ``r0``: the residual at ``q0``, already evaluated."""
    cs, data = robot.constraints, robot.data
    first = [] if r0 is None else [r0]

    def residual(q: np.ndarray) -> np.ndarray:
        # the solver's first call is at q0 (a copy): the residual already evaluated there
        return first.pop() if first else cs.residual(data, q)

    return solve_lm(
        robot.model,
        q0,
        residual,
        lambda q: cs.jacobian(data, q),
        free,
        _SOLVE_TOL,
        max_iter,
    )


def _per_closure(robot: Robot, residual: np.ndarray) -> dict[str, float]:
    """Largest residual component per closure and per coupling."""
    cs = robot.constraints
    return {
        name: float(np.max(np.abs(residual[a:b]), initial=0.0))
        for name, a, b in zip(cs.names, cs.offsets[:-1], cs.offsets[1:], strict=True)
    }


def singular(robot: Robot, q: np.ndarray, rng: np.random.Generator | None = None) -> bool:
    """Whether an assembled configuration is singular (see the module docstring).

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        rng: Random generator for the nearby configurations (default: fixed pseudo-random
            directions, without importing ``numpy.random`` on every load).

    Returns:
        ``True`` when singular.

    """
    cs, data = robot.constraints, robot.data
    if cs.n == 0:
        return False
    J = cs.jacobian(data, q)
    if robot.actuated_v.size:
        Jp = J[:, robot.passive_v]
        s_p = np.linalg.svd(Jp, compute_uv=False) if Jp.size else np.zeros(0)
        r_p = numerics.rank_of(s_p, RANK_RTOL, 1.0)  # (rank(J_passive))
        if r_p == J.shape[0] and full_rank_bound(s_p, J):
            return False  # rank J = rank J_passive = every row: not singular, nothing to probe
        r = rank(J)
        if r_p < r:
            return True
    else:
        r = rank(J)
    if r == J.shape[0]:  # full row rank: no configuration has a higher one (nothing to probe)
        return False
    Z = numerics.null_space(J, RANK_RTOL, 1.0)
    if Z.shape[1] == 0:
        return False
    for k in range(2):
        d = _direction(k, Z.shape[1]) if rng is None else rng.standard_normal(Z.shape[1])
        step = Z @ d
        step *= 0.05 / max(float(np.max(np.abs(step))), 1e-300)
        sol = _solve(robot, pin.integrate(robot.model, q, step), None, 60)
        if sol.converged and rank(cs.jacobian(data, sol.q)) > r:
            return True
    return False


FULL_RANK_MARGIN = 2.0
"""Factor between the passive columns' smallest singular value and the cut-off bound that
proves every row of the closure Jacobian counts (:func:`full_rank_bound`)."""


def full_rank_bound(s_passive: np.ndarray, J: np.ndarray) -> bool:
    """Whether ``rank(J)`` is every row of ``J``, proved from the passive columns' SVD alone.

    ``J`` (m, nv) holds the passive columns ``J_p`` and more: its m-th singular value is at
    least ``J_p``'s (interlacing) and its largest at most its Frobenius norm, so
    ``s_m(J_p) > 2 RTOL max(|J|_F, 1)`` puts ``s_m(J)`` above :func:`rank`'s cut-off
    ``RTOL max(s_1(J), 1)`` with a factor 2 to spare, which no rounding of the two SVDs
    (relative errors ~1e-15 of ``s_1``) can undo: :func:`rank` would count all m. ``False``
    when the bound does not prove it (the caller then computes ``rank(J)``).

    Args:
        s_passive: Singular values of ``J_p``, largest first (at least m of them to prove it).
        J: The closure Jacobian (m, nv).

    Returns:
        ``True`` when ``rank(J) == m`` is proved.

    """
    m = J.shape[0]
    if m == 0 or s_passive.size < m:
        return False
    frobenius = math.sqrt(float(np.einsum("ij,ij->", J, J)))
    return bool(s_passive[m - 1] > FULL_RANK_MARGIN * RANK_RTOL * max(frobenius, 1.0))


def _direction(k: int, n: int) -> np.ndarray:
    """A fixed, irregular direction in ``R^n`` (k-th of a sequence), entries in (-1, 1)."""
    i = np.arange(1, n + 1, dtype=float)
    return np.sin(i * (12.9898 + 78.233 * (k + 1))) * 43758.5453 % 2.0 - 1.0


def _random_start(
    robot: Robot, q0: np.ndarray, rng: np.random.Generator, spread: float
) -> np.ndarray:
    """``q0`` moved by a random step, 1-coordinate joints kept inside their finite limits."""
    model = robot.model
    q = pin.integrate(model, q0, rng.uniform(-spread, spread, model.nv))
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    for jid in range(1, model.njoints):
        jm = model.joints[jid]
        if jm.nq == 1:
            i = jm.idx_q
            if math.isfinite(lo[i]) and math.isfinite(hi[i]) and lo[i] < hi[i]:
                q[i] = min(max(q[i], lo[i]), hi[i])
    return q


def _moved_closures(
    robot: Robot, q: np.ndarray, per: dict[str, float], tol: float
) -> tuple[list[ClosureSpec], dict[str, float]]:
    """Closures whose second frame is moved onto the first at ``q`` when off by <= ``tol``."""
    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, q)
    out: list[ClosureSpec] = []
    moved: dict[str, float] = {}
    cms = {cm.name: cm for cm in robot.constraint_models}
    for c in robot.closures:
        off = per.get(c.name, 0.0)
        if off <= EXACT_TOL or off > tol:
            out.append(c)
            continue
        cm = cms[c.name]
        oM1 = data.oMi[cm.joint1_id] * cm.joint1_placement
        oM2 = data.oMi[cm.joint2_id] * cm.joint2_placement
        # frame2 placement in its link frame, so that frame2 coincides with frame1
        link_pose = oM2 * c.frame2.placement.inverse()
        new2 = link_pose.actInv(oM1)
        if c.kind == "point":  # a point closure: the second frame keeps its orientation
            new2 = pin.SE3(c.frame2.placement.rotation, new2.translation)
        out.append(dataclasses.replace(c, frame2=FrameRef(c.frame2.link, new2)))
        moved[c.name] = off
    return out, moved


def _moved_couplings(
    robot: Robot, residual: np.ndarray, tol: float
) -> tuple[list[CouplingSpec | LinearCouplingSpec], dict[str, float]]:
    """Couplings whose constant term absorbs a residual between ``EXACT_TOL`` and ``tol``."""
    cs = robot.constraints
    out: list[CouplingSpec | LinearCouplingSpec] = []
    adjusted: dict[str, float] = {}
    for k, c in enumerate(robot.couplings):
        r = float(residual[cs.nc + k])
        if EXACT_TOL < abs(r) <= tol:
            if isinstance(c, LinearCouplingSpec):  # sum a_i x_i - b = r: b absorbs r
                c = dataclasses.replace(c, offset=c.offset + r)
            else:  # x_j - x_j0 - p(u) = r: c_0 absorbs r
                coef = (c.coefficients[0] + r, *c.coefficients[1:])
                c = dataclasses.replace(c, coefficients=coef)
            adjusted[c.name] = abs(r)
        out.append(c)
    return out, adjusted


def _contradicting_coupling(robot: Robot, best: SolveResult, per: dict[str, float]) -> str | None:
    """The coupling to blame when the closures assemble without the couplings, else ``None``.

    Then (or when there are no closures) the couplings contradict the closures or one
    another: the one with the largest residual at the best configuration is named.
    """
    if not robot.couplings:
        return None
    names = [c.name for c in robot.couplings]
    if robot.constraints.nc:
        rigid = robot.constraints.closures
        data = robot.model.createData()
        sol = solve_lm(
            robot.model,
            best.q,
            lambda q: rigid.residual(data, q),
            lambda q: rigid.jacobian(data, q),
            None,
            _SOLVE_TOL,
            100,
        )
        if not sol.converged:
            return None
    return max(names, key=lambda k: per.get(k, 0.0))


def find_home(
    robot: Robot,
    q0: np.ndarray,
    qa: Sequence[float] | np.ndarray | None = None,
    tol: float = ASSEMBLY_TOL,
    user: bool = False,
) -> HomeResult:
    """An assembled, non-singular home configuration (see the module docstring).

    Args:
        robot: The robot (its closures as described).
        q0: Starting configuration (nq,): the description's own pose.
        qa: Actuated coordinates to keep (only the passive ones move), or ``None``.
        tol: Assembly tolerance [m or rad].
        user: The start was given by the user: a singular home is kept (with a warning).

    Returns:
        The home configuration and the (possibly adjusted) closures.

    Raises:
        InvalidInputError: ``tol`` is not a positive number.
        LoopClosureError: No assembled configuration found (a description error and an
            assembly error); names the closure that keeps the largest residual.

    """
    if not (isinstance(tol, int | float) and math.isfinite(tol) and tol > 0.0):
        raise InvalidInputError(
            "tol", f"the assembly tolerance must be a positive length, got {tol!r}"
        )
    closures = list(robot.closures)
    q = np.array(q0, dtype=float)
    free = None
    if qa is not None:
        q[robot.actuated_q] = qa
        free = robot.passive_v
    if robot.constraints.n == 0:
        return HomeResult(q, closures, {}, False)
    r_file = robot.constraints.residual(robot.data, q)
    sol = _solve(robot, q, free, 100, r_file)
    at_singularity = sol.converged and singular(robot, sol.q)  # (computed once)
    if sol.converged and (not at_singularity or (user and free is not None)):
        _warn_file_pose(robot, r_file, sol.q, q, tol)
        if user and at_singularity:
            warn(f"{robot.source}: the given home configuration is singular")
        return HomeResult(sol.q, closures, {}, False)
    best = sol if not sol.converged else None
    found = None
    if sol.converged or _worst(robot, sol) > tol:
        found, best = _search(robot, q, free, sol)
    if found is not None:
        d = dead_centre_distance(robot, found)
        if d is not None:
            warn(
                f"{robot.source}: the home found by search lies {d[0]:.3g} {d[1]} of actuator "
                f"'{d[2]}' motion from a singular configuration (a dead centre: the closures "
                "cannot be followed beyond it); give another home (home=..., --home)"
            )
        return HomeResult(found, closures, {}, True)
    assert best is not None
    per = _per_closure(robot, best.residual)
    name = max(per, key=lambda k: per[k])
    if per[name] <= tol:  # an inconsistent description, within the tolerance
        new, moved = _moved_closures(robot, best.q, per, tol)
        couplings, adjusted = _moved_couplings(robot, best.residual, tol)
        what = "closure" if name not in adjusted else "coupling"
        also = (
            f" ({len(adjusted)} coupling(s) also off: their constant terms were adjusted)"
            if adjusted
            else ""
        )
        warn(
            f"{robot.source}: {len(moved)} closure(s) cannot be closed exactly ({what} "
            f"'{name}' is off by {per[name]:.2g} at best: the description is inconsistent "
            f"within the assembly tolerance {tol:g}, as CAD rounding makes it); their second "
            f"frames were moved onto the first ones{also}"
        )
        return HomeResult(
            best.q, new, {**moved, **adjusted}, False, couplings if adjusted else None
        )
    coupling = _contradicting_coupling(robot, best, per)
    if coupling is not None:
        c = next(c for c in robot.couplings if c.name == coupling)
        relation = (
            "of joints " + ", ".join(repr(j) for j, _ in c.terms)
            if isinstance(c, LinearCouplingSpec)
            else f"joint '{c.joint}' " + (f"from {c.source!r}" if c.source else "locked")
        )
        raise LoopClosureError(
            robot.source,
            coupling,
            per[coupling],
            f"{robot.source}: coupling '{coupling}' ({relation}) contradicts the closures: "
            f"the mechanism cannot be assembled with it (residual {per[coupling]:.3g} at best, "
            "while the closures alone assemble); check its coefficients and reference "
            "positions",
            kind="coupling",
        )
    coupled = {c.name for c in robot.couplings}
    name = max((k for k in per if k not in coupled), key=lambda k: per[k])
    spec = next(c for c in robot.closures if c.name == name)
    raise LoopClosureError(
        robot.source,
        name,
        per[name],
        f"{robot.source}: the home configuration cannot be assembled: closure '{name}' "
        f"(between '{spec.frame1.link}' and '{spec.frame2.link}') keeps "
        f"a residual of {per[name]:.3g} at best (from the description's pose and "
        f"{_RESTARTS} random starts); check its frames and the joint types along its loop, "
        "or give an assembled configuration (home=..., --home)",
    )


NEAR_DEAD_CENTRE = 0.1
"""Actuator motion [rad; for a prismatic actuator, times the robot's size] within which a
searched home's singular configuration (dead centre) draws a warning."""

_DEAD_CENTRE_STEPS = 20


def dead_centre_distance(robot: Robot, q: np.ndarray) -> tuple[float, str, str] | None:
    """The actuator motion from ``q`` to a singular configuration, if within the warning range.

    Each actuator is moved alone, both ways, in :data:`_DEAD_CENTRE_STEPS` steps up to
    :data:`NEAR_DEAD_CENTRE`, the passive joints following the closures: a dead centre is where
    they cannot follow (the solve fails: a fold) or where the passive coordinates stop
    determining the configuration (``rank J_passive < rank J``).

    Args:
        robot: The robot.
        q: An assembled, non-singular configuration (nq,).

    Returns:
        ``(distance, unit, actuator)`` of the nearest one found, or ``None`` (also for a
        redundantly actuated robot, whose actuators cannot move one at a time).

    """
    if not robot.constraints.n or not robot.actuated_v.size:
        return None
    _, J = robot.constraints.residual_and_jacobian(robot.data, q)
    N = numerics.null_space(J, scale=1.0)
    if rank(N[robot.actuated_v]) < robot.actuated_v.size:
        # redundant actuation (a four-arm Delta, the four-branch walker): one actuator cannot
        # move alone, so "moving it until the passive joints cannot follow" measures nothing
        return None
    best: tuple[float, str, str, float] | None = None
    for k, name in enumerate(robot.actuator_names):
        prismatic = bool(robot.actuator_prismatic[k])
        reach = NEAR_DEAD_CENTRE * (robot.length_scale if prismatic else 1.0)
        h = reach / _DEAD_CENTRE_STEPS
        iq = int(robot.actuated_q[k])
        for sign in (-1.0, 1.0):
            qk = np.array(q, dtype=float)
            for _ in range(_DEAD_CENTRE_STEPS):
                nxt = _regular(robot, qk, iq, qk[iq] + sign * h)
                if nxt is not None:
                    qk = nxt
                    continue
                lo, hi = 0.0, h  # bisect the step that fails
                for _ in range(30):
                    mid = 0.5 * (lo + hi)
                    if _regular(robot, qk, iq, qk[iq] + sign * mid) is not None:
                        lo = mid
                    else:
                        hi = mid
                d = abs(float(qk[iq] - q[iq])) + 0.5 * (lo + hi)
                scale = robot.length_scale if prismatic else 1.0
                if best is None or d / scale < best[0] / best[3]:
                    best = (d, "m" if prismatic else "rad", name, scale)
                break
    return None if best is None else best[:3]


def _regular(robot: Robot, start: np.ndarray, iq: int, value: float) -> np.ndarray | None:
    """The configuration with coordinate ``iq`` at ``value`` (from ``start``), if regular."""
    qs = np.array(start, dtype=float)
    qs[iq] = value
    sol = _solve(robot, qs, robot.passive_v, 40)
    if not sol.converged:
        return None
    J = robot.constraints.jacobian(robot.data, sol.q)
    return sol.q if rank(J[:, robot.passive_v]) == rank(J) else None


def _worst(robot: Robot, sol: SolveResult) -> float:
    return max(_per_closure(robot, sol.residual).values(), default=0.0)


def _warn_file_pose(
    robot: Robot, residual: np.ndarray, q: np.ndarray, q0: np.ndarray, tol: float
) -> None:
    """Warn when the description's own pose (residual there) misses the closures by <= tol."""
    # the largest closure residual is the largest component (the closures' rows cover it);
    # per closure only when it warns (or is not a number: compared closure by closure)
    worst = float(np.max(np.abs(residual), initial=0.0))
    if math.isfinite(worst) and not EXACT_TOL < worst <= tol:
        return
    r_file = _per_closure(robot, residual)
    worst = max(r_file.values(), default=0.0)
    if EXACT_TOL < worst <= tol:
        name = max(r_file, key=lambda k: r_file[k])
        dq = float(np.max(np.abs(pin.difference(robot.model, q0, q))))
        warn(
            f"{robot.source}: the description's pose misses the closures by up to {worst:.2g} "
            f"(closure '{name}'; CAD rounding?); assembled by moving the joints by up to "
            f"{dq:.2g}"
        )


def _search(
    robot: Robot, q0: np.ndarray, free: np.ndarray | None, first: SolveResult
) -> tuple[np.ndarray | None, SolveResult | None]:
    """Seeded random restarts.

    Returns:
        An assembled configuration (non-singular when one was found, else ``None`` when none
        converged) and the attempt with the smallest residual among those that did not
        converge (``None`` when one did).

    """
    rng = np.random.default_rng(0)
    start = time.monotonic()
    fallback: np.ndarray | None = first.q if first.converged else None
    best: SolveResult | None = None if first.converged else first
    for k in range(_RESTARTS):
        if time.monotonic() - start > _SEARCH_SECONDS:
            break
        spread = (0.3, 1.0, math.pi)[min(k // 16, 2)]
        qs = _random_start(robot, q0, rng, spread)
        if free is not None:
            qs[robot.actuated_q] = q0[robot.actuated_q]
        sol = _solve(robot, qs, free, 100)
        if not sol.converged:
            if fallback is None and (best is None or _worst(robot, sol) < _worst(robot, best)):
                best = sol
            continue
        if not singular(robot, sol.q, rng):
            return sol.q, None
        if fallback is None:
            fallback = sol.q
    return fallback, (best if fallback is None else None)
