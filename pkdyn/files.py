"""Writing output files safely: to a temporary file beside the target, renamed when complete.

An interrupted run (Ctrl-C, SIGTERM, an exception) leaves the previous file intact and no
partial file under the target's name. Every file pkdyn writes goes through
:func:`atomic_write` (pkdyn writes the content) or :func:`atomic_path` (a library writes to a
path: matplotlib, pyarrow...).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from pkdyn.exceptions import OutputError

__all__ = ["atomic_path", "atomic_write", "check_writable"]


def _temporary(path: Path) -> Path:
    """A new empty file beside ``path`` with the same suffix (libraries infer formats from it)."""
    if path.name in ("", ".", "..") or path.is_dir():
        raise OutputError(str(path), "it is a directory, not a file name")
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    except FileNotFoundError:
        if not path.parent.is_dir():
            raise OutputError(str(path), f"directory '{path.parent}' does not exist") from None
        raise OutputError(  # /proc, /sys: directories that take no new file
            str(path), f"directory '{path.parent}' does not accept new files; choose another"
        ) from None
    except PermissionError:
        raise OutputError(
            str(path), f"no permission to create files in directory '{path.parent}'"
        ) from None
    except OSError as err:
        raise OutputError(str(path), err.strerror or str(err)) from None
    os.close(fd)
    return Path(tmp)


def check_writable(path: str | os.PathLike[str]) -> None:
    """Make sure ``path`` can be written, before any work: create and remove a temporary file.

    Permission checks (``os.access``) do not tell: root passes them everywhere, and virtual
    file systems (``/proc``) refuse new files whatever the permissions say.

    Raises:
        OutputError: A directory, a missing directory, no permission, or a directory that takes
            no new file.

    """
    _temporary(Path(path)).unlink(missing_ok=True)


def _commit(tmp: Path, path: Path) -> None:
    try:
        if path.exists():  # keep the target's permissions
            os.chmod(tmp, path.stat().st_mode & 0o777)
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except OSError as err:
        raise OutputError(str(path), err.strerror or str(err)) from None


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path to write ``path`` through; renamed onto ``path`` on success.

    Args:
        path: The file to (re)write.

    Yields:
        A temporary file path in the same directory, with the same suffix.

    Raises:
        OutputError: The directory does not exist or cannot be written.

    """
    target = Path(path)
    tmp = _temporary(target)
    try:
        yield tmp
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _commit(tmp, target)


@contextlib.contextmanager
def atomic_write(
    path: str | os.PathLike[str],
    mode: str = "w",
    encoding: str | None = "utf-8",
    newline: str | None = None,
) -> Iterator[IO[Any]]:
    """Open a temporary file to write ``path``; flushed, synced and renamed on success.

    Args:
        path: The file to (re)write.
        mode: ``"w"`` (text) or ``"wb"`` (bytes).
        encoding: Text encoding (ignored in binary mode).
        newline: As for :func:`open` (``""`` for the csv module).

    Yields:
        The open file.

    Raises:
        OutputError: The directory does not exist or cannot be written.

    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', got {mode!r}")
    with atomic_path(path) as tmp:
        kwargs: dict[str, Any] = {} if "b" in mode else {"encoding": encoding, "newline": newline}
        with open(tmp, mode, **kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
