"""Framing a robot: the bounding box of its geometry, a camera that sees it, pixel projection.

meshcat's camera is a three.js perspective camera (vertical field of view 75 degrees, up axis along
world z) whose orbit controls aim at the page's origin (:meth:`pkdyn.viewer.Scene.look_at` shifts
the scene accordingly). :func:`project` is the same pinhole model, so a test or a user can tell
where a point lands in a screenshot.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError

__all__ = ["FOV_DEG", "Camera", "bounding_box", "frame_box", "project"]

FOV_DEG = 75.0
"""Vertical field of view of meshcat's default camera [deg]."""

_UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Camera:
    """A camera looking at ``target`` from ``position`` (world frame, z up).

    Attributes:
        target: Point the camera looks at and orbits about (3,) [m].
        position: Camera centre (3,) [m].
        fov_deg: Vertical field of view [deg].

    """

    target: np.ndarray
    position: np.ndarray
    fov_deg: float = FOV_DEG

    def __post_init__(self) -> None:
        from pkdyn.inputs import positive, vector

        object.__setattr__(self, "target", vector("target", self.target, 3, "m"))
        object.__setattr__(self, "position", vector("position", self.position, 3, "m"))
        fov = positive("fov_deg", self.fov_deg, "deg")
        if not fov < 180.0:
            raise InvalidInputError("fov_deg", f"a field of view lies in (0, 180) deg, got {fov:g}")
        object.__setattr__(self, "fov_deg", fov)

    @property
    def offset_yup(self) -> list[float]:
        """Camera position relative to the target in three.js's y-up axes (meshcat's rotated)."""
        d = self.position - self.target
        return [float(d[0]), float(d[2]), float(-d[1])]


def bounding_box(
    model: pin.Model, geometry_model: pin.GeometryModel, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned world bounding box of a geometry model at a configuration.

    Args:
        model: Kinematic model.
        geometry_model: Geometry attached to ``model`` (coal shapes or meshes).
        q: Configuration (nq,).

    Returns:
        ``(lo, hi)`` corners (3,) [m]; a zero-size box at the origin for an empty model.

    """
    from pkdyn.inputs import instance, vector

    instance("model", model, pin.Model, "a pin.Model (robot.model)")
    instance("geometry_model", geometry_model, pin.GeometryModel, "a pin.GeometryModel")
    q = vector("q", q, model.nq, "rad or m")
    data = model.createData()
    gdata = geometry_model.createData()
    pin.updateGeometryPlacements(model, data, geometry_model, gdata, q)
    corners = []
    unit = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float)
    for gid, obj in enumerate(geometry_model.geometryObjects):
        geom = obj.geometry
        geom.computeLocalAABB()
        lo, hi = np.asarray(geom.aabb_local.min_), np.asarray(geom.aabb_local.max_)
        scale = np.asarray(obj.meshScale)
        local = (lo + unit * (hi - lo)) * scale
        M = gdata.oMg[gid]
        corners.append(local @ M.rotation.T + M.translation)
    if not corners:
        return np.zeros(3), np.zeros(3)
    pts = np.vstack(corners)
    return pts.min(axis=0), pts.max(axis=0)


def frame_box(
    lo: np.ndarray,
    hi: np.ndarray,
    direction: np.ndarray | None = None,
    margin: float = 1.15,
    aspect: float = 4.0 / 3.0,
) -> Camera:
    """A camera that sees the whole box, looking at its centre.

    The distance fits the box's bounding sphere in the narrower of the two fields of view.

    Args:
        lo: Box lower corner (3,) [m].
        hi: Box upper corner (3,) [m].
        direction: From the target towards the camera (3,), any length; default a
            three-quarter view from +x, -y, slightly above (well above for a flat box: a
            planar robot).
        margin: Extra room around the sphere (1 = tangent).
        aspect: Expected width / height of the view.

    Returns:
        The camera.

    """
    from pkdyn.inputs import positive, vector

    lo, hi = vector("lo", lo, 3, "m"), vector("hi", hi, 3, "m")
    margin = positive("margin", margin)
    aspect = positive("aspect", aspect)
    size = hi - lo
    if direction is not None:
        d = vector("direction", direction, 3)
        if not np.linalg.norm(d) > 0.0:
            raise InvalidInputError("direction", "a zero vector has no direction")
    elif size[2] < 0.2 * max(size[0], size[1]):
        d = np.array([0.6, -0.7, 1.4])
    else:
        d = np.array([1.0, -1.1, 0.55])
    d = d / np.linalg.norm(d)
    target = 0.5 * (np.asarray(lo, float) + np.asarray(hi, float))
    radius = max(0.5 * float(np.linalg.norm(np.asarray(hi) - np.asarray(lo))), 0.05)
    half_v = np.radians(FOV_DEG) / 2.0
    half = min(half_v, np.arctan(np.tan(half_v) * aspect))
    dist = margin * radius / np.sin(half)
    return Camera(target=target, position=target + dist * d)


def _numbers(x: Any) -> Any:
    """``x`` as given when it cannot be an array (its check names it), else an array."""
    try:
        return np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        return x


def project(camera: Camera, points: np.ndarray, width: int, height: int) -> np.ndarray:
    """Pixel coordinates of world points in a ``width`` x ``height`` view of ``camera``.

    Args:
        camera: The camera.
        points: World points (N, 3) [m].
        width: View width [px].
        height: View height [px].

    Returns:
        (N, 2) pixel coordinates (column, row), origin at the top-left corner.

    """
    from pkdyn.inputs import count, instance, matrix

    instance("camera", camera, Camera, "a Camera (pkdyn.viewer.frame_box)")
    pts = _numbers(points)
    if isinstance(pts, np.ndarray) and pts.ndim == 1:
        pts = pts[None, :]
    points = matrix("points", pts, None, 3, "m")
    width, height = count("width", width, 1, 100_000), count("height", height, 1, 100_000)
    f = camera.target - camera.position
    f = f / np.linalg.norm(f)
    right = np.cross(f, _UP)
    right = right / np.linalg.norm(right)
    up = np.cross(right, f)
    d = np.atleast_2d(points) - camera.position
    x, y, z = d @ right, d @ up, d @ f
    t = np.tan(np.radians(camera.fov_deg) / 2.0)
    ndc_x = x / (z * t * width / height)
    ndc_y = y / (z * t)
    return np.column_stack([(ndc_x + 1.0) * width / 2.0, (1.0 - ndc_y) * height / 2.0])
