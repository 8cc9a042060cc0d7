"""Progress bars for long computations (tqdm on stderr, only where someone is watching)."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import TypeVar

__all__ = ["progress", "progress_steps"]

T = TypeVar("T")


def progress(
    items: Iterable[T],
    desc: str,
    unit: str,
    enabled: bool | None = None,
    total: int | None = None,
    min_items: int = 0,
    leave: bool = True,
) -> Iterator[T]:
    """Iterate over ``items`` with a tqdm progress bar when it is worth showing.

    Args:
        items: What to iterate over.
        desc: Label of the bar.
        unit: Unit of one item (``sample``, ``phase``...).
        enabled: ``True``/``False`` forces the bar on/off; ``None`` (default) shows it when
            stderr is a terminal and there are at least ``min_items`` items.
        total: Number of items (default ``len(items)`` when it has one).
        min_items: Smallest number of items worth a bar when ``enabled`` is ``None``.
        leave: Keep the finished bar on the terminal (else it is erased).

    Returns:
        An iterator over ``items``.

    """
    if total is None and hasattr(items, "__len__"):
        total = len(items)  # type: ignore[arg-type]
    if enabled is None:
        enabled = sys.stderr.isatty() and (total is None or total >= min_items)
    if not enabled:
        return iter(items)
    from tqdm import tqdm

    return iter(tqdm(items, desc=desc, unit=unit, total=total, leave=leave))


@contextmanager
def progress_steps(
    total: int, desc: str, unit: str, enabled: bool | None = None
) -> Iterator[Callable[[], None]]:
    """A progress bar advanced by hand, for work that is not one loop.

    Args:
        total: Number of steps.
        desc: Label of the bar.
        unit: Unit of one step.
        enabled: As in :func:`progress` (``None``: when stderr is a terminal).

    Returns:
        A context manager yielding ``advance()``, which moves the bar one step; the bar is
        closed on exit.

    """
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        yield lambda: None
        return
    from tqdm import tqdm

    bar = tqdm(total=total, desc=desc, unit=unit)
    try:
        yield lambda: bar.update(1)
    finally:
        bar.close()
