"""A meshcat window that needs no server: it records the scene and writes it as one HTML file."""

from __future__ import annotations

from typing import Any

import umsgpack
from meshcat.servers.tree import SceneTree, find_node, walk

from pkdyn.viewer.html import static_html

__all__ = ["OfflineWindow", "TeeWindow"]


class OfflineWindow:
    """Stand-in for ``meshcat.visualizer.ViewerWindow`` that keeps the scene in memory.

    ``meshcat.Visualizer(window=OfflineWindow())`` accepts every drawing command; the window
    keeps the latest object, properties, transform and animation of each scene node, as meshcat's
    server does, and :meth:`get_scene` returns a self-contained HTML page of that scene (the
    viewer's JavaScript inlined, no network access, no server).
    """

    web_url = ""
    server_proc = None

    def __init__(self) -> None:
        self.tree: Any = SceneTree()
        self.animations: list[bytes] = []

    def send(self, command: Any) -> None:
        """Record one meshcat command (``SetObject``, ``SetTransform``, ``SetProperty``, ...)."""
        data = command.lower()
        kind = data["type"]
        blob = umsgpack.packb(data)
        if kind == "set_animation":
            self.animations = [blob]  # meshcat replaces the previous animation too
            return
        path = [p for p in data.get("path", "").split("/") if p]
        node = find_node(self.tree, path)
        if kind == "set_object":
            node.object = blob
            node.properties = []
        elif kind == "set_property":
            node.properties.append(blob)
        elif kind == "set_transform":
            node.transform = blob
        elif kind == "delete":
            if path:
                find_node(self.tree, path[:-1]).pop(path[-1], None)
            else:
                self.tree = SceneTree()
        else:
            raise ValueError(f"the offline meshcat window cannot handle '{kind}' commands")

    def commands(self) -> list[bytes]:
        """The msgpack commands that rebuild the scene, animations last (they bind to objects)."""
        out: list[bytes] = []
        for node in walk(self.tree):
            if node.object is not None:
                out.append(node.object)
            out.extend(node.properties)
            if node.transform is not None:
                out.append(node.transform)
        return out + self.animations

    def get_scene(self) -> str:
        """The scene as a self-contained HTML document (what ``Visualizer.static_html`` returns)."""
        return static_html(self.commands())

    def connect_zmq(self) -> None:  # pragma: no cover - interface of ViewerWindow
        """Nothing to connect to."""

    def open(self) -> OfflineWindow:
        """Nothing to open: write :meth:`get_scene` to a file and open that instead."""
        return self

    def close(self) -> None:
        """Nothing to close."""


class TeeWindow:
    """Sends every command to several windows (a live server and an :class:`OfflineWindow`)."""

    def __init__(self, *windows: Any) -> None:
        self.windows = windows

    @property
    def web_url(self) -> str:
        """URL of the first window that has one, else ``""``."""
        return next((w.web_url for w in self.windows if getattr(w, "web_url", "")), "")

    def send(self, command: Any) -> None:
        """Forward one command to every window."""
        for w in self.windows:
            w.send(command)

    def get_scene(self) -> str:
        """The static HTML of the first window."""
        return str(self.windows[0].get_scene())
