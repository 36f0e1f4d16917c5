"""One BLAS thread per process: set once, redone when it may have lapsed."""

from __future__ import annotations

import sys

from threadpoolctl import threadpool_info

from tutor import workers


def test_one_blas_thread_limits_every_blas_and_is_not_redone_needlessly(monkeypatch):
    calls = []
    import threadpoolctl

    real = threadpoolctl.threadpool_limits

    def counting(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)

    monkeypatch.setattr(threadpoolctl, "threadpool_limits", counting)
    monkeypatch.setattr(workers, "_LIMITED", None)
    workers.one_blas_thread()
    assert len(calls) == 1
    assert all(p["num_threads"] == 1 for p in threadpool_info() if p["user_api"] == "blas")
    workers.one_blas_thread()
    assert len(calls) == 1  # nothing new loaded: the limit stands
    monkeypatch.setitem(sys.modules, "a_module_that_may_load_a_blas", object())
    workers.one_blas_thread()
    assert len(calls) == 2  # a module came: limit again
    monkeypatch.setattr(workers, "_LIMITED", (-1, len(sys.modules)))  # another process's
    workers.one_blas_thread()
    assert len(calls) == 3
