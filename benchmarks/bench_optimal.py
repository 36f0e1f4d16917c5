"""Benchmark the optimal teacher (:mod:`tutor.study.optimal`) on both tasks.

- The greedy teacher over the full bank (3 careful draws per condition: 420 maze demos,
  300 pick-and-place demos) until eps = 1 (target <= 20 s per task, on both cores).
- The greedy step alone, as the next-demo hint (HF) would call it: the best of one draw
  per condition after 1 and 2 demos of the greedy path (target about 1 s for the tray).

Each figure is the median over ``--repeats`` runs (the bank is made once per task and
not timed: 0.5 s).

Run:  .venv/bin/python benchmarks/bench_optimal.py [--repeats 3] [--workers 2]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

from tutor.study import optimal
from tutor.tasks.maze import MazeTask
from tutor.tasks.pickplace import PickPlaceTask

DEFAULT_OUT = RESULTS / "bench_optimal.json"


def run(task, repeats: int, workers: int) -> dict:
    bank = optimal.make_bank(task, draws=3)
    greedy_s, found = [], None
    for _ in range(repeats):
        found = optimal.greedy(task, bank, workers=workers)
        greedy_s.append(found.seconds)
    hint = bank.first_draws(1)
    state = optimal.State.empty(task)
    steps = {}
    with optimal.Scorer(task, hint, workers) as scorer:
        for m, p in enumerate(found.positions[:2], start=1):
            state = state.added(task, bank.demos[p], bank.demo_points[p])[0]
            times = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                optimal.best_next(task, state, hint, scorer=scorer)
                times.append(time.perf_counter() - t0)
            steps[m] = float(np.median(times))
    return {
        "bank": len(bank),
        "greedy_s": float(np.median(greedy_s)),
        "greedy_efficacy": list(found.efficacies),
        "hint_candidates": len(hint),
        "hint_s_after": steps,
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    results = {}
    print(f"Optimal teacher, medians over {args.repeats} runs on {args.workers} workers")
    print(f"{'task':>10} {'bank':>5} {'greedy s':>9} {'eps path':>22} {'hint s (1, 2 demos)':>21}")
    for name, make in (("maze", MazeTask), ("pickplace", PickPlaceTask)):
        r = run(make(), args.repeats, args.workers)
        results[name] = r
        path = ", ".join(f"{e:.2f}" for e in r["greedy_efficacy"])
        hint = ", ".join(f"{s:.2f}" for s in r["hint_s_after"].values())
        print(f"{name:>10} {r['bank']:5d} {r['greedy_s']:9.1f} {path:>22} {hint:>21}")
    save(results, args.out)


if __name__ == "__main__":
    main()
