"""One BLAS thread for the computations made of many small matrices.

NumPy's and SciPy's OpenBLAS start one thread per core for products and factorizations above a
small size. On the batches of pkdyn's precision, calibration and identification work (matrices of
tens of rows, thousands of times) the threads spend more time waiting for each other than
computing, and on a loaded machine they compete with the other processes. Measured: the
stiffness of the library Gough-Stewart with steel links, 229 -> 145 ms on the idle 2-core
machine; the constrained fit of an identification, 14 -> 0.4 s of CPU under load.

:func:`single_blas_thread` limits the BLAS libraries to one thread inside a block with
``threadpoolctl`` (a dependency of pkdyn; without it, nothing is changed); worker processes
forked inside the block inherit the limit. A library loaded inside the block (SciPy's own
OpenBLAS, imported lazily by a command) keeps its threads until the next block.
:func:`one_blas_thread` decorates a function with it. The ``pkdyn`` command line runs every
command inside it.
"""

from __future__ import annotations

import contextlib
import functools
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any, ParamSpec, TypeVar

__all__ = ["one_blas_thread", "single_blas_thread"]

P = ParamSpec("P")
R = TypeVar("R")

_controllers: dict[bool, Any] = {}
"""threadpoolctl controllers by whether SciPy's linear algebra (its own OpenBLAS) was loaded
when they were made: a controller knows the libraries loaded before it."""


def _get_controller() -> Any:
    scipy_loaded = "scipy.linalg" in sys.modules
    if scipy_loaded not in _controllers:
        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:  # pragma: no cover - threadpoolctl is a dependency
            _controllers[scipy_loaded] = None
        else:
            _controllers[scipy_loaded] = ThreadpoolController()
    return _controllers[scipy_loaded]


_state = threading.local()
"""Per thread: the controller whose libraries this thread's outermost block limited."""


@contextlib.contextmanager
def single_blas_thread() -> Iterator[None]:
    """Limit the BLAS libraries to one thread inside the block (restored on exit).

    A block inside another of the same thread, with the same libraries loaded, changes nothing
    and costs nothing (``threadpoolctl`` reads and sets every library's limit, about 0.1 ms: a
    design study's precision metric was paying it per design); a library loaded since the
    outer block began is limited by the inner one.
    """
    controller = _get_controller()
    if controller is None:  # pragma: no cover - threadpoolctl is a dependency
        yield
        return
    outer = getattr(_state, "active", None)
    if outer is controller:
        yield
        return
    _state.active = controller
    try:
        with controller.limit(limits=1, user_api="blas"):
            yield
    finally:
        _state.active = outer


def one_blas_thread(fn: Callable[P, R]) -> Callable[P, R]:
    """Decorate ``fn`` to run inside :func:`single_blas_thread`."""

    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with single_blas_thread():
            return fn(*args, **kwargs)

    return wrapper
