"""Real processes for the tests: a Dask scheduler and workers, a pkdyn command, their children.

Every process is started in its own session (its own process group), bounded in time, and
killed with its group by :meth:`Processes.close` (a fixture's finaliser), whatever the test's
outcome.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

DASK = Path(sys.executable).parent / "dask"
"""The ``dask`` command of this environment."""

START_TIMEOUT = 90.0
"""Longest wait for a scheduler or a worker to start [s] (a loaded machine imports slowly)."""


def wait_for(predicate, timeout: float, what: str, period: float = 0.05) -> None:
    """Poll ``predicate()`` until it is true; fail the test after ``timeout`` seconds."""
    end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
        time.sleep(period)


def children(pid: int) -> list[int]:
    """Process ids whose parent is ``pid`` (from ``/proc``)."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            fields = stat.rsplit(")", 1)[1].split()
            if int(fields[1]) == pid:
                out.append(int(entry.name))
    return out


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie does not count)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def data_rows(path: Path) -> int:
    """Finished designs in a partial study file (its two first lines are headers)."""
    try:
        lines = path.read_text().splitlines()
    except OSError:
        return 0
    return max(0, len(lines) - 2)


class Processes:
    """Processes started by a test, each in its own session; all killed by :meth:`close`."""

    def __init__(self, workdir: Path) -> None:
        self.workdir = workdir
        self.procs: list[subprocess.Popen] = []

    def start(self, args: list[str], name: str, env: dict[str, str] | None = None):
        log = open(self.workdir / f"{name}.log", "w")  # noqa: SIM115 - closed with the process
        proc = subprocess.Popen(
            [str(a) for a in args],
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            env={**os.environ, **(env or {})},
            cwd=self.workdir,
        )
        proc.log = log  # type: ignore[attr-defined]
        self.procs.append(proc)
        return proc

    def kill(self, proc: subprocess.Popen) -> None:
        """SIGKILL a process and its group, and reap it."""
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:  # pragma: no cover
            pass

    def close(self) -> None:
        for proc in self.procs:
            self.kill(proc)
            proc.log.close()  # type: ignore[attr-defined]
        self.procs.clear()


class DaskCluster(Processes):
    """``dask scheduler`` on 127.0.0.1 (a free port) and ``dask worker`` processes."""

    def __init__(self, workdir: Path) -> None:
        super().__init__(workdir)
        self.address = ""
        self.scheduler: subprocess.Popen | None = None
        self.workers: list[subprocess.Popen] = []
        self._file = workdir / "scheduler.json"

    def start_scheduler(self) -> str:
        self._file.unlink(missing_ok=True)
        self.scheduler = self.start(
            [
                DASK,
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                self._file,
            ],  # fmt: skip
            "scheduler",
        )
        wait_for(self._file.exists, START_TIMEOUT, "the Dask scheduler")
        wait_for(lambda: bool(self._file.read_text().strip()), 5.0, "the scheduler file")
        self.address = json.loads(self._file.read_text())["address"]
        return self.address

    def add_worker(self, env: dict[str, str] | None = None) -> subprocess.Popen:
        proc = self.start(
            [
                DASK,
                "worker",
                self.address,
                "--no-nanny",
                "--nthreads",
                "1",
                "--no-dashboard",
                "--death-timeout",
                "20",
            ],  # fmt: skip
            f"worker{len(self.workers)}",
            env,
        )
        self.workers.append(proc)
        return proc

    def wait_workers(self, n: int) -> None:
        """Until the scheduler counts ``n`` workers."""
        from distributed import Client

        with Client(self.address, timeout=30, set_as_default=False) as client:
            client.wait_for_workers(n, timeout=START_TIMEOUT)
            wait_for(lambda: len(client.nthreads()) == n, 30.0, f"{n} workers")


def serial_table(directory: Path, study: list[str]) -> str:
    """The table of ``pkdyn <study> --workers 1`` run in this process, with no test pause."""
    import pytest

    from pkdyn.cli import main

    out = directory / "serial.csv"
    mp = pytest.MonkeyPatch()
    mp.setenv("PKDYN_TEST_DELAY", "0")
    try:
        assert main([*study, "--workers", "1", "--out", str(out)]) == 0
    finally:
        mp.undo()
    return out.read_text()
