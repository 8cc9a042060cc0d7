"""Design studies on a real Dask cluster, started as a cluster user starts one.

``dask scheduler --host 127.0.0.1`` and ``dask worker ADDRESS`` processes (each in its own
process group, killed with it at the end whatever happens), and ``pkdyn design ... --scheduler
ADDRESS``: the table is the local run's, byte for byte; a worker killed during the study: the
study finishes on the others, no row lost or duplicated; the scheduler killed during the study:
one line, exit 1, and the same command resumes the study from its partial file (locally here),
to the same table; a scheduler that accepts connections and never answers, or a cluster without
workers: one line within ``--timeout``.
"""

import socket
import threading
import time
from pathlib import Path

import pytest
from support.processes import DASK, DaskCluster, data_rows, serial_table, wait_for

from pkdyn.cli import main
from pkdyn.design.table import output_paths

pytestmark = pytest.mark.skipif(not DASK.exists(), reason="the dask command is not installed")

PLUGIN = str(Path(__file__).parent / "support" / "slow_metric.py")

STUDY = ["design", "delta", "--range", "la=0.2:0.3", "lb=0.4:0.6", "--metric", "slow_mass",
         "clavel_D", "--n", "16", "--seed", "4", "--plugin", PLUGIN, "--json"]  # fmt: skip
"""A study of 16 Deltas; ``slow_mass`` (a plug-in shipped by value) sleeps on the workers."""


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    c = DaskCluster(tmp_path_factory.mktemp("dask"))
    try:
        c.start_scheduler()
        c.add_worker()
        c.add_worker()
        c.wait_workers(2)
        yield c
    finally:
        c.close()


@pytest.fixture(scope="module")
def local_table(tmp_path_factory):
    """The study's table from a serial run in this process (no pause)."""
    return serial_table(tmp_path_factory.mktemp("local"), STUDY)


def _killer(path: Path, kill, rows: int = 2) -> threading.Thread:
    """A thread that calls ``kill()`` once ``path`` holds ``rows`` finished designs."""

    def run():
        wait_for(lambda: data_rows(path) >= rows, 120.0, "the first designs")
        kill()

    t = threading.Thread(target=run, daemon=True)
    t.start()
    return t


def _indices(csv_text: str) -> list[int]:
    return [int(line.split(",")[0]) for line in csv_text.splitlines()[1:]]


def test_cli_on_a_cluster_gives_the_local_table(cluster, local_table, tmp_path, capsys):
    out = tmp_path / "dask.csv"
    assert main([*STUDY, "--scheduler", cluster.address, "--out", str(out)]) == 0
    assert "Dask cluster at tcp://127.0.0.1" in capsys.readouterr().out
    assert out.read_text() == local_table


def test_the_workers_keep_their_freed_memory(cluster, tmp_path):
    """A Dask worker's heap is set as a pool worker's before its first chunk.

    Without it a Delta study's arrays fault in again at every design on the cluster (0.6 ms of
    system time per design: a third of the cluster path's overhead, bench/design.py).
    """
    from distributed import Client

    assert main([*STUDY, "--scheduler", cluster.address, "--out", str(tmp_path / "h.csv")]) == 0
    with Client(cluster.address, set_as_default=False, timeout=30) as client:
        kept = client.run(lambda: __import__("pkdyn.executors", fromlist=["_"])._HEAP_KEPT)
    assert kept and any(v == [True] for v in kept.values()), kept


def test_a_killed_worker_the_study_finishes_on_the_others(cluster, local_table, tmp_path):
    victim = cluster.add_worker()
    cluster.wait_workers(3)
    out = tmp_path / "w.csv"
    killer = _killer(output_paths(out)["partial"], lambda: cluster.kill(victim))
    assert main([*STUDY, "--scheduler", cluster.address, "--out", str(out)]) == 0
    killer.join(5.0)
    assert victim.poll() is not None  # it was killed during the study
    assert out.read_text() == local_table
    assert _indices(out.read_text()) == list(range(16))  # none lost, none repeated


def test_a_killed_scheduler_stops_with_one_line_and_the_study_resumes(
    local_table, tmp_path, capsys
):
    c = DaskCluster(tmp_path)
    try:
        address = c.start_scheduler()
        # no worker yet: refused within the timeout
        t0 = time.monotonic()
        assert main([*STUDY, "--scheduler", address, "--timeout", "1"]) == 1
        err = capsys.readouterr().err
        assert err.startswith("pkdyn: error: scheduler") and "no worker for 1 s" in err
        assert len(err.strip().splitlines()) == 1 and time.monotonic() - t0 < 30
        c.add_worker()
        c.wait_workers(1)
        out = tmp_path / "s.csv"
        partial = output_paths(out)["partial"]
        killer = _killer(partial, lambda: c.kill(c.scheduler))
        code = main([*STUDY, "--scheduler", address, "--out", str(out)])
        killer.join(5.0)
        err = capsys.readouterr().err
    finally:
        c.close()
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"pkdyn: error: scheduler {address}:") and "resume" in err
    assert not out.exists()
    kept = data_rows(partial)
    assert 2 <= kept < 16
    import sys

    sys.modules["slow_metric"].CALLS[0] = 0
    mp = pytest.MonkeyPatch()
    mp.setenv("PKDYN_TEST_DELAY", "0")
    try:
        assert main([*STUDY, "--workers", "1", "--out", str(out)]) == 0
    finally:
        mp.undo()
    assert out.read_text() == local_table
    assert sys.modules["slow_metric"].CALLS[0] == 16 - kept  # only the others evaluated


def test_a_scheduler_that_never_answers(tmp_path, capsys):
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    port = server.getsockname()[1]
    accepted = []

    def accept():
        try:
            while True:
                accepted.append(server.accept()[0])  # and never a word
        except OSError:
            pass

    threading.Thread(target=accept, daemon=True).start()
    t0 = time.monotonic()
    try:
        code = main([*STUDY, "--scheduler", f"tcp://127.0.0.1:{port}", "--timeout", "1"])
    finally:
        server.close()
        for conn in accepted:
            conn.close()
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1
    assert "no answer within 1 s (--timeout)" in err
    assert time.monotonic() - t0 < 15  # not distributed's unbounded handshake


def test_a_worker_without_the_plugin_is_one_line(cluster, tmp_path, monkeypatch, capsys):
    """A plug-in loaded by module name must be installed on the workers: one line says so."""
    (tmp_path / "only_here.py").write_text(
        "from pkdyn.design import Metric\n"
        "def one(robot, ctx):\n    return 1.0\n"
        "here = Metric('here', '-', one)\n"  # a named function: pickled by reference
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    code = main(["design", "delta", "--range", "la=0.2:0.3", "--metric", "only_here:here",
                 "--n", "2", "--plugin", "only_here", "--scheduler", cluster.address])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert "a worker failed (ModuleNotFoundError" in err and "plug-ins installed" in err
