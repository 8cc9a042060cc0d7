"""The examples of a Markdown page, extracted and run (README.md, urdf/README.md, docs/guide/).

What runs, in page order:

- every ```python block, in a fresh namespace (each block is complete by itself: a reader can
  copy any one), unless its first line is ``# (continued)``: then it shares the namespace of the
  block above;
- every ``pkdyn ...`` (or ``.venv/bin/pkdyn ...``) line of a ```sh / ```bash / ```console block,
  in-process through :func:`pkdyn.cli.main`; it must exit with status 0; a line ending with
  ``\\`` continues on the next; other shell lines (``make ...``, ``source ...``) and comment
  lines are not run;
- a block of another language (```xml, ```yaml...) whose first line is a comment naming a file,
  ``<!-- file: arm.urdf -->`` or ``# file: catalog.yaml``, is written to that file, for the
  examples after it.

Marked explicitly, not run: a Python block whose first line, or a CLI line that, carries
``(not run by the tests)`` (a live viewer, a long study). A CLI line that is a sketch (``...``
standing for options, ``pkdyn design ... --seed 1``) must carry that marker: a sketch without
it is an error of the page, so that nothing is left out silently.

The examples of one page run in one temporary directory where the repository's top-level files
and folders are linked: paths relative to the repository root (``urdf/delta.urdf``,
``tests/data/...``) work as in a checkout, and files written by one example are there for the
next. A failure names the page and line.
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
import traceback
from dataclasses import dataclass
from pathlib import Path

__all__ = ["CONTINUED", "SKIP", "Example", "PageError", "extract", "run_page"]

ROOT = Path(__file__).resolve().parents[2]
SKIP = "(not run by the tests)"
CONTINUED = "# (continued)"
_SHELLS = ("sh", "bash", "console", "shell")
_FILE = re.compile(r"^\s*(?:<!--|#)\s*file:\s*(\S+)\s*(?:-->)?\s*$")
_PKDYN = re.compile(r"^(?:\.venv/bin/)?pkdyn\s")


class PageError(ValueError):
    """A page breaks the rules of its examples (a sketch without the marker)."""


@dataclass(frozen=True)
class Example:
    """One runnable example: a Python block, a CLI line, or a file a block writes."""

    kind: str  # "python", "cli" or "file"
    line: int  # 1-based line in the page (the block's first code line)
    code: str
    name: str = ""  # the file's name (kind "file")


def _blocks(text: str) -> list[tuple[str, int, list[str]]]:
    """The fenced blocks: (language, first code line (1-based), lines)."""
    out = []
    lines = text.splitlines()
    k = 0
    while k < len(lines):
        fence = re.match(r"^(\s*)(```+)\s*([\w+-]*)[^`]*$", lines[k])
        if not fence:
            k += 1
            continue
        indent, ticks, lang = fence.group(1), fence.group(2), fence.group(3)
        start = k + 1
        k = start
        while k < len(lines) and not lines[k].strip().startswith(ticks):
            k += 1
        body = [line[len(indent) :] if line.startswith(indent) else line for line in lines[start:k]]
        out.append((lang, start + 1, body))
        k += 1
    return out


def extract(text: str, where: str = "page") -> list[Example]:
    """The page's examples, in order.

    Args:
        text: Markdown text.
        where: The page's name, for the error message.

    Raises:
        PageError: A CLI sketch (``...`` among its arguments) without the marker.

    """
    out: list[Example] = []
    for lang, first_line, body in _blocks(text):
        if lang == "python":
            if body and SKIP not in body[0]:
                out.append(Example("python", first_line, "\n".join(body)))
        elif lang in _SHELLS:
            i = 0
            while i < len(body):
                first, command = i, body[i].strip()
                while command.endswith("\\") and i + 1 < len(body):  # continued line
                    i += 1
                    command = command[:-1].rstrip() + " " + body[i].strip()
                i += 1
                command = command.removeprefix("$ ")
                if not _PKDYN.match(command) or SKIP in command:
                    continue
                if "..." in command.split("#")[0].split():  # `pkdyn cmd ... --opt`
                    raise PageError(
                        f"{where}:{first_line + first}: the sketch `{command}` must say "
                        f"{SKIP!r} (or give the options it stands for)"
                    )
                command = command.removeprefix(".venv/bin/")
                out.append(Example("cli", first_line + first, command))
        elif body and (m := _FILE.match(body[0])):
            out.append(Example("file", first_line, "\n".join(body[1:]) + "\n", m.group(1)))
    return out


def _run_cli(command: str) -> tuple[int, str]:
    from pkdyn.cli import main

    argv = shlex.split(command, comments=True)[1:]
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
        try:
            code = main(argv)
        except SystemExit as stop:  # --help, --version and usage errors exit through argparse
            code = stop.code if isinstance(stop.code, int) else 1
    return code, buf.getvalue()


def link_repository(directory: Path) -> None:
    """Link the repository's top-level files and folders into ``directory``."""
    for item in ROOT.iterdir():
        if item.name not in (".git", ".venv") and not (directory / item.name).exists():
            (directory / item.name).symlink_to(item, target_is_directory=item.is_dir())


def run_page(path: Path, examples: list[Example]) -> str | None:
    """Run a page's examples in the current directory; the first failure, or ``None``.

    Args:
        path: The page (for the messages and the tracebacks' line numbers).
        examples: Its examples (:func:`extract`).

    Returns:
        ``"page:line: what failed"``, or ``None`` when every example ran.

    """
    name = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
    namespace: dict[str, object] = {}
    for ex in examples:
        where = f"{name}:{ex.line}"
        if ex.kind == "file":
            Path(ex.name).write_text(ex.code, encoding="utf-8")
        elif ex.kind == "cli":
            try:
                status, output = _run_cli(ex.code)
            except BaseException:  # noqa: BLE001 - any failure names the page line
                return f"{where}: `{ex.code}` raised\n{traceback.format_exc()}"
            if status != 0:
                return f"{where}: `{ex.code}` exited with {status}:\n{output}"
        else:
            if not ex.code.startswith(CONTINUED):
                namespace = {"__name__": "__example__"}
            # padded so that tracebacks give the page's own line numbers
            code = compile("\n" * (ex.line - 1) + ex.code, str(path), "exec")
            try:
                exec(code, namespace)  # noqa: S102 - the page's code
            except BaseException:  # noqa: BLE001 - any failure names the page line
                return f"{where}: the Python block here failed\n{traceback.format_exc()}"
    return None


def run_page_in_scratch(path: Path, examples: list[Example], scratch: Path, monkeypatch) -> None:
    """Run a page's examples in ``scratch`` (the repository linked in, plots to files); a
    failure fails the calling test with the page's line.

    Args:
        path: The page.
        examples: Its examples (:func:`extract`).
        scratch: An empty temporary directory (``tmp_path``).
        monkeypatch: The test's ``monkeypatch`` (the directory and ``MPLBACKEND`` restored).

    """
    import matplotlib
    import pytest

    link_repository(scratch)
    monkeypatch.chdir(scratch)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    matplotlib.use("Agg")
    failure = run_page(path, examples)
    if failure is not None:
        pytest.fail(failure, pytrace=False)
