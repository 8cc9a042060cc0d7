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

_DATAS: dict[tuple[int, int], tuple[weakref.ref[pin.Model], pin.Data]] = {}
_LOCK = threading.Lock()


def scratch_data(model: pin.Model) -> pin.Data:
    """A data of ``model`` for this thread, made on first use (see the module docstring).

    The entries hold their model weakly and are checked against it (an ``id`` can be reused
    by a later model); the entries of dead models are dropped at the next new entry. No
    finalizer runs here: one run by the garbage collector while this thread holds the lock
    would wait for it forever.
    """
    key = (id(model), threading.get_ident())
    entry = _DATAS.get(key)
    if entry is not None and entry[0]() is model:
        return entry[1]
    data = model.createData()
    with _LOCK:
        for k in [k for k, (ref, _) in _DATAS.items() if ref() is None]:
            del _DATAS[k]
        _DATAS[key] = (weakref.ref(model), data)
    return data
