"""Reading input files and writing output files safely.

**Outputs** are written to a temporary file beside the target and renamed when complete: an
interrupted run (Ctrl-C, SIGTERM, an exception) leaves the previous file intact and no partial
file under the target's name. Every file pkdyn writes goes through :func:`atomic_write` (pkdyn
writes the content) or :func:`atomic_path` (a library writes to a path: matplotlib, pyarrow...),
and every output path is checked by :func:`output_target` (also before any work, by the CLI):

- an output is a regular file, or a name that does not exist yet in an existing, writable
  directory; a FIFO, a device (``/dev/stdout``, ``/dev/null``...), a socket or a directory is
  refused: renaming a file onto them would replace them (the data meant for a pipe or a terminal
  would land in a new regular file);
- a symbolic link is followed when it leads to a regular file: that file is written (atomically,
  beside itself) and the link is kept; a link to anything else, to nothing, or through ``/dev``
  or ``/proc`` (``/dev/stdout`` is a link to the process's standard output, whatever it is) is
  refused;
- a name longer than the file system allows (255 bytes on most) is refused with its length.

**Inputs** that pkdyn reads whole (study files, catalogs) go through :func:`read_text`: a
regular file (or a link to one) no larger than a limit given by the caller; a FIFO or a device
(``/dev/zero``) is refused before it is opened, so reading never blocks or runs away.
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

from pkdyn.exceptions import OutputError, PkdynError

__all__ = ["atomic_path", "atomic_write", "check_writable", "output_target", "read_text", "shown"]

_KIND = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
    stat.S_IFDIR: "a directory",
}


def shown(path: str | os.PathLike[str], width: int = 80) -> str:
    """A path for a message: shortened in the middle when longer than ``width`` characters."""
    text = str(path)
    if len(text) <= width:
        return text
    return f"{text[: width // 2 - 2]}...{text[-(width // 2 - 3) :]} ({len(text)} characters)"


def _kind(mode: int) -> str:
    return _KIND.get(stat.S_IFMT(mode), "not a regular file")


def _name_max(directory: Path) -> int:
    try:
        return int(os.pathconf(directory, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return 255


def _special_hop(link: Path) -> str | None:
    """The first hop of a chain of links that lies in ``/dev`` or ``/proc``, else ``None``.

    ``/dev/stdout`` leads through ``/proc/self/fd/1`` to whatever the standard output is: a
    terminal, a pipe, or a file that this process already writes through its descriptor
    (renaming a new file onto that one would lose what is printed after).
    """
    p = link
    for _ in range(40):
        try:
            nxt = os.readlink(p)
        except OSError:
            return None
        p = Path(os.path.normpath(p.parent / nxt))
        if p.parts[:2] in (("/", "dev"), ("/", "proc")):
            return str(p)
    return None


def output_target(path: str | os.PathLike[str], option: str = "") -> Path:
    """The regular file to write for the output ``path`` (the module docstring's rules).

    Args:
        path: The output path as given.
        option: The option that names it, for messages (``--csv``).

    Returns:
        The path to write: ``path`` itself, or the regular file a symbolic link leads to.

    Raises:
        OutputError: A directory, FIFO, device or socket; a dangling link or a link to one of
            those; a name too long; a missing or read-only directory.

    """
    if not isinstance(path, str | os.PathLike):
        raise OutputError(
            repr(path)[:80], f"{option + ': ' if option else ''}expected a file name (str or Path)"
        )
    p = Path(path)
    where = f"{option}: " if option else ""
    name = shown(path)
    if p.name in ("", ".", ".."):
        raise OutputError(name, f"{where}names a directory, not a file")
    parent = p.parent if str(p.parent) else Path(".")
    limit = _name_max(parent) if parent.is_dir() else 255
    if len(os.fsencode(p.name)) > limit:
        raise OutputError(
            name, f"{where}the file name is {len(os.fsencode(p.name))} bytes long; at most {limit}"
        )
    try:
        st = os.lstat(p)
    except FileNotFoundError:
        st = None
    except OSError as err:
        raise OutputError(name, f"{where}{err.strerror or err}") from None
    target = p
    if st is not None and stat.S_ISLNK(st.st_mode):
        special = _special_hop(p)
        if special is not None:
            raise OutputError(
                name,
                f"{where}a symbolic link to '{special}' (a device or a process's open file, "
                "such as /dev/stdout), not a regular file; pkdyn writes regular files only: "
                "name a file (or leave the option out to print)",
            )
        try:
            st = os.stat(p)
        except OSError:
            raise OutputError(
                name, f"{where}a symbolic link to nothing ('{os.readlink(p)}'); remove it"
            ) from None
        target = Path(os.path.realpath(p))
        if not stat.S_ISREG(st.st_mode):
            raise OutputError(
                name,
                f"{where}a symbolic link to {_kind(st.st_mode)} ('{target}'), not a regular file; "
                "pkdyn writes regular files only",
            )
    elif st is not None and not stat.S_ISREG(st.st_mode):
        raise OutputError(
            name, f"{where}{_kind(st.st_mode)}, not a regular file; pkdyn writes regular files only"
        )
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise OutputError(name, f"{where}directory '{shown(directory)}' does not exist")
    if not os.access(directory, os.W_OK):
        raise OutputError(name, f"{where}directory '{shown(directory)}' is not writable")
    return target


def read_text(
    path: str | os.PathLike[str],
    limit: int,
    error: Callable[[str], PkdynError],
    encoding: str = "utf-8",
) -> str:
    """The text of an input file, refused unless a regular file of at most ``limit`` bytes.

    A FIFO, a device or a directory is refused before it is opened (opening a FIFO waits for a
    writer; ``/dev/zero`` never ends).

    Args:
        path: The file (a symbolic link to a regular file is followed).
        limit: Largest size accepted [bytes].
        error: Makes the exception to raise from a message (the caller's type, naming the file).
        encoding: Text encoding.

    Raises:
        PkdynError: From ``error``: missing, unreadable, not a regular file, too large, or not
            text in ``encoding``.

    """
    if not isinstance(path, str | os.PathLike):  # (an int would be a file descriptor)
        raise error(f"expected a file name (str or Path), got {type(path).__name__}")
    try:
        st = os.stat(path)
    except OSError as err:
        raise error(f"cannot be read ({err.strerror or err})") from None
    if not stat.S_ISREG(st.st_mode):
        raise error(f"cannot be read: {_kind(st.st_mode)}, not a regular file")
    if st.st_size > limit:
        raise error(f"is {st.st_size / 1e6:.3g} MB, more than the {limit / 1e6:.3g} MB accepted")
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as fh:
            if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):  # replaced since the check
                raise error("cannot be read: not a regular file")
            data = fh.read(limit + 1)
    except OSError as err:
        raise error(f"cannot be read ({err.strerror or err})") from None
    if len(data) > limit:
        raise error(f"is more than the {limit / 1e6:.3g} MB accepted")
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as err:
        raise error(f"is not {encoding} text (byte {err.start})") from None


def _temporary(path: Path) -> Path:
    """A new empty file beside ``path`` with the same suffix (libraries infer formats from it)."""
    try:
        fd, tmp = tempfile.mkstemp(
            dir=path.parent, prefix=f".{path.stem[:40]}.", suffix=path.suffix[:40]
        )
    except FileNotFoundError:
        if not path.parent.is_dir():
            raise OutputError(
                shown(path), f"directory '{shown(path.parent)}' does not exist"
            ) from None
        raise OutputError(  # /proc, /sys: directories that take no new file
            shown(path),
            f"directory '{shown(path.parent)}' does not accept new files; choose another",
        ) from None
    except PermissionError:
        raise OutputError(
            shown(path), f"no permission to create files in directory '{shown(path.parent)}'"
        ) from None
    except OSError as err:
        if err.errno == errno.ENAMETOOLONG:
            raise OutputError(shown(path), "the name is too long for the file system") from None
        raise OutputError(shown(path), err.strerror or str(err)) from None
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
        raise OutputError(shown(path), err.strerror or str(err)) from None


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path to write ``path`` through; renamed onto ``path`` on success.

    Args:
        path: The file to (re)write (a symbolic link to a regular file: that file).

    Yields:
        A temporary file path in the same directory, with the same suffix.

    Raises:
        OutputError: Not a regular file (:func:`output_target`), or the directory does not
            exist or cannot be written.

    """
    target = output_target(path)
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
        OutputError: Not a regular file (:func:`output_target`), or the directory does not
            exist or cannot be written.

    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', got {mode!r}")
    with atomic_path(path) as tmp:
        kwargs: dict[str, Any] = {} if "b" in mode else {"encoding": encoding, "newline": newline}
        with open(tmp, mode, **kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
