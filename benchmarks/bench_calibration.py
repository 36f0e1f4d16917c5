"""Benchmark the calibration's unit of work: one simulated study, on each engine.

A calibration (``lfd-tutor calibrate``) is a loop of simulated studies (Experiment 1
with ``n1`` teachers and Experiment 2's NF condition with ``n2`` teachers), one per
particle tried, plus the refinement's and the predictive checks' studies. This script
times one study at the prior's middle (or at the point a calibration chose,
``--calibration DIR``) on one process, on the process pool and on a Dask LocalCluster
kept open (as ``calibrate --scheduler auto`` uses it), prints the medians over
``--repeats``, the speed-up over one process, and what the default budget's ABC-SMC
(about ``--studies`` simulated studies) costs on each. The statistics must not depend
on the engine: each is compared with the first.

Run:  .venv/bin/python benchmarks/bench_calibration.py [--repeats 3] [--workers 2]
"""

from __future__ import annotations

import argparse
import math
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from results_file import RESULTS, save  # noqa: E402

from tutor.engine import Engine  # noqa: E402
from tutor.study import calibration  # noqa: E402

DEFAULT_OUT = RESULTS / "bench_calibration.json"


def _same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(
        (math.isnan(a[k]) and math.isnan(b[k])) or a[k] == b[k] for k in a
    )


def run(repeats: int, workers: int, folder) -> dict:
    if folder is None:
        theta = {n: p.from_unit(0.5) for n, p in calibration.PARAMETERS.items()}
    else:
        theta = calibration.load(folder)[0].bundled()
    budget = calibration.FULL_BUDGET
    out = {"repeats": repeats, "workers": workers, "cores": os.cpu_count(),
           "theta": theta, "n1": budget.n1, "n2": budget.n2, "seconds": {}}
    reference = None
    for name, (w, scheduler) in {"here": (1, None), "pool": (workers, None),
                                 "dask warm": (workers, "auto")}.items():
        with Engine(w, scheduler) as engine:
            if scheduler is not None:  # the workers import and build the tasks once
                calibration.simulate(theta, 0, budget.n1, budget.n2, engine)
            times = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                stats = calibration.simulate(theta, 0, budget.n1, budget.n2, engine)
                times.append(time.perf_counter() - t0)
                if reference is None:
                    reference = stats
                elif not _same(reference, stats):
                    raise SystemExit(f"{name}: the statistics differ from one process's")
        out["seconds"][name] = float(np.median(times))
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--calibration", default=None,
                        help="time the point this calibration folder chose (default: the "
                        "prior's middle)")
    parser.add_argument("--studies", type=int, default=751,
                        help="simulated studies of the budget to cost (default 751: what "
                        "the default 60 particles x 3 generations simulated on 2026-12-06, "
                        "pyabc's first prior sample included)")
    parser.add_argument("--out", default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    res = run(args.repeats, args.workers, args.calibration)
    n = res["studies"] = args.studies
    print(f"One simulated study (Exp 1 x {res['n1']}, Exp 2 NF x {res['n2']}), "
          f"medians of {args.repeats} (s):")
    here = res["seconds"]["here"]
    for name, t in res["seconds"].items():
        print(f"  {name:10s} {t:6.2f}   speed-up {here / t:4.2f}   "
              f"{n} studies: {n * t / 60:5.1f} min")
    print("  (the statistics are identical on every engine)")
    save(res, args.out)


if __name__ == "__main__":
    main()
