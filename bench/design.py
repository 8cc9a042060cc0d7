"""Design-study throughput (issue 15): designs per second on 1 and 2 workers, a 10,000-design run.

The study is the worked Delta design of the user guide, docs/guide/design.md (``delta_study``
below): per design, the library Delta is built (URDF, Pinocchio model, collision geometry), Clavel's
figures, the required cylinder (D = 0.4 m, H = 0.1 m: reach and limits, worst and mean 1/cond, bar
clearances, on 425 poses) and the 0.5 s Adept cycle with 1 kg (arm torques, speeds, powers on 501
samples, closed form) are computed. Designs are Latin-hypercube samples of ``la``, ``lb``, ``ra``;
about half of them fail part-way (a fifth cannot be built: home out of reach; more leave the arm
limits on the cycle), as in a real study.

- designs/s: ``run_study`` on a warm executor (workers started), 1 worker (this process) and a
  pool of 2 processes, timed on alternating batches; scaling efficiency = rate(2) / (2 rate(1));
- the 10,000-design study as a user runs it (``run_study(study, out=..., workers=2)``: pool
  start-up, streaming to the partial file, CSV and Parquet at the end). Set
  ``PKDYN_BENCH_DESIGNS`` to run a smaller one.

The machine is shared: besides wall times, the CPU time of this process and of its worker
processes is reported (``resource.getrusage``), with the load average, so that a run on a busy
machine still tells what an idle one would do (CPU seconds per design, over 2 cores).

Run ``python bench/design.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import os
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from pkdyn.design import Study, run_study
from pkdyn.design.executors import ProcessExecutor, SerialExecutor

Row = tuple[str, str, str]

TARGET_S = 600.0
"""Target wall time of the 10,000-design study on a 2-core machine [s]."""


def delta_study(n: int, seed: int = 0) -> Study:
    """The worked Delta study (docs/guide/design.md), ``n`` Latin-hypercube designs."""
    return Study(
        "delta",
        {"la": (0.15, 0.35), "lb": (0.30, 0.70), "ra": (0.08, 0.22)},
        fixed={"z_home": -0.35},
        metrics=["clavel", "required", "sizing", "moving_mass"],
        requirement="cylinder:D=0.4,H=0.1,z=-0.35",
        trajectory="adept",
        trajectory_options={"cycle_time": 0.5},
        payload=1.0,
        constraints=["inv_cond_min>=0.2", "interference_margin>=0"],
        objectives=["min:peak_effort", "max:inv_cond_min"],
        sampler="lhs",
        n=n,
        seed=seed,
        name="Delta for a 0.4 x 0.1 m cylinder, Adept 0.5 s with 1 kg",
    )


def _rate(executor, n: int, seed: int) -> float:
    study = delta_study(n, seed)
    t0 = time.perf_counter()
    run_study(study, executor=executor, progress=False)
    return n / (time.perf_counter() - t0)


def rows() -> list[Row]:
    out: list[Row] = []
    serial, pool = SerialExecutor(), ProcessExecutor(2)
    _rate(pool, 16, 99)  # start the workers
    r1, r2 = [], []
    for k in range(3):
        r1.append(_rate(serial, 60, 10 + k))
        r2.append(_rate(pool, 120, 20 + k))
    pool.close()
    one, two = float(np.median(r1)), float(np.median(r2))
    out.append(("Delta design study, 1 worker (this process)", f"{one:.1f} designs/s", ""))
    out.append(("... 2 worker processes", f"{two:.1f} designs/s", ""))
    out.append(("... scaling efficiency rate(2) / (2 rate(1))", f"{two / (2 * one):.2f}", ""))
    n = int(os.environ.get("PKDYN_BENCH_DESIGNS", "10000"))
    with tempfile.TemporaryDirectory() as tmp:
        load0 = os.getloadavg()[0]
        cpu0 = _cpu()
        t0 = time.perf_counter()
        res = run_study(delta_study(n, 7), Path(tmp) / "study.csv", workers=2, progress=False)
        wall = time.perf_counter() - t0
        cpu = _cpu() - cpu0
        load = 0.5 * (load0 + os.getloadavg()[0])
    c = res.counts()
    out.append(
        (
            f"{n}-design Delta study, 2 workers, wall time (target {TARGET_S / 60:.0f} min "
            "for 10,000)",
            f"{wall:.0f} s ({n / wall:.1f} designs/s)",
            f"{c['feasible']} feasible, {c['constrained']} break a constraint, "
            f"{c['failed']} fail; load average {load:.1f}",
        )
    )
    out.append(
        (
            "... CPU time per design (parent + workers); idle 2-core projection for 10,000",
            f"{1e3 * cpu / n:.1f} ms; {1e4 * cpu / n / 2:.0f} s",
            "CPU seconds do not grow with the machine's load",
        )
    )
    return out


def _cpu() -> float:
    """CPU seconds of this process and of its finished children (the worker processes)."""
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


if __name__ == "__main__":
    from timing import print_table

    print_table(rows())
