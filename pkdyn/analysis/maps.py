"""Vectorised singularity and conditioning maps over workspace slices (closed forms).

For the Delta (Clavel's models, :mod:`pkdyn.closed_form.delta`) and the planar 3-RRR (Pasqui's
inverse model, :mod:`pkdyn.closed_form.planar_3rrr`), poses are mapped to actuator coordinates in
closed form and the reciprocal-screw matrices of :mod:`pkdyn.analysis.screws` give ``A`` and ``B``
without any numeric solve: ~1e5 poses per second. Each map holds, per pose:

- ``det_A``, ``det_B``: determinants in the seed's normalisation (signed, continuous: their
  zero level sets are the parallel and serial singularity loci);
- ``cond_A``, ``cond_B``: condition numbers of the orthonormal form used by
  :func:`pkdyn.analysis.kinematics.kinematic_models` (identical values, tested);
- ``cond_J``, ``lci``, ``manipulability``: dexterity of ``J = A^-1 B``
  (:mod:`pkdyn.analysis.dexterity`); at parallel singularities ``cond_J`` is capped at
  :data:`pkdyn.analysis.kinematics.COND_MAX`, ``lci`` is 0 and ``manipulability`` NaN;
- ``kind``: 0 regular, 1 serial, 2 parallel, 3 both (:mod:`pkdyn.analysis.singularity`'s
  scale-aware margins and thresholds), -1 unreachable.

Unreachable poses (outside the workspace of the chosen working mode) have ``valid`` False and NaN
values. The Delta's reduced model (nacelle = point) does not see Clavel's family c) (nacelle
rotation); :func:`pkdyn.analysis.singularity.classify` on the full model does. Plotting:
:func:`pkdyn.plotting.plot_conditioning_map`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkdyn.analysis.dexterity import (
    condition_number,
    homogenise,
    local_conditioning_index,
    manipulability,
)
from pkdyn.analysis.kinematics import (
    COND_MAX,
    NEAR_SERIAL_TOL,
    NEAR_SINGULAR_TOL,
    SINGULAR_TOL,
    relation_margins,
)
from pkdyn.analysis.screws import delta_AB, normalise, planar_3rrr_AB, planar_3rrr_chain_angles
from pkdyn.closed_form import delta as delta_cf
from pkdyn.closed_form import planar_3rrr as rrr_cf
from pkdyn.exceptions import InvalidInputError
from pkdyn.results import Result, jsonable
from pkdyn.units import quantity, value_range

__all__ = [
    "KIND_NAMES",
    "Conditioning",
    "ConditioningMap",
    "conditioning",
    "delta_conditioning",
    "planar_3rrr_conditioning",
    "delta_map",
    "planar_3rrr_map",
]

KIND_NAMES = ("regular", "serial", "parallel", "both")
"""Meaning of the ``kind`` codes 0..3 (-1: unreachable)."""


@dataclass
class Conditioning(Result):
    """Singularity and conditioning indicators of N poses.

    Attributes:
        valid: Pose reachable (N,).
        det_A: Determinant of the seed-normalised parallel matrix (N,).
        det_B: Determinant of the seed-normalised serial matrix (N,).
        cond_A: Condition number of ``A`` in orthonormal form (N,).
        cond_B: Condition number of ``B`` in orthonormal form (N,).
        cond_J: Condition number of ``J`` (N,).
        lci: Local conditioning index of ``J`` (N,).
        manipulability: ``sqrt(det(J J^T))`` (N,).
        kind: 0 regular, 1 serial, 2 parallel, 3 both, -1 unreachable (N,).
        near: Within the near-singular thresholds, singular ones included (N,).

    """

    valid: np.ndarray
    det_A: np.ndarray
    det_B: np.ndarray
    cond_A: np.ndarray
    cond_B: np.ndarray
    cond_J: np.ndarray
    lci: np.ndarray
    manipulability: np.ndarray
    kind: np.ndarray
    near: np.ndarray

    def to_json(self) -> dict[str, Any]:
        """Every indicator (dimensionless; ``None`` where not finite), ``kind`` codes."""
        return jsonable(dict(self.__dict__))

    def table(self) -> str:
        """Reachable poses, how many are singular of each kind, the range of the LCI."""
        kind = np.asarray(self.kind)
        counts = ", ".join(
            f"{name} {int(np.count_nonzero(kind == code))}"
            for code, name in enumerate(("regular", "serial", "parallel", "both"))
        )
        return (
            f"{int(np.count_nonzero(self.valid))} of {np.asarray(self.valid).size} poses "
            f"reachable: {counts}; {int(np.count_nonzero(self.near))} near a singularity; "
            f"{value_range('LCI', self.lci)} (dimensionless)"
        )

    def reshape(self, shape: tuple[int, ...]) -> Conditioning:
        """The same indicators reshaped (e.g. to a grid)."""
        return Conditioning(**{k: v.reshape(shape) for k, v in self.__dict__.items()})


def _cond(s: np.ndarray) -> np.ndarray:
    smax, smin = s[..., 0], s[..., -1]
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(smin > smax / COND_MAX, smax / np.where(smin > 0, smin, 1.0), COND_MAX)
    return np.where(np.isnan(smax), np.nan, k)


def conditioning(
    A: np.ndarray,
    B: np.ndarray,
    valid: np.ndarray,
    task: tuple[str, ...],
    length: float | None = None,
    tol: float = SINGULAR_TOL,
    near_tol: float = NEAR_SINGULAR_TOL,
    scale: float | None = None,
    near_serial_tol: float = NEAR_SERIAL_TOL,
) -> Conditioning:
    """Indicators from stacks of ``A`` (N, m, m) and ``B`` (N, m, n_a) matrices.

    Args:
        A: Parallel matrices (any normalisation).
        B: Serial matrices (same normalisation as ``A``).
        valid: Rows to evaluate (N,); others get NaN.
        task: Task component names (for ``length``).
        length: Characteristic length for the angular rows of ``J`` [m].
        tol: Singular threshold on the scale-aware margins
            (:func:`pkdyn.analysis.kinematics.relation_margins`, revolute actuators).
        near_tol: Near-singular threshold of the parallel margin.
        scale: The robot's length [m] for the margins (default 1 m); the kinds are the same
            for any length of the robot's order.
        near_serial_tol: Near-singular threshold of the serial margin (it grows like the
            square root of the distance to the singularity).

    Returns:
        The indicators (N,).

    """
    ok = np.asarray(valid, dtype=bool) & np.isfinite(A).all(axis=(-2, -1))
    ok &= np.isfinite(B).all(axis=(-2, -1))
    m = A.shape[-1]
    A0 = np.where(ok[:, None, None], A, np.eye(m))
    B0 = np.where(ok[:, None, None], B, 0.0)
    An, Bn = normalise(A0, B0)
    cA = _cond(np.linalg.svd(An, compute_uv=False))
    cB = _cond(np.linalg.svd(Bn, compute_uv=False))
    L = 1.0 if scale is None else float(scale)
    x_scale = np.array([L if t in ("x", "y", "z") else 1.0 for t in task])
    sA, sB, _ = relation_margins(A0, B0, np.ones(B0.shape[-1]), x_scale)
    parallel = sA[..., -1] < tol
    serial = sB[..., -1] < tol
    As = np.where(parallel[:, None, None], np.eye(m), A0)
    J = np.linalg.solve(As, B0)
    Jh = homogenise(J, task, length)
    cJ = np.where(parallel, COND_MAX, condition_number(Jh))
    lci = np.where(parallel, 0.0, local_conditioning_index(Jh))
    w = np.where(parallel, np.nan, manipulability(Jh))
    kind = parallel.astype(int) * 2 + serial.astype(int)
    near = (sA[..., -1] < near_tol) | (sB[..., -1] < near_serial_tol)  # (singular ones too)
    nan = np.full(ok.shape, np.nan)
    return Conditioning(
        valid=ok,
        det_A=np.where(ok, np.linalg.det(A0), nan),
        det_B=np.where(ok, np.linalg.det(B0) if B0.shape[-1] == m else nan, nan),
        cond_A=np.where(ok, cA, nan),
        cond_B=np.where(ok, cB, nan),
        cond_J=np.where(ok, cJ, nan),
        lci=np.where(ok, lci, nan),
        manipulability=np.where(ok, w, nan),
        kind=np.where(ok, kind, -1),
        near=ok & near,
    )


def delta_conditioning(g: delta_cf.DeltaGeometry, P: np.ndarray) -> Conditioning:
    """Indicators of nacelle positions of a Delta (Clavel's working branch).

    Args:
        g: Geometry (ra, rb, la, lb) [m].
        P: Nacelle positions (N, 3) [m].

    Returns:
        Indicators (N,); task ``x y z``.

    """
    P = np.atleast_2d(np.asarray(P, dtype=float))
    alpha, ok = delta_cf.inverse(g, P)
    A, B = delta_AB(g, P, np.where(np.isfinite(alpha), alpha, 0.0))
    return conditioning(A, B, ok, ("x", "y", "z"), scale=g.ra + g.la + g.lb)


def planar_3rrr_conditioning(
    g: rrr_cf.Planar3RRRGeometry,
    X: np.ndarray,
    elbow: int | np.ndarray = 1,
    length: float | None = None,
) -> Conditioning:
    """Indicators of platform poses of a planar 3-RRR.

    Args:
        g: Geometry.
        X: Poses ``(x, y, phi)`` (N, 3) [m, m, rad].
        elbow: Working mode, ``+1`` / ``-1`` (scalar or per chain), as in
            :func:`pkdyn.closed_form.planar_3rrr.inverse`.
        length: Characteristic length for the ``rz`` row of ``J`` [m].

    Returns:
        Indicators (N,); task ``x y rz``.

    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    q1, ok = rrr_cf.inverse(g, X, elbow)
    angles = planar_3rrr_chain_angles(g, X, np.where(np.isfinite(q1), q1, 0.0))
    A, B = planar_3rrr_AB(g, angles)
    scale = 2.0 * float(np.max(np.linalg.norm(g.base_xy, axis=-1)))
    return conditioning(A, B, ok, ("x", "y", "rz"), length, scale=scale)


@dataclass
class ConditioningMap(Result):
    """Indicators on a 2D grid of a workspace slice.

    Attributes:
        robot: ``"delta"`` or ``"planar_3rrr"``.
        axes: Names of the two grid coordinates, e.g. ``("x", "y")``.
        u: First grid coordinate values (nu,) [m or rad].
        v: Second grid coordinate values (nv,) [m or rad].
        fixed: The fixed coordinates of the slice, e.g. ``{"z": -0.35}``.
        data: Indicators of shape (nv, nu) (row ``i`` is ``v[i]``, as for ``imshow``).

    """

    robot: str
    axes: tuple[str, str]
    u: np.ndarray
    v: np.ndarray
    fixed: dict[str, float] = field(default_factory=dict)
    data: Conditioning | None = None

    def to_json(self) -> dict[str, Any]:
        """The grid (``u``, ``v`` [m or rad]), the slice and the indicators ((nv, nu) each)."""
        return jsonable(
            {
                "robot": self.robot,
                "axes": list(self.axes),
                "u": self.u,
                "v": self.v,
                "fixed": self.fixed,
                "data": None if self.data is None else self.data.to_json(),
            }
        )

    def table(self) -> str:
        """The slice and the grid, then the indicators' summary."""
        unit = {"x": "m", "y": "m", "z": "m"}
        grid = ", ".join(
            f"{ax} {quantity(float(w[0]), unit.get(ax, 'rad'))} .. "
            f"{quantity(float(w[-1]), unit.get(ax, 'rad'))} ({w.size})"
            for ax, w in zip(self.axes, (self.u, self.v), strict=True)
            if w.size
        )
        fixed = ", ".join(f"{k} = {quantity(v, unit.get(k, 'rad'))}" for k, v in self.fixed.items())
        head = f"{self.robot} map: {grid}" + (f"; {fixed}" if fixed else "")
        return head + ("" if self.data is None else "\n" + self.data.table())


_DELTA_AXES = {"xy": (0, 1, 2), "xz": (0, 2, 1), "yz": (1, 2, 0)}


def delta_map(
    g: delta_cf.DeltaGeometry,
    u: np.ndarray,
    v: np.ndarray,
    level: float,
    plane: str = "xy",
) -> ConditioningMap:
    """Singularity / conditioning map of a Delta over a plane slice.

    Args:
        g: Geometry (ra, rb, la, lb) [m], e.g. ``robot.params``.
        u: First in-plane coordinate values [m].
        v: Second in-plane coordinate values [m].
        level: Value of the third coordinate [m] (``z`` for ``plane="xy"``).
        plane: ``"xy"``, ``"xz"`` or ``"yz"``.

    Returns:
        The map (grid shape ``(len(v), len(u))``).

    Raises:
        InvalidInputError: Unknown plane, or not a three-armed Delta.

    """
    if plane not in _DELTA_AXES:
        raise InvalidInputError("plane", f"must be one of {', '.join(_DELTA_AXES)}, got {plane!r}")
    if delta_cf.arm_angles(g).size != 3:
        raise InvalidInputError(
            "g",
            f"Clavel's closed-form map needs a three-armed Delta, got "
            f"{delta_cf.arm_angles(g).size} arms (use pkdyn.analysis.maps.conditioning)",
        )
    iu, iv, iw = _DELTA_AXES[plane]
    U, Vg = np.meshgrid(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
    P = np.empty((U.size, 3))
    P[:, iu], P[:, iv], P[:, iw] = U.ravel(), Vg.ravel(), level
    names = "xyz"
    return ConditioningMap(
        "delta",
        (names[iu], names[iv]),
        np.asarray(u, dtype=float),
        np.asarray(v, dtype=float),
        {names[iw]: float(level)},
        delta_conditioning(g, P).reshape(U.shape),
    )


def planar_3rrr_map(
    g: rrr_cf.Planar3RRRGeometry,
    x: np.ndarray,
    y: np.ndarray,
    phi: float,
    elbow: int | np.ndarray | None = None,
    length: float | None = None,
) -> ConditioningMap:
    """Singularity / conditioning map of a planar 3-RRR at constant orientation.

    Args:
        g: Geometry, e.g. ``robot.params``.
        x: Platform x values [m].
        y: Platform y values [m].
        phi: Platform orientation [rad].
        elbow: Working mode (default ``g.elbow`` if the geometry has one, else +1).
        length: Characteristic length for the ``rz`` row of ``J`` [m].

    Returns:
        The map (grid shape ``(len(y), len(x))``).

    """
    mode = elbow if elbow is not None else getattr(g, "elbow", 1)
    Xg, Yg = np.meshgrid(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    X = np.column_stack([Xg.ravel(), Yg.ravel(), np.full(Xg.size, float(phi))])
    return ConditioningMap(
        "planar_3rrr",
        ("x", "y"),
        np.asarray(x, dtype=float),
        np.asarray(y, dtype=float),
        {"phi": float(phi)},
        planar_3rrr_conditioning(g, X, mode, length).reshape(Xg.shape),
    )
