"""Design-study speed (issues 15, 37): per design against its arithmetic, 1 and 2 workers, Dask.

The study is the worked Delta design of the user guide (``studies/delta_cylinder.yaml``,
``delta_study`` below): per design, the library Delta is built (written into the worker's
candidate: :mod:`pkdyn.model.candidate`), Clavel's figures, the required cylinder (D = 0.4 m,
H = 0.1 m: reach and limits, worst and mean 1/cond, bar clearances, on 425 poses) and the 0.5 s
Adept cycle with 1 kg (arm torques, speeds, powers on 501 samples, closed form) are computed.
Designs are Latin-hypercube samples of ``la``, ``lb``, ``ra``; about half of them fail part-way
(a fifth cannot be built: home out of reach; more leave the arm limits on the cycle), as in a
real study.

Rows:

- per design, ``evaluate_design`` as a worker calls it (CPU time of this process), against the
  *floor*: a hand-written loop of the same arithmetic on each built design (Clavel's inverse
  model on the 425 poses, the arm limits and bar cones, the conditioning's 3x3 SVDs, the bar
  clearances, the closed-form dynamics of the 501-sample cycle), without building or
  validating anything; and what the 10,000-design study would take at that floor (the
  command's start-up and ending, measured on a 20-design study, plus the floor on 2 workers)
  against its 15 s target, with the time per design that leaves for everything else;
- building one candidate: in place against the URDF path (text, parse, validation, model);
- designs/s on 1 worker (this process), 2 local worker processes and a 2-worker Dask cluster
  (``distributed.LocalCluster``, one thread per worker), the scaling efficiency
  ``rate(2) / (2 rate(1))`` and the Dask path's overhead per design;
- the 10,000-design study as a user runs it (``pkdyn design --study studies/delta_cylinder.yaml``
  in a subprocess): wall and CPU time, and whether its table is byte-identical to the table of
  the code before the in-place candidates (:data:`REFERENCE_SHA256`);
- a larger study (``PKDYN_BENCH_SCALING_DESIGNS``, default 100,000; 0 skips it) on 2 local
  workers and on the 2-worker Dask cluster: the same table, the scaling efficiency against the
  1-worker rate, the cluster path's overhead per design.

The machine is shared: CPU times (``resource.getrusage`` of this process, its children, and
the Dask workers) are reported beside wall times, with the load average: CPU seconds hardly
grow with the load, wall seconds do. ``PKDYN_BENCH_DESIGNS`` sets the size of the user's study
(default 10,000, the reference digest holds for that size only).

Run ``python bench/design.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import hashlib
import os
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.design import Study, run_study
from pkdyn.design.executors import DaskExecutor, Executor, ProcessExecutor, SerialExecutor

Row = tuple[str, str, str]

ROOT = Path(__file__).resolve().parent.parent
TARGET_S = 15.0
"""Target wall time of the 10,000-design study on the idle 2-core machine [s] (issue 37)."""

REFERENCE_SHA256 = "ddcf5c7ee337807fbd95d6ba7e3d98081fe7e1db877162ca7796ac2d27493c80"
"""SHA-256 of the CSV table of ``pkdyn design --study studies/delta_cylinder.yaml`` written by
the code before the in-place candidates (main at ac1154f): the study must give it byte for byte."""


def delta_study(n: int, seed: int = 0) -> Study:
    """The worked Delta study (``studies/delta_cylinder.yaml``), ``n`` Latin-hypercube designs."""
    return Study(
        "delta",
        {"la": (0.15, 0.35), "lb": (0.30, 0.70), "ra": (0.08, 0.22)},
        fixed={"z_home": -0.35},
        metrics=["clavel", "required", "sizing", "moving_mass"],
        requirement={"kind": "cylinder", "D": 0.4, "H": 0.1, "center": [0, 0, -0.35], "samples": 5},
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


# ---------------------------------------------------------------------- per design


def _floor_inputs(study: Study, X: np.ndarray) -> list[tuple[Any, ...]]:
    """Per built design, the inputs of the arithmetic (prepared outside the timing)."""
    from pkdyn.design.evaluate import build
    from pkdyn.dynamics.delta import DeltaDynamics
    from pkdyn.dynamics.trajectory import named_task
    from pkdyn.exceptions import PkdynError
    from pkdyn.workspace.delta import DeltaEvaluator

    P = np.array(study.requirement.positions)
    out = []
    for x in X:
        try:
            robot = build(study, x)
        except PkdynError:
            continue
        ev = DeltaEvaluator(robot)
        task = named_task(robot, "adept", cycle_time=0.5)
        dd = DeltaDynamics(robot, 1.0)
        out.append((robot.params, P, ev, dd, task))
    return out


def _floor(inputs: list[tuple[Any, ...]]) -> None:
    """The arithmetic of the study's metrics, design after design, nothing built or checked.

    Everything the table's numbers need from a built design: Clavel's inverse model on the
    required poses, the arm limits and the bars' cones (``_violations``, the limits' elbows
    kept), the conditioning's 3x3 SVDs and the bar clearances on the poses within them, the
    closed-form dynamics of the cycle and its peak torque.
    """
    from pkdyn.analysis.screws import delta_AB
    from pkdyn.closed_form.delta import inverse
    from pkdyn.exceptions import PkdynError

    for p, P, ev, dd, task in inputs:
        alpha, ok = inverse(p, P)
        _, made = ev._violations(P, ("stroke", "joint"), 0.0, (alpha, ok))
        if made is not None and made[0].size:
            todo, E, tip = made
            Pk = P[todo]
            A, B = delta_AB(p, Pk, alpha[todo])
            Jinv = A / np.einsum("nii->ni", B)[..., None]
            np.linalg.svd(Jinv, compute_uv=False)
            ev._clearance(Pk, E, tip)
        try:
            at = dd.solve(task)
        except PkdynError:
            continue
        np.max(np.abs(at.tau), axis=0)


def _start_up() -> float:
    """Wall time of the user's command on a 20-design study [s]: start-up and ending."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "pkdyn", "design", "--study", "studies/delta_cylinder.yaml"]
        cmd += ["--n", "20", "--out", str(Path(tmp) / "delta.csv")]
        walls = []
        for _ in range(3):
            t0 = time.perf_counter()
            subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True)
            walls.append(time.perf_counter() - t0)
    return float(min(walls))


def _per_design(n: int = 240) -> list[Row]:
    from pkdyn.design.evaluate import candidates, evaluate_design
    from pkdyn.exceptions import PkdynError
    from pkdyn.model.candidate import CandidateBuilder

    study = delta_study(n, 3)
    X = study.designs()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i in range(5):
            evaluate_design(study, i, X[i])
        times = []
        for _rep in range(3):
            t0 = time.process_time()
            for i in range(n):
                evaluate_design(study, i, X[i])
            times.append((time.process_time() - t0) / n)
        per = float(np.median(times))
        inputs = _floor_inputs(study, X)
        _floor(inputs[:5])
        floors = []
        for _rep in range(3):
            t0 = time.process_time()
            _floor(inputs)
            floors.append((time.process_time() - t0) / n)
        floor = float(np.median(floors))
        # building alone: in place against the URDF path
        params = []
        for x in X:
            try:
                params.append(study.space.params(x))
            except PkdynError:
                continue
        builder = candidates(study)
        fresh = CandidateBuilder("delta", collision=True)
        t0 = time.process_time()
        for p in params:
            builder.robot(p)
        t_place = (time.process_time() - t0) / len(params)
        t0 = time.process_time()
        for p in params[:60]:
            fresh._urdf_robot(p, None)
        t_urdf = (time.process_time() - t0) / min(60, len(params))
    built = len(inputs)
    fixed = _start_up()
    at_floor = fixed + 10000 * floor / 2
    left = (TARGET_S - at_floor) * 2 / 10000
    return [
        (
            "Delta design, per design as a worker evaluates it (`evaluate_design`, CPU)",
            f"{per * 1e3:.2f} ms vs the floor {floor * 1e3:.2f} ms: {per / floor:.1f}x",
            f"floor: the metrics' arithmetic on the {built} of {n} designs that build",
        ),
        (
            "... building one candidate: in place (the worker's model) vs the URDF path",
            f"{t_place * 1e3:.2f} ms vs {t_urdf * 1e3:.2f} ms ({t_urdf / t_place:.1f}x)",
            "the same robot bit for bit (tests/test_candidate.py)",
        ),
        (
            "... the 10,000-design study at the floor: the command's start-up and ending (a "
            "20-design study) + 10,000 x floor / 2 workers",
            f"{fixed:.1f} s + {10000 * floor / 2:.1f} s = {at_floor:.1f} s (target "
            f"{TARGET_S:.0f} s)",
            f"left per design for building, checking and the figures: {left * 1e3:.2f} ms "
            f"(building alone: {t_place * 1e3:.2f} ms)",
        ),
    ]


# ---------------------------------------------------------------------- executors


def _rate(executor: Executor, n: int, seed: int) -> tuple[float, float]:
    """Designs/s (wall) and CPU seconds per design of a study run on ``executor``."""
    study = delta_study(n, seed)
    c0 = _cpu_all(executor)
    t0 = time.perf_counter()
    run_study(study, executor=executor, progress=False)
    wall = time.perf_counter() - t0
    return n / wall, (_cpu_all(executor) - c0) / n


def _cpu_all(executor: Executor) -> float:
    """CPU seconds of this process, its finished children and the executor's live workers."""
    total = _cpu()
    if isinstance(executor, DaskExecutor):
        usage = executor.client.run(_own_cpu)
        total += sum(usage.values())
    elif isinstance(executor, ProcessExecutor) and executor._pool is not None:
        pool = executor._pool
        futures = [pool.submit(_own_cpu_slow) for _ in range(executor.workers * 4)]
        seen: dict[int, float] = {}
        for f in futures:
            pid, cpu = f.result()
            seen[pid] = max(cpu, seen.get(pid, 0.0))
        total += sum(seen.values())
    return total


def _own_cpu() -> float:
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime


def _own_cpu_slow() -> tuple[int, float]:
    time.sleep(0.05)  # (so that every worker takes one)
    return os.getpid(), _own_cpu()


def _cluster() -> tuple[Any, Any]:
    from distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    return cluster, Client(cluster)


def _executors(n: int = 400) -> list[Row]:
    serial, pool = SerialExecutor(), ProcessExecutor(2)
    cluster, client = _cluster()
    dask = DaskExecutor(client)
    try:
        for ex in (pool, dask):
            _rate(ex, 32, 99)  # start the workers, build their candidates
        r1, r2, rd = [], [], []
        for k in range(3):
            r1.append(_rate(serial, n // 2, 10 + k))
            r2.append(_rate(pool, n, 20 + k))
            rd.append(_rate(dask, n, 20 + k))
    finally:
        pool.close()
        dask.close()
        client.close()
        cluster.close()
    one, two, dk = (float(np.median([r[0] for r in rs])) for rs in (r1, r2, rd))
    c1, c2, cd = (float(np.median([r[1] for r in rs])) for rs in (r1, r2, rd))
    load = os.getloadavg()[0]
    return [
        (
            "Delta design study, 1 worker (this process)",
            f"{one:.1f} designs/s",
            f"{c1 * 1e3:.2f} ms CPU per design",
        ),
        (
            "... 2 local worker processes",
            f"{two:.1f} designs/s",
            f"{c2 * 1e3:.2f} ms CPU per design",
        ),
        (
            "... 2-worker Dask cluster (`LocalCluster`, 1 thread each)",
            f"{dk:.1f} designs/s",
            f"{cd * 1e3:.2f} ms CPU per design",
        ),
        (
            "... scaling efficiency rate(2) / (2 rate(1)): local, Dask",
            f"{two / (2 * one):.2f}, {dk / (2 * one):.2f}",
            f">= 0.8 (load average {load:.1f}: a busy machine has no second core to give)",
        ),
        (
            "... Dask path overhead per design (wall, CPU) against the local pool",
            f"{(1 / dk - 1 / two) * 1e3:.2f} ms, {(cd - c2) * 1e3:.2f} ms",
            "chunks of 32 designs",
        ),
    ]


# ---------------------------------------------------------------------- whole studies


def _user_study(n: int) -> list[Row]:
    """The user's command, in a subprocess: wall, CPU of it and its workers, table digest."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "delta.csv"
        cmd = [sys.executable, "-m", "pkdyn", "design", "--study", "studies/delta_cylinder.yaml"]
        if n != 10000:
            cmd += ["--n", str(n)]
        cmd += ["--out", str(out)]
        load0 = os.getloadavg()[0]
        c0 = _children_cpu()
        t0 = time.perf_counter()
        subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True)
        wall = time.perf_counter() - t0
        cpu = _children_cpu() - c0
        digest = hashlib.sha256(out.read_bytes()).hexdigest()
    load = 0.5 * (load0 + os.getloadavg()[0])
    same = "byte-identical to the table before the in-place candidates"
    if n != 10000:
        same = "(the reference digest is that of 10,000 designs)"
    elif digest != REFERENCE_SHA256:
        same = "**differs** from the table before the in-place candidates"
    return [
        (
            f"{n}-design Delta study as a user runs it (`pkdyn design --study "
            f"studies/delta_cylinder.yaml`), 2 workers, wall (target {TARGET_S:.0f} s idle)",
            f"{wall:.1f} s ({n / wall:.0f} designs/s), load average {load:.1f}",
            same,
        ),
        (
            "... CPU time of the command and its workers; idle 2-core wall projection",
            f"{cpu:.1f} s ({cpu / n * 1e3:.2f} ms per design); {cpu / 2:.0f} s",
            "CPU seconds hardly grow with the machine's load",
        ),
    ]


def _scaling(n: int) -> list[Row]:
    """A large study on 2 local workers and on the 2-worker Dask cluster: table, efficiency."""
    rate1, cpu1 = _rate(SerialExecutor(), 400, 5)
    out: list[Row] = []
    digests = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label in ("local", "dask"):
            cluster = client = None
            if label == "dask":
                cluster, client = _cluster()
            try:
                path = Path(tmp) / f"{label}.csv"
                ex: Executor = DaskExecutor(client) if client is not None else ProcessExecutor(2)
                c0 = _cpu_all(ex)
                load0 = os.getloadavg()[0]
                t0 = time.perf_counter()
                run_study(delta_study(n, 11), path, executor=ex, progress=False)
                wall = time.perf_counter() - t0
                if label == "dask":
                    cpu = _cpu_all(ex) - c0
                    ex.close()
                else:  # the pool's processes, finished, are then among this one's children
                    ex.close()
                    cpu = _cpu() - c0
                digests[label] = hashlib.sha256(path.read_bytes()).hexdigest()
            finally:
                if client is not None:
                    client.close()
                    cluster.close()
            load = 0.5 * (load0 + os.getloadavg()[0])
            eff = n / wall / (2 * rate1)
            where = "2 local workers" if label == "local" else "2-worker Dask cluster"
            out.append(
                (
                    f"{n}-design Delta study, {where}",
                    f"{wall:.0f} s ({n / wall:.0f} designs/s); efficiency {eff:.2f} (wall), "
                    f"{cpu1 * n / cpu:.2f} (CPU: 1 worker's CPU per design / this one's)",
                    f"{cpu / n * 1e3:.2f} ms CPU per design (1 worker: {cpu1 * 1e3:.2f}); "
                    f"load {load:.1f}",
                )
            )
    walls = [float(r[1].split(" s ")[0]) for r in out]
    out.append(
        (
            "... the two tables; the cluster path's overhead per design (wall)",
            "identical" if digests["local"] == digests["dask"] else "**differ**",
            f"{(walls[1] - walls[0]) / n * 1e3:.2f} ms",
        )
    )
    return out


def rows() -> list[Row]:
    out = _per_design()
    out += _executors()
    out += _user_study(int(os.environ.get("PKDYN_BENCH_DESIGNS", "10000")))
    n = int(os.environ.get("PKDYN_BENCH_SCALING_DESIGNS", "100000"))
    if n > 0:
        out += _scaling(n)
    return out


def _cpu() -> float:
    """CPU seconds of this process and of its finished children (the worker processes)."""
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _children_cpu() -> float:
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return kids.ru_utime + kids.ru_stime


if __name__ == "__main__":
    from timing import print_table

    print_table(rows())
