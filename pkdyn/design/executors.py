"""Where designs are evaluated: in this process, in local worker processes, or on Dask.

Every executor runs ``fn(payload, chunk)`` on chunks of designs and yields each chunk's result
as it completes (any order: the runner sorts by design index, so the table does not depend on
the executor). :func:`make_executor` picks one:

- ``workers=1``: :class:`SerialExecutor`, in this process;
- ``workers=N`` (default: the machine's cores): :class:`ProcessExecutor`, a pool of local
  worker processes (forked when this process runs no other thread, else spawned; a script that
  spawns needs the usual ``if __name__ == "__main__":`` guard);
- ``client=`` a :class:`distributed.Client`, or ``scheduler="tcp://host:8786"``:
  :class:`DaskExecutor` on a Dask cluster (its workers need pkdyn installed).
"""

from __future__ import annotations

import multiprocessing
import os
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any

from pkdyn.exceptions import InvalidInputError, StudyError

__all__ = ["DaskExecutor", "Executor", "ProcessExecutor", "SerialExecutor", "make_executor"]

ChunkFn = Callable[[Any, list[Any]], list[Any]]


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

    def close(self) -> None:  # noqa: B027 (most executors hold nothing)
        """Release the workers."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class SerialExecutor(Executor):
    """Everything in this process, in order."""

    name = "serial (this process)"

    def map_chunks(self, fn: ChunkFn, payload: Any, chunks: Sequence[list[Any]]) -> Iterator[Any]:
        """See :meth:`Executor.map_chunks`."""
        for chunk in chunks:
            yield fn(payload, chunk)


class ProcessExecutor(Executor):
    """A pool of local worker processes (started on first use, kept until :meth:`close`).

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
                max_workers=self.workers, mp_context=multiprocessing.get_context(method)
            )
        return self._pool

    def map_chunks(self, fn: ChunkFn, payload: Any, chunks: Sequence[list[Any]]) -> Iterator[Any]:
        """See :meth:`Executor.map_chunks` (at most ``4 x workers`` chunks in flight)."""
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
        except BaseException:
            for fut in running:
                fut.cancel()
            raise

    def close(self) -> None:
        """Shut the pool down (pending chunks cancelled)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


class DaskExecutor(Executor):
    """A Dask distributed cluster.

    Args:
        client: A connected :class:`distributed.Client` (left open on :meth:`close`), or
            ``None`` to connect to ``scheduler``.
        scheduler: Scheduler address (``tcp://host:8786``) when no client is given.
        timeout: Connection timeout [s].

    Raises:
        StudyError: The scheduler cannot be reached, or it has no worker.

    """

    def __init__(self, client: Any = None, scheduler: str | None = None, timeout: float = 10.0):
        self._own = client is None
        if client is None:
            if not scheduler:
                raise InvalidInputError("scheduler", "give a Dask client or a scheduler address")
            try:
                from distributed import Client
            except ImportError:  # pragma: no cover - a dependency
                raise StudyError("scheduler", "Dask distributed is not installed") from None
            try:
                client = Client(scheduler, timeout=timeout, set_as_default=False)
            except (OSError, TimeoutError, ValueError) as err:
                msg = str(err).splitlines()[0] if str(err) else type(err).__name__
                raise StudyError(
                    f"scheduler {scheduler}",
                    f"cannot connect ({msg}); start one with `dask scheduler` and workers with "
                    "`dask worker ADDRESS`, or drop --scheduler to use local processes",
                ) from None
        self.client = client
        info = client.scheduler_info()
        workers = info.get("workers", {})
        self.workers = max(1, sum(int(w.get("nthreads", 1)) for w in workers.values()))
        self.name = f"Dask cluster at {client.scheduler.address} ({len(workers)} workers)"

    def map_chunks(self, fn: ChunkFn, payload: Any, chunks: Sequence[list[Any]]) -> Iterator[Any]:
        """See :meth:`Executor.map_chunks`."""
        from distributed import as_completed

        shared = self.client.scatter(payload, broadcast=True)
        futures = [self.client.submit(fn, shared, chunk, pure=False) for chunk in chunks]
        try:
            for fut in as_completed(futures):
                yield fut.result()
        except BaseException:
            self.client.cancel(futures)
            raise

    def close(self) -> None:
        """Close the client if this executor opened it."""
        if self._own:
            self.client.close()


def make_executor(
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    timeout: float = 10.0,
) -> Executor:
    """The executor for these options (see the module docstring).

    Args:
        workers: Local worker processes (1: serial; default: the machine's cores).
        client: A Dask client (takes precedence).
        scheduler: A Dask scheduler address.
        timeout: How long to try to reach the scheduler [s].

    Raises:
        InvalidInputError: ``workers`` below 1.
        StudyError: The Dask scheduler cannot be reached.

    """
    if client is not None or scheduler:
        return DaskExecutor(client, scheduler, timeout)
    n = (os.cpu_count() or 1) if workers is None else int(workers)
    if n < 1:
        raise InvalidInputError("workers", f"must be >= 1, got {workers}")
    return SerialExecutor() if n == 1 else ProcessExecutor(n)
