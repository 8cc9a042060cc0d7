"""Local worker processes: capped at what the machine and the work justify, never outliving
their study.

A study run by ``pkdyn design --workers 2`` in a process of its own: killed with SIGKILL (no
handler runs), its workers end within a second (kernel parent-death signal, and a watchdog);
interrupted with Ctrl-C (SIGINT to the whole process group) or SIGTERM (to the study alone), one
line, exit 130 or 143, no worker left, and the same command resumes from the partial file to the
table a serial run gives.
"""

import os
import signal
import sys
import warnings
from pathlib import Path

import pytest
from support.processes import Processes, alive, children, data_rows, serial_table, wait_for

import pkdyn.workers as workers_mod
from pkdyn.cli import main
from pkdyn.design.executors import ProcessExecutor, SerialExecutor, make_executor
from pkdyn.design.table import output_paths
from pkdyn.exceptions import InvalidInputError
from pkdyn.workers import worker_count

PLUGIN = str(Path(__file__).parent / "support" / "slow_metric.py")
STUDY = ["design", "delta", "--range", "la=0.2:0.3", "--metric", "slow_mass", "--n", "24",
         "--plugin", PLUGIN]  # fmt: skip


@pytest.mark.parametrize(
    "requested, items, cores, expected, why",
    [
        (1000, 4, 2, 2, "2 usable cores"),
        (1000, 4, 64, 4, "there are 4 to share out"),
        (3, 100, 8, 3, None),
        (None, 100, 8, 8, None),
        (None, 3, 8, 3, None),
    ],
)
def test_workers_are_capped_with_a_message(monkeypatch, requested, items, cores, expected, why):
    monkeypatch.setattr(workers_mod, "usable_cores", lambda: cores)
    monkeypatch.setattr(workers_mod, "_available_memory", lambda: None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert worker_count(requested, items, "--workers") == expected
    if why is None:
        assert not caught
    else:
        assert len(caught) == 1 and why in str(caught[0].message)
        assert f"{requested} requested, {expected} started" in str(caught[0].message)


def test_memory_caps_the_workers(monkeypatch):
    monkeypatch.setattr(workers_mod, "usable_cores", lambda: 64)
    monkeypatch.setattr(workers_mod, "_available_memory", lambda: 3 * workers_mod.MEMORY_PER_WORKER)
    with pytest.warns(UserWarning, match="available memory holds 3"):
        assert worker_count(16, 100) == 3


@pytest.mark.parametrize("bad", [0, -1, 2.5, True, "2"])
def test_bad_worker_counts_are_refused(bad):
    with pytest.raises(InvalidInputError, match="workers"):
        make_executor(workers=bad)


def test_executor_for_a_thousand_workers_and_four_designs(monkeypatch):
    monkeypatch.setattr(workers_mod, "usable_cores", lambda: 64)
    with pytest.warns(UserWarning, match="1000 requested, 4 started"):
        ex = make_executor(workers=1000, designs=4)
    assert isinstance(ex, ProcessExecutor) and ex.workers == 4
    with pytest.warns(UserWarning):
        assert isinstance(make_executor(workers=5, designs=1), SerialExecutor)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The study's table from a serial run in this process (no pause)."""
    return serial_table(tmp_path_factory.mktemp("ref"), STUDY)


@pytest.fixture
def procs(tmp_path):
    p = Processes(tmp_path)
    yield p
    p.close()


def _study_process(procs, out):
    """``pkdyn design ... --workers 2`` in its own process group, once its workers work."""
    env = {"PKDYN_TEST_DELAY": "0.1", "PYTHONPATH": str(Path(__file__).parents[1])}
    proc = procs.start(
        [sys.executable, "-m", "pkdyn", *STUDY, "--workers", "2", "--out", out], "study", env
    )
    wait_for(lambda: data_rows(output_paths(out)["partial"]) >= 1, 120.0, "the first designs")
    kids = children(proc.pid)
    assert len(kids) >= 2, kids
    return proc, kids


def test_workers_never_outlive_their_study(procs, tmp_path):
    out = tmp_path / "k.csv"
    proc, kids = _study_process(procs, out)
    os.kill(proc.pid, signal.SIGKILL)  # no handler, no cleanup code runs
    proc.wait(10)
    wait_for(lambda: not any(alive(k) for k in kids), 10.0, "the orphaned workers to end")


@pytest.mark.parametrize(
    "how, code, line",
    [("ctrl-c", 130, "pkdyn: interrupted"), ("sigterm", 143, "pkdyn: terminated")],
)
def test_signals_one_line_no_worker_left_and_the_study_resumes(
    procs, reference, tmp_path, monkeypatch, how, code, line
):
    out = tmp_path / "i.csv"
    proc, kids = _study_process(procs, out)
    if how == "ctrl-c":
        os.killpg(proc.pid, signal.SIGINT)  # what the terminal does: the whole group
    else:
        os.kill(proc.pid, signal.SIGTERM)  # what a batch system does: the study alone
    assert proc.wait(60) == code
    log = (tmp_path / "study.log").read_text()
    assert log.strip().splitlines()[-1] == line, log
    assert "Traceback" not in log and len(log.strip().splitlines()) == 1, log
    wait_for(lambda: not any(alive(k) for k in kids), 10.0, "the workers to end")
    assert not out.exists()
    kept = data_rows(output_paths(out)["partial"])
    assert 1 <= kept < 24
    monkeypatch.setenv("PKDYN_TEST_DELAY", "0")
    from pkdyn.design import load_plugin

    calls = load_plugin(PLUGIN).CALLS
    calls[0] = 0
    assert main([*STUDY, "--workers", "1", "--out", str(out)]) == 0
    assert calls[0] <= 24 - kept
    assert out.read_text() == reference


def test_a_dead_worker_is_one_line(procs, tmp_path):
    """A worker killed from outside (the OOM killer): one line, the designs done kept."""
    out = tmp_path / "d.csv"
    proc, kids = _study_process(procs, out)
    os.kill(kids[-1], signal.SIGKILL)
    assert proc.wait(60) == 1
    log = (tmp_path / "study.log").read_text().strip().splitlines()
    assert len(log) == 1 and log[0].startswith("pkdyn: error: workers:"), log
    assert "a local worker process died" in log[0] and "resume" in log[0]
    assert data_rows(output_paths(out)["partial"]) >= 1 and not out.exists()
    wait_for(lambda: not any(alive(k) for k in kids), 10.0, "the other workers to end")


def _sleepy_chunk(payload, chunk):
    import time

    time.sleep(payload)
    return chunk


def test_a_broken_pool_is_stopped_before_close_returns():
    """After a worker died, ``close(abort=True)`` returns with the pool's manager thread stopped
    and its wake-up pipe closed: CPython 3.11's exit hook writes to the pipes of the managers
    still alive, and one closing meanwhile printed a "Bad file descriptor" traceback after the
    study's one line (seen once in ``test_a_dead_worker_is_one_line``)."""
    from concurrent.futures import process as cf_process

    from pkdyn.exceptions import StudyError

    ex = ProcessExecutor(2)
    chunks = ex.map_chunks(_sleepy_chunk, 0.2, [[k] for k in range(8)])
    assert next(chunks) in ([0], [1], [2], [3], [4], [5], [6], [7])
    pool = ex._pool
    manager = pool._executor_manager_thread
    wakeup = cf_process._threads_wakeups[manager]
    os.kill(next(iter(pool._processes)), signal.SIGKILL)
    with pytest.raises(StudyError, match="worker process died"):
        list(chunks)
    ex.close(abort=True)
    assert not manager.is_alive() and wakeup._closed
