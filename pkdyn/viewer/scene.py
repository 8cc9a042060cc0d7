"""A meshcat scene of one robot: geometry, frames, overlays, highlights, animation, export."""

from __future__ import annotations

import contextlib
import io
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import meshcat
import numpy as np
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from pkdyn.exceptions import InvalidInputError, OutputError, PkdynError
from pkdyn.files import atomic_write
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.viewer import highlight as hl
from pkdyn.viewer._server import LOOPBACK, ServerProcess, start_server
from pkdyn.viewer.animation import AnimationCommand, Clip, check_trajectory, keyframes
from pkdyn.viewer.camera import Camera, bounding_box, frame_box
from pkdyn.viewer.html import static_html
from pkdyn.viewer.overlays import Color, point_cloud, rgb, triad, triangle_mesh
from pkdyn.viewer.window import OfflineWindow, TeeWindow

__all__ = ["BACKGROUND", "Scene"]

BACKGROUND = ((1.0, 1.0, 1.0), (0.82, 0.84, 0.86))
"""Background gradient (top, bottom): light and neutral, so that every part colour shows."""


def _probe(x: Any) -> np.ndarray:
    """A colour's components (3 or 4), once :func:`rgb` accepted it."""
    return np.asarray(x, dtype=float).reshape(-1)


def _name(name: Any) -> str:
    """A scene object's name: a non-empty string."""
    if not isinstance(name, str) or not name:
        raise InvalidInputError("name", f"expected a non-empty string, got {name!r:.40}")
    return name


class Scene:
    """A meshcat scene of a robot, recorded for static HTML export and optionally served live.

    The robot is drawn from ``robot.visual_model`` (``collision=True`` draws the collision model,
    the visuals staying available, hidden, in the viewer's controls), with a triad on each frame
    of interest (the platform frame by default), the camera framing the robot.

    Args:
        robot: Robot loaded with its geometry (``pkdyn.load(..., geometry=True)``).
        q: Configuration to show (nq,); default ``robot.q_home``.
        collision: Draw the collision geometry instead of the visual one.
        frames: Names of the model frames to draw as triads; default the world frame
            (``universe``) and the platform frame.
        serve: Also start meshcat's server; the live scene is at :attr:`url`.
        host: Address the live server listens on: ``127.0.0.1`` (default) serves this machine
            only; another address (``0.0.0.0``: every interface) lets anyone who can reach the
            machine read the scene, and warns.
        viewer: An existing ``meshcat.Visualizer`` to draw into as well (a notebook's, say).

    Attributes:
        robot: The robot.
        vis: The meshcat visualizer (``vis[path]`` to draw anything else).
        record: The recording window behind :meth:`html`.
        root: Scene node of the robot (its name).
        q: The configuration shown.
        triad_scale: Length of the frame triads [m] (0.12 of the robot's box diagonal).

    Raises:
        PkdynError: The robot has no geometry, or a frame name is unknown.

    """

    @public
    def __init__(
        self,
        robot: Robot,
        q: np.ndarray | None = None,
        *,
        collision: bool = False,
        frames: Sequence[str] | None = None,
        serve: bool = False,
        host: str = LOOPBACK,
        viewer: meshcat.Visualizer | None = None,
    ) -> None:
        if robot.visual_model.ngeoms == 0 and robot.collision_model.ngeoms == 0:
            raise PkdynError(
                f"{robot.name} has no geometry to draw: give the links <visual> or <collision> "
                "elements (in Python, load with geometry=True)"
            )
        if robot.missing_meshes:
            from pkdyn.model.warn import missing_list

            warnings.warn(
                f"{robot.name}: {len(robot.missing_meshes)} mesh file(s) were not found when it "
                f"was loaded and are not drawn: {missing_list(robot.missing_meshes)}",
                UserWarning,
                stacklevel=2,
            )
        self.robot = robot
        self.record = OfflineWindow()
        windows: list[object] = [self.record]
        self._server: meshcat.Visualizer | None = None
        self._process: ServerProcess | None = None
        if serve:
            if host not in (LOOPBACK, "localhost", "::1"):
                warnings.warn(
                    f"the live viewer listens on {host!r}: anyone who can reach this machine "
                    "can read the scene (default 127.0.0.1: this machine only)",
                    UserWarning,
                    stacklevel=2,
                )
            self._process = start_server(host)
            with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL itself
                self._server = meshcat.Visualizer(zmq_url=self._process.zmq_url)
            windows.append(self._server.window)
        if viewer is not None:
            windows.append(viewer.window)
        self.vis = meshcat.Visualizer(window=TeeWindow(*windows))
        self.root = "".join(c if c.isalnum() or c in "_-" else "_" for c in robot.name) or "robot"
        self.collision = collision
        self.viz = MeshcatVisualizer(
            robot.model, robot.collision_model if collision else None, robot.visual_model
        )
        self.viz.initViewer(viewer=self.vis)
        self.viz.loadViewerModel(self.root)
        if collision:
            self.viz.displayCollisions(True)
            self.viz.displayVisuals(False)
        self._base: dict[str, np.ndarray] = {}  # own colour of each drawn node
        self._moving: list[str] = []  # nodes not fixed to the ground (coloured when singular)
        for kind, model in self._shown():
            for obj in model.geometryObjects:
                node = self._node(obj, kind)
                self._base[node] = rgb(obj.meshColor)
                if obj.parentJoint != 0:
                    self._moving.append(node)
        if frames is not None:
            from pkdyn.inputs import names

            frames = list(names("frames", frames, what="frame", empty=True))
        self._frames = self._frame_ids(frames)
        self._boxes: list[tuple[np.ndarray, np.ndarray]] = []
        self._auto_camera = True
        self.q = np.array(robot.q_home if q is None else q, dtype=float)
        lo, hi = self.robot_box(self.q)
        self.triad_scale = max(0.12 * float(np.linalg.norm(hi - lo)), 0.02)
        for name in self._frames:
            self.vis[f"{self.root}/triads/{name}"].set_object(triad(self.triad_scale))
        self.vis["/Axes"].set_property("visible", False)  # 0.5 m long: the world triad instead
        self.set_background(*BACKGROUND)
        self.display(self.q)

    # -- structure --------------------------------------------------------------------------

    def _shown(self) -> list[tuple[pin.GeometryType, pin.GeometryModel]]:
        if self.collision:
            return [(pin.GeometryType.COLLISION, self.robot.collision_model)]
        return [(pin.GeometryType.VISUAL, self.robot.visual_model)]

    def _node(self, obj: pin.GeometryObject, kind: pin.GeometryType) -> str:
        """Absolute meshcat path of a geometry object's node."""
        return str(self.vis[self.viz.getViewerNodeName(obj, kind)].path.lower())

    def _frame_ids(self, names: Sequence[str] | None) -> dict[str, int]:
        model = self.robot.model
        if names is None:
            pf = self.robot.platform_frame
            names = ["universe"] + ([] if pf is None else [model.frames[pf].name])
        out = {}
        for name in names:
            if not model.existFrame(name):
                known = ", ".join(f.name for f in model.frames)
                raise PkdynError(f"{self.robot.name}: no frame '{name}' (frames: {known})")
            out[name] = model.getFrameId(name)
        return out

    def nodes(self, name: str) -> list[str]:
        """Scene nodes drawn for a geometry object name.

        A visual or collision object name maps to its own node when that model is drawn; a
        collision object whose name is not drawn maps to the drawn objects on the same body.

        Raises:
            InvalidInputError: No geometry object has that name.

        """
        _name(name)
        out: list[str] = []
        for kind, model in self._shown():
            if model.existGeometryName(name):
                out.append(self._node(model.geometryObjects[model.getGeometryId(name)], kind))
        if not out:
            for other in (self.robot.collision_model, self.robot.visual_model):
                if other.existGeometryName(name):
                    frame = other.geometryObjects[other.getGeometryId(name)].parentFrame
                    for kind, model in self._shown():
                        out += [
                            self._node(o, kind)
                            for o in model.geometryObjects
                            if o.parentFrame == frame
                        ]
                    break
        if not out:
            known = ", ".join(o.name for _, m in self._shown() for o in m.geometryObjects)
            raise InvalidInputError("geometry", f"no geometry object '{name}' (known: {known})")
        return out

    @public
    def robot_box(self, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """World bounding box (lo, hi) [m] of the drawn geometry at ``q`` (default: shown q)."""
        from pkdyn.inputs import vector

        qq = self.q if q is None else vector("q", q, self.robot.nq, "rad or m")
        return bounding_box(self.robot.model, self._shown()[0][1], qq)

    # -- view -------------------------------------------------------------------------------

    @property
    def url(self) -> str | None:
        """URL of the live viewer (``serve=True``), else ``None``."""
        return None if self._server is None else str(self._server.url())

    def set_background(self, top: Color, bottom: Color) -> None:
        """Background gradient colours (RGB in [0, 1])."""
        top_rgb, bottom_rgb = rgb(top, "top")[:3], rgb(bottom, "bottom")[:3]
        self.vis["/Background"].set_property("top_color", [float(x) for x in top_rgb])
        self.vis["/Background"].set_property("bottom_color", [float(x) for x in bottom_rgb])

    def look_at(self, camera: Camera) -> None:
        """Place the camera (it orbits its target when the user drags the view).

        meshcat's orbit controls always aim at the world origin of the page, so the drawn
        content (``/meshcat``), the grid and the axes are shifted by ``-target`` and the camera
        is put at ``position - target``: what the page shows is the world seen from ``camera``.
        """
        from pkdyn.inputs import instance

        instance("camera", camera, Camera, "a Camera (pkdyn.viewer.frame_box)")
        self._auto_camera = False
        self._camera = camera
        shift = pin.SE3(np.eye(3), -np.asarray(camera.target, float)).homogeneous
        for node in (self.vis, self.vis["/Grid"], self.vis["/Axes"]):
            node.set_transform(shift)
        self.vis["/Cameras/default"].set_transform(np.eye(4))
        self.vis["/Cameras/default/rotated/<object>"].set_property("position", camera.offset_yup)

    @property
    def camera(self) -> Camera:
        """The current camera."""
        return self._camera

    @public
    def frame(self, direction: np.ndarray | None = None, aspect: float = 4.0 / 3.0) -> Camera:
        """Aim the camera at the robot (at the shown q) and the overlays.

        Args:
            direction: From the target towards the camera (3,); default a three-quarter view.
            aspect: Expected width / height of the view.

        Returns:
            The camera.

        """
        boxes = [self.robot_box(), *self._boxes]
        lo = np.min([b[0] for b in boxes], axis=0)
        hi = np.max([b[1] for b in boxes], axis=0)
        cam = frame_box(lo, hi, direction=direction, aspect=aspect)
        self.look_at(cam)
        self._auto_camera = True
        return cam

    def display(self, q: np.ndarray) -> None:
        """Show the robot at configuration ``q`` (nq,) (the camera follows until set by hand)."""
        from pkdyn.inputs import vector

        qq = vector("q", q, self.robot.nq, "rad or m")
        self.q = qq
        self.viz.display(qq)
        data = self.viz.data
        pin.updateFramePlacements(self.robot.model, data)
        for name, fid in self._frames.items():
            self.vis[f"{self.root}/triads/{name}"].set_transform(data.oMf[fid].homogeneous)
        if self._auto_camera:
            self.frame()

    # -- overlays and highlights ------------------------------------------------------------

    def add_points(
        self,
        name: str,
        points: np.ndarray,
        color: Color = (0.1, 0.6, 0.3),
        size: float = 0.005,
    ) -> None:
        """Overlay a point cloud (N, 3) [m] (a workspace sample) as ``overlays/<name>``."""
        from pkdyn.inputs import matrix, positive

        _name(name)
        P = matrix("points", points, None, 3, "m")
        obj = point_cloud(P, rgb(color)[: len(_probe(color))], positive("size", size, "m"))
        self.vis[f"overlays/{name}"].set_object(obj)
        self._boxes.append((P.min(axis=0), P.max(axis=0)))
        if self._auto_camera:
            self.frame()

    @public
    def add_mesh(
        self,
        name: str,
        vertices: np.ndarray,
        faces: np.ndarray,
        color: Color = (0.2, 0.5, 0.9, 0.35),
        wireframe: bool = False,
    ) -> None:
        """Overlay a triangle mesh (a workspace boundary) as ``overlays/<name>``."""
        from pkdyn.inputs import matrix

        _name(name)
        V = matrix("vertices", vertices, None, 3, "m")
        F = matrix("faces", faces, None, 3)
        if np.any(F != np.round(F)) or F.min() < 0 or F.max() >= len(V):
            raise InvalidInputError("faces", f"expected vertex indices in 0..{len(V) - 1}")
        mesh = triangle_mesh(V, F.astype(int), color, wireframe)
        self.vis[f"overlays/{name}"].set_object(mesh)
        self._boxes.append((V.min(axis=0), V.max(axis=0)))
        if self._auto_camera:
            self.frame()

    def highlight(self, names: Sequence[str], color: Color = hl.CLOSEST_COLOR) -> None:
        """Colour geometry objects (by visual or collision name, see :meth:`nodes`)."""
        from pkdyn.inputs import names as names_

        names = names_("names", names, what="geometry object")
        c = [float(x) for x in rgb(color)]
        for name in names:
            for node in self.nodes(name):
                self.vis[f"{node}/<object>"].set_property("color", c)

    def clear_highlights(self) -> None:
        """Restore every drawn object's own colour."""
        for node, c in self._base.items():
            self.vis[f"{node}/<object>"].set_property("color", [float(x) for x in c])

    @public
    def highlight_singular(self, q: np.ndarray | None = None) -> str:
        """Colour the moving parts if ``q`` (default: shown q) is singular or near-singular.

        Returns:
            ``"singular"``, ``"near"`` or ``"regular"`` (nothing coloured).

        """
        qq = self.q if q is None else np.asarray(q, dtype=float)
        label = int(hl.singularity_labels(self.robot, qq[None, :], progress=False)[0][0])
        color = {hl.SINGULAR: hl.SINGULAR_COLOR, hl.NEAR: hl.NEAR_COLOR}.get(label)
        if color is not None:
            for node in self._moving:
                alpha = float(self._base[node][3])
                self.vis[f"{node}/<object>"].set_property("color", [*color, alpha])
        return {hl.SINGULAR: "singular", hl.NEAR: "near"}.get(label, "regular")

    @public
    def highlight_closest(self, q: np.ndarray | None = None) -> tuple[str, str, float]:
        """Colour the two collision objects closest to each other at ``q`` (default: shown q).

        Returns:
            ``(a, b, distance)`` from :func:`pkdyn.analysis.collisions.distance_report` [m].

        """
        qq = self.q if q is None else np.asarray(q, dtype=float)
        a, b, d = hl.closest_pair(self.robot, qq)
        self.highlight([a, b])
        return a, b, d

    # -- animation --------------------------------------------------------------------------

    @public
    def animate(
        self,
        t: np.ndarray,
        Q: np.ndarray,
        *,
        singular: bool = False,
        closest: bool = False,
        max_rate: float = 60.0,
        loop: bool = True,
        progress: bool | None = None,
    ) -> np.ndarray:
        """Animate a trajectory (it plays when the page opens, looping by default).

        Args:
            t: Sample times (N,) [s], non-decreasing.
            Q: Assembled configurations (N, nq).
            singular: Colour the moving parts in singular (red) and near-singular (pink)
                samples.
            closest: Colour the two collision objects closest to each other at each sample.
            max_rate: At most this many keyframes per second [1/s].
            loop: Repeat forever (else play once and stop on the last sample).
            progress: Progress bar of the per-sample analyses: ``True`` / ``False`` force it on /
                off, ``None`` (default) shows it when stderr is a terminal and there are at least
                200 samples.

        Returns:
            Indices of the samples used as keyframes.

        """
        tt, QQ = check_trajectory(t, Q, self.robot.nq)
        keep = keyframes(tt, max_rate)
        times, Qk = tt[keep] - tt[0], QQ[keep]
        clips = self._pose_clips(times, Qk)
        colors = self._colors(Qk, singular, closest, progress)
        for node, C in colors.items():
            if np.any(C != self._base[node][:3]):  # a colour of its own at some keyframe
                clip = Clip(f"{node}/<object>")
                clip.color(times, C)
                clips.append(clip)
        self.display(Qk[0])
        self.vis.window.send(AnimationCommand(clips, play=True, loop=loop))
        return keep

    def _pose_clips(self, times: np.ndarray, Qk: np.ndarray) -> list[Clip]:
        """Position and quaternion tracks of every drawn object and frame triad."""
        model, data = self.robot.model, self.viz.data
        shown = [(kind, gmodel, gmodel.createData()) for kind, gmodel in self._shown()]
        triads = {
            str(self.vis[f"{self.root}/triads/{name}"].path.lower()): fid
            for name, fid in self._frames.items()
        }
        poses: dict[str, list[pin.SE3]] = {}
        for q in Qk:
            pin.forwardKinematics(model, data, q)
            pin.updateFramePlacements(model, data)
            for kind, gmodel, gdata in shown:
                pin.updateGeometryPlacements(model, data, gmodel, gdata)
                for gid, obj in enumerate(gmodel.geometryObjects):
                    poses.setdefault(self._node(obj, kind), []).append(pin.SE3(gdata.oMg[gid]))
            for node, fid in triads.items():
                poses.setdefault(node, []).append(pin.SE3(data.oMf[fid]))
        clips = []
        for node, Ms in poses.items():
            clip = Clip(node)
            pos = np.array([M.translation for M in Ms])
            quat = np.array([pin.Quaternion(M.rotation).coeffs() for M in Ms])  # x y z w
            clip.pose(times, pos, quat)
            clips.append(clip)
        return clips

    def _colors(
        self, Qk: np.ndarray, singular: bool, closest: bool, progress: bool | None
    ) -> dict[str, np.ndarray]:
        """Colour (K, 3) of each drawn node at each keyframe."""
        out = {node: np.tile(c[:3], (len(Qk), 1)) for node, c in self._base.items()}
        if singular:
            labels, _ = hl.singularity_labels(self.robot, Qk, progress)
            for k, label in enumerate(labels):
                color = {hl.SINGULAR: hl.SINGULAR_COLOR, hl.NEAR: hl.NEAR_COLOR}.get(int(label))
                if color is not None:
                    for node in self._moving:
                        out[node][k] = color
        if closest:
            for k, (a, b, _) in enumerate(hl.closest_pairs(self.robot, Qk, progress)):
                for node in self.nodes(a) + self.nodes(b):
                    out[node][k] = hl.CLOSEST_COLOR
        return out

    # -- export -----------------------------------------------------------------------------

    def html(self) -> str:
        """The scene (and its animation) as one self-contained HTML page (no server, no network)."""
        return static_html(self.record.commands(), title=f"pkdyn: {self.robot.name}")

    def save_html(self, path: str | Path) -> Path:
        """Write :meth:`html` to ``path`` and return the path.

        Raises:
            OutputError: The file cannot be written (an existing file is left intact).

        """
        from pkdyn.files import output_target

        output_target(path)
        p = Path(path)
        try:
            with atomic_write(p) as fh:
                fh.write(self.html())
        except OSError as err:
            raise OutputError(str(p), err.strerror or str(err)) from None
        return p

    def close(self) -> None:
        """Stop the live server, if any."""
        if self._process is not None:
            self._process.stop()
            self._process = None
        self._server = None
