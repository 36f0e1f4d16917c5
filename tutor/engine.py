"""Where a study's independent jobs run: here, a local process pool, or a Dask cluster.

Cohorts, robustness, the adaptive study, simulated classes and a class's replays all
map one function over many independent jobs (a teacher, a teacher-arm, a run file).
:class:`Engine` is the one way they do it:

- **here** (``workers=1``): one after another in this process;
- **a local process pool** (the default): :func:`tutor.workers.process_pool`;
- **a Dask cluster** (``scheduler=``): ``"auto"`` starts a ``LocalCluster`` on this
  machine (one single-threaded worker process per core, on loopback, no dashboard);
  ``"tcp://HOST:PORT"`` joins a running scheduler (e.g. one started by dask-jobqueue on
  a batch cluster, or by the Dask Helm chart on Kubernetes).

Jobs are sent in batches (:func:`batches`: about four per worker, and at most
:data:`MAX_BATCH` jobs, so a study of thousands of teacher-arms sends tens of runs per
task, not one, and no worker idles long at the end waiting for another's last batch),
every batch runs on one BLAS thread (:func:`tutor.workers.one_blas_thread`), and
results come back in the jobs' order. A job's result depends only on its arguments (each
seeds its own generator), so a study gives the same numbers here, on the pool and on
any cluster.

Examples
--------
>>> with Engine(workers=1) as engine:
...     engine.map(abs, [-2, 3])
[2, 3]
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Callable, Sequence

from .errors import InvalidParameterError
from .workers import max_workers, one_blas_thread, process_pool

__all__ = ["Engine", "MAX_BATCH", "batches", "check_scheduler", "run_batch"]

#: a scheduler's address: "auto" (a local Dask cluster) or tcp://HOST:PORT
_ADDRESS = re.compile(r"tcp://[A-Za-z0-9.\-\[\]:]{1,253}:\d{1,5}")
#: batches per worker: enough to balance uneven jobs, few enough to keep overheads small
BATCHES_PER_WORKER = 4
#: the most jobs in one batch (a teacher-arm of the adaptive study is 3 runs, 0.2-1.5 s):
#: with 468-job batches on 2 workers, one worker sat idle about 50 s at the end of the
#: adaptive study, and its checkpoint file got a line only every few minutes
MAX_BATCH = 16


def check_scheduler(scheduler) -> str | None:
    """``scheduler`` checked: None (no Dask), ``"auto"`` or ``"tcp://HOST:PORT"``."""
    if scheduler is None:
        return None
    if not isinstance(scheduler, str) or not (
        scheduler == "auto" or _ADDRESS.fullmatch(scheduler.strip())
    ):
        raise InvalidParameterError(
            f"scheduler must be 'auto' (a Dask cluster on this machine) or a scheduler's "
            f"address tcp://HOST:PORT, got {scheduler!r}"
        )
    return scheduler.strip()


def batches(n_jobs: int, workers: int) -> list[range]:
    """The jobs 0 .. n_jobs - 1 cut into consecutive batches, about
    :data:`BATCHES_PER_WORKER` per worker and at most :data:`MAX_BATCH` jobs each."""
    size = min(MAX_BATCH, max(1, math.ceil(n_jobs / (BATCHES_PER_WORKER * max(1, workers)))))
    return [range(i, min(i + size, n_jobs)) for i in range(0, n_jobs, size)]


def run_batch(fn: Callable, items: Sequence) -> list:
    """``fn`` of each item, on one BLAS thread (what a worker runs for one batch)."""
    one_blas_thread()
    return [fn(item) for item in items]


class Engine:
    """Run ``fn`` over jobs here, on a local process pool or on a Dask cluster.

    Parameters
    ----------
    workers : int, optional
        Processes (local pool or ``LocalCluster``); default all cores. Ignored when
        joining a running scheduler (its workers are what it has).
    scheduler : str, optional
        None for no Dask, ``"auto"`` for a Dask ``LocalCluster`` here, or a scheduler's
        address ``tcp://HOST:PORT``.
    timeout : float
        Seconds to wait for a scheduler to answer.

    Use it as a context manager; :meth:`map` may be called several times inside.
    """

    def __init__(
        self, workers: int | None = None, scheduler: str | None = None, timeout: float = 30.0
    ):
        self.workers = workers
        self.scheduler = scheduler
        self.timeout = timeout

    # ---------------------------------------------------------------- start, stop

    def __enter__(self) -> Engine:
        self.scheduler = check_scheduler(self.scheduler)
        workers = max_workers() if self.workers is None else self.workers
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise InvalidParameterError(f"workers must be a whole number >= 1, got {workers!r}")
        self.workers_ = workers
        self._pool = self._client = self._cluster = None
        if self.scheduler is not None:
            self._start_dask()
        elif workers > 1:
            self._pool = process_pool(workers)
        else:
            one_blas_thread()
        return self

    def _start_dask(self) -> None:
        try:
            from distributed import Client, LocalCluster
        except ImportError as exc:  # pragma: no cover - the cluster extra is not installed
            raise InvalidParameterError(
                "a Dask scheduler needs dask and distributed: pip install 'lfd-tutor[cluster]'"
            ) from exc
        if self.scheduler == "auto":
            with warnings.catch_warnings():  # "port 8787 in use": it takes another one
                warnings.simplefilter("ignore", UserWarning)
                self._cluster = LocalCluster(
                    n_workers=self.workers_,
                    threads_per_worker=1,
                    processes=True,
                    host="127.0.0.1",  # nothing listens beyond loopback
                    dashboard_address=None,  # no dashboard (its HTTP server: loopback too)
                    silence_logs=40,  # errors only
                )
            self._client = Client(self._cluster)
        else:
            try:
                self._client = Client(self.scheduler, timeout=f"{self.timeout}s")
            except (OSError, TimeoutError) as exc:
                raise InvalidParameterError(
                    f"no Dask scheduler answers at {self.scheduler} ({exc}); start one (e.g. "
                    "'dask scheduler' and 'dask worker', dask-jobqueue or the Dask Helm "
                    "chart) or use --scheduler auto"
                ) from exc
            self.workers_ = max(1, len(self._client.scheduler_info().get("workers", {})))

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
        if self._client is not None:
            self._client.close()
        if self._cluster is not None:
            self._cluster.close()

    @property
    def where(self) -> str:
        """Where the jobs run, in words."""
        if self._client is not None:
            return f"Dask ({self.scheduler}, {self.workers_} workers)"
        if self._pool is not None:
            return f"a local pool of {self.workers_} processes"
        return "this process"

    # ---------------------------------------------------------------- jobs

    def map(self, fn: Callable, items: Sequence, step: Callable | None = None,
            meanwhile: Callable | None = None) -> list:
        """``[fn(item) for item in items]``, computed where this engine runs jobs.

        ``step(k)`` is called here after each of the k first results to arrive (a
        progress bar's update), ``meanwhile()`` once while the workers work.
        """
        items = list(items)
        out: list = [None] * len(items)
        for k, (i, result) in enumerate(self.results(fn, items, meanwhile), start=1):
            out[i] = result
            if step is not None:
                step(k)
        return out

    def results(self, fn: Callable, items: Sequence, meanwhile: Callable | None = None):
        """Yield ``(i, fn(items[i]))`` as results arrive (a batch at a time), so that a
        long study can keep each one at once; ``meanwhile()`` runs once while the
        workers work."""
        items = list(items)
        if self._pool is None and self._client is None or len(items) < 2:
            for i, item in enumerate(items):
                yield i, fn(item)
            if meanwhile is not None:
                meanwhile()
            return
        cuts = batches(len(items), self.workers_)
        parts = [[items[i] for i in cut] for cut in cuts]
        for index, batch in self._submit(fn, parts, meanwhile):
            yield from zip(cuts[index], batch, strict=True)

    def _submit(self, fn, parts, meanwhile):
        """Yield (batch index, its results) as batches finish."""
        if self._client is not None:
            from distributed import as_completed

            futures = self._client.map(run_batch, [fn] * len(parts), parts, pure=False)
            where = {f.key: i for i, f in enumerate(futures)}
            if meanwhile is not None:
                meanwhile()
            for future in as_completed(futures):
                yield where[future.key], future.result()
            return
        from concurrent.futures import as_completed

        futures = {self._pool.submit(run_batch, fn, part): i for i, part in enumerate(parts)}
        if meanwhile is not None:
            meanwhile()
        for future in as_completed(futures):
            yield futures[future], future.result()
