"""Progress bars for long computations (tqdm on stderr, only where someone is watching)."""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from typing import TypeVar

__all__ = ["progress"]

T = TypeVar("T")


def progress(
    items: Iterable[T],
    desc: str,
    unit: str,
    enabled: bool | None = None,
    total: int | None = None,
    min_items: int = 0,
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

    return iter(tqdm(items, desc=desc, unit=unit, total=total))
