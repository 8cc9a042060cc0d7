"""The user guide's examples run: every page of docs/guide (rules in :mod:`support.examples`).

Each page runs in its own temporary directory, its examples in page order; a page with no
example is fine (the placeholders of pages written elsewhere).
"""

from __future__ import annotations

import matplotlib
import pytest
from support.examples import ROOT, extract, link_repository, run_page

GUIDE = ROOT / "docs" / "guide"
PAGES = sorted(p.name for p in GUIDE.glob("*.md"))


def test_the_guide_has_its_pages():
    for page in ("index.md", "getting-started.md", "describing.md", "cli.md", "evidence.md"):
        assert page in PAGES


@pytest.mark.parametrize("page", PAGES)
def test_guide_examples_run(page, tmp_path, monkeypatch):
    path = GUIDE / page
    examples = extract(path.read_text(encoding="utf-8"), f"docs/guide/{page}")
    link_repository(tmp_path)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    matplotlib.use("Agg")
    failure = run_page(path, examples)
    if failure is not None:
        pytest.fail(failure, pytrace=False)
