"""The closure layer's shortcut for closures moved by a ball or free joint (never planar).

:meth:`solvers.closure.ClosureRows._normals` skips :func:`solvers.planar.plane_normal` for a
closure whose support contains a ball or free joint; the arithmetic it skips must give the same
answer (no plane) on every robot of the library.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkdyn
from pkdyn.model.families import FAMILIES
from solvers.closure import ClosureRows


def _full(rows: ClosureRows, monkeypatch: pytest.MonkeyPatch) -> list[np.ndarray | None]:
    with monkeypatch.context() as m:
        m.setattr(ClosureRows, "_turns_freely", lambda self, j: False)
        return rows._normals()


@pytest.mark.parametrize("name", list(FAMILIES))
def test_shortcut_gives_the_normals_of_the_arithmetic(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = pkdyn.load(name, geometry=False)
    rows = robot.constraints._closure
    if rows is None or not rows.closures:
        pytest.skip(f"{name}: no closure")
    fast = rows._normals()
    full = _full(rows, monkeypatch)
    assert len(fast) == len(full)
    for a, b in zip(fast, full, strict=True):
        assert (a is None) == (b is None)
        if a is not None:
            assert np.array_equal(a, b)


def test_a_closure_moved_by_a_ball_joint_is_not_planar(monkeypatch: pytest.MonkeyPatch) -> None:
    robot = pkdyn.load("delta", geometry=False)
    rows = robot.constraints._closure
    assert rows is not None
    assert all(rows._turns_freely(c.joint1) for c in rows.closures)  # bars on ball joints
    assert rows._normals() == [None] * len(rows.closures) == _full(rows, monkeypatch)


def test_planar_closures_keep_their_normals() -> None:
    robot = pkdyn.load("planar_3rrr", geometry=False)
    rows = robot.constraints._closure
    assert rows is not None
    assert not any(
        rows._turns_freely(c.joint1) or rows._turns_freely(c.joint2) for c in rows.closures
    )
    assert all(n is not None for n in rows.normals)
