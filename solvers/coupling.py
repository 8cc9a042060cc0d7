"""Holonomic couplings between 1-DoF joint coordinates: linear sums, gears, cam laws, mimics.

Two kinds of coupling, one row each, evaluated by one row evaluator (:class:`CouplingRows`):

- :class:`LinearCoupling`: a linear relation over any number of joints,
  ``r = sum_i a_i x_i - b`` (sums and differences of joint coordinates along paths with ratios
  and an offset: a rotor geared to the sum of a knee and an ankle angle, a differential);
- :class:`JointCoupling`: a driven joint ``x_j`` tied to a source ``x_s`` by a polynomial
  (MuJoCo's ``polycoef``, a URDF mimic, a gear pair, a cam law),
  ``r = (x_j - x_j0) - p(x_s - x_s0),   p(u) = sum_k c_k u^k`` (1 to 5 coefficients), or,
  without a source, ``x_j`` held at ``x_j0 + c_0`` (a locked joint).

Both are the general row ``r = sum_i a_i x_i - b - p(u)``, ``u = x_s - x_s0`` (``p = 0`` for a
linear coupling; ``a = 1`` at the driven joint and ``b = x_j0`` for a polynomial one). ``x`` is the
joint's coordinate [rad or m]: ``q[idx_q]`` for a revolute or prismatic joint, the angle
``atan2(q[idx_q + 1], q[idx_q])`` of an unbounded revolute joint (Pinocchio's cos/sin pair). An
angle is defined modulo one turn, so the residual is wrapped to ``[-T/2, T/2)`` with the period
``T = 2 pi g`` it has: for a polynomial coupling whose driven joint is circular ``g = 1``; for a
linear coupling whose circular joints' coefficients are integer multiples of the smallest of
them, ``g`` is that smallest coefficient (in absolute value); otherwise the residual is not
wrapped (it is then defined on the angles' range ``(-pi, pi]``).

Derivatives with respect to a velocity increment (``pin.integrate``), exact:

- Jacobian row: ``a_i`` at each term's velocity index, ``-p'(u)`` at the source's;
- acceleration drift (``d^2 r/dt^2 = J a + gamma``): ``gamma = -p''(u) v_s^2``.

The multiplier ``mu`` of a coupling row (``J^T mu`` in the dynamics) is a generalized force
[N m or N]: joint ``i`` receives ``a_i mu`` (the driven joint of a polynomial coupling ``mu``), the
source ``-p'(u) mu``.

:class:`CouplingRows` evaluates a set of couplings at once, on one state or on a batch of
states (leading axes), with numpy. Robot-agnostic: joints are Pinocchio joint ids.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

__all__ = ["MAX_COEFFICIENTS", "Coupling", "CouplingRows", "JointCoupling", "LinearCoupling"]

MAX_COEFFICIENTS = 5
"""Largest number of polynomial coefficients (MuJoCo's ``polycoef``: degree 4)."""

_INTEGER_TOL = 1e-12
"""Relative tolerance of "an integer multiple" in the wrapping period of a linear coupling."""


@dataclass(frozen=True)
class JointCoupling:
    """One polynomial coupling (see the module docstring).

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


@dataclass(frozen=True)
class LinearCoupling:
    """One linear coupling ``sum_i a_i x_i = offset`` (see the module docstring).

    Attributes:
        name: Name, for messages and reports.
        terms: ``(joint id, coefficient a_i)`` pairs: 1-DoF joints, each once, non-zero
            coefficients [rad or m per rad or m of the row].
        offset: ``b`` [rad or m].

    """

    name: str
    terms: tuple[tuple[int, float], ...]
    offset: float = 0.0


Coupling = JointCoupling | LinearCoupling
"""Either kind of coupling."""


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


def _period(coefs: Sequence[float]) -> float:
    """Wrapping period ``2 pi g`` of a linear row whose circular joints have ``coefs``, or 0."""
    if not coefs:
        return 0.0
    g = min(abs(c) for c in coefs)
    for c in coefs:
        ratio = abs(c) / g
        if abs(ratio - round(ratio)) > _INTEGER_TOL * ratio:
            return 0.0
    return 2.0 * math.pi * g


@dataclass(frozen=True)
class _Row:
    """One coupling in the general form (module docstring), joints resolved to indices."""

    terms: tuple[tuple[int, int, bool, float], ...]  # (idx_q, idx_v, circular, a_i)
    source: tuple[int, int, bool] | None  # (idx_q, idx_v, circular)
    coefficients: tuple[float, ...]  # of p, constant first ((0,) without polynomial)
    b: float
    source_ref: float
    period: float


def _row(model: pin.Model, c: Coupling) -> _Row:
    """The general row of a coupling, checked (``ValueError`` naming the coupling)."""
    if isinstance(c, LinearCoupling):
        if not c.terms:
            raise ValueError(f"coupling {c.name!r}: no terms")
        seen: set[int] = set()
        terms = []
        for jid, a in c.terms:
            if int(jid) in seen:
                raise ValueError(f"coupling {c.name!r}: joint id {jid} appears twice")
            seen.add(int(jid))
            a = float(a)
            if not math.isfinite(a) or a == 0.0:
                raise ValueError(
                    f"coupling {c.name!r}: coefficient {a!r} of joint id {jid}; give a finite "
                    "non-zero number"
                )
            terms.append((*_index(model, int(jid), c.name), a))
        if not math.isfinite(float(c.offset)):
            raise ValueError(f"coupling {c.name!r}: the offset must be finite")
        period = _period([a for _, _, circ, a in terms if circ])
        return _Row(tuple(terms), None, (0.0,), float(c.offset), 0.0, period)
    n = len(c.coefficients)
    if not 1 <= n <= MAX_COEFFICIENTS:
        raise ValueError(f"coupling {c.name!r}: {n} coefficients; give 1 to {MAX_COEFFICIENTS}")
    values = (*c.coefficients, c.joint_ref, c.source_ref)
    if not all(math.isfinite(float(x)) for x in values):
        raise ValueError(f"coupling {c.name!r}: coefficients and references must be finite")
    jq, jv, jc = _index(model, int(c.joint), c.name)
    source = None
    coef: tuple[float, ...] = (float(c.coefficients[0]),)  # a locked joint: the constant only
    if c.source is not None:
        if int(c.source) == int(c.joint):
            raise ValueError(f"coupling {c.name!r}: a joint cannot drive itself")
        source = _index(model, int(c.source), c.name)
        coef = tuple(float(x) for x in c.coefficients)
    return _Row(
        ((jq, jv, jc, 1.0),),
        source,
        coef,
        float(c.joint_ref),
        float(c.source_ref),
        2.0 * math.pi if jc else 0.0,
    )


class CouplingRows:
    """Residuals, Jacobian rows and drifts of couplings on a Pinocchio model.

    Args:
        model: The kinematic tree.
        couplings: The couplings (:class:`LinearCoupling` or :class:`JointCoupling`).

    Raises:
        ValueError: A joint that is not 1-DoF or appears twice in a coupling, a coupling of a
            joint to itself, no terms, a zero coefficient, no or too many polynomial
            coefficients, or non-finite numbers.

    """

    def __init__(self, model: pin.Model, couplings: Sequence[Coupling]) -> None:
        self.couplings = tuple(couplings)
        self.nv = int(model.nv)
        rows = [_row(model, c) for c in self.couplings]
        k = len(rows)
        self.n = k
        self.names = [c.name for c in self.couplings]
        width = max((len(r.terms) for r in rows), default=1)
        # terms, padded with coefficient 0 on coordinate 0
        self.tq = np.zeros((k, width), dtype=int)
        self.tv = np.zeros((k, width), dtype=int)
        self.tcirc = np.zeros((k, width), dtype=bool)
        self.ta = np.zeros((k, width))
        entries = [(i, t[1], t[3]) for i, r in enumerate(rows) for t in r.terms]
        self._term_rows = np.array([e[0] for e in entries], dtype=int)
        self._term_cols = np.array([e[1] for e in entries], dtype=int)
        self._term_coef = np.array([e[2] for e in entries], dtype=float)
        self.sq = np.zeros(k, dtype=int)
        self.sv = np.zeros(k, dtype=int)
        self.scirc = np.zeros(k, dtype=bool)
        self.has_source = np.zeros(k, dtype=bool)
        self.coef = np.zeros((k, MAX_COEFFICIENTS))
        self.b = np.array([r.b for r in rows], dtype=float)
        self.sref = np.array([r.source_ref for r in rows], dtype=float)
        self.period = np.array([r.period for r in rows], dtype=float)
        for i, r in enumerate(rows):
            for t, (iq, iv, circ, a) in enumerate(r.terms):
                self.tq[i, t], self.tv[i, t], self.tcirc[i, t], self.ta[i, t] = iq, iv, circ, a
            if r.source is not None:
                self.sq[i], self.sv[i], self.scirc[i] = r.source
                self.has_source[i] = True
            self.coef[i, : len(r.coefficients)] = r.coefficients
        # the highest degree in use (trailing zero columns cost Horner steps for nothing)
        used = np.flatnonzero(np.any(self.coef != 0.0, axis=0))
        self.coef = self.coef[:, : max(2, int(used[-1]) + 1 if used.size else 2)]
        # derivative coefficients: p' and p''
        powers = np.arange(1, self.coef.shape[1])
        self.d1 = self.coef[:, 1:] * powers
        self.d2 = self.d1[:, 1:] * powers[:-1] if self.coef.shape[1] > 2 else np.zeros((k, 1))
        self.rows = np.arange(k)
        self._src_rows = np.flatnonzero(self.has_source)
        self._src_cols = self.sv[self._src_rows]
        self.tcirc_any = bool(self.tcirc.any())
        self.scirc_any = bool(self.scirc.any())
        self.all_sourced = bool(self.has_source.all())
        self.wrapped = bool(np.any(self.period > 0.0))
        # no source: the rows are constant (no drift, a constant Jacobian)
        self.constant = not bool(self.has_source.any())
        # no source and no circular joint: the residual of one state is ``A_q q - b - p(0)``
        self._Aq: np.ndarray | None = None
        self._b0 = self.b + self.coef[:, 0]  # b + p(0): a locked joint's constant included
        if self.constant and not self.tcirc_any and k:
            self._Aq = np.zeros((k, int(model.nq)))
            for i, r in enumerate(rows):
                for iq, _, _, a in r.terms:
                    self._Aq[i, iq] += a
        # one state at a time: plain floats (numpy's per-call overhead dominates small rows)
        self._scalar = [
            (
                [(iq, circ, a) for iq, _, circ, a in r.terms],
                r.source is not None,
                r.source[0] if r.source is not None else 0,
                r.source[2] if r.source is not None else False,
                self.coef[i].tolist()[::-1],
                self.d1[i].tolist()[::-1],
                self.d2[i].tolist()[::-1],
                r.b,
                r.source_ref,
                r.period,
            )
            for i, r in enumerate(rows)
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
        """Residuals (0), slopes ``p'`` (1) or ``p''`` (2) at one configuration, with floats."""
        out = np.empty(self.n)
        qs = q.tolist()
        atan2 = math.atan2
        for i, (terms, src, sq, sc, c0, c1, c2, b, sref, period) in enumerate(self._scalar):
            u = 0.0
            if src:
                u = (atan2(qs[sq + 1], qs[sq]) if sc else qs[sq]) - sref
            p = 0.0
            for ck in (c0, c1, c2)[what]:
                p = p * u + ck
            if what:
                out[i] = p
                continue
            r = -b - p
            for iq, circ, a in terms:
                r += a * (atan2(qs[iq + 1], qs[iq]) if circ else qs[iq])
            out[i] = ((r + 0.5 * period) % period) - 0.5 * period if period else r
        return out

    def _u(self, q: np.ndarray) -> np.ndarray:
        """Source displacement ``x_s - x_s0`` (..., k) (0 without a source)."""
        u = self._coordinate(q, self.sq, self.scirc, self.scirc_any) - self.sref
        return u if self.all_sourced else np.where(self.has_source, u, 0.0)

    def residual(self, q: np.ndarray) -> np.ndarray:
        """Residuals ``r`` (..., k) [rad or m] of configurations ``q`` (..., nq)."""
        if q.ndim == 1:
            if self._Aq is not None:  # (no wrapping: periods come from circular joints)
                return self._Aq.dot(q) - self._b0
            return self._one(q, 0)
        x = self._coordinate(q, self.tq, self.tcirc, self.tcirc_any)  # (..., k, width)
        r = np.einsum("...kt,kt->...k", x, self.ta) - self.b - self._horner(self.coef, self._u(q))
        if self.wrapped:
            T = self.period
            wrapped = np.remainder(r + 0.5 * T, np.where(T > 0.0, T, 1.0)) - 0.5 * T
            r = np.where(T > 0.0, wrapped, r)
        return r

    def slopes(self, q: np.ndarray) -> np.ndarray:
        """``p'(u)`` (..., k): the source's Jacobian entry is ``-p'(u)`` (0 without source)."""
        if q.ndim == 1:
            return self._one(q, 1)
        return self._horner(self.d1, self._u(q))

    def jacobian(self, q: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Jacobian rows (k, nv) at one configuration ``q`` (nq,), or (..., k, nv) of a batch.

        Args:
            q: Configuration (nq,) or configurations (..., nq).
            out: Array (k, nv) or (..., k, nv) to fill, zero but for the entries of earlier
                calls (default: a new one).

        Returns:
            The rows.

        """
        if out is None:
            out = np.zeros((*q.shape[:-1], self.n, self.nv))
        out[..., self._term_rows, self._term_cols] = self._term_coef
        if self._src_rows.size:
            s = self.slopes(q)
            out[..., self._src_rows, self._src_cols] = -s[..., self._src_rows]
        return out

    def velocity_error(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``J v`` (..., k) [rad/s or m/s] of states ``(q, v)`` with leading axes."""
        return (
            np.einsum("...kt,kt->...k", v[..., self.tv], self.ta) - self.slopes(q) * v[..., self.sv]
        )

    def drift(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Acceleration drift ``gamma = -p''(u) v_s^2`` (..., k) [rad/s^2 or m/s^2]."""
        if self.constant:
            return np.zeros((*v.shape[:-1], self.n))
        vs = v[..., self.sv]
        d2 = self._one(q, 2) if q.ndim == 1 else self._horner(self.d2, self._u(q))
        return -d2 * vs * vs  # p'' = 0 without a source

    def acceleration_error(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """``J a + gamma`` (..., k) [rad/s^2 or m/s^2]: the second derivative of ``r``."""
        return self.velocity_error(q, a) + self.drift(q, v)

    def joints(self, i: int) -> list[int]:
        """Velocity indices of the joints coupling ``i`` relates (terms, then the source)."""
        cols = [int(c) for c, a in zip(self.tv[i], self.ta[i], strict=True) if a != 0.0]
        return cols + ([int(self.sv[i])] if self.has_source[i] else [])
