"""Benchmark one teaching step on the maze: ``TeachingSession.add_demo`` at demo M.

A step is: preprocess the recording, warm refit of the TP-GMM (K = 11, 4 frames),
140 realisations (R^), the task criteria on all of them, and the failure flags.
Each figure is the median over several random demo sets and repeats (the session is
copied before each timed step, so every repeat adds the same M-th demo).

Run:  .venv/bin/python benchmarks/bench_session.py [--repeats 9] [--sets 5]
"""

from __future__ import annotations

import argparse
import copy
import json
import time
from pathlib import Path

import numpy as np

from tutor.framework import TeachingSession
from tutor.tasks.maze import MazeTask

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "bench_session.json"


def run(repeats: int = 9, n_sets: int = 5, steps=(5, 10, 20)) -> dict:
    task = MazeTask()
    out = {}
    for m in steps:
        times = []
        for s in range(n_sets):
            rng = np.random.default_rng(10_000 + 100 * m + s)
            starts = task.layout.sample_starts(m, rng)
            demos = [task.layout.reference_path(p, rng, jitter=0.004) for p in starts]
            session = TeachingSession(task)
            for d in demos[:-1]:
                session.add_demo(d)
            for _ in range(repeats):
                trial = copy.deepcopy(session)
                t0 = time.perf_counter()
                trial.add_demo(demos[-1])
                times.append(time.perf_counter() - t0)
        out[m] = {
            "add_demo_ms": 1e3 * float(np.median(times)),
            "add_demo_ms_p90": 1e3 * float(np.percentile(times, 90)),
        }
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--sets", type=int, default=5)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    results = run(args.repeats, args.sets)
    print(
        f"TeachingSession.add_demo on the maze: medians over {args.sets} demo sets "
        f"x {args.repeats} runs"
    )
    print(f"{'demo M':>7} {'median ms':>10} {'90th pct ms':>12}")
    for m, r in results.items():
        print(f"{m:>7} {r['add_demo_ms']:10.1f} {r['add_demo_ms_p90']:12.1f}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=2))
    print(f"written to {args.out}")


if __name__ == "__main__":
    main()
