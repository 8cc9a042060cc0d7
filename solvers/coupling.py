"""Scalar holonomic couplings between two 1-DoF joint coordinates (gears, mimic joints).

A coupling ties a driven joint coordinate ``x_j`` to a source coordinate ``x_s``:

    ``r = (x_j - x_j0) - p(x_s - x_s0),   p(u) = sum_k c_k u^k``  (1 to 5 coefficients),

or, without a source, holds ``x_j`` at ``x_j0 + c_0`` (a locked joint). ``x`` is the joint's
coordinate [rad or m]: ``q[idx_q]`` for a revolute or prismatic joint, the angle
``atan2(q[idx_q + 1], q[idx_q])`` of an unbounded revolute joint (Pinocchio's cos/sin pair); for
such a driven joint the residual is wrapped to ``[-pi, pi)`` (its angle is defined modulo one
turn).

Derivatives with respect to a velocity increment (``pin.integrate``), exact:

- Jacobian row: ``+1`` at the driven joint's velocity index, ``-p'(u)`` at the source's;
- acceleration drift (``d^2 r/dt^2 = J a + gamma``): ``gamma = -p''(u) v_s^2``.

The multiplier ``mu`` of a coupling row (``J^T mu`` in the dynamics) is the generalized force
[N m or N] the coupling applies to the driven joint; the source receives ``-p'(u) mu``.

:class:`CouplingRows` evaluates a set of couplings at once, on one state or on a batch of
states (leading axes), with numpy. Robot-agnostic: joints are Pinocchio joint ids.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

__all__ = ["MAX_COEFFICIENTS", "CouplingRows", "JointCoupling"]

MAX_COEFFICIENTS = 5
"""Largest number of polynomial coefficients (MuJoCo's ``polycoef``: degree 4)."""


@dataclass(frozen=True)
class JointCoupling:
    """One coupling (see the module docstring).

    Attributes:
        name: Name, for messages and reports.
        joint: Pinocchio joint id of the driven joint (one velocity coordinate).
        source: Joint id of the source joint, or ``None`` (the joint is locked).
        coefficients: ``c_0 .. c_k`` (1 to :data:`MAX_COEFFICIENTS`), constant term first.
        joint_ref: ``x_j0`` [rad or m].
        source_ref: ``x_s0`` [rad or m].

    """

    name: str
    joint: int
    source: int | None
    coefficients: tuple[float, ...]
    joint_ref: float = 0.0
    source_ref: float = 0.0


def _index(model: pin.Model, jid: int, name: str) -> tuple[int, int, bool]:
    """``(idx_q, idx_v, circular)`` of a 1-DoF joint, or ``ValueError``."""
    if not 0 < jid < model.njoints:
        raise ValueError(f"coupling {name!r}: joint id {jid} is not a joint of the model")
    jm = model.joints[jid]
    if jm.nv != 1 or jm.nq not in (1, 2):
        raise ValueError(
            f"coupling {name!r}: joint {model.names[jid]!r} has {jm.nv} velocity coordinates; "
            "couplings relate 1-DoF joints"
        )
    return int(jm.idx_q), int(jm.idx_v), jm.nq == 2


class CouplingRows:
    """Residuals, Jacobian rows and drifts of couplings on a Pinocchio model.

    Args:
        model: The kinematic tree.
        couplings: The couplings.

    Raises:
        ValueError: A joint that is not 1-DoF, a coupling of a joint to itself, no or too many
            coefficients, or non-finite numbers.

    """

    def __init__(self, model: pin.Model, couplings: Sequence[JointCoupling]) -> None:
        self.couplings = tuple(couplings)
        self.nv = int(model.nv)
        k = len(self.couplings)
        self.n = k
        self.names = [c.name for c in self.couplings]
        self.jq = np.zeros(k, dtype=int)
        self.jv = np.zeros(k, dtype=int)
        self.jcirc = np.zeros(k, dtype=bool)
        self.sq = np.zeros(k, dtype=int)
        self.sv = np.zeros(k, dtype=int)
        self.scirc = np.zeros(k, dtype=bool)
        self.has_source = np.zeros(k, dtype=bool)
        self.coef = np.zeros((k, MAX_COEFFICIENTS))
        self.jref = np.zeros(k)
        self.sref = np.zeros(k)
        for i, c in enumerate(self.couplings):
            n = len(c.coefficients)
            if not 1 <= n <= MAX_COEFFICIENTS:
                raise ValueError(
                    f"coupling {c.name!r}: {n} coefficients; give 1 to {MAX_COEFFICIENTS}"
                )
            values = (*c.coefficients, c.joint_ref, c.source_ref)
            if not all(math.isfinite(float(x)) for x in values):
                raise ValueError(f"coupling {c.name!r}: coefficients and references must be finite")
            self.jq[i], self.jv[i], self.jcirc[i] = _index(model, int(c.joint), c.name)
            if c.source is not None:
                if int(c.source) == int(c.joint):
                    raise ValueError(f"coupling {c.name!r}: a joint cannot drive itself")
                self.sq[i], self.sv[i], self.scirc[i] = _index(model, int(c.source), c.name)
                self.has_source[i] = True
                self.coef[i, :n] = c.coefficients
            else:
                self.coef[i, 0] = c.coefficients[0]  # a locked joint: the constant term only
            self.jref[i] = c.joint_ref
            self.sref[i] = c.source_ref
        # the highest degree in use (trailing zero columns cost Horner steps for nothing)
        used = np.flatnonzero(np.any(self.coef != 0.0, axis=0))
        self.coef = self.coef[:, : max(2, int(used[-1]) + 1 if used.size else 2)]
        # derivative coefficients: p' and p''
        powers = np.arange(1, self.coef.shape[1])
        self.d1 = self.coef[:, 1:] * powers
        self.d2 = self.d1[:, 1:] * powers[:-1] if self.coef.shape[1] > 2 else np.zeros((k, 1))
        self.rows = np.arange(k)
        self.jcirc_any = bool(self.jcirc.any())
        self.scirc_any = bool(self.scirc.any())
        self.all_sourced = bool(self.has_source.all())
        # one state at a time: plain floats (numpy's per-call overhead dominates small rows)
        self._scalar = [
            (
                int(self.jq[i]),
                bool(self.jcirc[i]),
                int(self.sq[i]),
                bool(self.scirc[i]),
                bool(self.has_source[i]),
                self.coef[i].tolist()[::-1],
                self.d1[i].tolist()[::-1],
                self.d2[i].tolist()[::-1],
                float(self.jref[i]),
                float(self.sref[i]),
            )
            for i in range(k)
        ]

    @staticmethod
    def _coordinate(q: np.ndarray, idx: np.ndarray, circ: np.ndarray, any_circ: bool) -> np.ndarray:
        x = q[..., idx]
        if any_circ:
            ang = np.arctan2(q[..., np.minimum(idx + 1, q.shape[-1] - 1)], x)
            x = np.where(circ, ang, x)
        return x

    @staticmethod
    def _horner(C: np.ndarray, u: np.ndarray) -> np.ndarray:
        out = np.broadcast_to(C[:, -1], u.shape).copy()
        for i in range(C.shape[1] - 2, -1, -1):
            out *= u
            out += C[:, i]
        return out

    def _one(self, q: np.ndarray, what: int) -> np.ndarray:
        """Residuals (0), slopes (1) or ``p''`` (2) at one configuration, with floats."""
        out = np.empty(self.n)
        qs = q.tolist()
        for i, (jq, jc, sq, sc, src, c0, c1, c2, jref, sref) in enumerate(self._scalar):
            u = 0.0
            if src:
                u = (math.atan2(qs[sq + 1], qs[sq]) if sc else qs[sq]) - sref
            p = 0.0
            for ck in (c0, c1, c2)[what]:
                p = p * u + ck
            if what:
                out[i] = p
                continue
            r = (math.atan2(qs[jq + 1], qs[jq]) if jc else qs[jq]) - jref - p
            out[i] = ((r + math.pi) % (2.0 * math.pi)) - math.pi if jc else r
        return out

    def _u(self, q: np.ndarray) -> np.ndarray:
        """Source displacement ``x_s - x_s0`` (..., k) (0 for locked joints)."""
        u = self._coordinate(q, self.sq, self.scirc, self.scirc_any) - self.sref
        return u if self.all_sourced else np.where(self.has_source, u, 0.0)

    def residual(self, q: np.ndarray) -> np.ndarray:
        """Residuals ``r`` (..., k) [rad or m] of configurations ``q`` (..., nq)."""
        if q.ndim == 1:
            return self._one(q, 0)
        x = self._coordinate(q, self.jq, self.jcirc, self.jcirc_any)
        r = x - self.jref - self._horner(self.coef, self._u(q))
        if self.jcirc_any:
            r = np.where(self.jcirc, np.remainder(r + math.pi, 2.0 * math.pi) - math.pi, r)
        return r

    def slopes(self, q: np.ndarray) -> np.ndarray:
        """``p'(u)`` (..., k): the source's Jacobian entry is ``-p'(u)``."""
        if q.ndim == 1:
            return self._one(q, 1)
        return self._horner(self.d1, self._u(q))

    def jacobian(self, q: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Jacobian rows (k, nv) at one configuration ``q`` (nq,).

        Args:
            q: Configuration (nq,).
            out: Array (k, nv) to fill, zero but for the entries of earlier calls (default: a
                new one).

        Returns:
            The rows.

        """
        if out is None:
            out = np.zeros((self.n, self.nv))
        out[self.rows, self.sv] = -self.slopes(q)  # 0 for locked joints: p' = 0
        out[self.rows, self.jv] = 1.0  # (after: a locked joint's dummy source index)
        return out

    def velocity_error(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``J v`` (..., k) [rad/s or m/s] of states ``(q, v)`` with leading axes."""
        return v[..., self.jv] - self.slopes(q) * v[..., self.sv]

    def drift(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Acceleration drift ``gamma = -p''(u) v_s^2`` (..., k) [rad/s^2 or m/s^2]."""
        vs = v[..., self.sv]
        d2 = self._one(q, 2) if q.ndim == 1 else self._horner(self.d2, self._u(q))
        return -d2 * vs * vs  # p'' = 0 for locked joints

    def acceleration_error(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """``J a + gamma`` (..., k) [rad/s^2 or m/s^2]: the second derivative of ``r``."""
        return a[..., self.jv] - self.slopes(q) * a[..., self.sv] + self.drift(q, v)
