"""Where independent pieces of work run: in this process, in local worker processes, or on Dask.

Every executor runs ``fn(payload, chunk)`` on chunks of work (the designs of a study, the
robots of a Monte Carlo, the poses of a precision map) and yields each chunk's result as it
completes (any order: the callers sort by index, so their results do not depend on the
executor; :func:`ordered` does it for a list of chunks). :func:`make_executor` picks one:

- ``workers=1``: :class:`SerialExecutor`, in this process;
- ``workers=N`` (default: as many as the machine and the study justify,
  :func:`pkdyn.workers.worker_count`): :class:`ProcessExecutor`, a pool of local worker
  processes (forked when this process runs no other thread, else spawned; a script that spawns
  needs the usual ``if __name__ == "__main__":`` guard), tied to this process: they die with it
  (:func:`pkdyn.workers.worker_init`);
- ``client=`` a :class:`distributed.Client`, or ``scheduler="tcp://host:8786"``:
  :class:`DaskExecutor` on a Dask cluster (its workers need pkdyn installed, and the plug-ins
  the study uses).

Failures of the machinery, never of a design, stop the study with a
:class:`~pkdyn.exceptions.StudyError` of one line: a local worker process that died (killed, out
of memory), a scheduler that cannot be reached, does not answer within ``timeout`` or is lost
during the study, a cluster left without workers for ``timeout`` seconds, a design that killed
its Dask workers repeatedly. A Dask worker lost during the study is not a failure: its designs
are evaluated again on the others. The designs finished before a failure are in the partial
file (:mod:`pkdyn.design.table`), so the same command resumes the study.
"""

from __future__ import annotations

import asyncio
import logging
import math
import multiprocessing
import numbers
import os
import sys
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, CancelledError, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from pkdyn.exceptions import InvalidInputError, PkdynError, StudyError
from pkdyn.workers import worker_count, worker_init

__all__ = [
    "MAX_TIMEOUT",
    "DaskExecutor",
    "Executor",
    "ProcessExecutor",
    "SerialExecutor",
    "check_scheduler",
    "check_timeout",
    "make_executor",
    "ordered",
]

ChunkFn = Callable[[Any, list[Any]], list[Any]]

MAX_TIMEOUT = 3600.0
"""Longest wait accepted for a scheduler or for workers [s]."""

_POLL = 0.02
"""Pause between looks at a Dask study with nothing finished [s]."""

_HEALTH_PERIOD = 1.0
"""Period of the Dask cluster's health check during a study [s]."""


def check_timeout(timeout: Any, name: str = "timeout") -> float:
    """A wait in seconds: a finite number in ``(0, MAX_TIMEOUT]``.

    Raises:
        InvalidInputError: Not a number, not finite, not positive or above :data:`MAX_TIMEOUT`.

    """
    if isinstance(timeout, bool) or not isinstance(timeout, int | float):
        raise InvalidInputError(name, f"expected a number of seconds, got {timeout!r}")
    t = float(timeout)
    if not (math.isfinite(t) and 0.0 < t <= MAX_TIMEOUT):
        raise InvalidInputError(
            name, f"must be a number of seconds in (0, {MAX_TIMEOUT:g}], got {timeout!r}"
        )
    return t


def check_scheduler(address: Any, name: str = "scheduler") -> str | None:
    """A Dask scheduler's address (``tcp://host:8786``), or ``None`` for none.

    Raises:
        InvalidInputError: Not a string, or an empty one (it would mean no scheduler).

    """
    if address is not None and (not isinstance(address, str) or not address.strip()):
        raise InvalidInputError(name, f"expected an address (tcp://host:8786), got {address!r:.40}")
    return address


_TRIM_THRESHOLD = 32 << 20
"""Freed memory a pool worker's heap keeps [bytes] (glibc ``M_TRIM_THRESHOLD``)."""

_MMAP_THRESHOLD = 1 << 20
"""Largest block a pool worker's heap serves itself [bytes] (glibc ``M_MMAP_THRESHOLD``)."""


def _pool_worker_init(parent: int) -> None:
    """:func:`pkdyn.workers.worker_init`, then the worker's heap kept (:func:`_keep_heap`)."""
    worker_init(parent)
    _keep_heap()


def _keep_heap() -> None:
    """Keep a worker's freed memory in its heap (glibc), instead of faulting it in again.

    A worker allocates and frees the same arrays task after task (a design study: arrays of
    100-250 kB per design). With glibc's default, dynamic, thresholds some runs hand them to
    ``mmap`` or trim the heap top after each task, and every page of them faults again: 0.1-0.6 ms
    of system time per Delta design. Only in the pool's workers (not in the caller's process);
    nothing on other C libraries.
    """
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # pragma: no cover - not glibc
        return
    mallopt(-1, _TRIM_THRESHOLD)  # M_TRIM_THRESHOLD
    mallopt(-3, _MMAP_THRESHOLD)  # M_MMAP_THRESHOLD


_HEAP_KEPT: list[bool] = []
"""Whether this process keeps its freed memory already (:func:`_on_worker`)."""


def _on_worker(fn: ChunkFn, payload: Any, chunk: list[Any]) -> Any:
    """``fn(payload, chunk)`` on a Dask worker, its heap kept first (:func:`_keep_heap`).

    A Dask worker is a process of the cluster's, not of the pool: its heap is set the way the
    pool's workers' is on the first chunk it runs (without it, a Delta study's arrays fault in
    again at every design: 0.6 ms of system time per design, a third of the cluster path's
    overhead).
    """
    if not _HEAP_KEPT:
        _keep_heap()
        _HEAP_KEPT.append(True)
    return fn(payload, chunk)


def _first_line(err: BaseException) -> str:
    text = str(err).strip()
    return f"{type(err).__name__}: {text.splitlines()[0]}" if text else type(err).__name__


class Executor(ABC):
    """Runs chunks of work; a context manager that releases its workers on exit.

    Attributes:
        workers: Number of workers (for chunk sizing).
        name: Description for reports.

    """

    workers = 1
    name = ""

    @abstractmethod
    def map_chunks(self, fn: ChunkFn, payload: Any, chunks: Sequence[list[Any]]) -> Iterator[Any]:
        """Yield ``fn(payload, chunk)`` for every chunk, as they complete."""

    def close(self, abort: bool = False) -> None:  # noqa: B027 (most executors hold nothing)
        """Release the workers (``abort``: stop them now, their work is abandoned)."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, exc_type: object, *exc: object) -> None:
        self.close(abort=exc_type is not None)


class SerialExecutor(Executor):
    """Everything in this process, in order."""

    name = "serial (this process)"

    def map_chunks(self, fn: ChunkFn, payload: Any, chunks: Sequence[list[Any]]) -> Iterator[Any]:
        """See :meth:`Executor.map_chunks`."""
        for chunk in chunks:
            yield fn(payload, chunk)


class ProcessExecutor(Executor):
    """A pool of local worker processes (started on first use, kept until :meth:`close`).

    The workers are tied to this process (:func:`pkdyn.workers.worker_init`): killed, even
    with SIGKILL, it leaves none behind.

    Args:
        workers: Number of processes.

    """

    def __init__(self, workers: int) -> None:
        self.workers = int(workers)
        self.name = f"{self.workers} local worker processes"
        self._pool: ProcessPoolExecutor | None = None

    def _get_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            fork = "fork" in multiprocessing.get_all_start_methods()
            method = "fork" if fork and threading.active_count() == 1 else "spawn"
            self._pool = ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=multiprocessing.get_context(method),
                initializer=_pool_worker_init,
                initargs=(os.getpid(),),
            )
        return self._pool

    def map_chunks(self, fn: ChunkFn, payload: Any, chunks: Sequence[list[Any]]) -> Iterator[Any]:
        """See :meth:`Executor.map_chunks` (at most ``4 x workers`` chunks in flight).

        Raises:
            StudyError: A worker process died (killed, out of memory).

        """
        pool = self._get_pool()
        todo = list(chunks)[::-1]
        running: set[Future[Any]] = set()
        try:
            while todo or running:
                while todo and len(running) < 4 * self.workers:
                    running.add(pool.submit(fn, payload, todo.pop()))
                done, running = wait(running, return_when=FIRST_COMPLETED)
                for fut in done:
                    yield fut.result()
        except BrokenProcessPool:
            raise StudyError(
                "workers",
                "a local worker process died (killed, or out of memory); the designs finished "
                "are kept: run the same command again to resume (fewer --workers if memory ran "
                "out)",
            ) from None
        except BaseException:
            for fut in running:
                fut.cancel()
            raise

    def close(self, abort: bool = False) -> None:
        """Shut the pool down: pending chunks cancelled; ``abort``: running ones too."""
        if self._pool is None:
            return
        pool, self._pool = self._pool, None
        if not abort:
            pool.shutdown(wait=True, cancel_futures=True)
            return
        procs = list((getattr(pool, "_processes", None) or {}).values())
        # the pool's manager thread, joined below: CPython 3.11's exit hook wakes every live
        # manager through a pipe that the manager closes when it stops; a manager still
        # stopping at exit (after a worker died, or an abort) races it and the interpreter
        # prints an "Exception ignored ... Bad file descriptor" traceback after pkdyn's line
        manager = getattr(pool, "_executor_manager_thread", None)
        pool.shutdown(wait=False, cancel_futures=True)
        for p in procs:
            if p.is_alive():
                p.terminate()
        for p in procs:
            p.join(timeout=5.0)
        if isinstance(manager, threading.Thread) and manager is not threading.current_thread():
            manager.join(timeout=5.0)


def _probe_scheduler(address: str, timeout: float) -> None:
    """Connect to a Dask scheduler and read its handshake, within ``timeout`` seconds.

    distributed's own connection waits for the handshake without a deadline (a server that
    accepts the connection and never answers blocks ``Client()`` for ever).

    Raises:
        StudyError: No answer within ``timeout``, or the connection fails.

    """
    from distributed.comm import connect

    async def handshake() -> None:
        comm = await connect(address, timeout=timeout)
        await comm.close()

    try:  # (a margin: a refused connection is distributed's own error, at ``timeout``)
        asyncio.run(asyncio.wait_for(handshake(), timeout + max(0.5, 0.2 * timeout)))
    except (TimeoutError, asyncio.TimeoutError):
        raise StudyError(
            f"scheduler {address}",
            f"no answer within {timeout:g} s (--timeout): is it a Dask scheduler? start one "
            "with `dask scheduler`, or drop --scheduler to use local processes",
        ) from None
    except (OSError, ValueError, TypeError) as err:
        raise StudyError(
            f"scheduler {address}",
            f"cannot connect ({_first_line(err)}); start one with `dask scheduler` and workers "
            "with `dask worker ADDRESS`, or drop --scheduler to use local processes",
        ) from None


class DaskExecutor(Executor):
    """A Dask distributed cluster.

    Args:
        client: A connected :class:`distributed.Client` (left open on :meth:`close`), or
            ``None`` to connect to ``scheduler``.
        scheduler: Scheduler address (``tcp://host:8786``) when no client is given.
        timeout: How long to wait [s] for the scheduler to answer, and for a worker when the
            cluster has none (at the start or after losing them all).

    Raises:
        InvalidInputError: A bad timeout, neither client nor address.
        StudyError: The scheduler cannot be reached or does not answer.

    """

    def __init__(self, client: Any = None, scheduler: str | None = None, timeout: float = 10.0):
        self.timeout = check_timeout(timeout)
        self._own = client is None
        self._quiet: list[tuple[logging.Logger, int]] = []
        if client is None:
            if not scheduler or not isinstance(scheduler, str):
                raise InvalidInputError("scheduler", "give a Dask client or a scheduler address")
            try:
                from distributed import Client
            except ImportError:  # pragma: no cover - a dependency
                raise StudyError("scheduler", "Dask distributed is not installed") from None
            self._silence()
            _probe_scheduler(scheduler, self.timeout)
            try:
                client = Client(scheduler, timeout=self.timeout, set_as_default=False)
            except (OSError, TimeoutError, ValueError) as err:
                self._restore()
                raise StudyError(
                    f"scheduler {scheduler}", f"cannot connect ({_first_line(err)})"
                ) from None
        self.client = client
        self.address = str(client.scheduler.address)
        workers = self._nthreads()
        self.workers = max(1, sum(workers.values()))
        self.name = f"Dask cluster at {self.address} ({len(workers)} workers)"

    # ------------------------------------------------------------------ cluster state

    def _silence(self) -> None:
        """Keep distributed's connection logs off stderr (its failures come as StudyError)."""
        for name in ("distributed", "distributed.client", "distributed.comm", "tornado"):
            log = logging.getLogger(name)
            self._quiet.append((log, log.level))
            log.setLevel(logging.CRITICAL + 1)

    def _restore(self) -> None:
        for log, level in self._quiet:
            log.setLevel(level)
        self._quiet.clear()

    def _lost(self, what: str) -> StudyError:
        return StudyError(
            f"scheduler {self.address}",
            f"{what}; the designs finished are kept: run the same command again to resume",
        )

    def _nthreads(self) -> dict[str, int]:
        """Threads of each worker, asked of the scheduler within the timeout."""
        client = self.client
        if client.status not in ("running", "newly-created"):
            raise self._lost("the connection to the scheduler was lost")
        try:
            out = client.sync(client.scheduler.ncores, callback_timeout=self.timeout)
        except (OSError, TimeoutError, asyncio.TimeoutError) as err:
            raise self._lost(f"the scheduler stopped answering ({_first_line(err)})") from None
        return {str(k): int(v) for k, v in dict(out).items()}

    def _wait_for_workers(self, since: float | None = None) -> None:
        """Return once the cluster has a worker; raise after ``timeout`` s without one."""
        start = time.monotonic() if since is None else since
        while not self._nthreads():
            if time.monotonic() - start > self.timeout:
                raise self._lost(
                    f"no worker for {self.timeout:g} s (--timeout); start some with "
                    f"`dask worker {self.address}`"
                )
            time.sleep(min(0.2, self.timeout))

    def _result(self, fut: Any) -> Any:
        """The result of a finished future, failures of the machinery as StudyError."""
        from distributed.scheduler import KilledWorker

        try:
            return fut.result(timeout=self.timeout)
        except PkdynError:
            raise
        except KilledWorker:
            raise StudyError(
                f"scheduler {self.address}",
                "a chunk of designs killed the workers that evaluated it several times (out of "
                "memory?); the designs finished are kept: run the same command again to resume",
            ) from None
        except (CancelledError, asyncio.CancelledError, TimeoutError, OSError) as err:
            raise self._lost(f"the study was stopped ({_first_line(err)})") from None
        except Exception as err:  # a worker without pkdyn or a plug-in, another version...
            raise StudyError(
                f"scheduler {self.address}",
                f"a worker failed ({_first_line(err)}); the workers need pkdyn and the study's "
                "plug-ins installed",
            ) from None

    # ------------------------------------------------------------------ the work

    def map_chunks(self, fn: ChunkFn, payload: Any, chunks: Sequence[list[Any]]) -> Iterator[Any]:
        """See :meth:`Executor.map_chunks`.

        Raises:
            StudyError: The scheduler is lost or stops answering, the cluster has no worker
                for ``timeout`` s, or a chunk repeatedly kills its workers.

        """
        from distributed import as_completed

        client = self.client
        self._wait_for_workers()
        try:
            shared = client.scatter(payload, broadcast=True, timeout=self.timeout)
        except (OSError, TimeoutError, asyncio.TimeoutError) as err:
            raise self._lost(
                f"the workers did not receive the study ({_first_line(err)})"
            ) from None
        futures = [client.submit(_on_worker, fn, shared, chunk, pure=False) for chunk in chunks]
        ac = as_completed(futures, loop=client.loop)
        checked = time.monotonic()
        idle_since: float | None = None
        try:
            while not ac.is_empty():
                if ac.has_ready():
                    for fut in ac.next_batch(block=False):
                        yield self._result(fut)
                    continue
                now = time.monotonic()
                if now - checked >= _HEALTH_PERIOD:
                    checked = now
                    if self._nthreads():
                        idle_since = None
                    else:
                        idle_since = now if idle_since is None else idle_since
                        self._wait_for_workers(idle_since)
                time.sleep(_POLL)
        except BaseException:
            if client.status == "running":
                client.cancel(futures)
            raise

    def close(self, abort: bool = False) -> None:
        """Close the client if this executor opened it."""
        if self._own:
            try:
                self.client.close(timeout=min(self.timeout, 5.0))
            except Exception:  # noqa: S110 - a client that lost its scheduler may fail to close
                pass
            self._restore()


def make_executor(
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    timeout: float = 10.0,
    designs: int | None = None,
) -> Executor:
    """The executor for these options (see the module docstring).

    Args:
        workers: Local worker processes (1: serial; default: the usable cores, at most one per
            design). More than the machine or the study justify are capped, with a warning
            (:func:`pkdyn.workers.worker_count`).
        client: A Dask client (takes precedence).
        scheduler: A Dask scheduler address.
        timeout: How long to wait for the scheduler and for workers [s].
        designs: Designs evaluated at once (a sweep: all of them; NSGA-II: the population).

    Raises:
        InvalidInputError: ``workers`` not a whole number >= 1, a bad timeout, a scheduler
            address that is not a non-empty string.
        StudyError: The Dask scheduler cannot be reached.

    """
    scheduler = check_scheduler(scheduler)
    if client is not None or scheduler:
        return DaskExecutor(client, scheduler, timeout)
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, numbers.Integral) or workers < 1
    ):
        raise InvalidInputError("workers", f"must be a whole number >= 1, got {workers!r}")
    n = worker_count(
        None if workers is None else int(workers),
        designs if designs is not None else 10**9,
        "--workers",
    )
    return SerialExecutor() if n == 1 else ProcessExecutor(n)


def ordered(ex: Executor, fn: ChunkFn, payload: Any, chunks: Sequence[list[Any]]) -> list[Any]:
    """``fn(payload, chunk)`` of every chunk on ``ex``, in the order of the chunks.

    Args:
        ex: The executor.
        fn: The chunk function (picklable: a module-level function).
        payload: What every chunk needs (sent once per worker on Dask).
        chunks: The chunks.

    Returns:
        The results, one per chunk, in chunk order.

    """
    tagged = [[(k, chunk)] for k, chunk in enumerate(chunks)]
    out: list[Any] = [None] * len(chunks)
    for part in ex.map_chunks(_tagged, (fn, payload), tagged):
        for k, value in part:
            out[k] = value
    return out


def _tagged(payload: Any, items: list[tuple[int, list[Any]]]) -> list[tuple[int, Any]]:
    fn, inner = payload
    return [(k, fn(inner, chunk)) for k, chunk in items]
