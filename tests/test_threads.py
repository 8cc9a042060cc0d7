"""pkdyn.threads: one BLAS thread inside a block; a nested block of the same thread is free."""

from __future__ import annotations

import threading

import pytest
from threadpoolctl import threadpool_info

from pkdyn import threads


def _blas_threads() -> list[int]:
    return [int(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"]


def test_nested_blocks_keep_one_thread_and_limit_once(monkeypatch: pytest.MonkeyPatch) -> None:
    before = _blas_threads()
    controller = threads._get_controller()
    calls = []
    limit = type(controller).limit

    def counting(self, *args, **kwargs):
        calls.append(1)
        return limit(self, *args, **kwargs)

    monkeypatch.setattr(type(controller), "limit", counting)
    with threads.single_blas_thread():
        assert set(_blas_threads()) <= {1}
        with threads.single_blas_thread():
            assert set(_blas_threads()) <= {1}
        assert set(_blas_threads()) <= {1}  # (the inner block restored nothing)

        seen: list[list[int]] = []

        def other() -> None:  # another thread's block limits (and restores) by itself
            with threads.single_blas_thread():
                seen.append(_blas_threads())

        t = threading.Thread(target=other)
        t.start()
        t.join()
        assert set(seen[0]) <= {1}
    assert _blas_threads() == before
    assert len(calls) == 2  # the outer block and the other thread's, not the nested one


def test_decorated_function_inside_a_block() -> None:
    @threads.one_blas_thread
    def f() -> list[int]:
        return _blas_threads()

    before = _blas_threads()
    assert set(f()) <= {1}
    with threads.single_blas_thread():
        assert set(f()) <= {1}
    assert _blas_threads() == before
