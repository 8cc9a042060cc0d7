"""What a simulation records: one dynamics evaluation, the preallocated recorder, the result."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from solvers.conditioning import SingularityEvent

__all__ = ["Evaluation", "ForwardResult", "Recorder"]


@dataclass
class Evaluation:
    """One dynamics evaluation: acceleration, actuator efforts, actuator and dissipated power."""

    a: np.ndarray
    tau: np.ndarray
    p_act: float
    p_fric: float


@dataclass
class ForwardResult:
    """Time series of a simulation, one row per recorded sample.

    Attributes:
        t: Times (N,) [s].
        q: Configurations (N, nq).
        v: Velocities (N, nv).
        a: Accelerations (N, nv) at the recorded states.
        tau: Actuator efforts (N, n_a) at the recorded states [N m or N].
        constraint_forces: Constraint multipliers ``lambda`` (N, n) at the recorded states
            [N, N m], in the convention of the inverse dynamics (see the module docstring):
            the closures' rows, then the couplings'.
        closure_residual: Largest closure residual component (N,) [m or rad].
        kinetic: Kinetic energy (N,) [J].
        potential: Gravitational potential energy (N,) [J].
        work: Actuator work done since the start (N,) [J], integrated with the step's
            quadrature (fifth order for ``dopri5``, fourth for ``rk4``, first for ``euler``).
        dissipated: Energy dissipated by the dampers and the friction since the start (N,) [J].
        projections: Number of output steps whose state was projected onto the closures.
        extras: Integrator statistics (``substeps``, ``rejected`` for ``dopri5``).
        elastic: Potential energy of the springs (N,) [J] (zeros without springs).
        energy_scale: A characteristic energy of the mechanism [J] (e.g. weight x size), the
            floor of :meth:`energy_drift`'s scale (0: none).
        coupling_residual: Largest coupling residual component (N,) [rad or m] (zeros
            without couplings).
        conditioning: Conditioning ``kappa`` of the closure forces (N,) at the recorded times
            (:mod:`solvers.conditioning`; 1 without rigid closures): checked every step near a
            singularity and at most ``CHECK_PERIOD`` (``ADAPTIVE_CHECK_PERIOD`` for ``dopri5``)
            steps apart elsewhere, interpolated linearly in time between the checks.
        events: Passages near or through singularities of the closures
            (:class:`~solvers.conditioning.SingularityEvent`), in time order.

    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    tau: np.ndarray
    constraint_forces: np.ndarray
    closure_residual: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    work: np.ndarray
    dissipated: np.ndarray
    projections: int = 0
    extras: dict[str, float] = field(default_factory=dict)
    elastic: np.ndarray | None = None
    energy_scale: float = 0.0
    coupling_residual: np.ndarray | None = None
    conditioning: np.ndarray | None = None
    events: list[SingularityEvent] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.elastic is None:
            self.elastic = np.zeros_like(self.kinetic)
        if self.coupling_residual is None:
            self.coupling_residual = np.zeros_like(self.kinetic)
        if self.conditioning is None:
            self.conditioning = np.ones_like(self.kinetic)

    @property
    def valid_until(self) -> float:
        """Time up to which the motion is the exact rigid one [s].

        The start of the first passage through a singularity (``through`` event): past it the
        closure force along the lost direction was let go, and the motion is the model's
        minimum-norm continuation (where the closures really lost rank, one of the branches
        the mechanism allows, the one rounding chose). The last recorded time when there is
        none.
        """
        for ev in self.events:
            if ev.through:
                return ev.start
        return float(self.t[-1]) if self.t.size else math.nan

    @property
    def energy(self) -> np.ndarray:
        """Mechanical energy ``kinetic + potential + elastic`` (N,) [J]."""
        assert self.elastic is not None
        return self.kinetic + self.potential + self.elastic

    def energy_drift(self, until: float | None = None) -> float:
        """Largest violation of the energy balance, relative to the energy exchanged.

        ``max |E(t) - E(0) - work(t) + dissipated(t)|`` divided by the largest of the kinetic
        energy, the actuator work and the dissipated energy along the run: for a passive
        undamped run, the relative drift of the mechanical energy (springs included). The
        potential energies are not used as the scale because their origin is arbitrary.

        Args:
            until: Only the samples up to this time [s] (e.g. :attr:`valid_until`; default:
                all of them).

        Returns:
            The relative drift (0 when nothing moves). Below ``1e-9 energy_scale`` of energy
            exchanged (a mechanism at rest), the scale is that floor: the round-off of a run
            that moves nothing is not reported as a drift of order one.

        """
        n = self.t.size if until is None else int(np.searchsorted(self.t, until, side="right"))
        n = max(n, 1)
        e = (self.energy - self.energy[0] - self.work + self.dissipated)[:n]
        scale = max(
            float(np.max(self.kinetic[:n])),
            float(np.max(np.abs(self.work[:n]))),
            float(np.max(self.dissipated[:n])),
            1e-9 * self.energy_scale,  # a run that exchanges no energy: round-off, not 100 %
        )
        return float(np.max(np.abs(e)) / scale) if scale > 0.0 else 0.0


class Recorder:
    """Preallocated storage of a :class:`ForwardResult`."""

    def __init__(self, n: int, nq: int, nv: int, na: int, nc: int) -> None:
        self.k = 0
        self.t = np.empty(n)
        self.q = np.empty((n, nq))
        self.v = np.empty((n, nv))
        self.a = np.empty((n, nv))
        self.tau = np.empty((n, na))
        self.lam = np.empty((n, nc))
        self.res = np.empty(n)
        self.res_k = np.zeros(n)
        self.ke = np.empty(n)
        self.pe = np.empty(n)
        self.work = np.empty(n)
        self.diss = np.empty(n)
        self.el = np.zeros(n)

    def add(
        self,
        fd: Any,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        ev: Evaluation,
        work: float,
        dissipated: float,
        residual: float | None = None,
    ) -> None:
        """Store one sample (``fd``: the :class:`~solvers.ForwardDynamics` recording).

        ``residual``: the largest constraint residual component at ``q`` when already known,
        with the kinematics of ``q`` in ``fd._kin`` (else computed here; always with couplings,
        whose residual is recorded apart).
        """
        k = self.k
        model, kin = fd.model, fd._kin
        self.t[k] = t
        self.q[k] = q
        self.v[k] = v
        self.a[k] = ev.a
        self.tau[k] = ev.tau
        if fd.nc:  # the residual runs the kinematics the force conversion needs
            cs = fd.constraints
            if residual is None or cs.nk:
                r = np.abs(cs.residual(kin, q))
                residual = float(np.max(r[: cs.nc], initial=0.0))
                self.res_k[k] = float(np.max(r[cs.nc :], initial=0.0))
            self.res[k] = residual
            self.lam[k] = fd.closure_forces(kin, fd.data.lambda_c)
        else:
            self.res[k] = 0.0
        self.ke[k] = fd.kinetic_energy(model, kin, q, v)
        self.pe[k] = pin.computePotentialEnergy(model, kin, q)
        if fd.passive is not None:
            self.el[k] = fd.passive.potential(q)
        self.work[k] = work
        self.diss[k] = dissipated
        self.k = k + 1

    def result(self) -> ForwardResult:
        """The samples recorded so far."""
        n = self.k
        return ForwardResult(
            self.t[:n],
            self.q[:n],
            self.v[:n],
            self.a[:n],
            self.tau[:n],
            self.lam[:n],
            self.res[:n],
            self.ke[:n],
            self.pe[:n],
            self.work[:n],
            self.diss[:n],
            elastic=self.el[:n],
            coupling_residual=self.res_k[:n],
        )
