"""Local worker processes: how many, and never outliving the process that started them.

pkdyn fans work out over local processes in three places (design studies,
:mod:`pkdyn.design.executors`; split workspace grids, :mod:`pkdyn.workspace.numeric`; the
samples of an identification, :mod:`pkdyn.identification.identify`, through :func:`fork_map`).
They start their workers with :func:`worker_init`, which ties each worker to its parent: on
Linux the kernel kills it when the parent dies (``PR_SET_PDEATHSIG``), and on every platform a
watchdog thread ends it within :data:`WATCH_PERIOD` once its parent is gone (the parent id
changes when an orphan is adopted). A study killed with ``kill -9`` therefore leaves no worker
behind. The workers also ignore Ctrl-C: the terminal sends SIGINT to the whole process group,
and the parent alone reports it (one line) and stops them.

:func:`worker_count` caps a requested number of workers at what the machine and the work justify
(the usable cores, the items to share out, the memory), saying so when it lowers a request.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
import warnings
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

__all__ = [
    "MEMORY_PER_WORKER",
    "WATCH_PERIOD",
    "can_fork",
    "fork_map",
    "usable_cores",
    "worker_count",
    "worker_init",
]

S = TypeVar("S")
J = TypeVar("J")
R = TypeVar("R")

WATCH_PERIOD = 0.5
"""How often a worker checks that its parent is alive [s]."""

MEMORY_PER_WORKER = 250 * 2**20
"""Memory a worker process may use [bytes] (a study worker holds about 130 MB)."""

_PR_SET_PDEATHSIG = 1


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity where the platform tells it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def _available_memory() -> int | None:
    """Memory available to new processes [bytes] (Linux ``MemAvailable``), else ``None``."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def worker_count(requested: int | None, items: int, what: str = "workers") -> int:
    """Number of local worker processes to start for ``items`` pieces of work.

    At most the usable cores (more processes than cores only share them), the number of items
    (an idle worker costs memory and start-up time) and what the available memory holds at
    :data:`MEMORY_PER_WORKER` each; at least 1.

    Args:
        requested: Workers asked for (``None``: as many as are useful).
        items: Pieces of work to share out.
        what: Name of the option, for the message.

    Returns:
        The number of workers; a warning says why when it is below ``requested``.

    """
    limits = {"usable cores": usable_cores(), "items of work": max(1, int(items))}
    memory = _available_memory()
    if memory is not None:
        limits["available memory"] = max(1, memory // MEMORY_PER_WORKER)
    cap = min(limits.values())
    if requested is None:
        return cap
    n = int(requested)
    if n > cap:
        why = min(limits, key=lambda k: limits[k])
        detail = {
            "usable cores": f"this machine has {limits['usable cores']} usable cores",
            "items of work": f"there are {limits['items of work']} to share out",
            "available memory": f"the available memory holds {cap} "
            f"(~{MEMORY_PER_WORKER // 2**20} MB each)",
        }[why]
        warnings.warn(f"{what}: {n} requested, {cap} started ({detail})", UserWarning, stacklevel=2)
        return cap
    return n


def _watch(parent: int) -> None:
    while True:
        time.sleep(WATCH_PERIOD)
        if os.getppid() != parent:
            os._exit(1)


def worker_init(parent: int) -> None:
    """Initialise a worker process: tied to ``parent``, deaf to Ctrl-C and SIGTERM handlers.

    Pass it as the ``initializer`` of a process pool with ``initargs=(os.getpid(),)``.

    Args:
        parent: Process id of the process that starts the pool.

    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent reports an interruption
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # not the parent's handler (a traceback)
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no prctl: the watchdog remains
            pass
    if os.getppid() != parent:  # the parent died while this worker started
        os._exit(1)
    threading.Thread(target=_watch, args=(parent,), daemon=True, name="pkdyn-parent").start()


def can_fork() -> bool:
    """Whether worker processes can be forked here (POSIX; not on Windows)."""
    import multiprocessing

    return "fork" in multiprocessing.get_all_start_methods()


def _run(fn: Callable[[Any, Any], Any], shared: Any, job: Any, send: Any, parent: int) -> None:
    """A forked worker: one job, its result (or its exception) sent back through a pipe."""
    worker_init(parent)
    try:
        message: tuple[str, Any] = ("ok", fn(shared, job))
    except BaseException as err:  # noqa: BLE001 - every failure goes back to the parent
        message = ("error", err)
    try:
        send.send(message)
    except Exception:  # noqa: BLE001 - an unpicklable exception: its text instead
        send.send(("error", RuntimeError(f"{type(message[1]).__name__}: {message[1]}")))
    finally:
        send.close()


def fork_map(fn: Callable[[S, J], R], shared: S, jobs: Sequence[J]) -> list[R]:
    """``[fn(shared, job) for job in jobs]``, each job in its own forked worker process.

    The workers are forked: ``fn`` and ``shared`` (a robot, arrays of samples...) reach them as
    this process's memory, not pickled, and no module holds them in a global; each result comes
    back pickled through a pipe. The workers are tied to this process (:func:`worker_init`: they
    die with it and ignore Ctrl-C); an exception raised in a worker is raised here as it was
    (pickled), and an interruption or an error here stops every worker before it propagates.

    Args:
        fn: The work of one job: ``fn(shared, job)``; its result must pickle.
        shared: What every job reads.
        jobs: One item per worker process.

    Returns:
        The results, in the order of ``jobs``.

    Raises:
        RuntimeError: A worker died without a result (killed, out of memory).
        Exception: What a worker raised.

    """
    import multiprocessing

    ctx = multiprocessing.get_context("fork")
    parent = os.getpid()
    procs, pipes = [], []
    try:
        for job in jobs:
            recv, send = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_run, args=(fn, shared, job, send, parent), daemon=True)
            proc.start()
            send.close()
            procs.append(proc)
            pipes.append(recv)
        out: list[R] = []
        for proc, recv in zip(procs, pipes, strict=True):
            try:
                status, value = recv.recv()
            except EOFError:
                proc.join()
                raise RuntimeError(
                    f"worker process {proc.pid} ended without a result (exit code "
                    f"{proc.exitcode}: killed or out of memory)"
                ) from None
            if status == "error":
                raise value
            out.append(value)
        return out
    finally:
        for proc in procs:
            if proc.is_alive():
                proc.kill()
        for proc in procs:
            proc.join()
        for recv in pipes:
            recv.close()
