"""Actuation selection and the drive model (motor, gearbox) of the actuators.

Joint friction, dampers and springs are :mod:`solvers.passive`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["Actuation", "Drives", "TorqueFn"]

TorqueFn = Callable[[float, np.ndarray, np.ndarray], np.ndarray]
"""Actuator efforts ``tau(t [s], q (nq,), v (nv,)) -> (n_a,)`` [N m or N]."""


class Actuation:
    """Actuated velocity coordinates and their transmission gains.

    The generalized force of actuator efforts ``tau`` (n_a,) is ``S^T tau`` with
    ``S[i, v_index[i]] = gains[i]``: ``gains`` are reductions when ``tau`` is a motor-side
    effort, ones (default) when ``tau`` is the joint-side effort.

    Args:
        v_index: Velocity index of each actuator (n_a,), distinct.
        gains: Transmission gain of each actuator (n_a,) (default: ones).
        names: Actuator names, for error messages (default ``a0, a1, ...``).

    Raises:
        ValueError: Repeated or negative indices, or sizes that do not match.

    """

    def __init__(
        self,
        v_index: Sequence[int] | np.ndarray,
        gains: Sequence[float] | np.ndarray | None = None,
        names: Sequence[str] | None = None,
    ) -> None:
        self.v_index = np.asarray(v_index, dtype=int).reshape(-1)
        n = self.v_index.size
        if np.unique(self.v_index).size != n or np.any(self.v_index < 0):
            raise ValueError(
                f"actuated velocity indices must be distinct and >= 0: {self.v_index.tolist()}"
            )
        self.gains = np.ones(n) if gains is None else np.asarray(gains, dtype=float).reshape(-1)
        if self.gains.size != n:
            raise ValueError(f"{self.gains.size} gains for {n} actuators")
        self.names = [f"a{i}" for i in range(n)] if names is None else list(names)
        if len(self.names) != n:
            raise ValueError(f"{len(self.names)} names for {n} actuators")

    @property
    def n(self) -> int:
        """Number of actuators."""
        return int(self.v_index.size)

    def matrix(self, nv: int) -> np.ndarray:
        """Selection matrix ``S`` (n_a, nv): the generalized force is ``S^T tau``.

        Args:
            nv: Size of the velocity vector.

        Returns:
            ``S``.

        """
        S = np.zeros((self.n, nv))
        S[np.arange(self.n), self.v_index] = self.gains
        return S

    def generalized(self, tau: np.ndarray, nv: int) -> np.ndarray:
        """Generalized force ``S^T tau`` (nv,) [N m or N] of actuator efforts ``tau`` (n_a,)."""
        out = np.zeros(nv)
        out[self.v_index] = self.gains * tau
        return out

    def velocity(self, v: np.ndarray) -> np.ndarray:
        """Actuator-side velocities ``S v`` (n_a,) conjugate to ``tau`` [rad/s or m/s]."""
        return self.gains * v[self.v_index]


def _per_actuator(x: float | Sequence[float] | np.ndarray, n: int, what: str) -> np.ndarray:
    out = np.array(np.broadcast_to(np.asarray(x, dtype=float), (n,)))
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{what} must be finite, got {out.tolist()}")
    return out


class Drives:
    r"""Motor and gearbox of each actuator: reduction, rotor inertia, efficiency, motor friction.

    Per actuator, with the motor speed ``omega = N qd`` (``N`` the reduction, ``qd`` the joint
    rate) and the motor torque ``tau_m``:

    .. math::

        \tau_{in} = \tau_m - f(\omega), \qquad f(\omega) = b\,\omega + c \tanh(\omega / \omega_s)

        \tau_j = N \kappa \tau_{in}, \qquad
        \kappa = \eta^{w} / \eta_b^{1 - w}, \qquad
        w = \tfrac12 \left(1 + \tanh(\operatorname{sign}(\tau_{in})\, \omega / \omega_s)\right)

    ``tau_j`` is the joint-side effort that enters the dynamics (``S^T tau_j``), ``f`` the motor's
    viscous and Coulomb friction [N m], ``eta`` the gearbox efficiency when the motor drives
    (power flows to the joint: ``kappa = eta``) and ``eta_b`` when the joint drives the motor
    (``kappa = 1 / eta_b``: the gearbox's losses then help the motor brake); ``w`` blends the two
    smoothly over ``|omega| < omega_s`` (at rest with ``eta = eta_b`` the gearbox transmits the
    torque without loss). ``tau_j`` is continuous in ``tau_m`` and ``omega`` and the map is
    inverted exactly by :meth:`motor_effort` (``sign(tau_in) = sign(tau_j)``).

    The rotor inertia ``J`` (rotor plus gearbox input, motor side) is reflected on the joint as
    the armature ``N^2 J`` of the actuated velocity coordinate (``pin.Model.armature``, used by
    ``rnea``, ``crba``, ``aba``, ``constraintDynamics`` and the kinetic energy): the rotor's
    inertia torque is lumped on the joint side, so the gearbox efficiency applies to it too
    (exact for ``eta = 1``; with losses it counts the rotor torque ``N J omega_dot`` as
    ``N J omega_dot / eta`` when driving, the conservative side for sizing). Inverse and forward
    dynamics use the same model, so they invert each other exactly.

    Power balance per actuator: ``tau_m omega = f(omega) omega + (1 - kappa) tau_in omega +
    tau_j qd`` (motor power = friction loss + gearbox loss + power delivered to the joint);
    both losses are >= 0 outside the smoothing band (and the gearbox loss everywhere when
    ``eta = eta_b``).

    For a prismatic actuator ``N`` is in rad/m (a screw: ``2 pi / lead``), ``J N^2`` in kg.

    Args:
        reduction: Reductions ``N`` (n_a,) (motor speed / joint speed), non-zero.
        rotor_inertia: Motor-side rotor inertias ``J`` (n_a,) [kg m^2] (default 0), >= 0.
        efficiency: Driving efficiencies ``eta`` (n_a,) in (0, 1] (default 1).
        backdrive_efficiency: Back-driven efficiencies ``eta_b`` (n_a,) in (0, 1]
            (default: ``efficiency``).
        viscous: Motor viscous friction ``b`` (n_a,) [N m s/rad] (default 0), >= 0.
        coulomb: Motor Coulomb friction ``c`` (n_a,) [N m] (default 0), >= 0.
        smoothing: Motor speed ``omega_s`` of the smooth sign and efficiency blend [rad/s].

    Raises:
        ValueError: Values out of range or sizes that do not match.

    """

    def __init__(
        self,
        reduction: Sequence[float] | np.ndarray,
        rotor_inertia: float | Sequence[float] | np.ndarray = 0.0,
        efficiency: float | Sequence[float] | np.ndarray = 1.0,
        backdrive_efficiency: float | Sequence[float] | np.ndarray | None = None,
        viscous: float | Sequence[float] | np.ndarray = 0.0,
        coulomb: float | Sequence[float] | np.ndarray = 0.0,
        smoothing: float = 0.1,
    ) -> None:
        N = np.asarray(reduction, dtype=float).reshape(-1)
        n = N.size
        self.reduction = _per_actuator(N, n, "reductions")
        if np.any(self.reduction == 0.0):
            raise ValueError(f"reductions must be non-zero, got {self.reduction.tolist()}")
        self.rotor_inertia = _per_actuator(rotor_inertia, n, "rotor inertias")
        self.efficiency = _per_actuator(efficiency, n, "efficiencies")
        eta_b = efficiency if backdrive_efficiency is None else backdrive_efficiency
        self.backdrive_efficiency = _per_actuator(eta_b, n, "back-driven efficiencies")
        self.viscous = _per_actuator(viscous, n, "viscous friction")
        self.coulomb = _per_actuator(coulomb, n, "Coulomb friction")
        for what, arr in (
            ("rotor inertias", self.rotor_inertia),
            ("viscous friction", self.viscous),
            ("Coulomb friction", self.coulomb),
        ):
            if np.any(arr < 0.0):
                raise ValueError(f"{what} must be >= 0, got {arr.tolist()}")
        for what, arr in (
            ("efficiencies", self.efficiency),
            ("back-driven efficiencies", self.backdrive_efficiency),
        ):
            if np.any((arr <= 0.0) | (arr > 1.0)):
                raise ValueError(f"{what} must lie in (0, 1], got {arr.tolist()}")
        if not smoothing > 0.0:
            raise ValueError(f"smoothing speed must be > 0, got {smoothing}")
        self.smoothing = float(smoothing)
        self._log_eta = np.log(self.efficiency)
        self._log_eta_b = np.log(self.backdrive_efficiency)

    @property
    def n(self) -> int:
        """Number of actuators."""
        return int(self.reduction.size)

    @property
    def armature(self) -> np.ndarray:
        """Reflected rotor inertias ``N^2 J`` (n_a,) [kg m^2 or kg], joint side."""
        return self.reduction**2 * self.rotor_inertia

    @property
    def lossless(self) -> bool:
        """Efficiencies of 1 and no motor friction: ``tau_j = N tau_m``."""
        return bool(
            np.all(self.efficiency == 1.0)
            and np.all(self.backdrive_efficiency == 1.0)
            and not np.any(self.viscous)
            and not np.any(self.coulomb)
        )

    def motor_speed(self, qd: np.ndarray) -> np.ndarray:
        """Motor speeds ``N qd`` (..., n_a) [rad/s] of joint rates ``qd`` (..., n_a)."""
        return self.reduction * np.asarray(qd, dtype=float)

    def friction(self, omega: np.ndarray) -> np.ndarray:
        """Motor friction torque ``f(omega)`` (..., n_a) [N m] at motor speeds ``omega``."""
        return self.viscous * omega + self.coulomb * np.tanh(omega / self.smoothing)

    def transmission_factor(self, sign: np.ndarray, omega: np.ndarray) -> np.ndarray:
        """``kappa`` (..., n_a) for the sign of the transmitted torque and the motor speed."""
        w = 0.5 * (1.0 + np.tanh(np.sign(sign) * omega / self.smoothing))
        return np.exp(w * self._log_eta - (1.0 - w) * self._log_eta_b)

    def joint_effort(self, tau_m: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Joint-side efforts ``tau_j`` (..., n_a) of motor torques ``tau_m`` at joint rates ``qd``.

        Args:
            tau_m: Motor torques (..., n_a) [N m].
            qd: Joint rates (..., n_a) [rad/s or m/s].

        Returns:
            ``N kappa (tau_m - f(N qd))`` [N m or N].

        """
        omega = self.motor_speed(qd)
        tau_in = np.asarray(tau_m, dtype=float) - self.friction(omega)
        return self.reduction * self.transmission_factor(tau_in, omega) * tau_in

    def motor_effort(self, tau_j: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Motor torques (..., n_a) [N m] producing joint-side efforts ``tau_j`` (exact inverse).

        Args:
            tau_j: Joint-side efforts (..., n_a) [N m or N] (inverse dynamics, armature
                included).
            qd: Joint rates (..., n_a) [rad/s or m/s].

        Returns:
            ``f(N qd) + tau_j / (N kappa)``.

        """
        tau_j = np.asarray(tau_j, dtype=float)
        omega = self.motor_speed(qd)
        kappa = self.transmission_factor(tau_j * self.reduction, omega)
        return self.friction(omega) + tau_j / (self.reduction * kappa)

    def losses(self, tau_m: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Power lost in the motor friction and in the gearbox (..., n_a) [W].

        Args:
            tau_m: Motor torques (..., n_a) [N m].
            qd: Joint rates (..., n_a) [rad/s or m/s].

        Returns:
            ``(f(omega) omega, (1 - kappa) tau_in omega)``.

        """
        omega = self.motor_speed(qd)
        f = self.friction(omega)
        tau_in = np.asarray(tau_m, dtype=float) - f
        kappa = self.transmission_factor(tau_in, omega)
        return f * omega, (1.0 - kappa) * tau_in * omega
