"""Local worker processes: how many, and never outliving the process that started them.

pkdyn fans work out over local processes in two places (design studies,
:mod:`pkdyn.design.executors`; split workspace grids, :mod:`pkdyn.workspace.numeric`). Both
start their workers with :func:`worker_init`, which ties each worker to its parent: on Linux the
kernel kills it when the parent dies (``PR_SET_PDEATHSIG``), and on every platform a watchdog
thread ends it within :data:`WATCH_PERIOD` once its parent is gone (the parent id changes when
an orphan is adopted). A study killed with ``kill -9`` therefore leaves no worker behind. The
workers also ignore Ctrl-C: the terminal sends SIGINT to the whole process group, and the parent
alone reports it (one line) and stops them.

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

__all__ = ["MEMORY_PER_WORKER", "WATCH_PERIOD", "usable_cores", "worker_count", "worker_init"]

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
