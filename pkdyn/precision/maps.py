"""Stiffness, deflection and lowest frequency over many poses and over workspace slices.

:func:`pose_figures` evaluates the design figures at platform poses by the fastest exact path:

- the library Gough-Stewart and Delta with the actuators' stiffness alone (rigid links, no
  spring of their own): the closed forms of :mod:`pkdyn.precision.vectorised`, all poses at once
  (frequencies: the Delta);
- any other robot, or compliant links: pose by pose, the general inverse geometric model (each
  pose warm-started from the previous solution) then :func:`pkdyn.precision.stiffness` and
  :func:`pkdyn.precision.modes.modes` on the virtual-joint model built once.

The figures: ``stiffness_min``, the smallest principal translational stiffness [N/m] (forces
only; the design metric ``stiffness_min``); ``deflection``, the translation of the reference
point under a tool wrench [m]; ``f1``, the lowest natural frequency [Hz] (metric ``f1_min``).
NaN marks poses not reached, or singular.

:func:`precision_map` maps them over a slice of the translation workspace (a plane through the
home pose at a fixed orientation), inside the robot's limits (:mod:`pkdyn.workspace`); plots:
:func:`pkdyn.plotting.plot_precision_map`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pkdyn.analysis.kinematics import NearSingularityWarning
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.inputs import is_complex
from pkdyn.model.arguments import public
from pkdyn.model.assembly import inverse_geometry
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.precision.condensation import translational
from pkdyn.precision.elastic import ElasticModel, elastic_model
from pkdyn.precision.material import Material
from pkdyn.precision.modes import modes
from pkdyn.precision.stiffness import _point, _wrench
from pkdyn.precision.vectorised import delta_figures, gough_stewart_figures, vectorised
from pkdyn.progress import progress as progress_bar
from pkdyn.threads import one_blas_thread
from pkdyn.workspace.limits import REACHABLE

__all__ = ["FIELDS", "MAX_POSES", "PoseFigures", "PrecisionMap", "pose_figures", "precision_map"]

FIELDS = {
    "stiffness_min": ("N/m", "smallest translational stiffness"),
    "deflection": ("m", "deflection under the tool wrench"),
    "f1": ("Hz", "lowest natural frequency"),
}
"""Map fields: unit and label."""

MAX_GENERAL_POSES = 200_000
"""Most poses evaluated on the general (pose-by-pose) path in one call: about 100 s."""
GENERAL_RATE = 2e3
"""Order of magnitude of the general path's speed [poses/s], for the estimate in messages."""
MAX_POSES = 4_000_000
"""Largest number of poses of one evaluation (refused up front beyond)."""


@dataclass(eq=False)  # numpy fields
class PoseFigures:
    """Figures per pose (NaN where not reached or singular).

    Attributes:
        valid: Evaluated (N,).
        stiffness_min: Smallest principal translational stiffness (N,) [N/m].
        deflection: Translation of the reference point under the wrench (N,) [m].
        f1: Lowest natural frequency (N,) [Hz].
        method: ``closed form`` or ``general``.

    """

    valid: np.ndarray
    stiffness_min: np.ndarray
    deflection: np.ndarray
    f1: np.ndarray
    method: str


def _poses(P: np.ndarray, R: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(P, str | bytes | dict) or is_complex(P):
        raise InvalidInputError("P", f"expected finite positions (N, 3) [m], got {P!r:.60}")
    try:
        P = np.atleast_2d(np.asarray(P, dtype=float))
    except (TypeError, ValueError):
        raise InvalidInputError(
            "P", f"expected finite positions (N, 3) [m], got {P!r:.60}"
        ) from None
    if P.ndim != 2 or P.shape[1] != 3 or not np.all(np.isfinite(P)):
        raise InvalidInputError("P", f"expected finite positions (N, 3) [m], got {P.shape}")
    if P.shape[0] > MAX_POSES:
        raise InvalidInputError(
            "P", f"{P.shape[0]} poses: at most {MAX_POSES} per evaluation (split the grid)"
        )
    if R is None:
        return P, np.broadcast_to(np.eye(3), (P.shape[0], 3, 3))
    Rm = np.asarray(R, dtype=float)
    return P, np.broadcast_to(Rm, (P.shape[0], 3, 3)) if Rm.ndim == 2 else Rm


@public
def pose_figures(
    robot: Robot,
    P: np.ndarray,
    R: np.ndarray | None = None,
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    *,
    material: str | Material | None = None,
    links: bool = True,
    point: Sequence[float] | np.ndarray | None = None,
    wrench: Sequence[float] | np.ndarray | None = None,
    frequency: bool = False,
    method: str = "auto",
    progress: bool | None = None,
) -> PoseFigures:
    """Stiffness, deflection and lowest frequency at platform poses (module docstring).

    Args:
        robot: The robot (with its geometry when links are beams).
        P: Platform frame positions (N, 3) [m].
        R: Platform orientations (N, 3, 3) or one (3, 3) (default: identity).
        actuator_stiffness: Joint-side stiffness, one or one per actuator [N m/rad or N/m];
            ``None``: the description's ``<pkdyn:stiffness>``.
        material: Material of the slender links; ``None``: the description's, if any.
        links: Model the links' compliance.
        point: Reference point, platform frame [m].
        wrench: Tool wrench (6: force [N], moment about the point [N m], world axes, or the task
            components): its deflection is reported.
        frequency: Compute the lowest natural frequency too.
        method: ``auto``, ``closed`` (refuse robots without a closed form) or ``general``.
        progress: Progress bar of the pose-by-pose path (``None``: when stderr is a terminal).

    Returns:
        The figures.

    Raises:
        InvalidInputError: Bad poses, stiffness, material, point, wrench or method, or too
            many poses.

    """
    if method not in ("auto", "closed", "general"):
        raise InvalidInputError("method", f"'{method}': use auto, closed or general")
    P, Rs = _poses(P, R)
    em = elastic_model(robot, actuator_stiffness, material, links)
    w = _wrench(robot, wrench)
    p = _point(point, robot)
    kind = vectorised(robot, frequency) if not em.links else None
    if method == "closed" and kind is None:
        raise InvalidInputError(
            "method",
            f"no closed form for {robot.name} with these options (closed forms: the library "
            "Gough-Stewart and three-armed ball-jointed Delta, actuator stiffness alone, "
            "frequencies for the Delta)",
        )
    if method != "general" and kind == "gough_stewart":
        k = em.actuator_stiffness
        if np.all(np.isfinite(k)):
            f = gough_stewart_figures(robot, P, R if R is not None else np.eye(3), k, p, w)
            return PoseFigures(f.valid, f.stiffness_min, f.deflection, f.f1, "closed form")
    if method != "general" and kind == "delta" and np.all(np.isfinite(em.actuator_stiffness)):
        f = delta_figures(robot, P, em.actuator_stiffness, w, frequency)
        return PoseFigures(f.valid, f.stiffness_min, f.deflection, f.f1, "closed form")
    if P.shape[0] > MAX_GENERAL_POSES:
        raise InvalidInputError(
            "P",
            f"{P.shape[0]} poses on the general (pose-by-pose) path would take about "
            f"{P.shape[0] / GENERAL_RATE / 60:.0f} min at ~{GENERAL_RATE:.0f} poses/s; give at "
            f"most {MAX_GENERAL_POSES} (a coarser grid)",
        )
    return _general(em, P, Rs, p, w, frequency, progress)


def _general(
    em: ElasticModel,
    P: np.ndarray,
    R: np.ndarray,
    point: np.ndarray,
    w: np.ndarray | None,
    frequency: bool,
    progress: bool | None,
) -> PoseFigures:
    robot = em.base
    N = P.shape[0]
    kmin, defl, f1 = np.full(N, np.nan), np.full(N, np.nan), np.full(N, np.nan)
    valid = np.zeros(N, dtype=bool)
    q_prev = robot.q_home
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSingularityWarning)
        for i in progress_bar(range(N), "precision", "pose", progress, min_items=200):
            q = None
            for start in (q_prev, robot.q_home):
                try:
                    target = pin.SE3(R[i], P[i])
                    q = inverse_geometry(robot, target, q_init=start, check_limits=False).q
                    break
                except PkdynError:
                    continue
            if q is None:
                continue
            q_prev = q
            try:
                kmin[i], defl[i] = translational(em, q, point, w)
                if frequency:
                    f1[i] = modes(em, q, point=point).f1
            except PkdynError:
                kmin[i] = defl[i] = np.nan
                continue
            valid[i] = True
    return PoseFigures(valid, kmin, defl, f1, "general")


@dataclass(eq=False)  # numpy fields
class PrecisionMap:
    """Figures over a plane of the translation workspace.

    Attributes:
        robot: Robot name.
        axes: The two coordinates of the plane (``("x", "y")``...).
        u: Grid values of the first axis (nu,) [m].
        v: Grid values of the second axis (nv,) [m].
        fixed: The third coordinate [m] and the orientation (roll, pitch, yaw) [rad].
        reachable: Inside the robot's limits (nv, nu).
        values: Field name -> values (nv, nu), NaN outside or where singular.
        method: How the figures were evaluated.
        options: The stiffness options (for titles and reports).

    """

    robot: str
    axes: tuple[str, str]
    u: np.ndarray
    v: np.ndarray
    fixed: dict[str, float]
    reachable: np.ndarray
    values: dict[str, np.ndarray]
    method: str
    options: dict[str, object] = field(default_factory=dict)

    def extreme(self, name: str) -> float:
        """Worst value of a field over the map (``nan`` when nothing was evaluated).

        The smallest stiffness or frequency, the largest deflection.
        """
        if not isinstance(name, str) or name not in self.values:
            raise InvalidInputError(
                "name", f"{name!r:.40} is not a field of the map ({', '.join(self.values)})"
            )
        x = self.values[name]
        if not np.isfinite(x).any():
            return float("nan")
        return float(np.nanmax(x) if name == "deflection" else np.nanmin(x))


_AXES = {"x": 0, "y": 1, "z": 2}


@one_blas_thread
@public
def precision_map(
    robot: Robot,
    plane: str = "xy",
    value: float | None = None,
    samples: int = 31,
    bounds: Sequence[float] | None = None,
    rpy: Sequence[float] = (0.0, 0.0, 0.0),
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    *,
    material: str | Material | None = None,
    links: bool = True,
    point: Sequence[float] | np.ndarray | None = None,
    wrench: Sequence[float] | np.ndarray | None = None,
    frequency: bool = False,
    limits: Sequence[str] = ("stroke", "joint"),
    method: str = "auto",
    progress: bool | None = None,
) -> PrecisionMap:
    """Stiffness (and deflection, lowest frequency) over a plane of the translation workspace.

    Args:
        robot: The robot.
        plane: Two of ``x``, ``y``, ``z`` (``xy``: a horizontal slice).
        value: The third coordinate of the plane [m] (default: the home pose's).
        samples: Grid samples per axis.
        bounds: ``(u_min, u_max, v_min, v_max)`` [m] (default: the workspace's box).
        rpy: Platform orientation [rad] (roll, pitch, yaw; ignored by a Delta).
        actuator_stiffness: Joint-side stiffness [N m/rad or N/m]; ``None``: described.
        material: Material of the slender links.
        links: Model the links' compliance.
        point: Reference point, platform frame [m].
        wrench: Tool wrench for the ``deflection`` field (6 values or the task components).
        frequency: Also map the lowest frequency ``f1``.
        limits: Limit kinds a pose must respect to be mapped (``reach`` always).
        method: ``auto``, ``closed`` or ``general`` (:func:`pose_figures`).
        progress: Progress bar of the pose-by-pose path.

    Returns:
        The map.

    Raises:
        InvalidInputError: A bad plane, bounds, sample count or option.

    """
    from pkdyn.workspace.translation import evaluator_for

    if (
        not isinstance(plane, str)
        or len(plane) != 2
        or any(c not in _AXES for c in plane)
        or plane[0] == plane[1]
    ):
        raise InvalidInputError("plane", f"'{plane}': two of x, y, z, e.g. xy")
    from pkdyn.inputs import count, vector

    samples = count("samples", samples, 2, 2001)
    if value is not None:
        from pkdyn.inputs import real

        value = real("value", value, "m", bound=100.0 * robot.length_scale)
    R = pin.rpy.rpyToMatrix(*as_finite("rpy", rpy, 3))
    iu, iv = _AXES[plane[0]], _AXES[plane[1]]
    iw = 3 - iu - iv
    home = robot.platform_placement(robot.q_home).translation
    ev = evaluator_for(robot, progress=progress)
    if bounds is None:
        box = ev.default_bounds(R)
        b = np.array([box[iu, 0], box[iu, 1], box[iv, 0], box[iv, 1]])
    else:
        b = vector("bounds", bounds, 4, "m", bound=100.0 * robot.length_scale)
        if not (b[0] < b[1] and b[2] < b[3]):
            raise InvalidInputError("bounds", f"{b.tolist()}: need u_min < u_max, v_min < v_max")
    u = np.linspace(b[0], b[1], samples)
    v = np.linspace(b[2], b[3], samples)
    U, V = np.meshgrid(u, v)
    P = np.zeros((U.size, 3))
    P[:, iu], P[:, iv] = U.ravel(), V.ravel()
    P[:, iw] = home[iw] if value is None else float(value)
    from pkdyn.workspace.limits import check_kinds

    codes = ev.violations(P, R, check_kinds(limits), 0.0)
    inside = codes == REACHABLE
    fig = pose_figures(
        robot,
        P[inside],
        R,
        actuator_stiffness,
        material=material,
        links=links,
        point=point,
        wrench=wrench,
        frequency=frequency,
        method=method,
        progress=progress,
    )
    values = {}
    for name in ("stiffness_min", "deflection", "f1"):
        if name == "deflection" and wrench is None or name == "f1" and not frequency:
            continue
        full = np.full(U.size, np.nan)
        full[inside] = getattr(fig, name)
        values[name] = full.reshape(U.shape)
    return PrecisionMap(
        robot=robot.name,
        axes=(plane[0], plane[1]),
        u=u,
        v=v,
        fixed={"xyz"[iw]: float(P[0, iw]), "roll": rpy[0], "pitch": rpy[1], "yaw": rpy[2]},
        reachable=inside.reshape(U.shape),
        values=values,
        method=fig.method,
        options={
            "actuator_stiffness": None
            if actuator_stiffness is None
            else np.atleast_1d(actuator_stiffness).tolist(),
            "material": None if material is None else str(getattr(material, "name", material)),
            "point": None if point is None else list(np.asarray(point, float)),
            "wrench": None if wrench is None else list(np.asarray(wrench, float)),
        },
    )
