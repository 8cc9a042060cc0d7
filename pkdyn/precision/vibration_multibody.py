"""The multibody method: the elastic model simulated, the reference for the modal method.

The elastic model's robot (:mod:`pkdyn.precision.elastic`: each compliant link's virtual joint a
free joint with its spring, the robot's own springs and dampers), carrying the payload, is
simulated by pkdyn's constrained forward dynamics (:func:`pkdyn.dynamics.simulate`: adaptive
Dormand-Prince 5(4), the closures kept by Pinocchio's proximal solver and projections), with

- each actuator a servo: ``tau = k (q_cmd - q) + c (q_cmd' - q') + tau_ff`` (the command
  interpolated by quintic Hermite polynomials between its samples, the feedforward by a cubic
  spline);
- the links' virtual springs damped by ``beta k`` (:mod:`pkdyn.precision.vibration_damping`);
- the start in the nonlinear static equilibrium of the first pose under gravity, the payload
  and the feedforward (:func:`pkdyn.precision.equilibrium.loaded_equilibrium`, the feedforward
  as an offset of the servos' rest positions), at rest.

Nothing is linearised: the deviation is the actual reference point's position (and rotation)
minus the commanded one, from the simulated configurations; its rate from the velocities. The
energy balance of the run (kinetic + gravity + springs against the servos' work and the
dissipation) is reported: :meth:`solvers.ForwardResult.energy_drift`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.interpolate import CubicSpline

from pkdyn.dynamics.forward import simulate
from pkdyn.exceptions import InvalidInputError
from pkdyn.model.robot import Robot
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.equilibrium import loaded_equilibrium
from pkdyn.precision.vibration_command import Command, Hermite5

__all__ = ["MultibodyResponse", "equilibrium", "multibody_response", "platform_motion"]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def platform_motion(
    robot: Robot, Q: np.ndarray, V: np.ndarray, A: np.ndarray | None, point: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Reference point and platform rotation along a sampled motion.

    Args:
        robot: The robot.
        Q: Configurations (N, nq).
        V: Velocities (N, nv).
        A: Accelerations (N, nv), or ``None`` (no accelerations returned: zeros).
        point: Reference point, platform frame [m].

    Returns:
        ``(p, p', p'', R, omega, alpha)``: point (N, 3) [m], its velocity and acceleration
        (world), rotation (N, 3, 3), angular velocity and acceleration (N, 3) (world).

    """
    model, data = robot.model, robot.model.createData()
    fid = robot.platform_frame
    assert fid is not None
    n = Q.shape[0]
    p, pd, pdd = np.empty((n, 3)), np.empty((n, 3)), np.zeros((n, 3))
    R, w, al = np.empty((n, 3, 3)), np.empty((n, 3)), np.zeros((n, 3))
    zero = np.zeros(model.nv)
    for k in range(n):
        pin.forwardKinematics(model, data, Q[k], V[k], zero if A is None else A[k])
        M = pin.updateFramePlacement(model, data, fid)
        vel = pin.getFrameVelocity(model, data, fid, _LWA)
        r = M.rotation @ point
        p[k] = M.translation + r
        R[k] = M.rotation
        w[k] = vel.angular
        pd[k] = vel.linear + np.cross(vel.angular, r)
        if A is not None:
            acc = pin.getFrameClassicalAcceleration(model, data, fid, _LWA)
            al[k] = acc.angular
            pdd[k] = (
                acc.linear
                + np.cross(acc.angular, r)
                + np.cross(vel.angular, np.cross(vel.angular, r))
            )
    return p, pd, pdd, R, w, al


def equilibrium(
    em: ElasticModel, q_cmd: np.ndarray, tau_ff: np.ndarray, point: np.ndarray
) -> np.ndarray:
    """Static equilibrium of the elastic model holding ``q_cmd`` under gravity and ``tau_ff``.

    The servos' feedforward ``tau_ff`` acts as a shift ``tau_ff / k`` of their rest positions.

    Args:
        em: The elastic model (its robot carries the payload).
        q_cmd: Commanded extended configuration (nq_ext,).
        tau_ff: Feedforward (n_a,) [N m or N].
        point: Reference point, platform frame [m].

    Returns:
        The extended configuration at equilibrium.

    """
    q0 = np.array(q_cmd, dtype=float)
    k = em.actuator_stiffness
    aq = np.asarray(em.robot.actuated_q)
    finite = np.isfinite(k)
    q0[aq[finite]] += tau_ff[finite] / k[finite]
    return loaded_equilibrium(em, q0, point, np.zeros(6), gravity=True).q


@dataclass(eq=False)  # numpy fields
class MultibodyResponse:
    """What the multibody method computes.

    Attributes:
        t: Output times (M,) [s].
        d: Platform deviation (M, 6): reference point [m], rotation [rad], world axes.
        d_dot: Its rate (M, 6).
        t_coarse: Times of ``u`` (K,) [s] (the command's samples, then the same step at rest).
        u: Deformation from the command at ``t_coarse`` (K, nv_ext).
        u_end: Deformation at the end of the motion (nv_ext,).
        u_dot_end: Its rate (nv_ext,).
        static_end: Platform deviation in the static equilibrium of the end pose (6,).
        energy_drift: Relative violation of the run's energy balance.
        steps: Accepted integration steps.
        simulation: The recorded simulation.

    """

    t: np.ndarray
    d: np.ndarray
    d_dot: np.ndarray
    t_coarse: np.ndarray
    u: np.ndarray
    u_end: np.ndarray
    u_dot_end: np.ndarray
    static_end: np.ndarray
    energy_drift: float
    steps: int
    simulation: Any


def _deviation(
    rob: Robot,
    Q: np.ndarray,
    V: np.ndarray,
    point: np.ndarray,
    t: np.ndarray,
    cmd_point: Hermite5,
    cmd_rot: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    p, pd, _, R, w, _ = platform_motion(rob, Q, V, None, point)
    pc, pcd, _ = cmd_point(t)
    Rc, wc = _rotation(cmd_rot, t)
    d = np.empty((t.size, 6))
    dd = np.empty((t.size, 6))
    d[:, :3] = p - pc
    dd[:, :3] = pd - pcd
    for i in range(t.size):
        d[i, 3:] = pin.log3(R[i] @ Rc[i].T)
    dd[:, 3:] = w - wc
    return d, dd


def _rotation(
    cmd_rot: tuple[np.ndarray, np.ndarray, np.ndarray], tq: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Commanded rotation and angular velocity at ``tq``.

    A cubic Hermite of the rotation vector relative to the previous sample (second order).
    """
    t, R, w = cmd_rot
    k = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, t.size - 2)
    h = t[k + 1] - t[k]
    s = np.clip((tq - t[k]) / h, 0.0, 1.0)
    out_R = np.empty((tq.size, 3, 3))
    out_w = np.empty((tq.size, 3))
    for i in range(tq.size):
        kk, ss, hh = int(k[i]), float(s[i]), float(h[i])
        Rk = R[kk]
        delta = pin.log3(Rk.T @ R[kk + 1])
        m0, m1 = Rk.T @ w[kk] * hh, Rk.T @ w[kk + 1] * hh
        s2, s3 = ss * ss, ss * ss * ss
        th = (s3 - 2 * s2 + ss) * m0 + (-2 * s3 + 3 * s2) * delta + (s3 - s2) * m1
        thd = (
            (3 * s2 - 4 * ss + 1) * m0 + (-6 * s2 + 6 * ss) * delta + (3 * s2 - 2 * ss) * m1
        ) / hh
        out_R[i] = Rk @ pin.exp3(th)
        out_w[i] = Rk @ thd
    if np.any(tq > t[-1]):
        out_w[tq > t[-1]] = 0.0
    return out_R, out_w


def _spline(t: np.ndarray, y: np.ndarray) -> Any:
    """Fast scalar evaluation of the cubic spline through ``(t, y)`` (held outside ``t``)."""
    sp = CubicSpline(t, y, axis=0)
    c = np.asarray(sp.c)  # (4, K, n)
    first, last = y[0], y[-1]
    K = t.size - 1

    def at(x: float) -> np.ndarray:
        if x <= t[0]:
            return first
        if x >= t[-1]:
            return last
        k = min(int(np.searchsorted(t, x, side="right")) - 1, K - 1)
        s = x - t[k]
        return c[3, k] + s * (c[2, k] + s * (c[1, k] + s * c[0, k]))

    return at


def multibody_response(
    em: ElasticModel,
    cmd: Command,
    damping_c: np.ndarray,
    servo_c: np.ndarray,
    point: np.ndarray,
    sub: int,
    rest: float,
) -> MultibodyResponse:
    """Simulate the elastic model along the command (see the module docstring).

    Args:
        em: The elastic model (its robot carries the payload).
        cmd: The command.
        damping_c: Viscous damping of the links' virtual joints (nv_ext,) [SI].
        servo_c: Servo damping per actuator (n_a,) [N m s/rad or N s/m].
        point: Reference point, platform frame [m].
        sub: Output steps per command sample interval.
        rest: Time simulated after the motion [s].

    Returns:
        The response.

    Raises:
        InvalidInputError: A rigid (infinite) actuator stiffness: a servo needs a finite one.
        SimulationError: The simulation fails.

    """
    k = np.asarray(em.actuator_stiffness, dtype=float)
    if not np.all(np.isfinite(k)):
        raise InvalidInputError(
            "actuator_stiffness",
            "the multibody method simulates each actuator as a servo of finite stiffness; "
            "give finite stiffnesses (or use the modal method)",
        )
    rob = em.robot
    aq = np.asarray(rob.actuated_q)
    av = np.asarray(rob.actuated_v)
    T = cmd.duration
    h = cmd.step
    n_rest = max(1, int(np.ceil(rest / h - 1e-9)))
    duration = T + n_rest * h
    act = cmd.actuators().scalar
    ff = _spline(cmd.t, cmd.tau_ff) if cmd.feedforward != "none" else None
    c = np.asarray(servo_c, dtype=float)

    def servo(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        qa, qad, _ = act(t)
        tau = k * (qa - q[aq]) + c * (qad - v[av])
        if ff is not None:
            tau = tau + ff(t)
        return tau

    q0 = equilibrium(em, cmd.q[0], cmd.tau_ff[0], point)
    v0 = cmd.v[0]
    dt = h / sub
    sim = simulate(
        rob,
        duration,
        dt,
        q0=q0,
        v0=v0,
        torque=servo,
        viscous=list(damping_c),
        integrator="dopri5",
    )
    # the command's reference point and rotation at the output times
    base = cmd.loaded
    p, pd, pdd, R, w, _ = platform_motion(base, cmd.joint.q, cmd.joint.v, cmd.joint.a, point)
    cmd_point = Hermite5(cmd.t, p, pd, pdd)
    cmd_rot = (cmd.t, R, w)
    t_out = np.asarray(sim.t)
    d, dd = _deviation(rob, sim.q, sim.v, point, t_out, cmd_point, cmd_rot)
    # deformation at the command's samples (display) and at the end of the motion
    idx = np.arange(0, t_out.size, sub)
    n_c = idx.size
    Qc = np.vstack([cmd.q, np.tile(cmd.q[-1], (max(n_c - cmd.q.shape[0], 0), 1))])[:n_c]
    u = np.array([pin.difference(rob.model, Qc[i], sim.q[idx[i]]) for i in range(n_c)])
    kT = (cmd.t.size - 1) * sub
    u_end = pin.difference(rob.model, cmd.q[-1], sim.q[kT])
    u_dot_end = sim.v[kT] - cmd.v[-1]
    q_static = equilibrium(em, cmd.q[-1], cmd.tau_ff[-1], point)
    zero_v = np.zeros((1, rob.nv))
    ps, _, _, Rs, _, _ = platform_motion(rob, q_static[None, :], zero_v, None, point)
    static = np.concatenate([ps[0] - p[-1], pin.log3(Rs[0] @ R[-1].T)])
    return MultibodyResponse(
        t=t_out,
        d=d,
        d_dot=dd,
        t_coarse=t_out[idx],
        u=u,
        u_end=u_end,
        u_dot_end=u_dot_end,
        static_end=static,
        energy_drift=float(sim.energy_drift()),
        steps=int(sim.extras.get("substeps", 0)),
        simulation=sim,
    )
