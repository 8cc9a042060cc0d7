"""Vibration along a motion (issue 38): the modal method as users call it, against its floor.

The DELTA 580 on the Adept cycle (0.5 s, 0.5 kg payload, 2e4 N m/rad servos, rigid links: its
three modes, 91 to 157 Hz at the pick points) and a 0.5 s dwell, CPU time of this process:

- ``vibration(robot, "adept", ...)`` from scratch (the closed forms of the library Delta: no
  pose solved), cycles per CPU second, target >= 50 /s; beside it the **floor**: the same
  arithmetic written by hand (the closed-form arm motion and efforts, the nacelle-space modes
  at every sample, the modal march and the figures, without the checks, the elastic model, the
  payload copy and the result), and the ratio of the two timed alternately;
- the ``settling_time`` design metric per design (a fresh design context each time, as a
  study evaluates a new design; the designs built beforehand), target >= 50 /s;
- the general path on the same Delta with carbon arms and bars (57 modes, 33 integrated; the
  mapping of the path, the modes at 65 poses, the unbalanced forces at 501 samples);
- the multibody simulation of the rigid-link cycle (the reference), and MuJoCo running the
  exported elastic model (rigid links: RK4 at 50 us; carbon links: implicit-in-velocity at
  40 us);
- ``size --fastest --band``'s search (the unshaped scan and bisection) on the Delta.

Run ``python bench/vibration.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import time

import numpy as np
from timing import Row, paired, print_table

import pkdyn
from pkdyn.dynamics.delta import DeltaDynamics
from pkdyn.dynamics.payload import with_payload
from pkdyn.dynamics.trajectory import named_task
from pkdyn.precision import elastic_model
from pkdyn.precision.vibration import analyse, prepare, vibration
from pkdyn.precision.vibration_closed_form import DeltaModes
from pkdyn.precision.vibration_command import command
from pkdyn.precision.vibration_figures import figures
from pkdyn.precision.vibration_modal import modal_response

OPTS = dict(cycle_time=0.5, payload=0.5, actuator_stiffness=2e4, band=1e-4, dwell=0.5)


def _cpu(fn, repeats: int = 5) -> float:
    """Median CPU time of ``fn()`` [s]."""
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return float(np.median(times))


def _floor(robot: pkdyn.Robot) -> None:
    """The same arithmetic as ``vibration(robot, "adept", **OPTS)``, by hand."""
    task = named_task(robot, "adept", cycle_time=0.5)
    loaded = with_payload(robot, 0.5)
    dd = DeltaDynamics(loaded)
    arms = dd.solve(task, check_limits=False)
    k = np.full(3, 2e4)
    dm = DeltaModes(dd, k)
    poses = dm.poses(task.pose[:, :3])
    n = task.t.size
    samples = np.arange(n)
    pm = dm.path_modes(poses, samples)
    f_mid = pm.frequencies[(n - 1) // 2]
    beta = 2 * 0.02 / (2 * np.pi * f_mid[0])
    C = dm.damping(poses, beta * k)
    F = np.einsum("nki,nk->ni", poses.Jinv, -arms.tau)
    rest = 0.5 + 2.0 / f_mid[0]  # (the dwell and two periods of mode 1)
    sub = int(np.ceil(1e-3 * f_mid[-1] * 16 * 1.25))
    r = modal_response(pm, task.t, task.t, F, C, None, sub, rest)
    static = pm.platform[-1].T @ ((pm.shapes[-1] @ F[-1]) / (2 * np.pi * pm.frequencies[-1]) ** 2)
    figures(r.t, r.d[:, :3], r.d_dot[:, :3], static[:3], 0.5, 0.5, 1e-4, rest)


def rows() -> list[Row]:
    robot = pkdyn.load("delta", geometry=False)
    t_user, t_floor, ratio = paired(
        lambda: vibration(robot, "adept", **OPTS), lambda: _floor(robot), 5, repeats=9
    )
    # the settling_time metric, per new design
    from pkdyn.design.context import Conditions, DesignContext
    from pkdyn.design.metrics import METRICS

    designs = [pkdyn.load("delta", geometry=False, la=la) for la in np.linspace(0.2, 0.26, 6)]
    cond = Conditions(
        trajectory="adept", trajectory_options={"cycle_time": 0.5}, payload=0.5,
        actuator_stiffness=2e4, band=1e-4, dwell=0.5,
    )  # fmt: skip
    metric = METRICS["settling_time"]

    def per_design() -> None:
        for d in designs:
            metric(d, DesignContext(d, cond))

    t_metric = _cpu(per_design, 5) / len(designs)
    # the general path: carbon links
    full = pkdyn.load("delta")
    t_carbon = _cpu(lambda: vibration(full, "adept", material="carbon", **OPTS), 3)
    # the references
    t_multi = _cpu(lambda: vibration(robot, "adept", method="multibody", **OPTS), 1)
    t_mj_rigid, t_mj_carbon = _mujoco(full)
    from pkdyn.precision.vibration_fastest import fastest_settling

    path = named_task(robot, "adept", cycle_time=1.0)
    t0 = time.process_time()
    res = fastest_settling(robot, path, 1e-4, 0.1, payload=0.5, actuator_stiffness=2e4,
                           shaper=None)  # fmt: skip
    t_search = time.process_time() - t0
    u = res.unshaped
    found = (
        f"x{u.scale:.3g}: {1e3 * u.motion_time:.0f} ms + 100 ms dwell"
        if u.scale is not None and u.motion_time is not None
        else "none up to x4"
    )
    return [
        (
            "delta, Adept cycle 0.5 s + 0.5 s dwell, 0.5 kg, rigid links (3 modes): "
            '`vibration(robot, "adept", ...)` from scratch',
            f"**{1e6 / t_user:.3g} cycles/s** ({1e-3 * t_user:.1f} ms)",
            ">= 50/s",
        ),
        (
            "the same arithmetic by hand (closed-form arms and efforts, modes at 501 samples, "
            "modal march, figures): the floor",
            f"{1e6 / t_floor:.3g} cycles/s ({1e-3 * t_floor:.1f} ms): user call "
            f"{ratio:.2f}x the floor",
            "",
        ),
        (
            "delta designs (la 0.20-0.26 m): the `settling_time` metric per new design",
            f"**{1.0 / t_metric:.3g} designs/s** ({1e3 * t_metric:.1f} ms)",
            ">= 50/s",
        ),
        (
            "delta with carbon arms and bars (57 modes, 33 integrated): general modal path "
            "(the path mapped, modes at 65 poses, forces at 501 samples)",
            f"{t_carbon:.3g} s per cycle",
            "",
        ),
        (
            "delta, rigid links: multibody simulation (dopri5, the reference)",
            f"{t_multi:.3g} s per cycle ({t_multi / (1e-6 * t_user):.0f} x the modal call)",
            "",
        ),
        (
            "MuJoCo on the exported elastic model, Adept cycle + dwell (rigid links: RK4 50 us; "
            "carbon links: implicitfast 40 us; the start equilibrium and the figures included)",
            f"{t_mj_rigid:.3g} s; {t_mj_carbon:.3g} s",
            "",
        ),
        (
            "delta: fastest Adept cycle settling within 0.1 mm in a 0.1 s dwell (toppra, then "
            f"{u.evaluations} modal evaluations)",
            f"{t_search:.3g} s ({found})",
            "",
        ),
    ]


def _mujoco(robot: pkdyn.Robot) -> tuple[float, float]:
    """CPU time of the MuJoCo runs of the Adept cycle, rigid and carbon links [s]."""
    from pkdyn.precision.vibration_mjcf import mujoco_figures

    out = []
    for material, h, integrator in ((None, 5e-5, "RK4"), ("carbon", 4e-5, "implicitfast")):
        em = elastic_model(robot, 2e4, material=material)
        p = np.zeros(3)
        cmd = command(em, named_task(robot, "adept", cycle_time=0.5), 0.5, p)
        st = prepare(robot, em, cmd, p, 0.5, "none", None, None, 1e-4, 0.5, None, None)
        r = analyse(st, cmd, "modal")
        cmd.q  # noqa: B018 (the path mapped and the start equilibrium beforehand)
        t0 = time.process_time()
        mujoco_figures(st, cmd, r, h, integrator)
        out.append(time.process_time() - t0)
    return out[0], out[1]


if __name__ == "__main__":
    print_table(rows())
