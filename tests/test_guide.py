"""The user guide's examples run: every page of docs/guide (rules in :mod:`support.examples`).

Each page runs in its own temporary directory, its examples in page order; a page with no
example is fine (the placeholders of pages written elsewhere).
"""

from __future__ import annotations

import pytest
from support.examples import ROOT, extract, run_page_in_scratch

GUIDE = ROOT / "docs" / "guide"
PAGES = sorted(p.name for p in GUIDE.glob("*.md"))


def test_the_guide_has_its_pages():
    for page in ("index.md", "getting-started.md", "describing.md", "cli.md", "evidence.md"):
        assert page in PAGES


@pytest.mark.parametrize("page", PAGES)
def test_guide_examples_run(page, tmp_path, monkeypatch):
    path = GUIDE / page
    examples = extract(path.read_text(encoding="utf-8"), f"docs/guide/{page}")
    run_page_in_scratch(path, examples, tmp_path, monkeypatch)


def test_the_described_robot_is_what_the_page_says():
    """docs/guide/describing.md: its lifter's mobility, home and the strut's holding torque."""
    import re

    import numpy as np

    import pkdyn
    from pkdyn.analysis import classify, static_equilibrium
    from pkdyn.analysis.mobility import mobility

    page = (GUIDE / "describing.md").read_text(encoding="utf-8")
    xml = re.search(r"```xml\n<!-- file: lifter.urdf -->\n(.*?)```", page, re.S).group(1)
    lifter = pkdyn.load_string(xml, "lifter.urdf")
    assert (lifter.dof(), lifter.loops) == (2, 2)
    assert [c.kind for c in lifter.closures] == ["hinge", "point", "weld"]
    m = mobility(lifter).to_json()
    assert (m["mobility"], m["internal"], m["hyperstatism"]) == (2, 0, 4)
    assert pkdyn.closure_residual(lifter, lifter.q_home) < 1e-12  # the zero pose is assembled
    assert classify(lifter, lifter.q_home).kind == "regular"
    hold = static_equilibrium(lifter, lifter.q_home, gravity=True).tau
    bare = static_equilibrium(lifter, lifter.q_home, gravity=True, passive=False).tau
    # recorded figures of the page: the strut turns motor 2's 1.02 N m into -0.42 N m
    assert np.allclose([hold[1], bare[1]], [-0.417, 1.023], atol=1e-3)
    assert np.isclose(hold[0], bare[0])  # the strut acts on crank 2 only
