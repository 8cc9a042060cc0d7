"""A Pinocchio data per model and thread, for the one-shot computations of a set-up.

A solver's set-up sometimes runs the kinematics once (the plane normals of the closures at the
neutral configuration, say) and reads the result at once. Pinocchio 4.1's ``Data`` takes about
64 nv^3 bytes and milliseconds to make on large models: :func:`scratch_data` makes one per
model and thread, kept while the model lives, for such passages. Nothing may keep results in it
across calls: the next set-up on the same model overwrites them.
"""

from __future__ import annotations

import threading
import weakref

import pinocchio as pin

__all__ = ["scratch_data"]

_DATAS: dict[tuple[int, int], pin.Data] = {}
_LOCK = threading.Lock()


def _drop(key: int) -> None:
    with _LOCK:
        for k in [k for k in _DATAS if k[0] == key]:
            del _DATAS[k]


def scratch_data(model: pin.Model) -> pin.Data:
    """A data of ``model`` for this thread, made on first use (see the module docstring)."""
    key = (id(model), threading.get_ident())
    data = _DATAS.get(key)
    if data is None:
        data = model.createData()
        with _LOCK:
            first = not any(k[0] == key[0] for k in _DATAS)
            _DATAS[key] = data
        if first:
            weakref.finalize(model, _drop, key[0])
    return data
