"""Benchmark the TP-GMM learner in the shape of the paper's Experiment 1.

State (t, x, y), K = 11 components, P = 4 frames (start, target, two obstacles),
T = 200 samples per demo, M = 5, 10, 20 demos from random starts in the maze's
start zone. Each figure is the median over several random demo sets (warm refits in
particular depend on how much the new demo moves the model), with the slowest
set's median beside it, and the robot's tracked attempts from all 140 start points
(:meth:`tutor.tasks.maze.MazeTask.realise`: reproduction plus the tracking controller).
BLAS runs on one thread, as in the tutor's apps and workers (on two cores the cold fit
at M = 20 took 17 ms with OpenBLAS's default threads, 12 ms on one). Prints the table
and writes it as JSON.

Run:  .venv/bin/python benchmarks/bench_tpgmm.py [--repeats 9] [--sets 5] [--out PATH]
"""

from __future__ import annotations

import argparse
import copy
import platform
import time
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

from tutor.tasks.maze import MazeTask, load_layout
from tutor.tpgmm import TPGMM
from tutor.workers import one_blas_thread

DEFAULT_OUT = RESULTS / "bench_tpgmm.json"


def _demos(layout, n_demos: int, seed: int):
    """Scripted demos from random starts (as in tests/conftest.maze_demos)."""
    rng = np.random.default_rng(seed)
    starts = layout.sample_starts(n_demos, rng)
    return [layout.reference_path(s, rng, jitter=0.004) for s in starts], [
        layout.frames(s) for s in starts
    ]


def _median_ms(fn, repeats: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times)), result


def run(repeats: int = 15, n_sets: int = 5) -> dict:
    """Time fits and reproductions on ``n_sets`` random demo sets per M."""
    one_blas_thread()
    layout = load_layout()
    task = MazeTask(layout)
    K = layout.n_components
    batch = layout.frame_batch(layout.test_starts)
    times = np.linspace(0.0, 1.0, layout.n_samples)
    results = {
        "machine": platform.processor() or platform.machine(),
        "repeats": repeats,
        "demo_sets": n_sets,
        "M": {},
    }
    for M in (5, 10, 20):
        cold, cold_iter, warm, warm_iter, repro, cached, tracked = [], [], [], [], [], [], []
        for s in range(n_sets):
            demos, frames = _demos(layout, M, seed=1000 * M + s)
            ms, model = _median_ms(lambda: TPGMM(K).fit(demos, frames), repeats)  # noqa: B023
            cold.append(ms)
            cold_iter.append(model.n_iter_)
            previous = TPGMM(K, warm_start=True).fit(demos[:-1], frames[:-1])

            def warm_fit(previous=previous, demos=demos, frames=frames):
                return copy.deepcopy(previous).fit(demos, frames)

            ms, warm_model = _median_ms(warm_fit, repeats)
            warm.append(ms)
            warm_iter.append(warm_model.n_iter_)

            def reproduce(model=model):
                model._gmr_cache.clear()  # include the per-frame regression
                return model.reproduce_batch(batch, times)

            repro.append(_median_ms(reproduce, repeats)[0])
            cached.append(_median_ms(lambda: model.reproduce_batch(batch, times), repeats)[0])  # noqa: B023
            tracked.append(_median_ms(lambda: task.realise(model), repeats)[0])  # noqa: B023
        results["M"][M] = {
            "cold_fit_ms": float(np.median(cold)),
            "cold_fit_ms_worst_set": float(np.max(cold)),
            "cold_fit_n_iter": int(np.median(cold_iter)),
            "warm_refit_ms": float(np.median(warm)),
            "warm_refit_ms_worst_set": float(np.max(warm)),
            "warm_refit_n_iter": int(np.median(warm_iter)),
            "reproduce_140_ms": float(np.median(repro)),
            "reproduce_140_cached_regression_ms": float(np.median(cached)),
            "realise_140_ms": float(np.median(tracked)),
        }
    return results


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9, help="timed runs per demo set")
    parser.add_argument("--sets", type=int, default=5, help="random demo sets per M")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    results = run(args.repeats, args.sets)
    print(
        f"TP-GMM benchmark (Experiment 1 shape: K=11, P=4, T=200): medians over "
        f"{args.sets} demo sets x {args.repeats} runs; 'worst' is the slowest set's median"
    )
    print(
        f"{'M':>3} {'cold fit ms':>12} {'worst':>7} {'n_iter':>7} {'warm refit ms':>14} "
        f"{'worst':>7} {'n_iter':>7} {'140 repro ms':>13} {'(cached GMR)':>13} "
        f"{'140 tracked ms':>15}"
    )
    for M, r in results["M"].items():
        print(
            f"{M:>3} {r['cold_fit_ms']:12.1f} {r['cold_fit_ms_worst_set']:7.1f} "
            f"{r['cold_fit_n_iter']:7d} {r['warm_refit_ms']:14.1f} "
            f"{r['warm_refit_ms_worst_set']:7.1f} {r['warm_refit_n_iter']:7d} "
            f"{r['reproduce_140_ms']:13.2f} {r['reproduce_140_cached_regression_ms']:13.2f} "
            f"{r['realise_140_ms']:15.2f}"
        )
    save(results, args.out)


if __name__ == "__main__":
    main()
