"""What a robot's computations build once and keep: Pinocchio datas, solvers.

A public call on a robot (:func:`pkdyn.dynamics.inverse_dynamics`, the sampled kinematics of
:func:`pkdyn.dynamics.joint_motion.actuator_trajectory`...) needs Pinocchio ``Data`` objects
and solver buffers whose size grows like nv^2 to nv^3 (Pinocchio 4.1's ``Data``: about
64 nv^3 bytes, 21 ms to make at nv = 81): made for every call, they cost more than the call's
arithmetic on large models. :func:`kept` makes such an object once per robot, purpose and
thread, and hands the same one to the next call; it goes with the robot (a weak reference:
nothing is kept for a robot no longer used). A kept object must not refer to the robot itself.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable, Hashable
from typing import Any, TypeVar

import pinocchio as pin

__all__ = ["kept", "kept_data"]

T = TypeVar("T")

_KEPT: weakref.WeakKeyDictionary[Any, dict[Hashable, Any]] = weakref.WeakKeyDictionary()
_LOCK = threading.Lock()
_MAX_PER_ROBOT = 16
"""Objects kept per robot (the oldest is dropped beyond)."""


def kept(robot: Any, key: Hashable, make: Callable[[], T]) -> T:
    """``make()`` once per ``robot``, ``key`` and thread, then the same object.

    Args:
        robot: The robot (any object with identity hashing and weak references).
        key: What the object is for (and the options it was made with).
        make: Makes it.

    Returns:
        The object.

    """
    full = (key, threading.get_ident())
    with _LOCK:
        store = _KEPT.get(robot)
        if store is None:
            store = _KEPT[robot] = {}
        obj = store.get(full)
    if obj is None:
        obj = make()
        with _LOCK:
            if len(store) >= _MAX_PER_ROBOT:
                store.pop(next(iter(store)))
            store[full] = obj
    return obj  # type: ignore[no-any-return]


def kept_data(robot: Any, purpose: str) -> pin.Data:
    """A Pinocchio ``Data`` of ``robot.model`` kept for ``purpose`` (see :func:`kept`).

    Two purposes never share one, so that a computation may call another inside it (a torque
    callback computing inverse dynamics during a simulation).
    """
    model = robot.model
    return kept(robot, ("data", purpose), model.createData)
