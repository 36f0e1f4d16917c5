"""Where a study's jobs run (tutor.engine): here, a process pool, or a Dask cluster.

The same study gives the same numbers on each: a cohort, ``lfd-tutor robustness`` and
``lfd-tutor adaptive --quick`` on a Dask LocalCluster against the process pool.
"""

from __future__ import annotations

import pandas as pd
import pytest

from tutor.engine import MAX_BATCH, Engine, batches, check_scheduler
from tutor.errors import InvalidParameterError


def _square(x):
    return x * x


def _fails(x):
    raise ValueError(f"job {x} failed")


@pytest.fixture(scope="module")
def cluster():
    """A Dask LocalCluster of 2 workers on loopback, and its scheduler's address."""
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None
    ) as local:
        yield local.scheduler_address


def test_batches_cover_every_job_once_in_order():
    for n, workers in ((1, 1), (7, 2), (100, 2), (3000, 8)):
        cuts = batches(n, workers)
        assert [i for cut in cuts for i in cut] == list(range(n))
        assert len(cuts) <= max(4 * workers, -(-n // MAX_BATCH))
        assert max(len(cut) for cut in cuts) <= MAX_BATCH
    # a cohort of 36 teachers on 2 workers: 8 batches of 4-5 (each worker takes 4)
    assert [len(cut) for cut in batches(36, 2)] == [5] * 7 + [1]
    # the adaptive study's 3744 teacher-arms: 234 batches of 16 (48 runs a task), not 8
    # batches of 468 whose last one kept a worker busy long after the other was done
    assert [len(cut) for cut in batches(3744, 2)] == [16] * 234


@pytest.mark.parametrize(
    "bad", ["", "local", "tcp://", "http://127.0.0.1:8786", "tcp://host", 8786, ["auto"]]
)
def test_a_bad_scheduler_is_a_named_error(bad):
    with pytest.raises(InvalidParameterError, match="tcp://HOST:PORT"):
        check_scheduler(bad)


def test_no_scheduler_answering_is_a_named_error_not_a_hang():
    with pytest.raises(InvalidParameterError, match="no Dask scheduler answers"):
        with Engine(scheduler="tcp://127.0.0.1:1", timeout=2):
            pass


@pytest.mark.parametrize("workers", [0, -1, 1.5, True, "2"])
def test_bad_workers_are_a_named_error(workers):
    with pytest.raises(InvalidParameterError, match="workers"):
        with Engine(workers):
            pass


def test_here_the_pool_and_dask_give_the_same_results_in_order(cluster):
    items = list(range(41))
    seen = {}
    for name, engine in {
        "here": Engine(1),
        "pool": Engine(2),
        "auto": Engine(2, "auto"),
        "address": Engine(scheduler=cluster),
    }.items():
        steps = []
        with engine:
            seen[name] = engine.map(_square, items, step=steps.append)
            assert engine.workers_ >= 1 and engine.where
        assert steps[-1] == len(items) and steps == sorted(steps)  # a progress bar's steps
    assert all(v == [x * x for x in items] for v in seen.values())


def test_a_failing_job_raises_its_error_on_every_engine(cluster):
    for engine in (Engine(1), Engine(2), Engine(scheduler=cluster)):
        with engine, pytest.raises(ValueError, match="failed"):
            engine.map(_fails, [1, 2, 3])


def test_a_cohort_on_dask_is_the_cohort_of_the_pool(cluster):
    from tutor.study.cohort import run_experiment

    pool = run_experiment(1, seed=3, n=3, workers=2, progress=False)
    dask = run_experiment(1, seed=3, n=3, progress=False, scheduler=cluster)
    pd.testing.assert_frame_equal(pool.runs, dask.runs)
    pd.testing.assert_frame_equal(pool.demos, dask.demos)


def _cli(argv, capsys):
    from tutor.__main__ import main

    code = main(argv)
    out = capsys.readouterr()
    assert code == 0, out.err
    return out.out


def test_robustness_on_a_local_cluster_equals_the_process_pool(tmp_path, capsys):
    tables = {}
    for name, extra in (("pool", ["--workers", "2"]), ("dask", ["--scheduler", "auto"])):
        out = tmp_path / name
        _cli(
            ["robustness", "--experiment", "1", "--n", "3", "--seeds", "2", "--out", str(out),
             "--no-progress", *extra],
            capsys,
        )
        tables[name] = pd.read_csv(out / "experiment1_robustness.csv")
    pd.testing.assert_frame_equal(tables["pool"], tables["dask"])


def test_the_quick_adaptive_study_on_a_local_cluster_equals_the_process_pool(tmp_path, capsys):
    found = {}
    for name, extra in (("pool", ["--workers", "2"]), ("dask", ["--scheduler", "auto"])):
        out = tmp_path / name
        _cli(
            ["adaptive", "--quick", "--no-progress", "--no-figures", "--out", str(out), *extra],
            capsys,
        )
        found[name] = sorted(p.name for p in out.iterdir() if p.suffix == ".csv")
        found[name + " runs"] = [pd.read_csv(out / f) for f in found[name]]
    assert found["pool"] == found["dask"] and found["pool"]
    for a, b in zip(found["pool runs"], found["dask runs"], strict=True):
        drop = [c for c in a.columns if "second" in c]  # wall-clock columns, if any
        pd.testing.assert_frame_equal(a.drop(columns=drop), b.drop(columns=drop))


def test_the_cli_refuses_a_bad_scheduler_in_one_line(capsys):
    from tutor.__main__ import main

    with pytest.raises(SystemExit) as stop:
        main(["robustness", "--experiment", "1", "--scheduler", "somewhere"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and "tcp://HOST:PORT" in err and "Traceback" not in err
