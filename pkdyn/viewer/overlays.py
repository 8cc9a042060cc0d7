"""meshcat objects for what is drawn over a robot: point clouds, triangle meshes, frame triads."""

from __future__ import annotations

from collections.abc import Sequence

import meshcat.geometry as mg
import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = ["Color", "hex_color", "point_cloud", "rgb", "triad", "triangle_mesh"]

Color = Sequence[float] | np.ndarray
"""An RGB or RGBA colour, components in [0, 1]."""


def rgb(color: Color, name: str = "color") -> np.ndarray:
    """Validate a colour and return its RGBA components (alpha 1 when omitted).

    Raises:
        InvalidInputError: Not 3 or 4 components in [0, 1].

    """
    from pkdyn.inputs import vector

    c = vector(name, color, (3, 4))
    if c.size not in (3, 4) or not np.all(np.isfinite(c)) or c.min() < 0 or c.max() > 1:
        raise InvalidInputError(name, f"expected 3 or 4 components in [0, 1], got {list(c)}")
    return np.append(c, 1.0) if c.size == 3 else c


def hex_color(color: Color) -> int:
    """A colour as the 0xRRGGBB integer three.js materials take."""
    c = np.round(rgb(color)[:3] * 255).astype(int)
    return int(c[0]) << 16 | int(c[1]) << 8 | int(c[2])


def _points(points: np.ndarray, name: str) -> np.ndarray:
    P = np.asarray(points, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] == 0:
        raise InvalidInputError(name, f"expected an (N, 3) array of points [m], got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise InvalidInputError(name, "contains NaN or infinite coordinates")
    return P


def point_cloud(
    points: np.ndarray,
    color: Color = (0.1, 0.6, 0.3),
    size: float = 0.005,
) -> mg.Points:
    """A cloud of points (a workspace sample, say).

    Args:
        points: Positions (N, 3) [m].
        color: One colour for all points, or one per point (N, 3) in [0, 1].
        size: Point size [m] (points shrink with distance).

    Returns:
        The meshcat object.

    """
    P = _points(points, "points")
    C = np.asarray(color, dtype=float)
    if C.ndim == 2:
        if C.shape != (P.shape[0], 3) or C.min() < 0 or C.max() > 1:
            raise InvalidInputError("colors", f"expected ({P.shape[0]}, 3) values in [0, 1]")
    else:
        C = np.tile(rgb(C)[:3], (P.shape[0], 1))
    return mg.PointCloud(
        position=P.T.astype(np.float32), color=C.T.astype(np.float32), size=float(size)
    )


def triangle_mesh(
    vertices: np.ndarray,
    faces: np.ndarray,
    color: Color = (0.2, 0.5, 0.9, 0.35),
    wireframe: bool = False,
) -> mg.Mesh:
    """A triangle mesh (a workspace boundary, say), translucent by default.

    Args:
        vertices: Vertex positions (N, 3) [m].
        faces: Vertex indices of each triangle (M, 3).
        color: RGB or RGBA; alpha < 1 makes it translucent.
        wireframe: Draw the edges only.

    Returns:
        The meshcat object.

    """
    V = _points(vertices, "vertices")
    F = np.asarray(faces)
    if F.ndim != 2 or F.shape[1] != 3 or F.shape[0] == 0 or not np.issubdtype(F.dtype, np.integer):
        raise InvalidInputError("faces", f"expected an (M, 3) integer array, got {F.shape}")
    if F.min() < 0 or F.max() >= V.shape[0]:
        raise InvalidInputError("faces", f"indices must lie in [0, {V.shape[0] - 1}]")
    c = rgb(color)
    material = mg.MeshLambertMaterial(
        color=hex_color(c),
        opacity=float(c[3]),
        transparent=bool(c[3] < 1.0),
        wireframe=wireframe,
        side=2,  # three.js DoubleSide: a boundary is seen from inside and outside
    )
    return mg.Mesh(mg.TriangularMeshGeometry(V, F.astype(np.uint32)), material)


def triad(scale: float) -> mg.LineSegments:
    """Frame axes x, y, z drawn in red, green, blue, ``scale`` [m] long."""
    return mg.triad(scale)
