"""One BLAS thread while identifying: the linear algebra is many small products and solves.

NumPy's and SciPy's OpenBLAS start one thread per core for products above a small size. On the
batches of identification (matrices of tens of rows) the threads spend more time waiting for
each other than computing, and with two worker processes on two cores they compete with the
other process: measured on a Delta, the constrained physical fit took 14 s of CPU with the
default threads and 0.4 s with one. :func:`single_blas_thread` limits the BLAS libraries to one
thread with ``threadpoolctl`` (a dependency of pkdyn; without it, nothing is changed); worker
processes forked inside the block inherit the limit.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

__all__ = ["single_blas_thread"]


@contextlib.contextmanager
def single_blas_thread() -> Iterator[None]:
    """Limit the BLAS libraries to one thread inside the block (restored on exit)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield
