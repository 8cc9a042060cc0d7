"""Geometric calibration of any loaded robot: robust Levenberg-Marquardt through the loops.

:func:`calibrate` estimates the errors ``p`` of a :class:`~pkdyn.precision.parameters.
ParameterModel` (placements, family shortcuts or family dimensions, actuator offsets and gains)
from :class:`~pkdyn.calibration.measurements.Measurements`:

1. the measurements are split into a calibration set and a held-out validation set (``holdout``,
   within each group for implicit kinds), or a validation set is given;
2. the nominal robot's forward geometry at the calibration readings gives the configurations,
   and :func:`pkdyn.precision.sensitivity.pose_sensitivity` the identification Jacobian;
   parameters the mechanism cannot absorb (an over-constrained loop: :attr:`PoseSensitivity.
   closure_gap`) are held at zero; the others are analysed by
   :func:`pkdyn.calibration.identifiability.identifiability`: only the identifiable subset is
   estimated, the unidentifiable parameters are reported with the combination that absorbs them
   and held at zero (the nominal value), never invented;
3. robust Levenberg-Marquardt (Gauss-Newton steps, halved or damped with Marquardt's scaling
   when they do not decrease the cost; iteratively reweighted: Huber or Cauchy
   weights on each measurement's residual, in units of its standard deviation, updated over the
   first accepted steps and then kept) on the residuals
   *model minus measurement*, each evaluation rebuilding the robot with the current parameters
   (:func:`pkdyn.precision.perturbation.perturbed`) and solving its forward geometry at the
   readings (warm-started from the previous solution: the assembly mode is kept), the Jacobian
   exact (:func:`pose_sensitivity` at the perturbed robot);
4. standard deviations of the estimates from the weighted normal matrix and the a-posteriori
   residual scale; errors before (nominal model) and after on both sets.

A weakly informative prior (:data:`PRIOR`: errors of a centimetre, 6 degrees, 1 % of gain)
is added to the least squares: it changes nothing the measurements determine, and keeps the
directions they barely see (an identifiable but ill-conditioned combination, e.g. with a few
fixed points in self-calibration) near the nominal robot instead of wandering with the noise.

Residuals, weighted by the measurement standard deviations ``sigma`` (position [m]) and
``sigma_rot`` (orientation [rad], default ``sigma`` divided by the robot's size): ``pose``:
``[p_model - p_measured; log3(R_measured^T R_model)]``; ``position``: the first three;
``point``: ``p_model - c_g`` (``c_g`` the group's unknown point); ``plane``: ``n_g . p_model -
d_g`` (the group's unknown unit normal and offset).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.calibration.identifiability import RTOL, Identifiability, identifiability
from pkdyn.calibration.measurements import Measurements
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel, parameter_model
from pkdyn.precision.perturbation import Perturbed, perturbed
from pkdyn.precision.sensitivity import pose_sensitivity
from pkdyn.threads import one_blas_thread
from solvers import numerics

__all__ = ["PRIOR", "ROBUST", "CalibrationResult", "ErrorStats", "calibrate", "parameter_scale"]

ROBUST = ("huber", "cauchy", "none")
"""Robust weights of :func:`calibrate`."""

_DAMPING = (0.0, 1e-4, 1e-2, 1.0, 1e2)
"""Marquardt damping factors tried in turn when the Gauss-Newton step (with halving) does not
decrease the cost."""
_HUBER_K = 2.5
_IRLS_ROUNDS = 3
"""Accepted steps after which the robust weights are updated; then kept, so that the
iterations converge on one weighted problem."""
_CAUCHY_K = 2.385
_GAP_TOL = 1e-9


PRIOR = (0.01, 0.1, 0.01)
"""Default prior standard deviations of the errors (length [m], angle [rad], gain): a
centimetre, 6 degrees, 1 %: far wider than any tolerance, so it only steadies the directions
the measurements barely see."""


def _prior(model: ParameterModel, prior: tuple[float, float, float]) -> np.ndarray:
    arr = np.asarray(prior, dtype=float)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise InvalidInputError("prior", f"{prior!r}: give (length, angle, gain) > 0")
    return model.tolerances(float(arr[0]), float(arr[1]), float(arr[2]))


def parameter_scale(robot: Robot, model: ParameterModel) -> np.ndarray:
    """Scale of each parameter [m per unit]: 1 for lengths, the robot's size for angles and gains.

    Makes parameters of different units commensurate (step sizes, observability indices).
    """
    L = robot.length_scale
    return np.array([1.0 if u == "m" else L for u in model.units])


@dataclass
class ErrorStats:
    """Errors of a model against measurements.

    Attributes:
        position_rms: RMS of the position error norm [m] (implicit kinds: of the distance to
            the group's point or plane).
        position_max: Largest position error norm [m].
        orientation_rms: RMS of the rotation error norm [rad] (``pose`` only, else 0).
        orientation_max: Largest rotation error norm [rad].
        count: Number of measurements.
        joint_rms: RMS of the measured joints' coordinate errors [rad or m] (``joints``).
        joint_max: Largest of them [rad or m].

    """

    position_rms: float
    position_max: float
    orientation_rms: float = 0.0
    orientation_max: float = 0.0
    count: int = 0
    joint_rms: float = 0.0
    joint_max: float = 0.0

    def as_dict(self) -> dict[str, float]:
        """JSON-ready form."""
        return dict(self.__dict__)


def _stats(kind: str, res: np.ndarray) -> ErrorStats:
    """Error statistics from unweighted residuals (N, rows)."""
    n = len(res)
    if n == 0:
        return ErrorStats(0.0, 0.0)
    if kind == "joints":
        e = np.abs(res)
        return ErrorStats(
            0.0, 0.0, count=n, joint_rms=float(np.sqrt(np.mean(e**2))), joint_max=float(e.max())
        )
    pos = np.linalg.norm(res[:, :3] if kind != "plane" else res[:, :1], axis=1)
    rot = np.linalg.norm(res[:, 3:6], axis=1) if kind == "pose" else np.zeros(n)
    return ErrorStats(
        float(np.sqrt(np.mean(pos**2))),
        float(np.max(pos)),
        float(np.sqrt(np.mean(rot**2))),
        float(np.max(rot)),
        n,
    )


@dataclass(eq=False)
class CalibrationResult:
    """The outcome of :func:`calibrate`.

    Attributes:
        robot: The calibrated robot (the nominal one with the identified errors).
        gains: Identified relative actuator gains (n_a,): joint coordinate ``(1 + gain) *
            reading``.
        nominal: The nominal robot.
        model: The parameter model.
        p: Identified parameter errors (n_par,) [m, rad, -]; zero for the parameters not
            estimated.
        std: Their standard deviations (n_par,); NaN for the parameters not estimated.
        identifiability: Identifiable subset, unidentifiable combinations and observability
            indices of the calibration poses (nominal robot).
        not_assembling: Parameters the mechanism cannot absorb (held at zero).
        nuisance: Identified unknowns of implicit measurements: ``{"points": (G, 3)}`` or
            ``{"planes": (G, 4)}`` (unit normal, offset [m]).
        sigma: Measurement standard deviations used as weights (position [m], orientation
            [rad]).
        scale: A-posteriori residual scale (RMS weighted residual in units of ``sigma``): near 1
            when ``sigma`` is the true noise.
        before: Errors of the nominal model on the calibration set.
        after: Errors of the calibrated model on the calibration set.
        validation_before: Nominal model on the validation set (``None``: no validation).
        validation_after: Calibrated model on the validation set.
        weights: Final robust weight of each calibration measurement.
        calibration_rows: Indices (in the input) of the calibration measurements.
        validation_rows: Indices of the validation measurements.
        iterations: Levenberg-Marquardt iterations.
        converged: Whether the iterations converged.

    """

    robot: Robot
    gains: np.ndarray
    nominal: Robot
    model: ParameterModel
    p: np.ndarray
    std: np.ndarray
    identifiability: Identifiability
    not_assembling: tuple[str, ...]
    nuisance: dict[str, np.ndarray]
    sigma: tuple[float, float]
    scale: float
    before: ErrorStats
    after: ErrorStats
    validation_before: ErrorStats | None
    validation_after: ErrorStats | None
    weights: np.ndarray
    calibration_rows: np.ndarray
    validation_rows: np.ndarray
    iterations: int
    converged: bool

    @property
    def estimated(self) -> np.ndarray:
        """Indices of the estimated (identifiable) parameters."""
        return np.asarray(self.identifiability.identifiable, dtype=int)

    @property
    def outliers(self) -> np.ndarray:
        """Calibration measurements (input indices) the robust weights reduced below 1/2."""
        return self.calibration_rows[self.weights < 0.5]

    def perturbed(self) -> Perturbed:
        """The calibrated robot and its gains."""
        return Perturbed(self.robot, self.gains)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready summary (parameters, identifiability, errors)."""
        ident = self.identifiability.as_dict()
        est = set(int(i) for i in self.estimated)
        return {
            "model": self.model.kind,
            "parameters": [
                {
                    "name": n,
                    "unit": u,
                    "value": float(v),
                    "std": float(s) if k in est else None,
                }
                for k, (n, u, v, s) in enumerate(
                    zip(self.model.names, self.model.units, self.p, self.std, strict=True)
                )
                if k in est
            ],
            "unidentifiable": ident["unidentifiable"],
            "not_assembling": list(self.not_assembling),
            "observability": ident["observability"],
            "noise_amplification": ident["noise_amplification"],
            "sigma": list(self.sigma),
            "scale": self.scale,
            "before": self.before.as_dict(),
            "after": self.after.as_dict(),
            "validation_before": None
            if self.validation_before is None
            else self.validation_before.as_dict(),
            "validation_after": None
            if self.validation_after is None
            else self.validation_after.as_dict(),
            "outliers": [int(i) for i in self.outliers],
            "poses": {
                "calibration": int(self.calibration_rows.size),
                "validation": int(self.validation_rows.size),
            },
            "iterations": self.iterations,
            "converged": self.converged,
        }


def _split(m: Measurements, holdout: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    n = len(m)
    if not 0.0 <= holdout < 1.0:
        raise InvalidInputError("holdout", f"{holdout}: give a fraction in [0, 1)")
    rng = np.random.default_rng(seed)
    if holdout == 0.0:
        return np.arange(n), np.zeros(0, dtype=int)
    groups = (
        [np.arange(n)]
        if m.group is None
        else [np.flatnonzero(m.group == g) for g in np.unique(m.group)]
    )
    val: list[int] = []
    for idx in groups:
        k = int(round(holdout * idx.size))
        val += list(rng.choice(idx, k, replace=False)) if k else []
    val_arr = np.sort(np.array(val, dtype=int))
    cal = np.setdiff1d(np.arange(n), val_arr)
    return cal, val_arr


class _Problem:
    """Residuals and Jacobian of one set of measurements, as functions of the parameters."""

    def __init__(
        self,
        robot: Robot,
        model: ParameterModel,
        m: Measurements,
        sigma: tuple[float, float],
        qs: list[np.ndarray],
    ) -> None:
        self.robot, self.model, self.m = robot, model, m
        self.sigma = sigma
        self.qs = qs
        self.groups = np.unique(m.group) if m.group is not None else np.zeros(0, int)
        self.n_nuis = {"point": 3, "plane": 3}.get(m.kind, 0) * self.groups.size
        self.normal0: list[np.ndarray] = []
        self.tangents: list[np.ndarray] = []
        self.last_gap = np.zeros(model.size)
        self.jq = np.zeros(0, dtype=int)
        self.jv = np.zeros(0, dtype=int)
        self.revolute = np.zeros(0, dtype=bool)
        if m.kind == "joints":
            ids = [robot.model.getJointId(j) for j in m.joints]
            joints = [robot.model.joints[i] for i in ids]
            self.jq = np.array([j.idx_q for j in joints], dtype=int)
            self.jv = np.array([j.idx_v for j in joints], dtype=int)
            self.revolute = np.array(["Prismatic" not in j.shortname() for j in joints])

    # -- nuisance parameters of implicit measurements
    def init_nuisance(self, positions: np.ndarray) -> np.ndarray:
        """Initial points (centroids) or planes (fitted) from positions of the nominal robot."""
        out = []
        assert self.m.group is not None or not self.n_nuis
        for g in self.groups:
            P = positions[self.m.group == g]
            c = P.mean(axis=0)
            if self.m.kind == "point":
                out.append(c)
                continue
            _, _, Vt = np.linalg.svd(P - c)
            n = Vt[-1]
            t1 = Vt[0]
            t2 = np.cross(n, t1)
            self.normal0.append(n)
            self.tangents.append(np.column_stack([t1, t2]))
            out.append(np.array([0.0, 0.0, float(n @ c)]))
        return np.concatenate(out) if out else np.zeros(0)

    def _plane(self, k: int, y: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
        """Unit normal, offset and d(normal)/d(phi) (3, 2) of plane ``k`` from its unknowns."""
        w = self.tangents[k] @ y[:2]
        R = pin.exp3(w)
        n = R @ self.normal0[k]
        dn = -R @ pin.skew(self.normal0[k]) @ pin.Jexp3(w) @ self.tangents[k]
        return n, float(y[2]), dn

    def nuisance_dict(self, y: np.ndarray) -> dict[str, np.ndarray]:
        """Points (G, 3) or planes (G, 4) from the unknowns."""
        if self.m.kind == "point":
            return {"points": y.reshape(-1, 3)}
        if self.m.kind == "plane":
            planes = []
            for k in range(self.groups.size):
                n, d, _ = self._plane(k, y[3 * k : 3 * k + 3])
                planes.append(np.concatenate([n, [d]]))
            return {"planes": np.array(planes)}
        return {}

    # -- model evaluation
    def solve(self, p: np.ndarray) -> tuple[Perturbed, list[np.ndarray], list[pin.SE3]]:
        """The perturbed robot and its configurations and platform poses at the readings."""
        P = perturbed(self.robot, self.model, p)
        qs, poses = [], []
        for q0, reading in zip(self.qs, self.m.qa, strict=True):
            g = forward_geometry(
                P.robot, P.joint_coordinates(reading), q_init=q0, check_limits=False
            )
            assert g.placement is not None
            qs.append(g.q)
            poses.append(g.placement)
        return P, qs, poses

    def raw_residuals(
        self, poses: list[pin.SE3], y: np.ndarray, qs: list[np.ndarray] | None = None
    ) -> np.ndarray:
        """Unweighted residuals (N, rows) [m, rad] (``joints``: of the configurations ``qs``)."""
        m = self.m
        out = np.zeros((len(poses), m.rows))
        if m.kind == "joints":
            assert qs is not None and m.q is not None
            Q = np.array([q[self.jq] for q in qs]).reshape(len(poses), -1)
            d = Q - m.q
            return np.where(self.revolute, np.angle(np.exp(1j * d)), d)
        for i, M in enumerate(poses):
            if m.kind in ("pose", "position"):
                assert m.position is not None
                out[i, :3] = M.translation - m.position[i]
                if m.kind == "pose":
                    out[i, 3:] = pin.log3(m.rotations[i].T @ M.rotation)
            elif m.kind == "point":
                assert m.group is not None
                k = int(np.searchsorted(self.groups, m.group[i]))
                out[i] = M.translation - y[3 * k : 3 * k + 3]
            else:
                assert m.group is not None
                k = int(np.searchsorted(self.groups, m.group[i]))
                n, d, _ = self._plane(k, y[3 * k : 3 * k + 3])
                out[i, 0] = n @ M.translation - d
        return out

    def row_sigma(self) -> np.ndarray:
        """Standard deviation of each residual row (rows,)."""
        s_pos, s_rot = self.sigma
        if self.m.kind == "joints":
            return np.where(self.revolute, s_rot, s_pos)
        per = np.array([s_pos, s_pos, s_pos, s_rot, s_rot, s_rot])[: self.m.rows]
        return per

    def jacobian(
        self,
        P: Perturbed,
        qs: list[np.ndarray],
        poses: list[pin.SE3],
        p: np.ndarray,
        y: np.ndarray,
        cols: np.ndarray,
    ) -> np.ndarray:
        """Unweighted Jacobian (N, rows, len(cols) + n_nuis) of the raw residuals."""
        m = self.m
        N, d = len(qs), m.rows
        out = np.zeros((N, d, cols.size + self.n_nuis))
        self.last_gap = np.zeros(self.model.size)
        for i, (q, M) in enumerate(zip(qs, poses, strict=True)):
            sens = pose_sensitivity(P.robot, q, self.model, at=p)
            if sens.gap.size:
                g = np.max(np.abs(sens.gap), axis=0)
                self.last_gap = np.maximum(self.last_gap, g)
            K = sens.K[:, cols]
            if m.kind == "joints":
                assert sens.joints is not None
                out[i, :, : cols.size] = sens.joints[self.jv][:, cols]
                continue
            if m.kind in ("pose", "position"):
                out[i, :3, : cols.size] = K[:3]
                if m.kind == "pose":
                    E = m.rotations[i].T @ M.rotation
                    out[i, 3:, : cols.size] = pin.Jlog3(E) @ K[3:]
            elif m.kind == "point":
                assert m.group is not None
                k = int(np.searchsorted(self.groups, m.group[i]))
                out[i, :, : cols.size] = K[:3]
                out[i, :, cols.size + 3 * k : cols.size + 3 * k + 3] = -np.eye(3)
            else:
                assert m.group is not None
                k = int(np.searchsorted(self.groups, m.group[i]))
                n, _, dn = self._plane(k, y[3 * k : 3 * k + 3])
                out[i, 0, : cols.size] = n @ K[:3]
                out[i, 0, cols.size + 3 * k : cols.size + 3 * k + 2] = M.translation @ dn
                out[i, 0, cols.size + 3 * k + 2] = -1.0
        return out


def _inverse(A: np.ndarray) -> np.ndarray:
    """Inverse of a normal matrix (positive definite: its columns are identifiable).

    A pseudo-inverse cut at round-off (:mod:`solvers.numerics`) if it is singular after all.
    """
    try:
        return np.linalg.inv(A)
    except np.linalg.LinAlgError:
        return numerics.lstsq(A, np.eye(A.shape[0]), numerics.machine_rtol(A))


def _rank(J: np.ndarray) -> int:
    """Rank of a Jacobian with its columns normalised (:data:`RTOL`)."""
    if J.size == 0:
        return 0
    W = J / np.maximum(np.linalg.norm(J, axis=0), 1e-300)
    s = np.linalg.svd(W, compute_uv=False)
    return int(np.sum(s > RTOL * s[0])) if s.size and s[0] > 0 else 0


def _scaled_readings(m: Measurements, gain: np.ndarray) -> Measurements:
    """The measurements with their readings multiplied by the encoder gains (joint coords)."""
    return Measurements(m.kind, m.qa * gain, m.position, m.rpy, m.group, m.joints, m.q)


def _check_far(robot: Robot, m: Measurements, rows: np.ndarray, positions: np.ndarray) -> None:
    """Refuse a measured position more than 100 robot sizes from the nominal model's."""
    if m.position is None:
        return
    gap = np.linalg.norm(m.position - positions, axis=1)
    far = np.flatnonzero(gap > 100.0 * robot.length_scale)
    if far.size:
        i = int(far[0])
        raise InvalidInputError(
            "measurements",
            f"row {int(rows[i]) + 1}: the measured position lies {gap[i]:.3g} m from the nominal "
            f"{robot.name}'s, more than 100 times its size ({robot.length_scale:.3g} m): a unit "
            "or frame error (positions in metres, in the robot's world frame)",
        )


def _nominal_configurations(robot: Robot, m: Measurements, rows: np.ndarray) -> list[np.ndarray]:
    qs = []
    for i, reading in zip(rows, m.qa, strict=True):
        try:
            qs.append(forward_geometry(robot, reading, check_limits=False).q)
        except PkdynError as err:
            raise InvalidInputError(
                "measurements",
                f"row {int(i) + 1}: the nominal {robot.name} cannot be assembled at these "
                f"actuator readings ({err})",
            ) from None
    return qs


def _weights(u: np.ndarray, robust: str, known: bool) -> np.ndarray:
    """Robust weight of each measurement from its residual norm ``u`` (units of sigma)."""
    if robust == "none" or u.size == 0:
        return np.ones_like(u)
    scale = 1.0 if known else max(1.4826 * float(np.median(u)), 1e-300)
    t = u / scale
    if robust == "huber":
        return np.where(t <= _HUBER_K, 1.0, _HUBER_K / np.maximum(t, 1e-300))
    return 1.0 / (1.0 + (t / _CAUCHY_K) ** 2)


def _structural_rank(
    robot: Robot, model: ParameterModel, m: Measurements, qs: list[np.ndarray], keep: np.ndarray
) -> int:
    """Rank the model reaches on many configurations interpolated between the measured ones."""
    rng = np.random.default_rng(1)
    n = max(2 * model.size // max(m.rows, 1) + 6, 12)
    rows = []
    n_meas = len(m)
    for _ in range(n):
        i, j = rng.integers(n_meas, size=2)
        t = rng.uniform(0.0, 1.0)
        qa = (1.0 - t) * m.qa[i] + t * m.qa[j]
        qa = qa + rng.normal(0.0, 0.02, qa.size) * robot.actuator_scale
        try:
            q = forward_geometry(robot, qa, q_init=qs[i], check_limits=False).q
            sens = pose_sensitivity(robot, q, model)
            if m.kind == "joints":
                assert sens.joints is not None
                ids = [robot.model.getJointId(j) for j in m.joints]
                K = sens.joints[[robot.model.joints[k].idx_v for k in ids]]
            else:
                K = sens.K[: min(m.rows, 6) if m.kind != "plane" else 3]
        except PkdynError:
            continue
        rows.append(K[:, keep])
    if not rows:
        return 0
    W = np.vstack(rows)
    W = W / np.maximum(np.linalg.norm(W, axis=0), 1e-300)
    s = np.linalg.svd(W, compute_uv=False)
    return int(np.sum(s > RTOL * s[0]))


def _sigma(robot: Robot, noise: float | Sequence[float] | None) -> tuple[tuple[float, float], bool]:
    from pkdyn.inputs import vector

    if noise is None:
        s = 1e-5
        return (s, s / robot.length_scale), False
    try:
        arr = vector("noise", noise, (1, 2))
    except InvalidInputError:
        arr = np.array([np.nan])
    if arr.size not in (1, 2) or not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise InvalidInputError(
            "noise",
            f"{noise!r:.60}: give the position noise [m] and optionally the orientation "
            "noise [rad], > 0",
        )
    if arr[0] > robot.length_scale or (arr.size == 2 and arr[1] > math.pi):
        raise InvalidInputError(
            "noise",
            f"{noise!r:.60}: a measurement noise larger than the robot ({robot.length_scale:.3g} "
            "m) or than pi rad measures nothing; give the standard deviation [m] [rad]",
        )
    s_pos = float(arr[0])
    s_rot = float(arr[1]) if arr.size == 2 else s_pos / robot.length_scale
    return (s_pos, s_rot), True


@one_blas_thread
def calibrate(
    robot: Robot,
    measurements: Measurements,
    model: ParameterModel | str = "auto",
    noise: float | Sequence[float] | None = None,
    holdout: float = 0.2,
    validation: Measurements | None = None,
    robust: str = "huber",
    rtol: float = RTOL,
    gains: bool = False,
    max_iter: int = 30,
    seed: int = 0,
    prior: tuple[float, float, float] | None = PRIOR,
) -> CalibrationResult:
    """Identify a robot's geometric errors from measurements (module docstring).

    Args:
        robot: The nominal robot.
        measurements: The measurements (:func:`pkdyn.calibration.read_csv`).
        model: A parameter model, or its name for :func:`pkdyn.precision.parameters.
            parameter_model` (``auto``: family shortcuts for the Delta and Gough-Stewart,
            else every placement).
        noise: Measurement standard deviation: position [m], or ``(position [m], orientation
            [rad])``; ``None``: unknown (weights from ``1e-5`` m, the robust scale estimated).
        holdout: Fraction of the measurements held out for validation (ignored when
            ``validation`` is given).
        validation: Separate validation measurements (same kind).
        robust: ``huber``, ``cauchy`` or ``none``.
        rtol: Identifiability threshold (:data:`pkdyn.calibration.identifiability.RTOL`).
        gains: With a model name: add one relative gain per actuator.
        max_iter: Largest number of Levenberg-Marquardt iterations.
        seed: Seed of the hold-out split.
        prior: Prior standard deviations of the errors ``(length [m], angle [rad], gain)``
            (:data:`PRIOR`): a weakly informative prior that keeps directions the measurements
            barely see near the nominal robot instead of letting noise move them far; ``None``:
            none.

    Returns:
        The calibration.

    Raises:
        InvalidInputError: Bad options, measurements the nominal robot cannot be assembled at,
            or fewer measured values than identifiable parameters (the message says how many
            poses are needed).

    """
    from pkdyn.inputs import count, flag, instance, positive, real, vector
    from pkdyn.inputs import seed as _seed

    instance("robot", robot, Robot, "a Robot (pkdyn.load)")
    instance(
        "measurements", measurements, Measurements, "Measurements (pkdyn.calibration.read_csv)"
    )
    if validation is not None:
        instance("validation", validation, Measurements, "Measurements or None")
    if robust not in ROBUST:
        raise InvalidInputError("robust", f"'{robust}': use {', '.join(ROBUST)}")
    holdout = real("holdout", holdout)
    rtol = positive("rtol", rtol, bound=0.5)
    gains = flag("gains", gains)
    max_iter = count("max_iter", max_iter, 1, 10_000)
    seed = _seed("seed", seed)
    if prior is not None:
        pr = vector("prior", prior, 3, "m, rad, -", bound=1e3)
        if np.any(pr <= 0.0):
            raise InvalidInputError("prior", f"{tuple(pr)}: give three standard deviations > 0")
        prior = (float(pr[0]), float(pr[1]), float(pr[2]))
    if not isinstance(model, str | ParameterModel):
        instance("model", model, (str, ParameterModel), "a ParameterModel or its kind's name")
    if len(measurements.qa[0]) != len(robot.actuators):
        raise InvalidInputError(
            "measurements",
            f"{measurements.qa.shape[1]} actuator readings per row; {robot.name} has "
            f"{len(robot.actuators)} ({', '.join(robot.actuator_names)})",
        )
    pm = parameter_model(robot, model, gains) if isinstance(model, str) else model
    sigma, known = _sigma(robot, noise)
    # readings -> the nominal robot's joint coordinates (its <pkdyn:encoder gain>, 1 unless it
    # was calibrated before); the relative gains estimated here multiply them
    base_gain = np.array([float(a.encoder_gain) for a in robot.actuators])
    if np.any(base_gain != 1.0):
        measurements = _scaled_readings(measurements, base_gain)
        if validation is not None:
            validation = _scaled_readings(validation, base_gain)
    if validation is not None:
        if validation.kind != measurements.kind:
            raise InvalidInputError("validation", "must be measurements of the same kind")
        cal_rows, val_rows = np.arange(len(measurements)), np.zeros(0, dtype=int)
        cal, val = measurements, validation
    else:
        cal_rows, val_rows = _split(measurements, holdout, seed)
        cal, val = measurements.subset(cal_rows), measurements.subset(val_rows)
    if len(cal) == 0:
        raise InvalidInputError("measurements", "no measurement left for the calibration")
    cal.check_groups()
    qs = _nominal_configurations(robot, cal, cal_rows)
    prob = _Problem(robot, pm, cal, sigma, qs)
    row_sigma = np.tile(prob.row_sigma(), len(cal))

    # identifiability at the nominal robot
    zero = np.zeros(pm.size)
    P0, qs0, poses0 = prob.solve(zero)
    prob.qs = qs0
    positions0 = np.array([M.translation for M in poses0])
    _check_far(robot, cal, cal_rows, positions0)
    y0 = prob.init_nuisance(positions0)
    J_all = prob.jacobian(P0, qs0, poses0, zero, y0, np.arange(pm.size))
    gaps = prob.last_gap
    keep = np.flatnonzero(gaps <= _GAP_TOL)
    not_assembling = tuple(pm.names[k] for k in np.flatnonzero(gaps > _GAP_TOL))
    J0 = np.concatenate([J_all[:, :, keep], J_all[:, :, pm.size :]], axis=2)
    J0 = J0.reshape(len(cal) * cal.rows, -1)
    W0 = J0 / row_sigma[:, None]
    names = tuple(pm.names[k] for k in keep) + _nuisance_names(cal, prob.groups)
    scale_all = np.concatenate([parameter_scale(robot, pm)[keep], _nuisance_scale(robot, prob)])
    prior_all = None
    if prior is not None:
        prior_all = np.concatenate([_prior(pm, prior)[keep], _nuisance_prior(robot, prob)])
    ident = identifiability(W0, names, len(cal), scale_all, rtol, prior_all)
    n_values = len(cal) * cal.rows
    own = _rank(J0)  # what these poses can tell apart, noise aside
    if own < min(n_values, keep.size + prob.n_nuis):
        r_struct = _structural_rank(robot, pm, cal, qs0, keep) + prob.n_nuis
        if own < r_struct:
            warnings.warn(
                f"these {len(cal)} poses identify {own} of the {r_struct} parameters that "
                f"poses spread over the workspace would ({pm.kind} model): the others are held "
                "at nominal; measure more varied poses (pkdyn.calibration.selection)",
                stacklevel=2,
            )
    if ident.rank >= n_values or n_values <= keep.size + prob.n_nuis:
        r_struct = _structural_rank(robot, pm, cal, qs0, keep) + prob.n_nuis
        if n_values <= r_struct:
            need = math.ceil((r_struct + 1) / cal.rows)
            n_total = need if val_rows.size == 0 else math.ceil(need / (1.0 - holdout))
            raise InvalidInputError(
                "measurements",
                f"{len(cal)} calibration poses give {n_values} measured values for "
                f"{r_struct} identifiable parameters ({pm.kind} model, {cal.kind} "
                f"measurements): measure at least {need} poses"
                + (f" ({n_total} with the {holdout:.0%} hold-out)" if val_rows.size else ""),
            )
    # estimated columns: identifiable robot parameters and nuisance unknowns
    est = ident.identifiable
    n_rob = keep.size
    rob_cols = np.sort(est[est < n_rob])
    nuis_cols = np.sort(est[est >= n_rob]) - n_rob
    cols = keep[rob_cols]

    def unpack(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = np.zeros(pm.size)
        p[cols] = z[: cols.size]
        y = y0.copy()
        y[nuis_cols] = y[nuis_cols] + z[cols.size :]
        return p, y

    def weighted(poses: list[pin.SE3], y: np.ndarray, qs_: list[np.ndarray]) -> np.ndarray:
        return prob.raw_residuals(poses, y, qs_).reshape(-1) / row_sigma

    def jac(
        P: Perturbed, qs_: list[np.ndarray], poses: list[pin.SE3], p: np.ndarray, y: np.ndarray
    ) -> np.ndarray:
        Jfull = prob.jacobian(P, qs_, poses, p, y, cols).reshape(len(cal) * cal.rows, -1)
        Jz = np.hstack([Jfull[:, : cols.size], Jfull[:, cols.size :][:, nuis_cols]])
        return Jz / row_sigma[:, None]

    # weakly informative prior on the robot's errors (none on the unknowns of implicit kinds)
    pw = np.zeros(cols.size + nuis_cols.size)
    if prior is not None:
        pri = _prior(pm, prior)[cols]
        pw[: cols.size] = 1.0 / pri**2

    def total(rr: np.ndarray, zz: np.ndarray, ww: np.ndarray) -> float:
        return 0.5 * float(np.sum(ww * rr**2)) + 0.5 * float(np.sum(pw * zz**2))

    z = np.zeros(cols.size + nuis_cols.size)
    p, y = unpack(z)
    P, qcur, poses = P0, qs0, poses0
    r = weighted(poses, y, qcur)
    J0z = np.hstack([J_all.reshape(len(cal) * cal.rows, -1)[:, cols], J0[:, n_rob:][:, nuis_cols]])
    J = J0z / row_sigma[:, None]  # exact at the nominal robot; refreshed while nonlinear
    fresh = True
    d = cal.rows
    w = _weights(np.linalg.norm(r.reshape(-1, d), axis=1) / math.sqrt(d), robust, known)
    wr = np.repeat(w, d)
    cost = total(r, z, wr)
    iterations, converged, accepted = 0, False, 0
    for it in range(1, max_iter + 1):
        iterations = it
        A = J.T @ (wr[:, None] * J) + np.diag(pw)
        g = J.T @ (wr * r) + pw * z
        D = np.maximum(np.diag(A), 1e-12 * max(float(np.max(np.diag(A), initial=0.0)), 1e-300))
        step_ok = False
        # Gauss-Newton with backtracking, then Levenberg-Marquardt damping if that fails:
        # a persistent Marquardt damping would crawl along ill-conditioned directions
        for mu in _DAMPING:
            try:
                direction = np.linalg.solve(A + mu * np.diag(D), -g)
            except np.linalg.LinAlgError:
                continue
            for alpha in (1.0, 0.5, 0.25) if mu == 0.0 else (1.0,):
                delta = alpha * direction
                z_new = z + delta
                p_new, y_new = unpack(z_new)
                try:
                    P_new, q_new, poses_new = prob.solve(p_new)
                    r_new = weighted(poses_new, y_new, q_new)
                    cost_new = total(r_new, z_new, wr)
                except PkdynError:
                    cost_new = math.inf
                if cost_new <= cost:
                    step_ok = True
                    break
            if step_ok:
                break
        if not step_ok:  # no step decreases the cost: a minimum, within round-off
            if fresh:
                converged = True
                break
            J, fresh = jac(P, qcur, poses, p, y), True
            continue
        predicted = -float(g @ delta + 0.5 * delta @ (A @ delta))
        rho = (cost - cost_new) / max(predicted, 1e-300)
        decrease = (cost - cost_new) / max(cost, 1e-300)
        # a step far below the parameters' uncertainty (diag of the inverse normal matrix, in
        # units of sigma) changes nothing that the measurements can tell
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            unc = np.sqrt(np.maximum(np.diag(_inverse(A)), 1e-300))
        small = bool(np.max(np.abs(delta) / unc, initial=0.0) < 1e-3)
        z, p, y = z_new, p_new, y_new
        P, qcur, poses, r = P_new, q_new, poses_new, r_new
        prob.qs = qcur
        accepted += 1
        if accepted <= _IRLS_ROUNDS and robust != "none":  # reweighted a few times, then kept
            w = _weights(np.linalg.norm(r.reshape(-1, d), axis=1) / math.sqrt(d), robust, known)
            wr = np.repeat(w, d)
        frozen = robust == "none" or accepted >= _IRLS_ROUNDS
        cost = total(r, z, wr)
        if frozen and (small or decrease < 1e-7):
            if not fresh:  # make sure the fixed point is the exact Jacobian's
                J, fresh = jac(P, qcur, poses, p, y), True
                continue
            converged = True
            break
        if decrease > 0.5 or rho < 0.9:  # far from the solution, or the model is off: the
            J, fresh = jac(P, qcur, poses, p, y), True  # Jacobian moves; else it is kept
        else:
            fresh = False
    if not fresh:
        J = jac(P, qcur, poses, p, y)
    # uncertainties (posterior: the prior included)
    A = J.T @ (wr[:, None] * J) + np.diag(pw)
    dof = max(r.size - z.size, 1)
    s_hat = math.sqrt(float(np.sum(wr * r**2)) / dof)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cov = _inverse(A)
    std_z = np.sqrt(np.maximum(np.diag(cov), 0.0)) * s_hat
    std = np.full(pm.size, np.nan)
    std[cols] = std_z[: cols.size]
    # errors before / after
    res_before = prob.raw_residuals(poses0, y0, qs0)
    res_after = prob.raw_residuals(poses, y, qcur)
    val_before = val_after = None
    if len(val):
        vq = _nominal_configurations(robot, val, val_rows)
        vprob = _Problem(robot, pm, val, sigma, vq)
        vprob.groups, vprob.normal0, vprob.tangents = prob.groups, prob.normal0, prob.tangents
        _, vq0, vposes0 = vprob.solve(zero)
        vprob.qs = vq0
        val_before = _stats(val.kind, vprob.raw_residuals(vposes0, y0, vq0))
        try:
            _, vq1, vposes = vprob.solve(p)
            val_after = _stats(val.kind, vprob.raw_residuals(vposes, y, vq1))
        except PkdynError as err:
            raise InvalidInputError(
                "validation", f"the calibrated robot cannot reach a validation pose ({err})"
            ) from None
    full_ident = _robot_identifiability(ident, keep, n_rob, pm)
    return CalibrationResult(
        robot=P.robot,
        gains=P.gains,
        nominal=robot,
        model=pm,
        p=p,
        std=std,
        identifiability=full_ident,
        not_assembling=not_assembling,
        nuisance=prob.nuisance_dict(y),
        sigma=sigma,
        scale=s_hat,
        before=_stats(cal.kind, res_before),
        after=_stats(cal.kind, res_after),
        validation_before=val_before,
        validation_after=val_after,
        weights=w,
        calibration_rows=cal_rows,
        validation_rows=val_rows,
        iterations=iterations,
        converged=converged,
    )


def _nuisance_names(m: Measurements, groups: np.ndarray) -> tuple[str, ...]:
    if m.kind == "point":
        return tuple(f"point{g}.{c}" for g in groups for c in "xyz")
    if m.kind == "plane":
        return tuple(f"plane{g}.{c}" for g in groups for c in ("tilt1", "tilt2", "offset"))
    return ()


def _nuisance_scale(robot: Robot, prob: _Problem) -> np.ndarray:
    if prob.m.kind == "plane":
        return np.tile([robot.length_scale, robot.length_scale, 1.0], prob.groups.size)
    return np.ones(prob.n_nuis)


def _nuisance_prior(robot: Robot, prob: _Problem) -> np.ndarray:
    """Prior scale of the unknowns of implicit measurements: a metre, a radian (no prior)."""
    if prob.m.kind == "plane":
        return np.tile([1.0, 1.0, robot.length_scale], prob.groups.size)
    return np.full(prob.n_nuis, robot.length_scale)


def _robot_identifiability(
    ident: Identifiability, keep: np.ndarray, n_rob: int, pm: ParameterModel
) -> Identifiability:
    """The analysis re-indexed on the full parameter model (nuisance unknowns named after)."""
    names = pm.names + ident.names[n_rob:]

    def full(i: int) -> int:
        return int(keep[i]) if i < n_rob else pm.size + i - n_rob

    ids = np.array([full(int(i)) for i in ident.identifiable], dtype=int)
    un = np.array([full(int(i)) for i in ident.unidentifiable], dtype=int)
    combos = {full(int(j)): c for j, c in ident.combinations.items()}
    out = Identifiability(
        tuple(names),
        ids,
        un,
        combos,
        ident.r_diag,
        ident.singular_values,
        ident.indices,
        ident.poses,
        np.array([full(int(i)) for i in ident.weak], dtype=int),
    )
    return out
