"""The worked Delta study's table, byte for byte, against the table of the code before the speedups.

``tests/data/design/delta_cylinder_300.<kernel>.csv`` is the CSV of ``studies/delta_cylinder.yaml``
with 300 designs, written by the code of ``main`` before the speed-ups of issue 37 (in-place
candidates' constraint layer, the Delta's closed-form metrics): every change that makes a study
faster must leave every figure of it unchanged, bit for bit. The figures that go through
OpenBLAS (``1 / cond(J)``'s SVD, the dynamics' 3x3 solves) round differently on its Haswell and
SkylakeX kernels: one reference per kernel, chosen by the kernel this process runs (the test is
skipped on a kernel without one).
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from pkdyn.design.run import run_study
from pkdyn.design.study import Study

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data" / "design"


def _kernel() -> str | None:
    """The OpenBLAS kernel numpy's linear algebra runs (``Haswell``, ``SkylakeX``...)."""
    import numpy as np
    from threadpoolctl import threadpool_info

    np.linalg.svd(np.eye(3))  # (loaded)
    for info in threadpool_info():
        if info.get("internal_api") == "openblas" and "numpy" in info.get("filepath", ""):
            return str(info.get("architecture"))
    for info in threadpool_info():
        if info.get("internal_api") == "openblas":
            return str(info.get("architecture"))
    return None


def test_worked_study_table_is_unchanged() -> None:
    reference = DATA / f"delta_cylinder_300.{_kernel()}.csv"
    if not reference.is_file():
        pytest.skip(f"no reference table for the OpenBLAS kernel {_kernel()}")
    data = yaml.safe_load((ROOT / "studies" / "delta_cylinder.yaml").read_text())
    data["n"] = 300
    result = run_study(Study.from_dict(data), workers=1, progress=False)
    text = result.designs.to_csv()
    expected = reference.read_text()
    assert text.count("\n") == expected.count("\n") == 301
    for k, (got, want) in enumerate(zip(text.splitlines(), expected.splitlines(), strict=True)):
        assert got == want, f"line {k + 1} differs"
    assert text == expected
