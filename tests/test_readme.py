"""The README examples run: every ```python block and every ``pkdyn`` line of a ```sh block.

The examples of ``README.md`` and ``urdf/README.md`` are extracted and run in file order, in
one temporary directory (files written by one example, e.g. ``cloud.npy``, are there for the
next) where the repository's top-level files and folders are linked, so that paths relative to
the repository root (``urdf/delta.urdf``, ``tests/data/...``) work as in a checkout. Each Python
block runs in a fresh namespace, so that each is complete by itself (a reader can copy any one);
a block whose first line is ``# (continued)`` shares the namespace of the block above instead.
CLI lines run in-process through ``pkdyn.cli.main`` and must exit with status 0; a line ending
with ``\\`` continues on the next; other shell lines (``make ...``), comment lines and sketches
(a line with ``...`` for some of its arguments) are not run. An example that would run too long
or forever (a live viewer) carries the comment ``(not run by the tests)``: on the CLI line, or
on the first line of a Python block. A failure names the README file and line.
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
import traceback
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).resolve().parent.parent
READMES = ["README.md", "urdf/README.md"]
SKIP = "(not run by the tests)"
CONTINUED = "# (continued)"


@dataclass(frozen=True)
class Example:
    """One runnable example: a Python block or a CLI line."""

    kind: str  # "python" or "cli"
    line: int  # 1-based line in the README (the block's first code line)
    code: str


def extract(text: str) -> list[Example]:
    """The ```python blocks and ``pkdyn`` lines of ```sh blocks, in order."""
    out: list[Example] = []
    lines = text.splitlines()
    k = 0
    while k < len(lines):
        fence = re.match(r"^```(\w*)\s*$", lines[k])
        if not fence:
            k += 1
            continue
        lang, start = fence.group(1), k + 1
        k = start
        while k < len(lines) and not lines[k].startswith("```"):
            k += 1
        body = lines[start:k]
        k += 1
        if lang == "python":
            if body and SKIP not in body[0]:
                out.append(Example("python", start + 1, "\n".join(body)))
        elif lang in ("sh", "bash", "console"):
            i = 0
            while i < len(body):
                first, command = i, body[i].strip()
                while command.endswith("\\") and i + 1 < len(body):  # continued line
                    i += 1
                    command = command[:-1].rstrip() + " " + body[i].strip()
                i += 1
                sketch = "..." in command.split("#")[0].split()  # `pkdyn cmd ... --opt`
                if command.startswith("pkdyn ") and SKIP not in command and not sketch:
                    out.append(Example("cli", start + 1 + first, command))
    return out


def test_extractor_finds_blocks_lines_and_markers():
    text = "\n".join(
        [
            "intro",
            "```python",
            "x = 1",
            "```",
            "```sh",
            "make demo   # not a pkdyn line",
            "pkdyn info delta --json   # comment",
            "#   continuation comment",
            "pkdyn view delta   # live (not run by the tests)",
            "pkdyn design ... --seed 1   # a sketch: `...` stands for the options above",
            "pkdyn mobility delta \\",
            "  --json",
            "```",
            "```python",
            "# slow (not run by the tests)",
            "```",
            "```xml",
            "pkdyn info delta",
            "```",
        ]
    )
    assert extract(text) == [
        Example("python", 3, "x = 1"),
        Example("cli", 7, "pkdyn info delta --json   # comment"),
        Example("cli", 11, "pkdyn mobility delta --json"),
    ]


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


@pytest.mark.parametrize("readme", READMES)
def test_readme_examples_run(readme, tmp_path, monkeypatch):
    path = ROOT / readme
    examples = extract(path.read_text(encoding="utf-8"))
    if readme == "README.md":
        assert len(examples) > 10  # the extractor still finds the tour's examples
    for item in ROOT.iterdir():
        if item.name not in (".git", ".venv") and not (tmp_path / item.name).exists():
            (tmp_path / item.name).symlink_to(item, target_is_directory=item.is_dir())
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    matplotlib.use("Agg")
    namespace: dict[str, object] = {}
    for ex in examples:
        where = f"{readme}:{ex.line}"
        failure = None
        if ex.kind == "cli":
            try:
                status, output = _run_cli(ex.code)
                if status != 0:
                    failure = f"`{ex.code}` exited with {status}:\n{output}"
            except BaseException:  # noqa: BLE001 - any failure names the README line
                failure = f"`{ex.code}` raised\n{traceback.format_exc()}"
        else:
            if not ex.code.startswith(CONTINUED):
                namespace = {"__name__": "__readme__"}
            # padded so that tracebacks give the README's own line numbers
            code = compile("\n" * (ex.line - 1) + ex.code, str(path), "exec")
            try:
                exec(code, namespace)  # noqa: S102 - the README's code
            except BaseException:  # noqa: BLE001 - any failure names the README line
                failure = f"the Python block here failed\n{traceback.format_exc()}"
        if failure is not None:
            pytest.fail(f"{where}: {failure}", pytrace=False)
