"""Worker processes for the simulations and replays: one BLAS thread each.

Cohorts, the adaptive study, simulated classes, a class's replays and the lookahead's
scoring all spread independent work over processes. They share this one way of doing
it: :func:`process_pool` forks where the platform can (the workers inherit what the
parent has loaded) and spawns otherwise, and every worker, like a serial run, does its
arithmetic on one BLAS thread (:func:`one_blas_thread`), so a result does not depend on
how many processes computed it.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import sys
from concurrent.futures import ProcessPoolExecutor

__all__ = ["can_fork", "one_blas_thread", "init_worker", "max_workers", "process_pool"]

_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")

#: the active threadpoolctl limit of this process (kept so it stays in force)
_LIMITER = None
#: (process id, modules loaded) when the limit was last set (see one_blas_thread)
_LIMITED: tuple[int, int] | None = None


def can_fork() -> bool:
    """Whether worker processes can fork from this one (not on Windows, say)."""
    return "fork" in mp.get_all_start_methods()


def one_blas_thread() -> None:
    """One BLAS thread in this process: the same arithmetic here and in every worker.

    Limiting scans the loaded libraries (about 3 ms), so it is redone only in a new
    process or once a module has been imported since (it may have loaded a BLAS).
    """
    global _LIMITER, _LIMITED
    done = (os.getpid(), len(sys.modules))
    if _LIMITED == done:
        return
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - numpy then uses its default threads
        return
    _LIMITER = threadpool_limits(1)
    _LIMITED = (os.getpid(), len(sys.modules))


def init_worker() -> None:
    """A worker's start: one thread for OpenMP and BLAS, in itself and its children."""
    for var in _THREAD_VARIABLES:
        os.environ[var] = "1"
    one_blas_thread()


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _process_limit() -> int | None:
    """The processes this user may start (RLIMIT_NPROC's soft limit), None if unlimited."""
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_NPROC)
    except (ImportError, AttributeError, OSError, ValueError):  # pragma: no cover
        return None
    return None if soft == resource.RLIM_INFINITY else int(soft)


def max_workers() -> int:
    """The most worker processes worth starting here: the cores this process may run on,
    and fewer than the processes the user may start (RLIMIT_NPROC)."""
    limit = _process_limit()
    most = _cores() if limit is None else min(_cores(), limit - 1)
    return max(1, most)


def process_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` processes started by :func:`init_worker` (fork if possible);
    more than :func:`max_workers` are clamped to it, with a message (never a hang on
    processes the system will not start)."""
    most = max_workers()
    if workers > most:
        print(
            f"Using {most} worker processes, not {workers}: this machine lets this process "
            f"use {_cores()} cores (and {_process_limit() or 'unlimited'} processes).",
            file=sys.stderr,
        )
        workers = most
    ctx = mp.get_context("fork" if can_fork() else "spawn")
    return ProcessPoolExecutor(workers, mp_context=ctx, initializer=init_worker)
