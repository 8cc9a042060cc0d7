"""Valid inputs of the entry points: robots, configurations and files, built once per process.

Each file maker returns bytes (cached): the registry copies them into each example's scratch
directory, where the bad-input classes derive their variants (a BOM, CRLF, a huge cell...).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

import pkdyn

__all__ = [
    "calibration_csv",
    "catalog_yaml",
    "identification_csv",
    "positions_csv",
    "plugin_py",
    "q_at",
    "robot",
    "study_yaml",
    "trajectory_csv",
    "urdf_text",
]


@functools.cache
def robot(family: str, geometry: bool = False) -> pkdyn.Robot:
    """A library robot, loaded once per process (entry points must not change it)."""
    return pkdyn.load(family, geometry=geometry)


@functools.cache
def _q(family: str, pose: tuple[float, ...] | None) -> np.ndarray:
    r = robot(family)
    if pose is None:
        return r.q_home.copy()
    return pkdyn.inverse_geometry(r, list(pose), check_limits=False).q


def q_at(family: str, pose: tuple[float, ...] | None = None) -> np.ndarray:
    """An assembled configuration (nq,) of ``family`` at a platform pose (default: home)."""
    return _q(family, pose).copy()


@functools.cache
def urdf_text(family: str) -> bytes:
    """The URDF of a library family, as written by ``pkdyn urdf``."""
    from pkdyn.model.families import family as get

    f = get(family)
    return f.build_urdf(f.make_params({})).encode()


@functools.cache
def trajectory_csv() -> bytes:
    """The Adept cycle of the Delta in task space (``t,x,y,z``), 0.004 s samples."""
    from pkdyn.dynamics.trajectory import named_task

    task = named_task(robot("delta"), "adept", dt=0.004)
    rows = ["t,x,y,z"] + [
        f"{t:.10g},{p[0]:.12g},{p[1]:.12g},{p[2]:.12g}"
        for t, p in zip(task.t, task.pose, strict=True)
    ]
    return ("\n".join(rows) + "\n").encode()


def _multisine(r: pkdyn.Robot, T: float, dt: float, amp: float, seed: int):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, T, dt)
    n = len(r.actuators)
    qa = np.tile(r.q_home[r.actuated_q], (t.size, 1))
    qd, qdd = np.zeros_like(qa), np.zeros_like(qa)
    for h in range(1, 5):
        w = 2 * np.pi * 0.25 * h
        A, B = amp * rng.uniform(-1, 1, n) / h, amp * rng.uniform(-1, 1, n) / h
        s, c = np.sin(w * t[:, None]), np.cos(w * t[:, None])
        qa += A * s + B * (c - 1)
        qd += w * (A * c - B * s)
        qdd += -w * w * (A * s + B * c)
    return t, qa, qd, qdd


@functools.cache
def identification_csv(seed: int = 5, duration: float = 4.0) -> bytes:
    """A measured motion of the five-bar (its drives' friction and rotor inertia identified):
    ``t, qa_*, qa_dot_*, qa_ddot_*, tau_*``, efforts from the nominal model plus 1e-3 noise."""
    from pkdyn.identification import parameter_set, predict_efforts

    r = robot("five_bar")
    ps = parameter_set(r)
    t, qa, qd, qdd = _multisine(r, duration, 1e-2, 0.3, seed)
    tau = predict_efforts(r, ps, ps.nominal, t, qa, qd, qdd)
    tau = tau + 1e-3 * np.random.default_rng(seed).standard_normal(tau.shape)
    names = r.actuator_names
    cols = ["t"] + [f"{k}_{n}" for k in ("qa", "qa_dot", "qa_ddot", "tau") for n in names]
    data = np.column_stack([t, qa, qd, qdd, tau])
    lines = [",".join(cols)] + [",".join(f"{v:.12g}" for v in row) for row in data]
    return ("\n".join(lines) + "\n").encode()


@functools.cache
def positions_csv() -> bytes:
    """The motion of :func:`identification_csv` without rates: ``t, qa_*, tau_*`` (the rates
    are filtered from the positions)."""
    lines = identification_csv().decode().splitlines()
    head = lines[0].split(",")
    keep = [i for i, c in enumerate(head) if not c.startswith(("qa_dot", "qa_ddot"))]
    return ("\n".join(",".join(ln.split(",")[i] for i in keep) for ln in lines) + "\n").encode()


@functools.cache
def calibration_csv() -> bytes:
    """Delta platform positions measured at 30 actuator readings (nominal robot + 10 um
    noise): ``qa_motor1..3, x, y, z``."""
    r = robot("delta")
    rng = np.random.default_rng(0)
    home = r.q_home[r.actuated_q]
    rows = []
    while len(rows) < 30:
        qa = home + 0.3 * rng.uniform(-1, 1, home.size)
        try:
            p = pkdyn.forward_geometry(r, qa).placement.translation
        except pkdyn.PkdynError:
            continue
        rows.append([*qa, *(p + rng.normal(0.0, 1e-5, 3))])
    head = [f"qa_{n}" for n in r.actuator_names] + ["x", "y", "z"]
    lines = [",".join(head)] + [",".join(f"{v:.12g}" for v in row) for row in rows]
    return ("\n".join(lines) + "\n").encode()


def study_yaml() -> bytes:
    """A four-design study of the Delta (one cheap metric)."""
    return (
        b"family: delta\nranges:\n  la: [0.2, 0.3]\nfixed: {}\nmetrics: [moving_mass]\n"
        b"constraints: []\nobjectives: []\nrequirement: null\ntrajectory: adept\n"
        b"trajectory_options: {}\npayload: 0.0\nsampler: lhs\nn: 4\nseed: 0\n"
    )


def catalog_yaml() -> bytes:
    """The example motor catalog shipped with pkdyn."""
    from importlib.resources import files

    return (files("pkdyn.dynamics") / "catalogs" / "example.yaml").read_bytes()


def plugin_py() -> bytes:
    """A plug-in module with one metric."""
    return (
        b"from pkdyn.design import metric\n\n\n"
        b"@metric('contract_arm_ratio', '-', 'la / lb')\n"
        b"def arm_ratio(robot, ctx):\n    return robot.params.la / robot.params.lb\n"
    )


def any_value(x: Any) -> Any:
    """``x`` (a helper for lambdas in the registry)."""
    return x
