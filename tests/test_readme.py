"""The README examples run: README.md and urdf/README.md (rules in :mod:`support.examples`)."""

from __future__ import annotations

import pytest
from support.examples import ROOT, Example, PageError, extract, run_page_in_scratch

READMES = ["README.md", "urdf/README.md"]


def test_extractor_finds_blocks_lines_files_and_markers():
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
            "pkdyn design ... --seed 1   # a sketch (not run by the tests)",
            "pkdyn mobility delta \\",
            "  --json",
            ".venv/bin/pkdyn --version",
            "```",
            "```python",
            "# slow (not run by the tests)",
            "```",
            "```xml",
            "pkdyn info delta",
            "```",
            "```xml",
            "<!-- file: arm.urdf -->",
            "<robot/>",
            "```",
            "```yaml",
            "# file: c.yaml",
            "motors: []",
            "```",
        ]
    )
    assert extract(text) == [
        Example("python", 3, "x = 1"),
        Example("cli", 7, "pkdyn info delta --json   # comment"),
        Example("cli", 11, "pkdyn mobility delta --json"),
        Example("cli", 13, "pkdyn --version"),
        Example("file", 22, "<robot/>\n", "arm.urdf"),
        Example("file", 26, "motors: []\n", "c.yaml"),
    ]


def test_a_sketch_without_its_marker_is_an_error_of_the_page():
    with pytest.raises(PageError, match="page:2: the sketch"):
        extract("```sh\npkdyn design ... --seed 1\n```")


@pytest.mark.parametrize("readme", READMES)
def test_readme_examples_run(readme, tmp_path, monkeypatch):
    path = ROOT / readme
    examples = extract(path.read_text(encoding="utf-8"), readme)
    if readme == "README.md":
        assert len(examples) > 10  # the extractor still finds the tour's examples
    run_page_in_scratch(path, examples, tmp_path, monkeypatch)
