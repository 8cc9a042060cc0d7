"""The contract in real processes: signals during work, and memory and CPU limits.

Signals (``test_contract_signals_...``): a command at work gets SIGINT or SIGTERM; it ends with
one line (``pkdyn: interrupted`` / ``pkdyn: terminated``), exit 130 or 143, no traceback, its
output file as it was and no temporary left.

Limits (``test_contract_unbounded_...``): a sample of inputs that would need unbounded memory or
time, run under ``resource.setrlimit`` (address space, CPU seconds): each is refused up front
with one line, never killed by the limit and never ``out of memory``.
"""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

SLOW_METRIC = Path(__file__).resolve().parents[1] / "support" / "slow_metric.py"

READY = "import sys; from pkdyn.cli import main; print('ready', flush=True); sys.exit(main({}))"

LONG_RUNS = {
    "size": ["size", "delta", "--cycles", "400", "--csv", "{out}"],
    "simulate": ["simulate", "five_bar", "--duration", "600", "--dt", "0.001", "--csv", "{out}"],
    # the numeric path (~8 s): the closed form's 512,000 poses now end within the 2 s wait
    "workspace": ["workspace", "gough_stewart", "--samples", "40", "--method", "numeric",
                  "--plot", "{out}.png"],
    "design": ["design", "delta", "--plugin", str(SLOW_METRIC), "--range", "la=0.2:0.3",
               "--metric", "slow_mass", "--n", "400", "--workers", "1", "--out", "{out}"],
}  # fmt: skip


def _spawn(argv: list[str], env: dict[str, str] | None = None, limits=None) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-c", READY.format(argv)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        preexec_fn=limits,
        start_new_session=True,
    )


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()


@pytest.mark.slow
@pytest.mark.parametrize("command", list(LONG_RUNS))
@pytest.mark.parametrize(
    "sig, code, word", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")]
)
def test_contract_signals_during_work(tmp_path, command, sig, code, word):
    out = tmp_path / "out.csv"
    target = out if command != "workspace" else tmp_path / "out.csv.png"
    target.write_text("previous results\n")
    argv = [a.replace("{out}", str(out)) for a in LONG_RUNS[command]]
    env = dict(os.environ, PKDYN_TEST_DELAY="0.05")
    proc = _spawn(argv, env)
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == "ready"
        time.sleep(2.0)  # inside main(): loading, then at work
        assert proc.poll() is None, proc.communicate()
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        _stop(proc)
    assert proc.returncode == code, err[-2000:]
    lines = [ln for ln in err.splitlines() if ln.startswith("pkdyn:") and "warning" not in ln]
    assert lines == [f"pkdyn: {word}"], err[-2000:]
    assert "Traceback" not in err
    assert target.read_text() == "previous results\n"
    left = sorted(p.name for p in tmp_path.iterdir())
    if command == "design":  # the designs finished before the signal: the documented resume file
        partial = tmp_path / ".out.partial.csv"
        if partial.exists():
            left.remove(partial.name)
            head = partial.read_text()[:200]
            assert head.startswith("# pkdyn design study "), head
    assert left == [target.name]  # no temporary left


MEMORY = 3 << 30  # [bytes]: far more than any refused case needs, far less than the machine
CPU = 60  # [s]


def _limits() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))
    resource.setrlimit(resource.RLIMIT_CPU, (CPU, CPU))


UNBOUNDED = {
    "samples": ["workspace", "delta", "--samples", "100000"],
    "duration": ["simulate", "five_bar", "--duration", "1e9"],
    "dt": ["size", "delta", "--dt", "1e-12"],
    "cycles": ["size", "delta", "--cycles", "1000000000"],
    "grid": ["accuracy", "delta", "--map", "xy", "--grid", "100000"],
    "designs": ["design", "delta", "--range", "la=0.2:0.3", "--metric", "moving_mass", "--n",
                "1000000000000"],
    "n1": ["workspace", "gough_stewart", "--kind", "orientation", "--n1", "1000000",
           "--n2", "1000000"],
    "swing": ["tripod", "scenario", "--no-machining", "--swing-time", "1e9"],
    "points_zero": ["view", "five_bar", "--qa", "1.2", "1.9", "--html", "{tmp}/v.html",
                    "--points", "/dev/zero"],
    "trajectory_zero": ["size", "delta", "--trajectory", "/dev/zero"],
}  # fmt: skip


@pytest.mark.parametrize("case", list(UNBOUNDED))
def test_contract_unbounded_work_is_refused_under_limits(tmp_path, case):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in UNBOUNDED[case]]
    proc = _spawn(argv, limits=_limits)
    try:
        _, err = proc.communicate(timeout=120)
    finally:
        _stop(proc)
    assert proc.returncode in (1, 2), f"exit {proc.returncode} (killed by a limit?)\n{err[-1500:]}"
    errors = [ln for ln in err.splitlines() if ln.startswith("pkdyn: error:")]
    assert len(errors) == 1 and "Traceback" not in err, err[-1500:]
    assert "out of memory" not in errors[0], errors[0]


def test_contract_unbounded_memory_limit_is_effective():
    """The limit the cases above run under does stop a real allocation (the check has teeth)."""
    code = "import numpy as np; np.ones(int(1e10))"
    proc = subprocess.run(
        [sys.executable, "-c", code], preexec_fn=_limits, capture_output=True, text=True,
        timeout=120, check=False,
    )  # fmt: skip
    assert proc.returncode != 0 and "MemoryError" in proc.stderr
