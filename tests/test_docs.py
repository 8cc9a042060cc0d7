"""The documentation builds with warnings as errors (what ``make docs`` builds, minus HTML).

The build is Sphinx's ``text`` builder on the whole site: the user guide (MyST), the command
line reference generated from the parsers, the API reference from every public docstring
(autosummary + napoleon), the notebooks. Every page is read and its references resolved, so
broken Markdown, links, toctrees, includes and RST in docstrings (``|x|`` read as a
substitution) fail here; only the HTML writing is left to ``make docs``. The command-line
reference is read as built: the options keep their two hyphens (no typographic dashes). The
notebooks are rendered, not executed (``PKDYN_DOCS_EXECUTE=off``): the notebook tests (nbmake)
execute the same notebooks, and ``make docs`` executes the copies it renders.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def test_docs_build_with_warnings_as_errors(tmp_path):
    shutil.rmtree(DOCS / "_autosummary", ignore_errors=True)  # as `make docs` does
    env = dict(os.environ, PKDYN_DOCS_EXECUTE="off", MPLBACKEND="Agg")
    command = [sys.executable, "-m", "sphinx", "-b", "text", "-W", "--keep-going", "-q", "-E"]
    command += ["-j", "2", "-d", str(tmp_path / "doctrees"), str(DOCS), str(tmp_path / "out")]
    proc = subprocess.run(command, capture_output=True, text=True, env=env, check=False)
    problems = [
        line
        for line in proc.stderr.splitlines()
        if re.search(r"WARNING|ERROR|CRITICAL|Traceback|Exception", line)
    ]
    assert proc.returncode == 0 and not problems, "\n".join(problems) or proc.stderr[-3000:]
    reference = (DOCS / "_generated" / "cli.md").read_text(encoding="utf-8")
    assert "## `pkdyn size`" in reference and "### `pkdyn tripod scenario`" in reference
    # the built page keeps options as typed (no smart dashes): copy-paste works
    built = (tmp_path / "out" / "guide" / "cli.txt").read_text(encoding="utf-8")
    assert "--pose" in built and "(no --step)" in built and "\u2013" not in built


NUMBERS = "zero one two three four five six seven eight nine ten eleven twelve".split()


def test_the_pages_count_the_notebooks():
    """The home page and the notebooks page say how many studies there are: all of them."""
    count = NUMBERS[len(list((ROOT / "notebooks").glob("*.ipynb")))]
    assert f"{count} studies" in (DOCS / "index.md").read_text(encoding="utf-8")
    assert f"tells {count} studies" in (DOCS / "notebooks.md").read_text(encoding="utf-8")


RELATIVE = re.compile(r"""Path\(\s*["']\.\.|["']\.\./|join\(\s*["']\.\.["']""")


def test_notebooks_find_their_files_wherever_they_run():
    """``make docs`` executes copies in docs/notebooks: no path relative to the notebook."""
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        for cell in json.loads(path.read_text(encoding="utf-8"))["cells"]:
            source = "".join(cell["source"])
            if cell["cell_type"] == "code":
                assert not RELATIVE.search(source), f"{path.name}: {RELATIVE.search(source)}"
