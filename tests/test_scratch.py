"""The per-model scratch data of the solvers' set-ups (solvers/scratch.py)."""

from __future__ import annotations

import gc
import threading

import pinocchio as pin

from solvers.scratch import _DATAS, _LOCK, scratch_data


def _model(n: int) -> pin.Model:
    model = pin.Model()
    parent = 0
    for i in range(n):
        parent = model.addJoint(parent, pin.JointModelRZ(), pin.SE3.Identity(), f"j{i}")
    return model


def test_one_data_per_model_and_thread_and_never_another_models():
    a, b = _model(2), _model(3)
    assert scratch_data(a) is scratch_data(a)
    assert scratch_data(b) is not scratch_data(a)
    assert scratch_data(b).oMi.__len__() == b.njoints
    other = []
    t = threading.Thread(target=lambda: other.append(scratch_data(a)))
    t.start()
    t.join()
    assert other[0] is not scratch_data(a)
    for _ in range(200):  # models die and their ids come back: never a dead model's data
        m = _model(1 + _ % 4)
        assert len(scratch_data(m).oMi) == m.njoints
        del m


def test_dead_models_entries_are_dropped_and_a_collection_inside_cannot_deadlock():
    for _ in range(50):
        m = _model(2)
        scratch_data(m)
        del m
    gc.collect()
    scratch_data(_model(2))  # a new entry sweeps the dead ones
    alive = [k for k, (ref, _) in _DATAS.items() if ref() is not None]
    assert len(_DATAS) - len(alive) <= 1
    # a model collected while this thread holds the lock (the garbage collector runs inside a
    # set-up) runs no code of ours that waits for it: the former finalizer hung the suite here
    done = threading.Event()

    def collect_under_the_lock() -> None:
        m = [_model(2)]
        m.append(m)  # a cycle: only the collector frees it
        scratch_data(m[0])  # type: ignore[arg-type]
        del m
        with _LOCK:
            gc.collect()
        done.set()

    worker = threading.Thread(target=collect_under_the_lock, daemon=True)
    worker.start()
    assert done.wait(20.0), "a model collected under the lock waited for the lock"
