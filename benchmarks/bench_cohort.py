"""Benchmark the simulated cohorts end to end: both of the paper's experiments.

One repeat of an experiment is what ``python -m tutor reproduce`` does: simulate every
teacher (Experiment 1: 30 teachers x NF, VF, VR; Experiment 2: 36 teachers x 3 runs)
on all cores, run the statistics and write the CSV, JSON, report and figure (to a
temporary folder). Prints the median wall time of each experiment and of both.

Run:  .venv/bin/python benchmarks/bench_cohort.py [--repeats 3] [--seed 0] [--workers N]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from results_file import RESULTS, save  # noqa: E402

from tutor.study.cohort import run_experiment  # noqa: E402
from tutor.study.report import analyse, save_result  # noqa: E402

DEFAULT_OUT = RESULTS / "bench_cohort.json"


def one(experiment: int, seed: int, workers) -> float:
    t0 = time.perf_counter()
    result = run_experiment(experiment, seed=seed, workers=workers, progress=False)
    with tempfile.TemporaryDirectory() as tmp:
        save_result(result, analyse(result), tmp)
    return time.perf_counter() - t0


def run(repeats: int = 3, seed: int = 0, workers=None) -> dict:
    times = {1: [], 2: []}
    for _ in range(repeats):
        for exp in (1, 2):
            times[exp].append(one(exp, seed, workers))
    both = [a + b for a, b in zip(times[1], times[2], strict=True)]
    return {
        "repeats": repeats,
        "seed": seed,
        "workers": workers or os.cpu_count(),
        "cores": os.cpu_count(),
        "experiment1_s": float(np.median(times[1])),
        "experiment2_s": float(np.median(times[2])),
        "both_s": float(np.median(both)),
        "all_s": {"1": times[1], "2": times[2]},
        "target_s": 90.0,
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    r = run(args.repeats, args.seed, args.workers)
    print(
        f"Simulated cohorts end to end, median of {r['repeats']} runs on {r['cores']} cores "
        f"({r['workers']} workers, seed {r['seed']}):"
    )
    print(f"  Experiment 1 (30 teachers x 3 conditions): {r['experiment1_s']:6.1f} s")
    print(f"  Experiment 2 (36 teachers x 3 runs):       {r['experiment2_s']:6.1f} s")
    print(
        f"  both:                                      {r['both_s']:6.1f} s "
        f"(target <= {r['target_s']:.0f} s)"
    )
    save(r, args.out)


if __name__ == "__main__":
    main()
