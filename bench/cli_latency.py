"""CLI latency: ``pkdyn info delta`` against ``python -c "import pinocchio, numpy"``.

The floor is the interpreter starting and importing the two libraries every pkdyn command needs;
the target is ``pkdyn info delta`` within 1.2x of it. Both commands run alternately in one
process tree (``runs`` times each, after a warm-up), wall-clock and CPU medians compared, so
machine load affects both alike (the CPU time is the steadier figure on a shared machine);
bytecode caches are allowed (``PYTHONDONTWRITEBYTECODE`` is dropped for the runs, as on a user's
machine). ``--hyperfine`` uses hyperfine instead (wall clock only), when it is installed.

    python bench/cli_latency.py [--runs 30] [--hyperfine]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PYTHON = sys.executable
PKDYN = str(Path(sys.executable).with_name("pkdyn"))
FLOOR = [PYTHON, "-c", "import pinocchio, numpy"]
COMMANDS = {
    "info delta": [PKDYN, "info", "delta"],
    "--version": [PKDYN, "--version"],
    "fk delta": [PKDYN, "fk", "delta", "--q", "0.5", "0.5", "0.5"],
}


ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
"""As a user runs it: bytecode caches written once, then used."""


def _time(cmd: list[str]) -> tuple[float, float]:
    """Wall-clock and CPU (user + system) time of one run [s]."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        raise RuntimeError(f"{cmd} exited with {proc.returncode}")
    return wall, usage.ru_utime + usage.ru_stime


def measure(runs: int = 30, commands: dict[str, list[str]] | None = None) -> dict[str, object]:
    """Median wall-clock and CPU times of the floor and of each command, timed alternately.

    The CPU time (user + system of the child) is the steadier figure on a shared machine.

    Returns:
        ``{"floor": s, "floor_cpu": s, "commands": {name: {"median", "ratio", "cpu",
        "cpu_ratio"}}}``.

    """
    commands = COMMANDS if commands is None else commands
    for cmd in [FLOOR, *commands.values()]:  # warm the file and bytecode caches
        _time(cmd)
    floor: list[tuple[float, float]] = []
    times: dict[str, list[tuple[float, float]]] = {k: [] for k in commands}
    for _ in range(runs):
        floor.append(_time(FLOOR))
        for k, cmd in commands.items():
            times[k].append(_time(cmd))
    f = statistics.median(w for w, _ in floor)
    fc = statistics.median(c for _, c in floor)
    out = {}
    for k, v in times.items():
        w = statistics.median(x for x, _ in v)
        c = statistics.median(y for _, y in v)
        out[k] = {"median": w, "ratio": w / f, "cpu": c, "cpu_ratio": c / fc}
    return {"floor": f, "floor_cpu": fc, "runs": runs, "commands": out}


def hyperfine(runs: int) -> dict[str, object]:
    """The same comparison with hyperfine (``pkdyn info delta`` only)."""
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "h.json"
        subprocess.run(
            [
                "hyperfine",
                "--warmup",
                "3",
                "--runs",
                str(runs),
                "--export-json",
                str(out),
                f"{PYTHON} -c 'import pinocchio, numpy'",
                f"{PKDYN} info delta",
            ],
            check=True,
            stdout=subprocess.DEVNULL,
            env=ENV,
        )
        res = json.loads(out.read_text())["results"]
    floor, info = res[0]["median"], res[1]["median"]
    return {"floor": floor, "commands": {"info delta": {"median": info, "ratio": info / floor}}}


def rows(runs: int = 15) -> list[tuple[str, str, str]]:
    """Rows for ``make bench`` (``bench/run.py``): CPU and wall ratios to the floor."""
    res = measure(runs)
    out = [
        (
            "floor: `python -c 'import pinocchio, numpy'`",
            f"{1e3 * res['floor_cpu']:.0f} ms CPU, {1e3 * res['floor']:.0f} ms wall",  # type: ignore[operator]
            "-",
        )
    ]
    for k, v in res["commands"].items():  # type: ignore[attr-defined]
        out.append(
            (
                f"`pkdyn {k}` / floor",
                f"{v['cpu_ratio']:.2f}x CPU, {v['ratio']:.2f}x wall",
                "1.2x" if k == "info delta" else "-",
            )
        )
    return out


def main() -> None:
    """Print the medians and ratios (markdown)."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=30)
    ap.add_argument("--hyperfine", action="store_true")
    args = ap.parse_args()
    if args.hyperfine and not shutil.which("hyperfine"):
        sys.exit("hyperfine is not installed")
    res = hyperfine(args.runs) if args.hyperfine else measure(args.runs)
    cpu = "floor_cpu" in res
    print(
        f"floor `python -c 'import pinocchio, numpy'`: {1e3 * res['floor']:.0f} ms wall"
        + (f", {1e3 * res['floor_cpu']:.0f} ms CPU" if cpu else "")
        + " (medians)"
    )
    print("| command | wall | / floor | CPU | / floor (target 1.2x for info) |")
    print("|---|---|---|---|---|")
    for k, v in res["commands"].items():  # type: ignore[attr-defined]
        c = f"{1e3 * v['cpu']:.0f} ms | {v['cpu_ratio']:.2f}x" if cpu else "- | -"
        print(f"| `pkdyn {k}` | {1e3 * v['median']:.0f} ms | {v['ratio']:.2f}x | {c} |")


if __name__ == "__main__":
    main()
