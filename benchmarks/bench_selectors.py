"""Benchmark the adaptive selectors: the cost of picking r after one demo (target <= 20 ms).

For each selector of :data:`tutor.framework.selectors.SELECTORS`, the time of one call
``selector(k, context)`` after demo M, on the pick-and-place task (100 plants, K = 9,
3 frames, T = 200) and on the maze (140 start points, 4 frames). The context is what a
:class:`~tutor.framework.TeachingSession` passes after a demo: the fitted learner, the
frames of B^, the product-of-frames means it has just computed for the criteria (so the
disagreement selector regresses once per frame but does not reproduce again), the
verdict (for the oracle) and the run's generator.

Each figure is the median over several random demo sets and repeats.

Run:  .venv/bin/python benchmarks/bench_selectors.py [--repeats 15] [--sets 3] [--k 5]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

from tutor.framework import TeachingSession
from tutor.framework.selectors import SELECTORS, SelectionContext

DEFAULT_OUT = RESULTS / "bench_selectors.json"
#: the cost each selector must stay within, per demo (ms)
TARGET_MS = 20.0


def contexts(task, m: int, n_sets: int, seed: int):
    """``n_sets`` selection contexts after demo ``m`` of random demos on ``task``."""
    out = []
    for s in range(n_sets):
        rng = np.random.default_rng(seed + 100 * m + s)
        session = TeachingSession(task, feedback="none")
        if hasattr(task, "layout"):  # the maze: scripted strokes from random starts
            starts = task.layout.sample_starts(m, rng)
            for start in starts:
                session.add_demo(task.layout.reference_path(start, rng, jitter=0.004))
        else:
            plants = rng.choice(len(task.test_points), size=m, replace=False)
            for p in plants:
                session.add_demo(task.demonstrate(int(p), rng), point=task.test_points[p])
        out.append(
            SelectionContext.of_task(
                task, session.demo_points, session.learner,
                realisations=session.realisations, passed=session.latest.passed,
                rng=np.random.default_rng(s),
            )
        )
    return out


def run(task, repeats: int = 15, n_sets: int = 3, steps=(1, 3, 6), k: int = 5, seed=30_000):
    """Median milliseconds of each selector per demo count: {m: {selector: ms}}."""
    out = {}
    for m in steps:
        ctxs = contexts(task, m, n_sets, seed)
        out[m] = {}
        for name, selector in SELECTORS.items():
            times = []
            for ctx in ctxs:
                selector(k, ctx)  # warm the learner's caches, as after a real demo
                for _ in range(repeats):
                    t0 = time.perf_counter()
                    selector(k, ctx)
                    times.append(time.perf_counter() - t0)
            out[m][name] = 1e3 * float(np.median(times))
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--sets", type=int, default=3)
    parser.add_argument("--k", type=int, default=5)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)

    from tutor.tasks.maze import MazeTask
    from tutor.tasks.pickplace import PickPlaceTask

    results = {}
    tasks = (("pickplace (100 plants)", PickPlaceTask()), ("maze (140 starts)", MazeTask()))
    for label, task in tasks:
        res = run(task, args.repeats, args.sets, k=args.k)
        results[label] = res
        print(f"{label}, k = {args.k}: median ms per demo (target <= {TARGET_MS:g} ms)")
        names = list(SELECTORS)
        print("  M  " + "".join(f"{n:>14}" for n in names))
        for m, row in res.items():
            print(f"  {m:<3}" + "".join(f"{row[n]:>14.2f}" for n in names))
    save(results, args.out)


if __name__ == "__main__":
    main()
