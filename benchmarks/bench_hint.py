"""Benchmark the next-demo hint (condition HF, :mod:`tutor.tasks.hint`) on the tray.

The hint as the tutor computes it: in this process only (no worker processes, as in a
notebook kernel), over the ``HINT_CANDIDATES`` frame-disagreement candidates with the
one-draw bank (made once per task: timed apart). Median over ``--sets`` demo sets
(random plants, each with its own seed) and ``--repeats`` calls each, at M = 0, 1, 3
and 6 demos (M = 0 reads the optimal teacher's first pick). Target: well within 1 s.

Run:  .venv/bin/python benchmarks/bench_hint.py [--sets 5] [--repeats 3]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

from tutor.tasks.hint import HINT_CANDIDATES, hint_bank, next_demo_hint
from tutor.tasks.pickplace import PickPlaceTask
from tutor.tasks.pickplace_protocol import PickPlaceRun

DEFAULT_OUT = RESULTS / "bench_hint.json"
STEPS = (0, 1, 3, 6)
TARGET_S = 1.0


def run(task, sets: int = 5, repeats: int = 3, steps=STEPS) -> dict:
    """Median seconds of one hint at each M in ``steps`` (and the bank's build time)."""
    t0 = time.perf_counter()
    hint_bank(task)
    bank_s = time.perf_counter() - t0
    times: dict[int, list[float]] = {m: [] for m in steps}
    for k in range(sets):
        rng = np.random.default_rng([7, k])
        plants = rng.choice(len(task.test_points), max(steps), replace=False)
        run_ = PickPlaceRun("HF", task)
        for m in range(max(steps) + 1):
            if m in times:
                for _ in range(repeats):
                    times[m].append(next_demo_hint(task, run_).seconds)
            if m < max(steps):
                run_.demonstrate(int(plants[m]), rng=rng)
    return {
        "candidates": HINT_CANDIDATES,
        "bank_s": bank_s,
        "median_s": {m: float(np.median(t)) for m, t in times.items()},
        "max_s": {m: float(np.max(t)) for m, t in times.items()},
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    result = run(PickPlaceTask(), args.sets, args.repeats)
    print(
        f"Next-demo hint, {result['candidates']} candidates, one process; bank made once in "
        f"{result['bank_s']:.2f} s"
    )
    print(f"{'M':>3} {'median s':>9} {'max s':>7}")
    for m in STEPS:
        print(f"{m:3d} {result['median_s'][m]:9.3f} {result['max_s'][m]:7.3f}")
    save(result, args.out)


if __name__ == "__main__":
    main()
