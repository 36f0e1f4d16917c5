"""Benchmark the adaptive-feedback study (``lfd-tutor adaptive``).

Two numbers: the cost of one simulated run in each arm (median seconds on one process,
over a few teachers: what sizes the study), and the wall time of a whole study plan on
all cores (simulation, statistics and files), median of ``--repeats``. The full plan
(``--plan full``: 36 teachers x 3 runs x 10 seeds in every arm, four variants on
three seeds) takes about twenty minutes, so the default is ``--plan quick``.

Run:  .venv/bin/python benchmarks/bench_adaptive.py [--plan quick|full] [--repeats 1]
          [--teachers 3] [--workers N]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from results_file import RESULTS, save  # noqa: E402

from tutor.study.adaptive import (  # noqa: E402
    QUICK,
    StudyPlan,
    available_policies,
    run_study,
    teach_policy,  # noqa: E402
)
from tutor.study.adaptive_report import analyse_study, save_study  # noqa: E402
from tutor.workers import one_blas_thread  # noqa: E402

DEFAULT_OUT = RESULTS / "bench_adaptive.json"


def per_run(teachers: int = 3) -> dict:
    """Median seconds per simulated run of every arm (one process, seed 0)."""
    one_blas_thread()
    teach_policy("BF", 0, 0, 1)  # warm the task and the imports
    out = {}
    for name in available_policies():
        times = []
        for teacher in range(teachers):
            rows, _ = teach_policy(name, 0, teacher, 3)
            times += [r["compute_seconds"] for r in rows]
        out[name] = float(np.median(times))
    return out


def whole(plan: StudyPlan, workers, repeats: int) -> list[float]:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = run_study(plan, workers=workers, progress=False)
        with tempfile.TemporaryDirectory() as tmp:
            save_study(result, analyse_study(result), tmp)
        times.append(time.perf_counter() - t0)
    return times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plan", choices=("quick", "full"), default="quick")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--teachers", type=int, default=3, help="teachers per arm for per-run cost")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--out", default=str(DEFAULT_OUT))
    args = ap.parse_args()
    plan = QUICK if args.plan == "quick" else StudyPlan()
    costs = per_run(args.teachers)
    times = whole(plan, args.workers, args.repeats)
    report = {
        "plan": args.plan,
        "cores": os.cpu_count(),
        "load_average": os.getloadavg(),
        "seconds_per_run": costs,
        "study_s": float(np.median(times)),
        "all_s": times,
        "target_s": 600.0,
    }
    for name, s in costs.items():
        print(f"{name:<6} {s:.3f} s per run (median, one process)")
    print(f"{args.plan} study: median {report['study_s']:.1f} s over {args.repeats} "
          f"(target for the full study <= 600 s)")
    save(report, args.out)


if __name__ == "__main__":
    main()
