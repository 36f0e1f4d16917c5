"""Benchmark the TP-GMM learner in the shape of the paper's Experiment 1.

State (t, x, y), K = 11 components, P = 4 frames (start, target, two obstacles),
T = 200 samples per demo, M = 5, 10, 20 demos from random starts in the maze's
start zone. Prints medians and writes them as JSON.

Run:  .venv/bin/python benchmarks/bench_tpgmm.py [--repeats 15] [--out PATH]
"""

from __future__ import annotations

import argparse
import copy
import json
import platform
import time
from pathlib import Path

import numpy as np

from tutor.tasks.maze import load_layout
from tutor.tpgmm import TPGMM

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "bench_tpgmm.json"


def _demos(layout, n_demos: int, seed: int):
    rng = np.random.default_rng(seed)
    z = layout.start_zone
    starts = np.column_stack(
        [rng.uniform(z.x0 + 0.005, z.x1 - 0.005, n_demos), rng.uniform(z.y0 + 0.005, z.y1 - 0.005, n_demos)]
    )
    demos = [layout.reference_path(s, rng, jitter=0.004) for s in starts]
    return demos, [layout.frames(s) for s in starts]


def _median_ms(fn, repeats: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times)), result


def run(repeats: int = 15) -> dict:
    layout = load_layout()
    K = layout.n_components
    batch = layout.frame_batch(layout.test_starts)
    times = np.linspace(0.0, 1.0, layout.n_samples)
    results = {"machine": platform.processor() or platform.machine(), "repeats": repeats, "M": {}}
    for M in (5, 10, 20):
        demos, frames = _demos(layout, M, seed=M)
        cold_ms, model = _median_ms(lambda: TPGMM(K).fit(demos, frames), repeats)  # noqa: B023

        previous = TPGMM(K, warm_start=True).fit(demos[:-1], frames[:-1])

        def warm(previous=previous, demos=demos, frames=frames):
            return copy.deepcopy(previous).fit(demos, frames)

        warm_ms, warm_model = _median_ms(warm, repeats)
        model.reproduce_batch(batch, times)  # the first call fills the regression cache

        def reproduce(model=model):
            model._gmr_cache.clear()
            return model.reproduce_batch(batch, times)

        repro_ms, _ = _median_ms(reproduce, repeats * 4)
        cached_ms, _ = _median_ms(lambda: model.reproduce_batch(batch, times), repeats * 4)  # noqa: B023
        results["M"][M] = {
            "cold_fit_ms": cold_ms,
            "cold_fit_n_iter": model.n_iter_,
            "warm_refit_ms": warm_ms,
            "warm_refit_n_iter": warm_model.n_iter_,
            "reproduce_140_ms": repro_ms,
            "reproduce_140_cached_regression_ms": cached_ms,
        }
    return results


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    results = run(args.repeats)
    print(f"TP-GMM benchmark (Experiment 1 shape: K=11, P=4, T=200), medians of {args.repeats} runs")
    print(f"{'M':>3} {'cold fit ms':>12} {'n_iter':>7} {'warm refit ms':>14} {'n_iter':>7} "
          f"{'140 repro ms':>13} {'(cached GMR)':>13}")
    for M, r in results["M"].items():
        print(f"{M:>3} {r['cold_fit_ms']:12.1f} {r['cold_fit_n_iter']:7d} {r['warm_refit_ms']:14.1f} "
              f"{r['warm_refit_n_iter']:7d} {r['reproduce_140_ms']:13.2f} "
              f"{r['reproduce_140_cached_regression_ms']:13.2f}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=2))
    print(f"written to {args.out}")


if __name__ == "__main__":
    main()
