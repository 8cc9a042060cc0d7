"""Vibration along a motion (issue 38): the modal method's speed, against the multibody method.

The DELTA 580 on the Adept cycle (0.5 s, 0.5 kg payload, 2e4 N m/rad servos, rigid links: its
three modes, 91 to 157 Hz at the pick points), CPU time of this process:

- the modal response and its figures for one timing of a path whose modes are known (the
  fastest-cycle search and a design study's re-timings do this): cycles per CPU second; target
  >= 50 /s;
- a whole modal analysis of a new command, the mapping to the joints excepted (modes at 33
  poses, the unbalanced forces at 501 samples, the response, the figures);
- the multibody simulation of the same cycle (the reference);
- ``size --fastest --settle``'s search (the unshaped scan and bisection) on the Delta.

Run ``python bench/vibration.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import time

import numpy as np
from timing import Row, print_table

import pkdyn
from pkdyn.dynamics.trajectory import named_task
from pkdyn.precision import elastic_model
from pkdyn.precision.vibration import analyse, prepare, static_deflection
from pkdyn.precision.vibration_command import command
from pkdyn.precision.vibration_figures import figures
from pkdyn.precision.vibration_modal import loads, modal_response, path_modes, pose_samples


def _cpu(fn, repeats: int = 5) -> float:
    """Median CPU time of ``fn()`` [s]."""
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return float(np.median(times))


def rows() -> list[Row]:
    robot = pkdyn.load("delta", geometry=False)
    em = elastic_model(robot, 2e4)
    p = np.zeros(3)
    cmd = command(em, named_task(robot, "adept", cycle_time=0.5), 0.5, p)
    st = prepare(robot, em, cmd, p, 0.5, "none", None, None, 1e-4, 0.5, None, 33)
    samples = pose_samples(cmd.t.size, 33)
    pm = path_modes(st.elastic, cmd.joint.q, samples, p)
    F = loads(st.elastic, cmd.q, cmd.v, cmd.a, cmd.tau_ff)
    sub = st.sub(cmd.step, cmd.duration)
    static = static_deflection(pm, F[-1])

    def response() -> None:
        r = modal_response(pm, cmd.t[samples], cmd.t, F, st.c, None, sub, st.rest)
        figures(r.t, r.d[:, :3], r.d_dot[:, :3], static[:3], cmd.duration, 0.5, 1e-4, st.rest)

    t_resp = _cpu(response, 7)
    t_full = _cpu(lambda: analyse(st, cmd, "modal"), 3)
    t_multi = _cpu(lambda: analyse(st, cmd, "multibody"), 1)
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
            "delta, Adept cycle 0.5 s + 0.5 s dwell: modal response and figures, modes known "
            "(3 modes, 33 poses)",
            f"**{1.0 / t_resp:.3g} cycles/s** ({1e3 * t_resp:.1f} ms)",
            ">= 50/s",
        ),
        (
            "delta, Adept cycle: whole modal analysis of a new command (modes at 33 poses, forces "
            "at 501 samples, response, figures; mapping excepted)",
            f"{1.0 / t_full:.3g} cycles/s ({1e3 * t_full:.0f} ms)",
            "",
        ),
        (
            "delta, Adept cycle: multibody simulation (dopri5, the reference)",
            f"{t_multi:.3g} s per cycle ({t_multi / t_full:.0f} x the modal analysis)",
            "",
        ),
        (
            "delta: fastest Adept cycle settling within 0.1 mm in a 0.1 s dwell (toppra, then "
            f"{u.evaluations} modal evaluations)",
            f"{t_search:.3g} s ({found})",
            "",
        ),
    ]


if __name__ == "__main__":
    print_table(rows())
