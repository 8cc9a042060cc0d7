"""Required workspaces: the poses every design must reach, sampled.

Three shapes, each placed by its centre ``(x, y, z)`` [m] in the base frame:

- ``box``: sizes ``dx, dy, dz`` [m], platform orientation fixed (roll, pitch, yaw 0);
- ``cylinder``: vertical axis, diameter ``D`` and height ``H`` [m] (``H = 0``: a disc);
- ``orientation``: the platform at the centre, turned by ``psi`` about z (``yaw`` range), then by
  ``theta1`` about the fixed x axis (``roll`` range), then ``theta2`` about the fixed y axis
  (``pitch`` range): ``R = Rot(y, theta2) Rot(x, theta1) Rot(z, psi)``, each angle in
  ``[-range, range]`` [rad]. This is Merlet's two-axis parametrisation (seed 002) with
  ``X1 = x``, ``X2 = y``, ``R0 = Rot(z, psi)``, so ``pkdyn workspace --kind orientation --x1 1 0 0
  --x2 0 1 0 --rpy 0 0 PSI`` maps the same set; at ``psi = 0`` it is roll-pitch-yaw.

Samples include the boundary (faces, rim, corners) and a regular interior: ``samples`` per axis
(box: ``samples^3``; cylinder: ``samples`` levels of hexagonal rings, ``1 + 6 s (s - 1)`` points
each, the outer ring with ``12 (s - 1)``; orientation: ``samples^3`` rotations, ``samples^2``
when the yaw range is 0). Containment is checked on the samples: a narrow gap between them can
be missed, so raise ``samples`` for a final check.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkdyn.design import fields
from pkdyn.exceptions import InvalidInputError

__all__ = ["KINDS", "MAX_REQUIRED_POSES", "Requirement"]

MAX_REQUIRED_POSES = 100_000
"""Most sampled poses in a required workspace (each design checks them all)."""

KINDS = {
    "box": ("dx", "dy", "dz"),
    "cylinder": ("D", "H"),
    "orientation": ("roll", "pitch", "yaw"),
}
"""Shapes and their size parameters."""


def _rot(axis: int, a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    R = np.zeros(a.shape + (3, 3))
    i, j = [k for k in range(3) if k != axis]
    R[..., axis, axis] = 1.0
    R[..., i, i], R[..., j, j] = c, c
    R[..., i, j], R[..., j, i] = -s, s
    if axis == 1:  # Rot(y): [[c, 0, s], [0, 1, 0], [-s, 0, c]]
        R[..., i, j], R[..., j, i] = s, -s
    return R


@dataclass(frozen=True)
class Requirement:
    """A required workspace.

    Attributes:
        kind: ``box``, ``cylinder`` or ``orientation``.
        size: Size parameters of the kind (see :data:`KINDS`) [m or rad].
        center: Centre ``(x, y, z)`` [m].
        samples: Samples per axis (>= 2).

    Raises:
        InvalidInputError: Unknown kind, missing, unknown, negative or non-finite sizes.

    """

    kind: str
    size: dict[str, float]
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    samples: int = 5
    _cache: dict[str, Any] = field(default_factory=dict, repr=False, compare=False, init=False)

    def __post_init__(self) -> None:
        kind = fields.text("requirement", self.kind, tuple(KINDS))
        need = KINDS[kind]
        raw = fields.mapping(f"requirement {kind}", self.size)
        bad = [k for k in raw if k not in need]
        if bad:
            raise InvalidInputError(
                "requirement", f"{kind}: unknown size '{bad[0]}' (use {', '.join(need)})"
            )
        size: dict[str, float] = {}
        for k in need:
            if k not in raw and k not in ("H", "yaw"):
                raise InvalidInputError("requirement", f"{kind}: give its size {k}")
            size[k] = fields.number(f"requirement {kind} {k}", raw.get(k, 0.0), 0.0)
        if kind != "orientation" and max(size.values()) == 0.0:
            raise InvalidInputError("requirement", f"{kind}: every size is 0")
        if kind == "orientation" and max(size.values()) > math.pi:
            raise InvalidInputError(
                "requirement", f"orientation: angle ranges are at most pi rad, got {size}"
            )
        object.__setattr__(self, "size", size)
        center = self.center
        if isinstance(center, str) or not isinstance(center, Sequence) or len(center) != 3:
            raise InvalidInputError(
                "requirement", f"centre must be 3 finite numbers [x, y, z], got {center!r}"
            )
        c = tuple(fields.number("requirement centre", x) for x in center)
        object.__setattr__(self, "center", c)
        samples = fields.integer("requirement samples (--samples)", self.samples, 2)
        object.__setattr__(self, "samples", samples)
        count = self.count
        if count > MAX_REQUIRED_POSES:
            raise InvalidInputError(
                "requirement",
                f"{kind} at {samples} samples per axis is {count:,} poses per design, more than "
                f"{MAX_REQUIRED_POSES:,} (a pose check is microseconds to a millisecond, and "
                "every design checks them all); use fewer --samples",
            )

    @property
    def count(self) -> int:
        """Number of sampled poses (see the module docstring), computed without sampling."""
        return self.count_at(self.samples)

    def count_at(self, samples: int) -> int:
        """Number of poses this requirement would have at ``samples`` per axis."""
        s, z = fields.integer("samples", samples, 2), self.size
        if self.kind == "box":
            return int(np.prod([s if z[k] > 0.0 else 1 for k in ("dx", "dy", "dz")]))
        if self.kind == "cylinder":
            disc = 1 + 3 * (s - 2) * (s - 1) + 12 * (s - 1) if z["D"] > 0.0 else 1
            return disc * (s if z["H"] > 0.0 else 1)
        return (
            (s if z["roll"] > 0.0 else 1)
            * (s if z["pitch"] > 0.0 else 1)
            * (s if z["yaw"] > 0.0 else 1)
        )

    @classmethod
    def parse(cls, text: str, samples: int = 5) -> Requirement:
        """``KIND:K=V,K=V,...``, e.g. ``cylinder:D=0.4,H=0.1,z=-0.35``.

        ``x``, ``y``, ``z`` place the centre (default 0); the other keys are sizes.

        Raises:
            InvalidInputError: Malformed text or values.

        """
        if not isinstance(text, str):
            raise InvalidInputError("requirement", f"expected KIND:K=V,..., got {text!r}")
        kind, _, rest = text.partition(":")
        size: dict[str, float] = {}
        center = [0.0, 0.0, 0.0]
        seen: set[str] = set()
        for item in filter(None, (s.strip() for s in rest.split(","))):
            key, sep, value = item.partition("=")
            if key.strip() in seen:
                raise InvalidInputError("--require", f"'{key.strip()}' is given twice")
            seen.add(key.strip())
            try:
                val = float(value)
            except ValueError:
                val = math.nan
            if not sep or not math.isfinite(val):
                raise InvalidInputError("--require", f"'{item}': expected KEY=NUMBER")
            if key.strip() in ("x", "y", "z"):
                center["xyz".index(key.strip())] = val
            else:
                size[key.strip()] = val
        return cls(kind.strip(), size, (center[0], center[1], center[2]), samples)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | str) -> Requirement:
        """From the study-file form (see :meth:`as_dict`).

        Raises:
            InvalidInputError: Not a mapping (or ``KIND:K=V`` text), a field of the wrong type.

        """
        if isinstance(data, str):
            return cls.parse(data)
        d = fields.mapping("requirement", data)
        if "kind" not in d:
            raise InvalidInputError("requirement", "needs a 'kind'")
        kind = d.pop("kind")
        center = d.pop("center", (0.0, 0.0, 0.0))
        samples = d.pop("samples", 5)
        return cls(kind, d, center, samples)

    def as_dict(self) -> dict[str, Any]:
        """Plain form for study files."""
        return {
            "kind": self.kind,
            **self.size,
            "center": list(self.center),
            "samples": self.samples,
        }

    def describe(self) -> str:
        """One line, e.g. ``cylinder D=0.4 H=0.1 at (0, 0, -0.35)``."""
        sizes = " ".join(f"{k}={v:g}" for k, v in self.size.items())
        return f"{self.kind} {sizes} at ({', '.join(f'{c:g}' for c in self.center)})"

    @property
    def positions(self) -> np.ndarray:
        """Sampled platform positions (N, 3) [m]."""
        return self._samples()[0]

    @property
    def rotations(self) -> np.ndarray:
        """Sampled platform orientations (N, 3, 3)."""
        return self._samples()[1]

    @property
    def fixed_orientation(self) -> bool:
        """All samples at the identity orientation."""
        return self.kind != "orientation"

    def _samples(self) -> tuple[np.ndarray, np.ndarray]:
        if "P" not in self._cache:
            P, R = self._make()
            P.setflags(write=False)
            R.setflags(write=False)
            self._cache["P"], self._cache["R"] = P, R
        return self._cache["P"], self._cache["R"]

    def _make(self) -> tuple[np.ndarray, np.ndarray]:
        s, c, z = self.samples, np.array(self.center), self.size
        if self.kind == "box":
            axes = [np.linspace(-0.5, 0.5, s) * z[k] for k in ("dx", "dy", "dz")]
            G = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
            P = np.unique(G, axis=0) + c
        elif self.kind == "cylinder":
            pts = [np.zeros(2)]
            for k in range(1, s):
                n = 12 * k if k == s - 1 else 6 * k
                phi = 2.0 * np.pi * np.arange(n) / n
                r = 0.5 * z["D"] * k / (s - 1)
                pts.append(np.column_stack([r * np.cos(phi), r * np.sin(phi)]).reshape(-1))
            disc = np.concatenate(pts).reshape(-1, 2)
            levels = np.unique(np.linspace(-0.5, 0.5, s) * z["H"])
            P = np.concatenate([np.column_stack([disc, np.full(len(disc), h)]) for h in levels])
            P = P + c
        else:
            t1 = np.linspace(-1.0, 1.0, s) * z["roll"]
            t2 = np.linspace(-1.0, 1.0, s) * z["pitch"]
            psi = np.unique(np.linspace(-1.0, 1.0, s) * z["yaw"])
            T1, T2, PS = (a.ravel() for a in np.meshgrid(t1, t2, psi, indexing="ij"))
            R = _rot(1, T2) @ _rot(0, T1) @ _rot(2, PS)
            return np.broadcast_to(c, (len(T1), 3)).copy(), R
        return P, np.broadcast_to(np.eye(3), (len(P), 3, 3)).copy()
