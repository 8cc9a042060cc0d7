r"""Natural frequencies and mode shapes of any loaded robot about a static equilibrium.

The constrained dynamics linearised about an equilibrium ``q`` (no load, or a wrench and the
weight: the loaded mode's tangent stiffness): in the allowed motions ``u = N z`` of the
virtual-joint model (:mod:`pkdyn.precision.condensation`; independent coordinates of the
closures, the actuators and the links' deflections), small free vibrations obey

.. math::

    M_z \ddot z + K_z z = 0, \qquad M_z = N^T M(q) N, \quad K_z = N^T K_u N

with ``M(q)`` the joint-space mass matrix of the extended tree (Pinocchio's ``crba``, rotor
inertias included as the armature). The modes solve ``K_z x = omega^2 M_z x``; frequencies
``f = omega / (2 pi)`` [Hz], ascending. Directions without stiffness that leave the platform
still (the spin of a Delta's bars) have ``omega = 0``: they are reported as internal mobilities,
not as modes (the elastic modes are mass-orthogonal to them: they carry no spin momentum).
Directions without mass (a massless virtual link tip between two springs) are condensed out
statically (Guyan) before the eigenproblem. Mode shapes are mass-normalised (``x^T M_z x = 1``)
and given as joint motions (the robot's velocity coordinates), link deflections and platform
motions (reference point and rotation, world axes).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
import scipy.linalg

from pkdyn.exceptions import InvalidInputError, PkdynError, SingularConfigurationError
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.precision._format import chop
from pkdyn.precision.condensation import Reduced, compliance, negligible, reduce
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.equilibrium import loaded_equilibrium, reassembled, tangent_along
from pkdyn.precision.material import Material
from pkdyn.precision.stiffness import nothing_compliant, prepared
from pkdyn.precision.validity import Flagged, Validity, stiffness_check
from pkdyn.results import Result, deprecated, jsonable, renamed_keyword
from pkdyn.threads import one_blas_thread
from pkdyn.units import quantity
from solvers import numerics

__all__ = ["Modes", "mass_matrix", "mode_trajectory", "modes", "modes_json"]

_MASSLESS = 1e-12
"""Mass eigenvalues below this fraction of the largest are zero."""
_ZERO_FREQ = 1e-10
"""Eigenvalues ``omega^2`` below this fraction of the largest are internal mobilities."""


@dataclass(eq=False)  # numpy fields
class Modes(Flagged, Result):
    """Natural frequencies and mode shapes (see the module docstring).

    Attributes:
        q: Configuration (nq,) of the equilibrium (link deflections dropped).
        q_elastic: Extended configuration of the equilibrium (the elastic model's robot).
        frequencies: Natural frequencies (n,) [Hz], ascending (none when the robot is rigid).
        shapes: Mode shapes in the extended velocity coordinates (n, nv_ext), mass-normalised.
        joints: Joint motions of each mode (n, nv) (the robot's velocity coordinates).
        deflections: Each compliant link's deflection per mode (n, n_links, 6) [m, rad].
        platform: Platform motion per mode (n, 6): reference point [m], rotation [rad], world.
        internal: Internal mobilities without stiffness (not modes).
        condensed: Directions without mass condensed out statically.
        point: Reference point, platform frame [m].
        rigid: Every actuator rigid and nothing else compliant: no mode (infinite frequencies).
        validity: ``valid`` and ``warnings`` (:mod:`pkdyn.precision.validity`).
        robot: The robot's name.
        links: Names of the compliant links.
        top: Modes :meth:`to_json` and :meth:`table` report, the lowest first (``None``: all;
            ``count`` is its former name, kept for one release).
        elastic: The elastic model the modes were computed on (at their configuration).

    """

    q: np.ndarray
    q_elastic: np.ndarray
    frequencies: np.ndarray
    shapes: np.ndarray
    joints: np.ndarray
    deflections: np.ndarray
    platform: np.ndarray
    internal: int
    condensed: int
    point: np.ndarray
    rigid: bool = False
    validity: Validity = field(default_factory=Validity)
    robot: str = ""
    links: tuple[str, ...] = ()
    top: int | None = None
    elastic: ElasticModel | None = field(default=None, repr=False)

    @property
    def f1(self) -> float:
        """Lowest natural frequency [Hz] (``inf`` for a rigid robot)."""
        return float(self.frequencies[0]) if self.frequencies.size else float("inf")

    @property
    def count(self) -> int | None:
        """Deprecated: :attr:`top` (kept for one release)."""
        deprecated("Modes.count", "Modes.top")
        return self.top

    @count.setter
    def count(self, value: int | None) -> None:
        deprecated("Modes.count", "Modes.top")
        self.top = value

    def _shown(self, top: int | None) -> int:
        from pkdyn.inputs import count as whole

        n = self.frequencies.size
        c = self.top if top is None else whole("top", top, 1)
        return n if c is None else min(int(c), n)

    @renamed_keyword("count", "top")
    def to_json(self, top: int | None = None) -> dict[str, Any]:
        """JSON values: ``frequencies`` [Hz], ``platform`` motions, ``internal_mobilities``...

        Args:
            top: Report the lowest ``top`` modes (default: :attr:`top`, else all; ``count``:
                its former name, kept for one release).

        """
        n = self._shown(top)
        unit = np.linalg.norm(self.platform[:n], axis=1, keepdims=True)
        return {
            "robot": self.robot,
            "frequencies": jsonable(self.frequencies[:n]),
            "platform": jsonable(self.platform[:n] / np.maximum(unit, 1e-300)),
            "internal_mobilities": self.internal,
            "modes": int(self.frequencies.size),
            "point": jsonable(self.point),
            "rigid": self.rigid,
            **self.validity.to_json(),
            "links": list(self.links),
            "convention": "frequencies ascending [Hz]; platform: direction of each mode's "
            "platform motion [translation of the point, rotation], world axes, unit norm",
        }

    @renamed_keyword("count", "top")
    def table(self, top: int | None = None) -> str:
        """The frequencies with their units, what each mode moves, the flags.

        Args:
            top: Report the lowest ``top`` modes (default: :attr:`top`, else all; ``count``:
                its former name, kept for one release).

        """
        n = self._shown(top)
        lines = [f"natural frequencies of {self.robot or 'the robot'}"]
        if self.rigid:
            lines.append(
                "rigid: every actuator is held rigidly (inf) and nothing else is compliant: "
                "no vibration mode (infinite frequencies)"
            )
        L = self.elastic.base.length_scale if self.elastic is not None else 1.0
        for k in range(n):
            P = chop(self.platform[k], float(np.abs(self.platform[k]).max()) / L)
            lines.append(
                f"  mode {k + 1}: {quantity(self.frequencies[k], 'Hz')}, platform moves "
                f"{quantity(float(np.linalg.norm(P[:3])), 'm')} and turns "
                f"{quantity(float(np.linalg.norm(P[3:])), 'rad')} per unit modal amplitude"
            )
        if n < self.frequencies.size:
            lines.append(f"  ({self.frequencies.size - n} more modes up to "
                         f"{quantity(self.frequencies[-1], 'Hz')})")  # fmt: skip
        if self.internal:
            lines.append(f"internal mobilities without stiffness (not modes): {self.internal}")
        if self.links:
            lines.append(f"compliant links: {', '.join(self.links)}")
        return "\n".join(lines + self.validity.lines())


def mass_matrix(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Joint-space mass matrix (nv, nv) at ``q``, symmetric, rotor inertias included."""
    M = np.array(pin.crba(robot.model, robot.data, q))
    return np.triu(M) + np.triu(M, 1).T


def _eigen(red: Reduced, M: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """``(omega^2, z shapes (nz, n), condensed)``, internal mobilities included first."""
    N, Kz = red.N, red.Kz
    Mz = N.T @ M @ N
    Mz = 0.5 * (Mz + Mz.T)
    Ks = 0.5 * (Kz + Kz.T)
    mu, W = np.linalg.eigh(Mz)
    massless = negligible(mu, _MASSLESS)
    if not massless.any():
        lam, X = scipy.linalg.eigh(Ks, Mz)
        return lam, X, 0
    P, Q = W[:, ~massless], W[:, massless]
    Kpp, Kpq, Kqq = P.T @ Ks @ P, P.T @ Ks @ Q, Q.T @ Ks @ Q
    G = numerics.lstsq(Kqq, np.eye(Kqq.shape[0]), 1e-12)  # (massless and free: dropped)
    Kc = Kpp - Kpq @ G @ Kpq.T
    lam, Xp = scipy.linalg.eigh(0.5 * (Kc + Kc.T), np.diag(mu[~massless]))
    X = P @ Xp - Q @ (G @ Kpq.T @ Xp)
    return lam, X, int(massless.sum())


@one_blas_thread
@public
def modes(
    robot: Robot | ElasticModel,
    q: Sequence[float] | np.ndarray,
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    *,
    material: str | Material | None = None,
    links: bool = True,
    point: Sequence[float] | np.ndarray | None = None,
    wrench: Sequence[float] | np.ndarray | None = None,
    gravity: bool = False,
    shear: bool = True,
) -> Modes:
    """Natural frequencies [Hz] and mode shapes of a robot about an equilibrium.

    Args:
        robot: The robot (with its geometry when links are beams), or an
            :class:`~pkdyn.precision.elastic.ElasticModel`.
        q: Assembled configuration (nq,): the equilibrium without load (actuators at their
            commanded positions).
        actuator_stiffness: Joint-side stiffness, one or one per actuator [N m/rad or N/m];
            ``None``: the description's ``<pkdyn:stiffness>``.
        material: Material of the slender links; ``None``: the description's, if any.
        links: Model the links' compliance.
        point: Reference point of the platform motions, platform frame [m].
        wrench: A static wrench on the platform (6, world axes, moment about the point): the
            vibrations are about the loaded equilibrium, geometric terms included.
        gravity: The weight is part of the load (equilibrium and geometric terms).
        shear: Include the beams' shear deflection (Timoshenko; ``False``: Euler-Bernoulli).

    Returns:
        The modes.

    Raises:
        InvalidInputError: Bad stiffness, material, point or wrench, or ``q`` not assembled.
        SingularConfigurationError: A motion without stiffness moves the platform.
        PkdynError: No elastic mode at all.

    """
    from pkdyn.inputs import flag

    gravity = flag("gravity", gravity)
    em, qq, p, w = prepared(robot, q, actuator_stiffness, material, links, shear, point, wrench)
    base = em.base
    q_ext = em.embed(qq)
    if nothing_compliant(em):
        return _rigid_modes(em, qq, q_ext, p)
    if w is None and not gravity:
        red = reduce(em, q_ext, p)
    else:
        load = np.zeros(6) if w is None else w
        eq = loaded_equilibrium(em, q_ext, p, load, gravity)
        qa_rest = np.array(q_ext[np.asarray(em.robot.actuated_q)])
        q_ext = eq.q

        def tangent(N: np.ndarray) -> np.ndarray:
            return tangent_along(em, eq.q, eq.lambdas, qa_rest, p, load, gravity, N)

        red = reduce(em, q_ext, p, tangent)
    C6, internal = compliance(em, red)  # raises when the platform moves without stiffness
    validity = _validity(em, red, C6, qq, p)
    lam, X, condensed = _eigen(red, mass_matrix(em.robot, q_ext))
    elastic = ~negligible(lam, max(_ZERO_FREQ, red.free_tol)) & (lam > 0.0)
    if not elastic.any():
        raise PkdynError(f"{base.name}: no spring resists any motion: there is no elastic mode")
    lam, X = lam[elastic], X[:, elastic]
    free = int((~elastic).sum())
    U = (red.N @ X).T  # (n, nv_ext)
    validity.warn(stacklevel=3)
    return Modes(
        q=em.restrict(q_ext),
        q_elastic=q_ext,
        frequencies=np.sqrt(lam) / (2.0 * np.pi),
        shapes=U,
        joints=U[:, em.v_index],
        deflections=U[:, em.deflection_v] if em.links else np.zeros((U.shape[0], 0, 6)),
        platform=(red.Jz @ X).T,
        internal=max(internal, free),
        condensed=condensed,
        point=p,
        validity=validity,
        robot=base.name,
        links=tuple(dict.fromkeys(lc.link for lc in em.links)),
        elastic=em,
    )


def _validity(
    em: ElasticModel, red: Reduced, C6: np.ndarray, q: np.ndarray, point: np.ndarray
) -> Validity:
    """Not valid where the stiffness is unbounded: the platform does not move in the modes."""
    try:
        validity, _, _ = stiffness_check(em, red.q, point, C6, q)
    except SingularConfigurationError as err:
        return Validity(
            False,
            (
                f"{err}; the modes are the mechanism's own, the platform does not move in them "
                "to first order",
            ),
        )
    return validity


def _rigid_modes(em: ElasticModel, q: np.ndarray, q_ext: np.ndarray, point: np.ndarray) -> Modes:
    """No mode: every actuator rigid and nothing compliant (the platform must not move)."""
    compliance(em, reduce(em, q_ext, point))  # (a parallel singularity is still refused)
    nv = em.robot.nv
    return Modes(
        q=q,
        q_elastic=q_ext,
        frequencies=np.zeros(0),
        shapes=np.zeros((0, nv)),
        joints=np.zeros((0, em.base.nv)),
        deflections=np.zeros((0, len(em.links), 6)),
        platform=np.zeros((0, 6)),
        internal=0,
        condensed=0,
        point=point,
        rigid=True,
        robot=em.base.name,
        elastic=em,
    )


@renamed_keyword("count", "top")
def modes_json(robot: Robot, q: np.ndarray, top: int | None = None, **kwargs: Any) -> dict:
    """JSON-ready :func:`modes` (keys of :meth:`Modes.to_json`; ``top``: the lowest shown)."""
    return modes(robot, q, **kwargs).to_json(top)


def mode_trajectory(
    em: ElasticModel,
    result: Modes,
    index: int = 0,
    amplitude: float | None = None,
    period: float = 2.0,
    cycles: int = 2,
    samples: int = 48,
) -> tuple[np.ndarray, np.ndarray]:
    """A mode played slowly, for display: ``q(t) = q ⊕ a sin(2 pi t / period) u``, assembled.

    Args:
        em: The elastic model the modes were computed on.
        result: The modes.
        index: Mode number, 0 = lowest frequency.
        amplitude: Largest displacement of a joint origin or of the platform point [m]
            (default: 5 % of the robot's size).
        period: Displayed period [s] (the real one is ``1 / frequency``).
        cycles: Number of periods.
        samples: Samples per period.

    Returns:
        ``(t, Q)``: times (N,) [s] and configurations of ``em.robot`` (N, nq_ext).

    Raises:
        InvalidInputError: No such mode, or a non-positive amplitude, period or count.

    """
    from pkdyn.inputs import count, instance, positive

    instance("em", em, ElasticModel, "an ElasticModel (pkdyn.precision.elastic_model)")
    instance("result", result, Modes, "Modes (pkdyn.precision.modes)")
    n = result.frequencies.size
    index = count("index", index, 0)
    if not index < n:
        raise InvalidInputError("mode", f"{index + 1} is not a mode number: 1 to {n}")
    period = positive("period", period, "s")
    cycles = count("cycles", cycles, 1, 1000)
    samples = count("samples", samples, 2, 10_000)
    if amplitude is not None:
        amplitude = positive("amplitude", amplitude, "m")
    if result.elastic is not None and result.elastic.robot.nq == em.robot.nq:
        em = result.elastic  # (the model at the modes' configuration)
    r = em.robot
    q0 = result.q_elastic
    u = result.shapes[index]
    size = _largest_motion(r, q0, u)
    a = (0.05 * r.length_scale if amplitude is None else float(amplitude)) / max(size, 1e-300)
    if not (np.isfinite(a) and a > 0.0):
        raise InvalidInputError("amplitude", f"must be > 0 m, got {amplitude}")
    t = np.linspace(0.0, cycles * period, int(cycles * samples) + 1)
    Q = np.empty((t.size, r.nq))
    for i, ti in enumerate(t):
        qi = pin.integrate(r.model, q0, a * np.sin(2.0 * np.pi * ti / period) * u)
        if r.constraints.n:
            qi = reassembled(em, qi).q
        Q[i] = qi
    return t, Q


def _largest_motion(robot: Robot, q: np.ndarray, u: np.ndarray) -> float:
    """Largest displacement [m] of a joint origin or the platform frame per unit of ``u``."""
    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, q)
    before = [M.translation.copy() for M in data.oMi] + [
        data.oMf[robot.platform_frame].translation.copy() if robot.platform_frame else np.zeros(3)
    ]
    h = 1e-6
    pin.framesForwardKinematics(model, data, pin.integrate(model, q, h * u))
    after = [M.translation for M in data.oMi] + [
        data.oMf[robot.platform_frame].translation if robot.platform_frame else np.zeros(3)
    ]
    return max(float(np.linalg.norm(b - a)) for a, b in zip(before, after, strict=True)) / h
