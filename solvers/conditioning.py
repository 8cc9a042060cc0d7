"""Conditioning of the closure forces along a motion, and the singular passages it reveals.

The constrained dynamics (:mod:`solvers.forward_dynamics`) find the closure forces ``lambda``
from the closures' acceleration equations through the Delassus matrix ``G = J M^-1 J^T`` (the
inverse inertia the closures see): ``G lambda = b - J M^-1 (tau - h)``. Where the closure rows
lose rank, ``G`` does too: the force along the lost direction is no longer determined by the
rigid model, and near there it grows like ``1 / kappa^2`` (``kappa`` below) unless the motion
happens to need none. With the actuators locked such a configuration is a parallel singularity
of the robot (the passive joints gain a motion); it is the kind the actuators cannot help
with, since the closures degenerate whatever the actuators do (the free-falling Delta, whose
bars and arms line up and fold through them).

**The figure.** ``kappa = sigma_r / sigma_1``, the ``r``-th singular value of ``S J M^-1/2``
relative to its largest, computed as ``sqrt(g_r / g_1)`` from the eigenvalues
``g_1 >= g_2 >= ...`` of ``S G S``:

- the mass metric ``M^-1/2`` makes it independent of how the joints are parametrised and of
  their units (a reparametrisation ``v = T w`` changes ``J M^-1/2`` by an orthogonal factor);
- ``S`` multiplies the angular rows of welds by the robot's length, so that forces and moments
  weigh alike: the robot scaled by any factor, or its masses, gets the same ``kappa``;
- ``r`` is the closures' generic rank: the rank at the initial state by the cut-off rule of
  :mod:`solvers.numerics` at :data:`SINGULAR` (or given by the caller), so that rows redundant
  by construction (the two points of a hinge, a planar loop's out-of-plane rows) do not count.

``kappa`` lies in ``[0, 1]`` and grows linearly with the distance (in configuration) to the
singular set, like the margins of the kinematic singularity analysis
(:mod:`pkdyn.analysis.singularity`), whose thresholds it shares:

- below :data:`NEAR_SINGULAR` (1e-4) the motion passes **near** a singularity: a
  :class:`SingularityEvent` is recorded. The closure forces are still resolved (the dynamics
  solve them exactly and the adaptive integrator shortens its steps with ``kappa``), but they
  lose digits like ``eps / kappa^2`` (``G``'s condition number is ``1 / kappa^2``): 8 of 16 at
  1e-4;
- below :data:`THROUGH` (1e-5) it passes **through** one: the force along the lost direction
  carries a relative error of ``eps / kappa^2`` = 2e-6 and more, which no error control can
  follow (its steps would shrink to 1e-12 s). The dynamics drop it (minimum-norm forces, the
  components below :data:`THROUGH` cut off) and cross: the motion after it is the model's
  minimum-norm continuation, not the exact rigid one, and where the closures really lose rank
  (the singular set is a hypersurface the motion crosses: the free-falling Delta crosses the
  one where the normals of its three parallelograms become coplanar and the nacelle may turn)
  which branch the mechanism takes afterwards is decided by rounding. In double precision the
  smallest eigenvalues of ``G`` are known to about ``eps g_1``, ``kappa`` to
  ``sqrt(eps)`` = 1.5e-8: below :data:`SINGULAR` (1e-7, the cut-off of the closures' rank) a
  configuration is exactly singular.

Robot-agnostic (pinocchio and numpy).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from solvers import numerics

__all__ = [
    "LEAVE",
    "NEAR_SINGULAR",
    "PARALLEL_SINGULARITY",
    "SINGULAR",
    "THROUGH",
    "Conditioning",
    "Passages",
    "SingularityEvent",
    "reach",
]

NEAR_SINGULAR = 1e-4
"""Below this ``kappa`` a motion passes near a singularity (the kinematic analysis'
``NEAR_SINGULAR_TOL``: about 1e-4 of the robot's size from a singular configuration)."""

SINGULAR = 1e-7
"""Below this ``kappa`` the closures have lost rank at double precision (the kinematic
analysis' ``SINGULAR_TOL``); the cut-off of their generic rank."""

THROUGH = 1e-5
"""Below this ``kappa`` a passage goes through the singularity: the closure force along the
lost direction, known to ``eps / kappa^2`` relative or worse, is dropped (module docstring)."""

LEAVE = 2.0
"""A passage ends when ``kappa`` rises above ``LEAVE * NEAR_SINGULAR`` (hysteresis: a motion
that lingers at the threshold is one passage, not many)."""

VERTEX_WATCH = 100.0 * NEAR_SINGULAR
"""Bottoms between samples are estimated where the lowest of three samples is below this."""

PARALLEL_SINGULARITY = "parallel_singularity"
"""The kind of event this module reports."""

_POINT = pin.ContactType.CONTACT_3D


@dataclass
class SingularityEvent:
    """A passage of a motion near or through a singularity of its closures.

    Attributes:
        time: Time of the smallest conditioning seen in the passage [s].
        conditioning: That smallest ``kappa`` (module docstring), in ``[0, 1]``; the true
            minimum between two samples may be lower, by about the factor by which ``kappa``
            changed from one sample to the next (the adaptive integrator halves it at most).
        through: ``kappa`` fell below :data:`THROUGH`: the closure force along the lost
            direction was dropped there, and the motion after ``start`` is the model's
            minimum-norm continuation (where the closures really lost rank, one of the branches
            the mechanism allows, the one rounding chose).
        start: Time at which ``kappa`` fell below :data:`NEAR_SINGULAR` [s].
        end: Time at which it rose above ``LEAVE * NEAR_SINGULAR`` [s] (NaN: still inside at
            the end of the run).
        kind: ``"parallel_singularity"``.

    """

    time: float
    conditioning: float
    through: bool
    start: float
    end: float = math.nan
    kind: str = PARALLEL_SINGULARITY

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict (times [s], ``end`` ``None`` while open)."""
        return {
            "kind": self.kind,
            "time": self.time,
            "conditioning": self.conditioning,
            "through": self.through,
            "start": self.start,
            "end": self.end if math.isfinite(self.end) else None,
        }

    def describe(self) -> str:
        """One line: ``near a parallel singularity at t = 0.575 s (conditioning 3.2e-05)``."""
        how = "through" if self.through else "near"
        return (
            f"{how} a parallel singularity at t = {self.time:.6g} s "
            f"(conditioning {self.conditioning:.2g})"
        )


def reach(model: pin.Model, data: pin.Data, q: np.ndarray) -> float:
    """The largest distance of a joint from the world origin at ``q``, at least 0.1 [m]."""
    pin.forwardKinematics(model, data, q)
    far = max((float(np.linalg.norm(M.translation)) for M in data.oMi), default=0.0)
    return max(0.1, far)


class Conditioning:
    """``kappa`` of the closure forces from a factorized dynamics evaluation (module docstring).

    Args:
        constraint_models: The rigid constraint models, in the order of the dynamics.
        length_scale: The robot's length [m], the weight of the welds' angular rows.
        rank: Generic rank of the closures (default: the rank at the first evaluation).

    Attributes:
        rank: The generic rank (``None`` until the first evaluation when not given).

    """

    def __init__(
        self,
        constraint_models: Sequence[pin.RigidConstraintModel],
        length_scale: float,
        rank: int | None = None,
    ) -> None:
        scale: list[float] = []
        for cm in constraint_models:
            scale += [1.0] * 3 if cm.type == _POINT else [1.0] * 3 + [float(length_scale)] * 3
        self.scale = np.array(scale)
        self._welds = bool(np.any(self.scale != 1.0))
        self._outer = self.scale[:, None] * self.scale[None, :]  # S G S = G * outer
        self.rank = rank
        self.nc = self.scale.size

    def delassus(self, data: pin.Data, mu: float) -> tuple[np.ndarray, np.ndarray]:
        """``G + mu I`` as factorized (unscaled) and the scaled ``S G S`` (both (nc, nc)).

        Args:
            data: The data of the last ``pin.constraintDynamics`` call (its factorization).
            mu: The proximal regularisation it was made with.

        """
        G_mu = data.constraint_chol.getInverseOperationalSpaceInertiaMatrix()
        G = np.array(G_mu)
        G.flat[:: self.nc + 1] -= mu
        if self._welds:
            G *= self.scale[:, None]
            G *= self.scale[None, :]
        return G_mu, G

    def kappa(self, g: np.ndarray) -> float:
        """``kappa`` from the eigenvalues ``g`` of ``S G S`` (ascending, as numpy returns them).

        The first call sets :attr:`rank` when it was not given.
        """
        sigma = np.sqrt(np.maximum(g[::-1], 0.0))
        if self.rank is None:
            self.rank = numerics.rank_of(sigma, SINGULAR)
        r = self.rank
        if r == 0 or not sigma[0] > 0.0:
            return 1.0
        return float(sigma[r - 1] / sigma[0])

    def __call__(self, data: pin.Data, mu: float) -> float:
        """``kappa`` at the last evaluation made with ``data`` (one symmetric eigen-solve).

        Pinocchio returns ``G + mu I`` as a new array, worked on in place: with points only
        (``S = I``) its eigenvalues less ``mu`` are those of ``G``.
        """
        if not self.nc:
            return 1.0
        G = data.constraint_chol.getInverseOperationalSpaceInertiaMatrix()
        if not self._welds:
            g = np.linalg.eigvalsh(G)
            g -= mu
            return self.kappa(g)
        G.flat[:: self.nc + 1] -= mu
        G *= self._outer
        return self.kappa(np.linalg.eigvalsh(G))


class Passages:
    """The singular passages of a motion, from samples of ``kappa`` in time order.

    A passage starts at a sample below :data:`NEAR_SINGULAR` and ends at the first one above
    ``LEAVE * NEAR_SINGULAR``. Between samples the bottom of a passage is estimated: ``kappa^2``
    is smooth through a singularity (the closures' singular value crosses zero linearly, its
    square is a parabola) while ``kappa`` has a corner there, so where three consecutive samples
    turn from falling to rising the vertex of the parabola through their ``kappa^2`` is taken as
    a sample (time and ``kappa``, 0 if negative). A fixed-step run that steps over the bottom of
    a passage, or over a whole passage, thus reports it.

    Attributes:
        events: The passages, in time order; the last one is updated while the motion is in it.

    """

    def __init__(self) -> None:
        self.events: list[SingularityEvent] = []
        self._open: SingularityEvent | None = None
        self._last: list[tuple[float, float]] = []  # the last two samples (t, kappa^2)

    def reset(self) -> None:
        """Forget every passage (a new run)."""
        self.events = []
        self._open = None
        self._last = []

    @property
    def inside(self) -> bool:
        """The last sample was in a passage."""
        return self._open is not None

    def observe(self, t: float, kappa: float) -> SingularityEvent | None:
        """Take a sample ``kappa`` at time ``t`` [s].

        Returns:
            The event this sample opened (a passage estimated between the last samples
            included), else ``None``.

        """
        opened = None
        vertex = self._vertex(t, kappa * kappa)
        if vertex is not None:
            opened = self._sample(*vertex)
        return self._sample(t, kappa) or opened

    def _vertex(self, t: float, k2: float) -> tuple[float, float] | None:
        """The bottom estimated between the last samples, if they turned from falling to rising."""
        last = self._last
        if last and not t - last[-1][0] > 1e-12 * max(1.0, abs(t)):
            # the same time again (a state projected back on the closures: a jump, not a
            # motion), or a caller stepping back in time: the sample replaces the last one
            last[-1] = (t, k2)
            return None
        last.append((t, k2))
        if len(last) < 3:
            return None
        (t1, a), (t2, b), (t3, c) = last
        del last[0]
        if not (a > b <= c and b < VERTEX_WATCH * VERTEX_WATCH):
            return None
        # the parabola through the three points, in s = t - t2
        h1, h3 = t1 - t2, t3 - t2
        d1, d3 = (a - b) / h1, (c - b) / h3
        curv = (d3 - d1) / (h3 - h1)  # second divided difference
        if not curv > 0.0:
            return None
        slope = d1 - curv * h1  # derivative at t2
        s = -slope / (2.0 * curv)
        if not h1 < s < h3:
            return None
        low = b + slope * s + curv * s * s
        return t2 + s, math.sqrt(max(low, 0.0))

    def _sample(self, t: float, kappa: float) -> SingularityEvent | None:
        ev = self._open
        if ev is None:
            if not kappa < NEAR_SINGULAR:
                return None
            ev = SingularityEvent(t, kappa, kappa < THROUGH, t)
            self.events.append(ev)
            self._open = ev
            return ev
        if kappa < ev.conditioning:
            ev.conditioning = kappa
            ev.time = t
            ev.start = min(ev.start, t)  # (a bottom estimated before the first sample below)
            ev.through = ev.through or kappa < THROUGH
        if kappa > LEAVE * NEAR_SINGULAR:
            ev.end = t
            self._open = None
        return None
