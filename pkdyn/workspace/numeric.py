"""Workspace limits of any robot by the general numeric path.

Each platform position is solved with the inverse geometric model (closures and platform pose
together, :func:`pkdyn.model.assembly.solve_pose`, Levenberg-Marquardt on Pinocchio's C++
constraint Jacobian), then checked: actuated coordinates against their joint limits, passive
joints against their cones and pyramids, and the collision geometry with coal
(:class:`pkdyn.analysis.collisions.CollisionChecker`). Valid for every description; the
closed-form evaluators (:mod:`pkdyn.workspace.legs`, :mod:`pkdyn.workspace.delta`) give the same
classification where both apply (see the tests).

What keeps it fast:

- cheap rejection: before any solve, a position is ``reach``-rejected when a closure cannot be
  spanned: for each closure, the two contact points hang from bodies whose placement the pose
  fixes (the base, the platform) through chains of bounded length (link offsets and rotary
  joints), so the distance between the chains' anchor points must not exceed the sum of the
  lengths (:class:`ReachBound`, vectorised over the grid);
- early stop: an unreachable pose makes the solver creep towards a least-squares minimum that is
  not a solution; it stops when three accepted steps in a row each keep more than 95 % of the
  squared residual; no message is formatted in the loop;
- continuation: :meth:`NumericEvaluator.box_grid` solves the grid breadth first from the sample
  nearest to the home pose, each sample warm-started from a solved neighbour's solution moved
  along the grid line to first order (with the solver's last Jacobian), retried from that
  solution itself then from the home configuration only when the solve fails, and kept in the
  home assembly mode (the platform pose components the robot does not control, where they do
  not move at home, are imposed at their home values; where they do move, a solution that
  jumps is refused): the closed forms' classification on every sample of the test grids;
- both cores: grids of at least :data:`PARALLEL_SAMPLES` samples are split in two and solved in
  two processes (``fork``; serial elsewhere).

Collision pairs that already interpenetrate at the home configuration (parts that overlap by
design, such as a rod in its cylinder or a knuckle on its rod, within one branch of the tripod)
are left out of the interference check; :attr:`NumericEvaluator.excluded_pairs` lists them.
"""

from __future__ import annotations

import math
import multiprocessing
import os
from collections import deque
from collections.abc import Iterator

import numpy as np
import pinocchio as pin

from pkdyn.analysis.collisions import CollisionChecker, interference_checker
from pkdyn.model.assembly import solve_pose
from pkdyn.model.description import ConeLimit
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.workers import usable_cores, worker_count, worker_init
from pkdyn.workspace.limits import (
    LIMIT_KINDS,
    REACHABLE,
    PoseEvaluator,
    passive_joint_margins,
    pyramid_normals,
)
from solvers import FramePoseTask

__all__ = ["PARALLEL_SAMPLES", "NumericEvaluator", "ReachBound", "configuration_violation"]

PARALLEL_SAMPLES = 20_000
"""Grids with at least this many samples are solved in two processes (when two cores exist)."""

_TOL = 1e-9  # convergence of the inverse geometric model [m or rad]
_STALL = 0.95  # early stop: three accepted steps in a row each keeping this much of |r|^2
_MAX_ITER = 50
_JUMP = 0.2  # largest predicted change of a coordinate in one grid step [rad or m]
_FREE_TOL = 1e-6  # uncontrolled pose components that do not move: their change allowed [m, rad]
_FREE_JUMP = 0.5  # ... that do move: their largest change in one grid step [m or rad]
_REVOLUTE = ("RX", "RY", "RZ", "RevoluteUnaligned")
_ROTARY = ("RX", "RY", "RZ", "RevoluteUnaligned", "RUBX", "RUBY", "RUBZ", "Spherical", "Universal")
_REACH = LIMIT_KINDS.index("reach")
_STROKE = LIMIT_KINDS.index("stroke")
_JOINT = LIMIT_KINDS.index("joint")
_INTERFERENCE = LIMIT_KINDS.index("interference")

_WORKER: NumericEvaluator | None = None  # the evaluator a forked worker process uses


def configuration_violation(
    robot: Robot,
    q: np.ndarray,
    kinds: tuple[str, ...],
    margin: float,
    checker: CollisionChecker | None = None,
) -> int:
    """First limit kind an assembled configuration breaks (``reach`` excluded), general path.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        kinds: Kinds to check.
        margin: Safety distance [m] for ``interference``.
        checker: Coal checker (required for ``interference``).

    Returns:
        Index in :data:`LIMIT_KINDS`, or :data:`REACHABLE`.

    """
    if "stroke" in kinds:
        iq = robot.actuated_q
        lo, hi = robot.model.lowerPositionLimit[iq], robot.model.upperPositionLimit[iq]
        if np.any((q[iq] < lo) | (q[iq] > hi)):
            return _STROKE
    if "joint" in kinds:
        if any(m < 0.0 for m in passive_joint_margins(robot, q).values()):
            return _JOINT
    if "interference" in kinds:
        assert checker is not None
        if np.min(checker.distances(q)) < margin:
            return _INTERFERENCE
    return REACHABLE


def _extension(jm: pin.JointModel) -> float:
    """Largest distance a joint moves its child frame's origin [m].

    0 for rotary joints, ``inf`` otherwise (joint limits are not reach: the inverse model
    ignores them, ``stroke`` reports them).
    """
    name = jm.shortname().replace("JointModel", "")
    return 0.0 if name in _ROTARY or name.startswith("SphericalZYX") else math.inf


class ReachBound:
    """Necessary condition for a platform pose to be reachable: every closure can be spanned.

    For each closure side, the contact point hangs from the nearest *anchor* above it in the
    tree (the world, or the platform's body, both placed by the pose) through a chain of rotary
    joints (which do not move their own origin) and fixed offsets; the distance between the two
    anchor points of a closure cannot exceed the sum of both chains' lengths. Chains with
    prismatic or other joints give no bound (joint limits are checked as ``stroke``, not reach).

    Args:
        robot: A robot with a platform frame.

    """

    def __init__(self, robot: Robot) -> None:
        model = robot.model
        assert robot.platform_frame is not None
        frame = model.frames[robot.platform_frame]
        self._jp = int(frame.parentJoint)
        self._Mf = frame.placement
        anchors = {0, self._jp}
        # per bound: anchor-1 point (on world or platform), anchor-2 point, length
        self.bounds: list[tuple[int, np.ndarray, int, np.ndarray, float]] = []
        for cm in robot.constraint_models:
            sides = []
            for j, M in ((cm.joint1_id, cm.joint1_placement), (cm.joint2_id, cm.joint2_placement)):
                j = int(j)
                point = np.array(M.translation)
                length = 0.0 if j in anchors else float(np.linalg.norm(point))
                while j not in anchors:
                    length += _extension(model.joints[j])
                    point = np.array(model.jointPlacements[j].translation)
                    parent = int(model.parents[j])
                    if parent not in anchors:
                        length += float(np.linalg.norm(point))
                    j = parent
                sides.append((j, point, length))
            (a1, p1, l1), (a2, p2, l2) = sides
            if a1 != a2 and math.isfinite(l1 + l2):
                self.bounds.append((a1, p1, a2, p2, l1 + l2))

    def admits(self, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Which platform positions pass the condition (N,) bool.

        Args:
            P: Platform frame positions (N, 3) [m].
            R: Platform frame orientation (3, 3).

        """
        P = np.atleast_2d(P)
        ok = np.ones(P.shape[0], dtype=bool)
        Rj = R @ self._Mf.rotation.T  # platform body orientation; its origin: P - Rj t_f
        t_f = self._Mf.translation
        for a1, p1, _, p2, length in self.bounds:
            # world point w and platform point c: the platform one sits at P + Rj (c - t_f)
            w, c = (p1, p2) if a1 == 0 else (p2, p1)
            d = P + Rj @ (c - t_f) - w
            ok &= np.einsum("ni,ni->n", d, d) <= (length * (1.0 + 1e-9) + 1e-12) ** 2
        return ok


class _PassiveLimits:
    """Cones and pyramids of the passive joints, checked from ``data.liMi`` (no kinematics)."""

    def __init__(self, robot: Robot) -> None:
        model = robot.model
        self.items = []
        for spec in robot.description.joints:
            if spec.limit is None:
                continue
            jid = model.getJointId(spec.name)
            R0T = model.jointPlacements[jid].rotation.T
            axis = np.asarray(spec.limit.axis, dtype=float)
            if isinstance(spec.limit, ConeLimit):
                test = (np.array([axis]), math.cos(spec.limit.half_angle))
            elif max(spec.limit.half_angles) < math.pi / 2:
                test = (pyramid_normals(spec.limit), 0.0)
            else:  # wide pyramid: the angle formula
                test = None
            self.items.append((jid, R0T, axis, spec.limit, test))

    def broken(self, robot: Robot, data: pin.Data) -> bool:
        """Whether a passive joint is outside its limit (``data``: kinematics at ``q``)."""
        liMi = data.liMi
        for jid, R0T, axis, limit, test in self.items:
            R = R0T @ liMi[jid].rotation
            if test is None:
                if limit.margin(R) < 0.0:
                    return True
                continue
            normals, bound = test
            d = R @ axis
            if np.any(normals @ d < bound * math.sqrt(float(d @ d))):
                return True
        return False


class NumericEvaluator(PoseEvaluator):
    """General numeric limits (see the module docstring).

    Args:
        robot: Any robot with a platform frame (with geometry for ``interference``).
        progress: Progress bar over the poses: ``True`` / ``False`` force it on / off,
            ``None`` shows it when stderr is a terminal (default off: the workspace samplers
            show their own).
        warm_start: Start each solve from the previous solution (then from ``q_home``); without
            it every pose is solved from ``q_home``.
        workers: Processes for large grids (default: two when the machine has two cores and
            ``fork`` exists; 1: serial; more than the usable cores or the grid's longest axis
            are capped, with a warning). They die with this process
            (:func:`pkdyn.workers.worker_init`).

    """

    method = "numeric (inverse geometric model and coal, continuation over the grid)"

    def __init__(
        self,
        robot: Robot,
        progress: bool | None = False,
        warm_start: bool = True,
        workers: int | None = None,
    ) -> None:
        super().__init__(robot)
        self.progress = progress
        self.warm_start = warm_start
        self.workers = workers
        self._checker: CollisionChecker | None = None
        self.excluded_pairs: list[tuple[str, str]] = []
        self.q = robot.q_home.copy()
        assert robot.platform_frame is not None
        self._jacobian: np.ndarray | None = None  # of the last solve (predictions)
        self._free_rows = np.setdiff1d(np.arange(6), robot.task_rows)
        self._home_placement = robot.platform_placement(robot.q_home)
        self._free_fixed = self._free_rows.size > 0 and _free_components_fixed(robot)
        # uncontrolled components that do not move are imposed too (at their home values):
        # the solver then cannot drift into another assembly mode through them
        rows = np.arange(6) if self._free_fixed else robot.task_rows
        self._task = FramePoseTask(robot.model, robot.platform_frame, rows)
        self._home_rotation = bool(self._free_fixed and {3, 4, 5} <= set(self._free_rows.tolist()))
        self.reach = ReachBound(robot)
        self._passive = _PassiveLimits(robot)
        iq = robot.actuated_q
        self._iq = iq
        self._lo = robot.model.lowerPositionLimit[iq]
        self._hi = robot.model.upperPositionLimit[iq]
        # rotary actuators: an angle counts modulo 2 pi (a continuation may pass +-pi)
        rotary = [
            robot.model.joints[int(j)].shortname().replace("JointModel", "") in _REVOLUTE
            for j in robot.actuated_joints
        ]
        self._wrap = np.array(rotary, dtype=bool)

    def checker(self) -> CollisionChecker:
        """The coal checker (built on first use; pairs overlapping at home left out)."""
        if self._checker is None:
            self._checker = interference_checker(self.robot)
            self.excluded_pairs = self._checker.excluded
        return self._checker

    # ------------------------------------------------------------------ one pose

    def solve(self, M: pin.SE3, q0: np.ndarray) -> np.ndarray | None:
        """Assembled configuration with the platform at ``M`` from ``q0``, or ``None``.

        On success the robot's data holds the kinematics of the solution.
        """
        if self._home_rotation:  # the orientation is not controlled and stays at home's
            M = pin.SE3(self._home_placement.rotation, M.translation)
        self._task.target = M
        sol = solve_pose(self.robot, self._task, q0, _TOL, _MAX_ITER, _STALL)
        if not sol.converged:
            return None
        self._jacobian = sol.jacobian
        pin.forwardKinematics(self.robot.model, self.robot.data, sol.q)
        return sol.q

    def _tangents(self) -> np.ndarray | None:
        """Configuration increments (nv, 3) per unit platform displacement along x, y, z.

        From the last solve's Jacobian: minimum-norm solutions of ``J dq = e`` (``None`` if
        singular).
        """
        J = self._jacobian
        if J is None:
            return None
        rows, cols = J.shape
        E = np.zeros((rows, 3))
        nc = self.robot.constraints.n_local  # (the solve's constraint rows)
        for i, axis in enumerate(self._task.rows.tolist()):
            if axis < 3:
                E[nc + i, axis] = 1.0  # d(p - p_target) = J dq - dp_target = 0
        try:
            if rows == cols:
                return np.linalg.solve(J, E)
            if rows < cols:
                return J.T.dot(np.linalg.solve(J.dot(J.T), E))
            return np.linalg.solve(J.T.dot(J), J.T.dot(E))
        except np.linalg.LinAlgError:
            return None

    def _limits(self, q: np.ndarray, kinds: tuple[str, ...], margin: float) -> int:
        """First limit an assembled ``q`` breaks (robot data: kinematics at ``q``)."""
        if "stroke" in kinds:
            qa = q[self._iq]
            if self._wrap.any():
                qa = np.where(self._wrap, self._lo + np.mod(qa - self._lo, 2.0 * math.pi), qa)
            if np.any((qa < self._lo) | (qa > self._hi)):
                return _STROKE
        if "joint" in kinds and self._passive.broken(self.robot, self.robot.data):
            return _JOINT
        if "interference" in kinds and float(np.min(self.checker().distances(q))) < margin:
            return _INTERFERENCE
        return REACHABLE

    def _classify(
        self, M: pin.SE3, q0: np.ndarray | None, kinds: tuple[str, ...], margin: float
    ) -> tuple[int, np.ndarray | None]:
        """Code and solution of a pose solved from ``q0`` then, if needed, from ``q_home``."""
        home = self.robot.q_home
        code, found = _REACH, None
        for start in (home,) if q0 is None else (q0, home):
            q = self.solve(M, start)
            if q is None or not self._mode_kept(None):
                continue
            code = self._limits(q, kinds, margin)
            if found is None or code == REACHABLE:
                found = q
            if code == REACHABLE:
                break
        return code, found

    def _mode_kept(self, ref: pin.SE3 | None) -> bool:
        """Whether the solution in the robot data keeps the assembly mode (see the class doc).

        Compares the platform pose components the robot does not control with the home
        configuration's where they are invariant, else (when given) with a neighbour's
        placement ``ref``, allowing :data:`_FREE_JUMP`.
        """
        if not self._free_rows.size:
            return True
        M = pin.updateFramePlacement(self.robot.model, self.robot.data, self._task.frame_id)
        if self._free_fixed:
            ref, tol = self._home_placement, _FREE_TOL
        elif ref is None:
            return True
        else:
            tol = _FREE_JUMP
        d = np.concatenate([M.translation - ref.translation, pin.log3(ref.rotation.T @ M.rotation)])
        return float(np.max(np.abs(d[self._free_rows]))) <= tol

    def _continue(
        self, M: pin.SE3, q0: np.ndarray, parent: np.ndarray, kinds: tuple[str, ...], margin: float
    ) -> tuple[int, np.ndarray | None]:
        """Code and solution of a pose by continuation from a neighbour's solution.

        ``q0`` is the prediction from the neighbour's solution ``parent``; then ``parent``
        itself, then ``q_home``, while the solve fails or leaves the assembly mode
        (:meth:`_mode_kept`: e.g. a Delta whose ball-jointed parallelograms cross and turn the
        nacelle).
        """
        ref = None
        if self._free_rows.size and not self._free_fixed:
            ref = self.robot.platform_placement(parent)
        home = self.robot.q_home
        starts = (q0, parent, home) if q0 is not parent else (parent, home)
        for start in starts:
            q = self.solve(M, start)
            if q is not None and self._mode_kept(ref):
                return self._limits(q, kinds, margin), q
        return _REACH, None

    def classify_pose(self, M: pin.SE3, kinds: tuple[str, ...], margin: float) -> int:
        """First limit broken with the platform at ``M`` (see :meth:`violations`).

        Solved from the previous reachable solution; when that breaks a limit or fails, solved
        again from ``q_home``, which keeps the assembly mode of the home configuration where a
        warm start would have jumped to another one.
        """
        code, q = self._classify(M, self.q if self.warm_start else None, kinds, margin)
        if code == REACHABLE and q is not None:
            self.q = q
        return code

    def violations(
        self, P: np.ndarray, R: np.ndarray, kinds: tuple[str, ...], margin: float
    ) -> np.ndarray:
        """See :meth:`PoseEvaluator.violations` (pose by pose, in the given order)."""
        P = np.atleast_2d(np.asarray(P, dtype=float))
        out = np.full(P.shape[0], _REACH, dtype=np.int8)
        todo = np.flatnonzero(self.reach.admits(P, R))
        for k in progress_bar(todo, "poses", "pose", self.progress, leave=False):
            out[k] = self.classify_pose(pin.SE3(R, P[k]), kinds, margin)
        return out

    # ------------------------------------------------------------------ grids

    def box_grid(
        self,
        xs: np.ndarray,
        ys: np.ndarray,
        zs: np.ndarray,
        R: np.ndarray,
        kinds: tuple[str, ...],
        margin: float,
        progress: bool | None = None,
    ) -> np.ndarray:
        """Violation codes on the grid ``xs x ys x zs`` (nx, ny, nz), by continuation.

        Args:
            xs: Grid coordinates along x [m].
            ys: Grid coordinates along y [m].
            zs: Grid coordinates along z [m].
            R: Platform orientation (3, 3).
            kinds: Kinds to check (``reach`` first).
            margin: Safety distance for ``interference`` [m].
            progress: Progress bar over the poses (``None``: when stderr is a terminal; not
                shown by the worker processes of a split grid).

        Returns:
            (nx, ny, nz) codes (see :meth:`PoseEvaluator.violations`).

        """
        if "interference" in kinds:
            self.checker()
        shape = (xs.size, ys.size, zs.size)
        n = int(np.prod(shape))
        workers = self.workers
        if workers is None:
            workers = 2 if usable_cores() >= 2 and n >= PARALLEL_SAMPLES else 1
        elif workers > 1:
            workers = worker_count(workers, shape[int(np.argmax(shape))], "workers")
        axis = int(np.argmax(shape))
        if workers < 2 or shape[axis] < 2 or "fork" not in multiprocessing.get_all_start_methods():
            return self._grid_serial(xs, ys, zs, R, kinds, margin, progress)
        parts = np.array_split(np.arange(shape[axis]), min(workers, shape[axis]))
        jobs = []
        for idx in parts:
            axes = [xs, ys, zs]
            axes[axis] = axes[axis][idx]
            jobs.append((axes[0], axes[1], axes[2], R, kinds, margin, False))
        global _WORKER
        _WORKER = self
        try:
            ctx = multiprocessing.get_context("fork")
            with ctx.Pool(len(jobs), initializer=worker_init, initargs=(os.getpid(),)) as pool:
                results = pool.map(_grid_job, jobs)
        finally:
            _WORKER = None
        return np.concatenate(results, axis=axis)

    def _grid_serial(
        self,
        xs: np.ndarray,
        ys: np.ndarray,
        zs: np.ndarray,
        R: np.ndarray,
        kinds: tuple[str, ...],
        margin: float,
        progress: bool | None,
    ) -> np.ndarray:
        shape = (xs.size, ys.size, zs.size)
        X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
        P = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
        codes = np.full(P.shape[0], _REACH, dtype=np.int8)
        ok = self.reach.admits(P, R)
        steps = self._continuation(P, R, shape, ok, codes, kinds, margin)
        total = int(ok.sum())
        for _ in progress_bar(steps, "workspace", "pose", progress, total=total, leave=False):
            pass
        return codes.reshape(shape)

    def _continuation(
        self,
        P: np.ndarray,
        R: np.ndarray,
        shape: tuple[int, int, int],
        ok: np.ndarray,
        codes: np.ndarray,
        kinds: tuple[str, ...],
        margin: float,
    ) -> Iterator[int]:
        """Breadth-first solve of the admitted samples (yields once per sample solved)."""
        # the frontier: warm start, whether it was reachable, and the step it was taken from
        # (a solution and the grid direction), to predict the next one along a line
        warm: dict[int, tuple[np.ndarray, np.ndarray, int]] = {}
        model = self.robot.model
        queued = ~ok  # rejected samples are never solved
        strides = np.array([shape[1] * shape[2], shape[2], 1])
        home = self.robot.platform_placement(self.robot.q_home).translation
        todo = np.flatnonzero(ok)
        order = todo[np.argsort(np.einsum("ni,ni->n", P[todo] - home, P[todo] - home))]
        queue: deque[int] = deque()
        for seed in order:
            if queued[seed]:
                continue
            queued[seed] = True
            queue.append(int(seed))
            seeded = True
            while queue:
                s = queue.popleft()
                M = pin.SE3(R, P[s])
                if seeded or not self.warm_start or s not in warm:
                    code, q = self._classify(M, None, kinds, margin)
                    parent, came = None, 0
                else:
                    start, parent, came = warm.pop(s)
                    code, q = self._continue(M, start, parent, kinds, margin)
                seeded = False
                codes[s] = code
                yield s
                if q is None:
                    continue
                idx = np.unravel_index(s, shape)
                tangents: np.ndarray | None | bool = False  # computed when a neighbour needs it
                for d in range(3):
                    for step in (-1, 1):
                        c = idx[d] + step
                        if 0 <= c < shape[d]:
                            nb = s + step * int(strides[d])
                            if not queued[nb]:
                                queued[nb] = True
                                if tangents is False:
                                    tangents = self._tangents()
                                q0 = q  # first-order prediction along the grid line
                                if isinstance(tangents, np.ndarray):
                                    dq = tangents[:, d] * (P[nb, d] - P[s, d])
                                    if float(np.abs(dq).max()) < _JUMP:
                                        q0 = pin.integrate(model, q, dq)
                                warm[nb] = (q0, q, step * (d + 1))
                                queue.append(nb)

    def default_bounds(self, R: np.ndarray) -> np.ndarray:
        """Home platform position +- the robot's size (farthest joint from the platform)."""
        data = self.robot.model.createData()
        pin.forwardKinematics(self.robot.model, data, self.robot.q_home)
        c = self.robot.platform_placement(self.robot.q_home).translation
        size = max(float(np.linalg.norm(M.translation - c)) for M in data.oMi)
        return np.column_stack([c - size, c + size])


def _free_components_fixed(robot: Robot) -> bool:
    """Whether the platform pose components the robot does not control stay put at home.

    True when no motion the closures allow at ``q_home`` moves them (a Delta's nacelle
    orientation, the height and tilt of a planar robot): then any solution in the home assembly
    mode has them at their home values.
    """
    assert robot.platform_frame is not None
    from pkdyn.analysis.kinematics import platform_jacobian

    model = robot.model
    Jx = platform_jacobian(robot, robot.q_home)
    free = np.setdiff1d(np.arange(6), robot.task_rows)
    if robot.constraints.n:
        J = robot.constraints.jacobian(model.createData(), robot.q_home)
        _, sv, Vt = np.linalg.svd(J)
        Z = Vt[int(np.sum(sv > 1e-9 * max(float(sv[0]), 1e-300))) :].T
    else:
        Z = np.eye(model.nv)
    K = Jx[free] @ Z
    return bool(np.max(np.abs(K), initial=0.0) <= 1e-9 * max(1.0, float(np.max(np.abs(Jx)))))


def _grid_job(
    job: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, tuple[str, ...], float, bool],
) -> np.ndarray:
    """One part of a grid, in a forked worker (the evaluator is inherited)."""
    assert _WORKER is not None
    return _WORKER._grid_serial(*job)
