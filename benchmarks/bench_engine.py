"""Benchmark the engines a study runs on: here, the process pool, a Dask LocalCluster.

Simulates the paper-sized cohorts of both experiments (seed 0, no statistics) on each
engine and prints the median wall time over ``--repeats``, with the speed-up over one
process: "dask auto" starts a LocalCluster for the cohort (its workers import the
package and build the task first), "dask warm" runs on one kept open (as robustness and
the adaptive study do); and the LocalCluster's start and stop alone. The numbers must not depend on
the engine: each run's tables are compared with the first engine's.

Run:  .venv/bin/python benchmarks/bench_engine.py [--repeats 3] [--workers 2]
"""

from __future__ import annotations

import argparse
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from results_file import RESULTS, save  # noqa: E402

from tutor.engine import Engine  # noqa: E402
from tutor.study.cohort import run_experiment  # noqa: E402

DEFAULT_OUT = RESULTS / "bench_engine.json"


def _cohort(experiment: int, workers: int, scheduler, engine=None):
    t0 = time.perf_counter()
    if engine is None:
        result = run_experiment(
            experiment, seed=0, workers=workers, progress=False, scheduler=scheduler
        )
    else:
        result = run_experiment(experiment, seed=0, progress=False, engine=engine)
    return time.perf_counter() - t0, result.runs


def _startup(workers: int) -> float:
    t0 = time.perf_counter()
    with Engine(workers, "auto"):
        pass
    return time.perf_counter() - t0


def run(repeats: int, workers: int) -> dict:
    engines = {"here": (1, None), "pool": (workers, None), "dask auto": (workers, "auto")}
    out = {"repeats": repeats, "workers": workers, "cores": os.cpu_count(), "seconds": {}}
    reference = {}
    for experiment in (1, 2):
        for name, (w, scheduler) in engines.items():
            times = []
            for _ in range(repeats):
                seconds, runs = _cohort(experiment, w, scheduler)
                times.append(seconds)
                if experiment in reference:  # the same numbers on every engine
                    pd.testing.assert_frame_equal(reference[experiment], runs)
                else:
                    reference[experiment] = runs
            out["seconds"][f"experiment {experiment}, {name}"] = float(np.median(times))
        # one cluster kept open (as robustness and the adaptive study do): workers warm
        with Engine(workers, "auto") as engine:
            _cohort(experiment, workers, None, engine)  # the workers import and build once
            times = []
            for _ in range(repeats):
                seconds, runs = _cohort(experiment, workers, None, engine)
                times.append(seconds)
                pd.testing.assert_frame_equal(reference[experiment], runs)
        out["seconds"][f"experiment {experiment}, dask warm"] = float(np.median(times))
    out["dask auto start+stop"] = float(np.median([_startup(workers) for _ in range(repeats)]))
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    res = run(args.repeats, args.workers)
    print(f"Cohorts of the paper's size, seed 0, medians of {args.repeats} (s):")
    for exp in (1, 2):
        here = res["seconds"][f"experiment {exp}, here"]
        for name in ("here", "pool", "dask auto", "dask warm"):
            t = res["seconds"][f"experiment {exp}, {name}"]
            print(f"  experiment {exp}  {name:10s} {t:7.2f}   speed-up {here / t:4.2f}")
    print(f"  LocalCluster start + stop alone: {res['dask auto start+stop']:.2f} s")
    print("  (the tables are identical on every engine)")
    save(res, args.out)


if __name__ == "__main__":
    main()
