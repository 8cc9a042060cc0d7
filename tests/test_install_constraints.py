"""constraints.txt pins every package a development install takes (the versions tested).

``make`` installs with ``pip install -c constraints.txt -e ".[dev]"``: a dependency of
``pyproject.toml`` missing from the file would be installed at whatever version is newest that
day, and a fresh clone would no longer test what the suite was tested with.
"""

import re
from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # (Python 3.11+)

ROOT = Path(__file__).resolve().parents[1]


def _name(requirement: str) -> str:
    """The normalised project name of a requirement (``dask[distributed]>=2024.1`` -> dask)."""
    return re.split(r"[\s\[<>=!~;]", requirement.strip(), maxsplit=1)[0].lower().replace("_", "-")


def test_every_dependency_is_pinned_to_one_version():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    wanted = list(project["dependencies"])
    for extra in ("dev", "docs"):
        wanted += project["optional-dependencies"][extra]
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            name, _, version = line.partition("==")
            assert version and re.fullmatch(r"[\w.+!-]+", version), line
            pins[_name(name)] = version
    missing = sorted({_name(r) for r in wanted} - set(pins))
    assert not missing, f"add to constraints.txt (make constraints): {missing}"
    assert "pkdyn" not in pins  # the project itself is installed from the tree
