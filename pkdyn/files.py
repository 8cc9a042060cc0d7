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

**Inputs** are checked by :func:`input_file` before they are opened: a regular file (or a link
to one) no larger than a limit given by the caller; a FIFO, a device (``/dev/zero``) or a
directory is refused, so reading never blocks or runs away. :func:`read_text` and
:func:`read_bytes` read through it.

**Inputs are never outputs.** :func:`resolve_paths` takes every input and output path of a
command (the command line declares them: :mod:`pkdyn.cli._paths`) and, before any work, refuses
an output that is the same file as an input or as another output: by device and inode for
existing files (a link, a hard link or a relative path does not slip through), by resolved path
for new ones. A trailing slash means a directory: ``-o old.urdf/`` where ``old.urdf`` is a file
is refused, and so is ``-o newdir/`` (never a file called ``newdir``) unless the output is a
directory. While :func:`recording_reads` is active (the command line runs every command in it),
every file read through :func:`input_file` is remembered, and :func:`output_target` refuses to
write onto one of them: the includes, sidecars and catalogs a command discovers while it works
are protected too.
"""

from __future__ import annotations

import contextlib
import contextvars
import errno
import os
import stat
import tempfile
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from pkdyn.exceptions import InvalidInputError, OutputError, PkdynError

__all__ = [
    "PathArg",
    "atomic_path",
    "atomic_write",
    "check_writable",
    "input_file",
    "output_target",
    "read_bytes",
    "read_text",
    "recording_reads",
    "resolve_paths",
    "shown",
]

_READS: contextvars.ContextVar[dict[tuple[int, int], str] | None] = contextvars.ContextVar(
    "pkdyn_reads", default=None
)
"""The files read by the running command (device, inode) -> path, while recorded."""

_KIND = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
    stat.S_IFDIR: "a directory",
}


def shown(path: str | os.PathLike[str], width: int = 240) -> str:
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
    if _trailing_slash(path):
        if p.is_dir():
            raise OutputError(
                name, f"{where}a directory, not a regular file; pkdyn writes regular files only"
            )
        if p.exists():
            raise OutputError(
                name,
                f"{where}a trailing slash names a directory, but '{shown(p)}' is a file; "
                "drop the slash to write the file",
            )
        raise OutputError(
            name,
            f"{where}names a directory (trailing slash); this output is a file: name one "
            "(no file named after the directory is written)",
        )
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
    reads = _READS.get()
    if reads and st is not None:
        key = _identity(target)
        if key is not None and key in reads:
            raise OutputError(
                name,
                f"{where}is the file '{shown(reads[key])}' this command read; an output never "
                "replaces an input: choose another name",
            )
    return target


def _trailing_slash(path: str | os.PathLike[str]) -> bool:
    text = os.fspath(path)
    return isinstance(text, str) and len(text) > 1 and text.endswith(("/", os.sep))


def _identity(path: str | os.PathLike[str]) -> tuple[int, int] | None:
    """(device, inode) of the file ``path`` leads to, or ``None`` when there is none."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return (st.st_dev, st.st_ino)


@contextlib.contextmanager
def recording_reads() -> Iterator[None]:
    """Remember every file read through :func:`input_file` meanwhile; refuse outputs onto them.

    The command line runs each command inside it (module docstring).
    """
    token = _READS.set({})
    try:
        yield
    finally:
        _READS.reset(token)


def input_file(
    path: str | os.PathLike[str],
    limit: int,
    error: Callable[[str], PkdynError],
    record: bool = True,
) -> os.stat_result:
    """Check an input before it is opened: a regular file of at most ``limit`` bytes.

    A FIFO, a device or a directory (or a symbolic link to one) is refused before it is
    opened: opening a FIFO waits for a writer, ``/dev/zero`` never ends. The file is
    remembered while :func:`recording_reads` is active.

    Args:
        path: The file (a symbolic link to a regular file is followed).
        limit: Largest size accepted [bytes].
        error: Makes the exception to raise from a message (the caller's type, naming the file).
        record: Remember it as an input of the command (``False``: a command's own earlier
            output read back to resume, which it rewrites).

    Returns:
        Its ``os.stat`` result.

    Raises:
        PkdynError: From ``error``: missing, unreadable, not a regular file, or too large.

    """
    if not isinstance(path, str | os.PathLike):  # (an int would be a file descriptor)
        raise error(f"path: expected a file name (str or Path), got {type(path).__name__}")
    try:
        st = os.stat(path)
    except OSError as err:
        raise error(f"cannot be read ({err.strerror or err})") from None
    if not stat.S_ISREG(st.st_mode):
        raise error(f"cannot be read: {_kind(st.st_mode)}, not a regular file")
    if st.st_size > limit:
        raise error(f"is {st.st_size / 1e6:.3g} MB, more than the {limit / 1e6:.3g} MB accepted")
    reads = _READS.get()
    if reads is not None and record:
        reads[(st.st_dev, st.st_ino)] = os.fspath(path)
    return st


def read_bytes(
    path: str | os.PathLike[str],
    limit: int,
    error: Callable[[str], PkdynError],
    record: bool = True,
) -> bytes:
    """The bytes of an input file, refused unless a regular file of at most ``limit`` bytes.

    Args:
        path: The file (a symbolic link to a regular file is followed).
        limit: Largest size accepted [bytes].
        error: Makes the exception to raise from a message (the caller's type, naming the file).
        record: As for :func:`input_file`.

    Raises:
        PkdynError: From ``error`` (:func:`input_file`), or the file grew past ``limit``.

    """
    input_file(path, limit, error, record)
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
    return data


def read_text(
    path: str | os.PathLike[str],
    limit: int,
    error: Callable[[str], PkdynError],
    encoding: str = "utf-8",
    record: bool = True,
) -> str:
    """The text of an input file, refused unless a regular file of at most ``limit`` bytes.

    A FIFO, a device or a directory is refused before it is opened (opening a FIFO waits for a
    writer; ``/dev/zero`` never ends).

    Args:
        path: The file (a symbolic link to a regular file is followed).
        limit: Largest size accepted [bytes].
        error: Makes the exception to raise from a message (the caller's type, naming the file).
        encoding: Text encoding.
        record: As for :func:`input_file`.

    Raises:
        PkdynError: From ``error``: missing, unreadable, not a regular file, too large, or not
            text in ``encoding``.

    """
    data = read_bytes(path, limit, error, record)
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


@dataclass(frozen=True)
class PathArg:
    """One input or output path of a command, as given.

    Attributes:
        option: The option or argument that names it, for messages (``--csv``, ``ROBOT``).
        path: The path as given.
        directory: An output that is a directory the command writes into (a trailing slash
            is then expected, not refused).

    """

    option: str
    path: str
    directory: bool = False


def _keys(path: str) -> set[Any]:
    """What identifies a file: its (device, inode) when it exists, and its resolved path."""
    keys: set[Any] = {os.path.realpath(path)}
    ident = _identity(path)
    if ident is not None:
        keys.add(ident)
    return keys


def _input_error(arg: PathArg) -> Callable[[str], PkdynError]:
    return lambda msg: InvalidInputError(arg.option, f"'{shown(arg.path)}' {msg}")


def resolve_paths(
    inputs: Sequence[PathArg],
    outputs: Sequence[PathArg],
    limit: int,
) -> None:
    """Check every input and output path of a command together, before any work.

    - every input is a regular file (or a link to one) of at most ``limit`` bytes
      (:func:`input_file`): no FIFO, device or directory;
    - every output is one pkdyn may write (:func:`output_target`; a trailing slash names a
      directory: refused unless the output is one);
    - no output is the same file as an input or as another output: compared by device and
      inode where the file exists (links, hard links, ``./x`` and ``x`` alike) and by
      resolved path where it does not.

    Args:
        inputs: The command's input files.
        outputs: The command's output files (a command writing several files from one option,
            such as a study's table, lists each).
        limit: Largest input accepted [bytes].

    Raises:
        InvalidInputError: An input that is not a regular file, is missing or too large.
        OutputError: An output that cannot be written, or that is an input or another output.

    """
    seen: list[tuple[PathArg, set[Any], str]] = []
    for arg in inputs:
        input_file(arg.path, limit, _input_error(arg))
        seen.append((arg, _keys(arg.path), "input"))
    for arg in outputs:
        keys = _keys(arg.path)
        for other, other_keys, kind in seen:
            if keys & other_keys:
                same = "" if other.path == arg.path else f" ('{shown(other.path)}')"
                raise OutputError(
                    shown(arg.path),
                    f"{arg.option}: is the same file as the {kind} {other.option}{same}; "
                    f"an output never replaces {'an input' if kind == 'input' else 'another'}"
                    ": choose another name",
                )
        if arg.directory and _trailing_slash(arg.path):
            if os.path.exists(arg.path) and not os.path.isdir(arg.path):
                raise OutputError(
                    shown(arg.path),
                    f"{arg.option}: a trailing slash names a directory, but it is a file",
                )
        else:
            output_target(arg.path, arg.option)
        seen.append((arg, keys, "output"))
