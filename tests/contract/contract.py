"""The contract every entry point keeps, and the code that checks one call against it.

**API**: a call either returns a valid result (no NaN in its numbers; infinities are allowed
where they flag a singular figure) or raises a :class:`pkdyn.PkdynError` subclass whose
message is one line and names the culprit. Never a bare ``ValueError``, ``TypeError``,
``LinAlgError``, ``KeyError``, ``IndexError``, ``SystemExit``...; never longer than the case's
time limit.

**Command line**: exit 0, or exit 1 or 2 with exactly one ``pkdyn: error:`` line on the
standard error and no ``Traceback``; within the time limit.

**Files** (both): an input file is never changed; a refused call leaves the directory as it
was (no partial output, no temporary left behind); an accepted one leaves no temporary.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import math
import os
import signal
import stat
import threading
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass, fields, is_dataclass
from pathlib import Path
from typing import Any

import numpy as np

import pkdyn

__all__ = [
    "CaseTimeout",
    "CliOutcome",
    "check_api",
    "check_cli",
    "non_finite",
    "run_cli",
    "snapshot",
    "time_limit",
]


class CaseTimeout(BaseException):
    """A case ran past its time limit (raised by SIGPROF or SIGALRM in the main thread)."""


WALL_FACTOR = 12.0
"""A case's wall-clock limit, in multiples of its time limit (which bounds its CPU time): the
machine running the suite may be shared (a load average of 9 on 2 cores took a tripod case past
4x), and a case blocked on a read spends no CPU: the wall limit catches those, still bounded."""


MEMORY_HEADROOM = 2 << 30
"""Address space a case may add to the process's [bytes] (2 GiB): beyond, allocations fail
with ``MemoryError``, which the harness reports as unbounded memory (reading ``/dev/zero``)."""


def _address_space() -> int:
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError):
        return 0


@contextlib.contextmanager
def time_limit(seconds: float, memory: int = MEMORY_HEADROOM) -> Iterator[None]:
    """Raise :class:`CaseTimeout` in the main thread after ``seconds`` of the process's CPU
    time or ``WALL_FACTOR * seconds`` of wall-clock time (elsewhere: no limit), and cap the
    address space at its present size plus ``memory`` meanwhile."""
    import resource

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def on_alarm(signum: int, frame: Any) -> None:
        if signum == signal.SIGPROF:
            raise CaseTimeout(f"no answer within {seconds:g} s of CPU time")
        raise CaseTimeout(f"no answer within {WALL_FACTOR * seconds:g} s")

    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    used = _address_space()
    capped = False
    if used and memory:
        cap = used + memory
        if hard == resource.RLIM_INFINITY or cap < hard:
            resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
            capped = True
    previous = signal.signal(signal.SIGALRM, on_alarm), signal.signal(signal.SIGPROF, on_alarm)
    signal.setitimer(signal.ITIMER_PROF, seconds)
    signal.setitimer(signal.ITIMER_REAL, WALL_FACTOR * seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.setitimer(signal.ITIMER_PROF, 0.0)
        signal.signal(signal.SIGALRM, previous[0])
        signal.signal(signal.SIGPROF, previous[1])
        if capped:
            resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def snapshot(directory: Path) -> dict[str, tuple[str, str]]:
    """Every entry below ``directory``: its kind and, for a regular file, its content's hash."""
    out: dict[str, tuple[str, str]] = {}
    for root, dirs, files in os.walk(directory):
        for name in dirs + files:
            p = Path(root) / name
            try:
                st = os.lstat(p)
            except OSError:
                continue
            rel = str(p.relative_to(directory))
            if stat.S_ISREG(st.st_mode):
                out[rel] = ("file", hashlib.sha256(p.read_bytes()).hexdigest())
            elif stat.S_ISLNK(st.st_mode):
                out[rel] = ("link", os.readlink(p))
            else:
                out[rel] = (stat.filemode(st.st_mode)[0], "")
    return out


def file_changes(
    before: dict[str, tuple[str, str]], after: dict[str, tuple[str, str]]
) -> tuple[list[str], list[str], list[str]]:
    """``(changed, created, removed)`` names between two snapshots."""
    changed = [k for k in before if k in after and after[k] != before[k]]
    created = [k for k in after if k not in before]
    removed = [k for k in before if k not in after]
    return changed, created, removed


def non_finite(value: Any, where: str = "result", depth: int = 0) -> str | None:
    """Where the first NaN of a result is (``None``: none), looking through dataclasses,
    mappings, sequences and arrays. Infinities are allowed (a singular figure is infinite)."""
    if depth > 6:
        return None
    if isinstance(value, float | np.floating):
        return where if math.isnan(float(value)) else None
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "fc" and value.size and np.isnan(value).any():
            return f"{where}[{np.flatnonzero(np.isnan(value.ravel()))[0]}]"
        return None
    if isinstance(value, dict):
        for k, v in list(value.items())[:200]:
            found = non_finite(v, f"{where}[{k!r}]", depth + 1)
            if found:
                return found
        return None
    if isinstance(value, list | tuple):
        for i, v in enumerate(value[:200]):
            found = non_finite(v, f"{where}[{i}]", depth + 1)
            if found:
                return found
        return None
    if is_dataclass(value) and not isinstance(value, type):
        for f in fields(value):
            if f.name.startswith("_"):
                continue
            found = non_finite(getattr(value, f.name, None), f"{where}.{f.name}", depth + 1)
            if found:
                return found
    return None


ESCAPE_MESSAGE = "escaped as {kind}: {text}"


def check_api(
    call: Callable[[], Any],
    names: tuple[str, ...],
    refuse: bool,
    timeout: float,
    nan_ok: bool = False,
) -> tuple[str, Any]:
    """Run one API call and check it against the contract.

    Args:
        call: The call, its arguments bound.
        names: Words one of which a refusal's message must contain.
        refuse: The contract demands a refusal.
        timeout: Time limit [s].
        nan_ok: A NaN in the result is allowed (a figure documented as undefined).

    Returns:
        ``("refused", error)`` or ``("accepted", result)``.

    Raises:
        AssertionError: The contract is broken (the message says how).

    """
    try:
        with time_limit(timeout):
            result = call()
    except pkdyn.PkdynError as err:
        text = str(err)
        assert "\n" not in text, f"a pkdyn error of several lines: {text!r}"
        assert text.strip(), f"{type(err).__name__} without a message"
        assert not refuse or names_culprit(text, names), (
            f"{type(err).__name__} does not name the culprit (one of {names}): {text}"
        )
        return "refused", err
    except CaseTimeout as err:
        raise AssertionError(f"unbounded: {err}") from None
    except KeyboardInterrupt:
        raise
    except MemoryError:
        raise AssertionError(
            f"unbounded memory: more than {MEMORY_HEADROOM >> 30} GiB (MemoryError)"
        ) from None
    except BaseException as err:  # noqa: BLE001 - the contract: nothing else escapes
        tb = "".join(traceback.format_exception(type(err), err, err.__traceback__, limit=-4))
        raise AssertionError(
            ESCAPE_MESSAGE.format(kind=type(err).__name__, text=str(err)[:300]) + "\n" + tb
        ) from None
    assert not refuse, (
        f"accepted (returned {type(result).__name__}): the contract demands a refusal"
    )
    if not nan_ok:
        bad = non_finite(result)
        assert bad is None, f"accepted with a NaN in {bad}: neither refused nor flagged"
    return "accepted", result


@dataclass
class CliOutcome:
    """What one in-process run of the command line did."""

    code: int
    out: str
    err: str
    escaped: str = ""


def run_cli(argv: list[str], timeout: float) -> CliOutcome:
    """Run ``pkdyn.cli.main(argv)`` in this process, capturing its output.

    An exception escaping :func:`pkdyn.cli.main` (a traceback for a user) is returned in
    ``escaped``; ``SystemExit`` gives its code (argparse's usage errors: 2).
    """
    from pkdyn.cli import main

    out, err = io.StringIO(), io.StringIO()
    escaped = ""
    code: int
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            with time_limit(timeout):
                code = main(argv)
    except SystemExit as exc:
        c = exc.code
        code = c if isinstance(c, int) else (0 if c is None else 1)
        if c is not None and not isinstance(c, int):
            err.write(f"{c}\n")
    except CaseTimeout as exc:
        raise AssertionError(f"unbounded: pkdyn {' '.join(argv)}: {exc}") from None
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # noqa: BLE001 - a traceback the user would see
        escaped = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__, limit=-4))
        code = -1
    return CliOutcome(code, out.getvalue(), err.getvalue(), escaped)


def check_cli(
    argv: list[str], names: tuple[str, ...], refuse: bool, usage_ok: bool, timeout: float
) -> CliOutcome:
    """Run the command line once and check it against the contract.

    Args:
        argv: The arguments.
        names: Words one of which the error line must contain.
        refuse: The contract demands a refusal (exit 1 or 2).
        usage_ok: Exit 2 (a usage error) is an acceptable refusal.
        timeout: Time limit [s].

    Raises:
        AssertionError: The contract is broken.

    """
    res = run_cli(argv, timeout)
    shown = "pkdyn " + " ".join(a if len(a) < 60 else a[:57] + "..." for a in argv)
    assert not res.escaped, f"{shown}: a traceback escaped main():\n{res.escaped}"
    assert "Traceback" not in res.err, f"{shown}: a traceback on stderr:\n{res.err}"
    errors = [ln for ln in res.err.splitlines() if ln.startswith("pkdyn: error:")]
    if res.code == 0:
        assert not refuse, f"{shown}: exit 0, the contract demands a refusal\n{res.out[-500:]}"
        assert not errors, f"{shown}: exit 0 with an error line: {errors}"
        return res
    assert res.code in (1, 2), f"{shown}: exit {res.code}\n{res.err[-800:]}"
    assert len(errors) == 1, (
        f"{shown}: exit {res.code}, {len(errors)} error lines:\n{res.err[-800:]}"
    )
    others = [
        ln
        for ln in res.err.splitlines()
        if ln.strip()
        and not ln.startswith(("pkdyn: error:", "pkdyn: warning:", "pkdyn: note:"))
        and "\r" not in ln  # (a progress bar)
    ]
    assert not others, f"{shown}: stray lines on stderr: {others[:3]}"
    assert "out of memory" not in errors[0], f"{shown}: unbounded memory: {errors[0]}"
    if res.code == 2:
        assert usage_ok, (
            f"{shown}: refused as a usage error, a value the option should take: {errors[0]}"
        )
    assert not refuse or names_culprit(errors[0], names), (
        f"{shown}: the error line does not name the culprit (one of {names}): {errors[0]}"
    )
    return res


def names_culprit(text: str, names: tuple[str, ...]) -> bool:
    """``text`` names one of ``names`` (case aside; a number in any of its spellings)."""
    low = text.lower()
    for n in names:
        if n and n.lower() in low:
            return True
        try:
            x = float(n)
        except ValueError:
            continue
        if any(f in low for f in {f"{x:g}", repr(x), f"{x:.6g}"}):
            return True
    return False


def same_result(a: str, b: str) -> bool:
    """Two outputs of the command line equal (JSON compared as data, numbers to 1e-9)."""
    import json

    try:
        ja, jb = json.loads(a), json.loads(b)
    except ValueError:
        return a == b
    return _close(ja, jb)


def _close(a: Any, b: Any) -> bool:
    if isinstance(a, float | int) and isinstance(b, float | int):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b, strict=True))
    return bool(a == b)


def temporaries(created: list[str]) -> list[str]:
    """Created names that look like pkdyn's temporary files (``.NAME.xxxx.ext``)."""
    return [c for c in created if Path(c).name.startswith(".")]
