"""What a robot keeps for its computations (pkdyn.model.reuse): made once, per robot and thread."""

from __future__ import annotations

import gc
import threading
import weakref

import pinocchio as pin

import pkdyn
from pkdyn.model.reuse import _KEPT, kept, kept_data


def test_made_once_per_robot_key_and_thread() -> None:
    robot = pkdyn.load("five_bar", geometry=False)
    other = pkdyn.load("five_bar", geometry=False)
    made: list[int] = []

    def make() -> object:
        made.append(1)
        return object()

    a = kept(robot, "k", make)
    assert kept(robot, "k", make) is a and len(made) == 1
    assert kept(other, "k", make) is not a and len(made) == 2
    assert kept(robot, "other key", make) is not a
    seen: list[object] = []
    t = threading.Thread(target=lambda: seen.append(kept(robot, "k", make)))
    t.start()
    t.join()
    assert seen[0] is not a  # (another thread: its own)


def test_datas_per_purpose_and_dropped_with_the_robot() -> None:
    robot = pkdyn.load("five_bar", geometry=False)
    d1 = kept_data(robot, "one")
    assert isinstance(d1, pin.Data)
    assert kept_data(robot, "one") is d1 and kept_data(robot, "two") is not d1
    gc.collect()  # (robots earlier tests left in cycles: collected now, not counted below)
    n = len(_KEPT)
    assert robot in _KEPT
    alive = weakref.ref(robot)
    del robot, d1
    gc.collect()
    assert alive() is None and len(_KEPT) == n - 1
