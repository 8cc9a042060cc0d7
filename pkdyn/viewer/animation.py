"""Trajectory animation as three.js keyframe clips (what meshcat's ``set_animation`` plays).

A clip per scene node: position and quaternion tracks for the moving bodies and frames, a
``.material.color`` track for the geometry whose colour changes (singular configurations,
closest legs). Key times are the trajectory's own sample times [s], so the animation runs in
real time whatever the sampling; three.js interpolates linearly (slerp for rotations).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = ["AnimationCommand", "Clip", "chain", "check_trajectory", "keyframes"]


def check_trajectory(t: np.ndarray, Q: np.ndarray, nq: int) -> tuple[np.ndarray, np.ndarray]:
    """Validate a sampled trajectory.

    Args:
        t: Sample times (N,) [s], non-decreasing.
        Q: Configurations (N, nq).
        nq: Expected configuration size.

    Returns:
        ``(t, Q)`` as float arrays.

    Raises:
        InvalidInputError: Wrong shapes, NaN, or times going backwards.

    """
    from pkdyn.inputs import matrix, vector

    tt = vector("t", t, unit="s")
    if tt.size == 0:
        raise InvalidInputError("t", "expected a non-empty (N,) array of times [s]")
    QQ = matrix("Q", Q, tt.size, nq, "rad or m")
    if np.any(np.diff(tt) < 0):
        k = int(np.flatnonzero(np.diff(tt) < 0)[0])
        raise InvalidInputError("t", f"times go backwards at sample {k + 1} ({tt[k + 1]} s)")
    return tt, QQ


def keyframes(t: np.ndarray, max_rate: float = 60.0) -> np.ndarray:
    """Indices of the samples kept as keyframes: at most ``max_rate`` per second.

    The first and last samples are always kept; a sample is kept when at least
    ``1 / max_rate`` seconds passed since the previous kept one.

    Args:
        t: Non-decreasing sample times (N,) [s].
        max_rate: Keyframe rate cap [1/s].

    Returns:
        Increasing sample indices.

    """
    from pkdyn.inputs import positive

    max_rate = positive("max_rate", max_rate, "1/s")
    keep = [0]
    step = 1.0 / max_rate
    for i in range(1, len(t) - 1):
        if t[i] - t[keep[-1]] >= step:
            keep.append(i)
    if len(t) > 1:
        keep.append(len(t) - 1)
    return np.asarray(keep, dtype=int)


def chain(
    segments: Sequence[tuple[np.ndarray, np.ndarray]], pause: float = 0.5
) -> tuple[np.ndarray, np.ndarray]:
    """Play trajectories one after the other.

    Each segment starts ``pause`` seconds after the previous one ended, holding the previous
    segment's last configuration meanwhile (then jumping to the next one's first).

    Args:
        segments: ``(t, Q)`` pairs, times (N_i,) [s] and configurations (N_i, nq).
        pause: Hold between two segments [s].

    Returns:
        The chained ``(t, Q)``, time starting at 0.

    """
    from pkdyn.inputs import non_negative

    pause = non_negative("pause", pause, "s")
    if isinstance(segments, str | bytes) or not hasattr(segments, "__iter__"):
        raise InvalidInputError("segments", f"expected (t, Q) pairs, got {segments!r:.40}")
    segments = list(segments)
    if any(not isinstance(s, tuple | list) or len(s) != 2 for s in segments):
        raise InvalidInputError("segments", "expected (t, Q) pairs")
    nq = np.shape(segments[0][1])[-1] if segments and np.ndim(segments[0][1]) == 2 else 0
    segments = [check_trajectory(t, Q, nq) for t, Q in segments]
    ts: list[np.ndarray] = []
    Qs: list[np.ndarray] = []
    end = 0.0
    for k, (t, Q) in enumerate(segments):
        tt = np.asarray(t, dtype=float) - float(t[0])
        if k:
            ts.append(np.array([end + pause]))
            Qs.append(Qs[-1][-1:])
            end += pause + 1e-3
        ts.append(tt + end)
        Qs.append(np.asarray(Q, dtype=float))
        end = float(ts[-1][-1])
    if not ts:
        raise InvalidInputError("segments", "nothing to chain")
    return np.concatenate(ts), np.vstack(Qs)


@dataclass
class Clip:
    """The keyframe tracks of one scene node.

    Attributes:
        path: Absolute meshcat path of the node (``/meshcat/...``).
        tracks: three.js tracks ``{"name", "type", "times", "values"}``.

    """

    path: str
    tracks: list[dict[str, Any]] = field(default_factory=list)

    def pose(self, times: np.ndarray, position: np.ndarray, quaternion_xyzw: np.ndarray) -> None:
        """Add position (K, 3) [m] and quaternion (K, 4) tracks at ``times`` (K,) [s]."""
        self._add(".position", "vector3", times, position)
        self._add(".quaternion", "quaternion", times, quaternion_xyzw)

    def color(self, times: np.ndarray, rgb: np.ndarray) -> None:
        """Add a material colour track (K, 3) at ``times`` (K,) [s] (the node is a mesh)."""
        self._add(".material.color", "color", times, rgb)

    def _add(self, name: str, kind: str, times: np.ndarray, values: np.ndarray) -> None:
        vals = np.asarray(values, dtype=float).reshape(len(times), -1)
        self.tracks.append(
            {
                "name": name,
                "type": kind,
                "keys": [
                    {"time": float(ti), "value": [float(x) for x in v]}
                    for ti, v in zip(times, vals, strict=True)
                ],
            }
        )

    def lower(self) -> dict[str, Any]:
        """The clip in meshcat's wire format (fps 1: key times in seconds)."""
        return {"path": self.path, "clip": {"fps": 1, "name": "default", "tracks": self.tracks}}


class AnimationCommand:
    """meshcat ``set_animation`` command for a list of clips.

    The command is addressed to the node ``/pkdyn_animation`` rather than the scene root:
    meshcat's server replays its scene tree depth first to each browser that connects, and an
    animation stored at the root would come before the objects it animates.
    """

    def __init__(self, clips: Sequence[Clip], play: bool = True, loop: bool = True) -> None:
        self.clips = list(clips)
        self.play = play
        self.loop = loop

    def lower(self) -> dict[str, Any]:
        """The command as meshcat's viewer expects it."""
        return {
            "type": "set_animation",
            "animations": [c.lower() for c in self.clips],
            "options": {"play": self.play, "repetitions": float("inf") if self.loop else 1},
            "path": "/pkdyn_animation",
        }
