"""Warm starts against cold fits: do they give the same verdicts? (issue 22)

For each task, simulated careful demos (``task.scripted_demo``) at 10 random test
points, added one at a time, ``--seeds`` times. After each demo a warm-started learner
(refitted from the previous model) and a cold one (fitted from scratch) realise every
test point (:meth:`tutor.framework.Task.realise`) and are judged by the task's criteria.
Prints the share of test points whose verdicts differ (mean and worst over steps), the
largest efficacy difference, and the median fit times.

Measured 2026-12-06 (6 seeds x 10 demos, EM tol 3e-4):

- maze: verdicts differ on 0.5 % of start points on average, at worst 4.3 %; eps
  within 0.043. The maze's learner warm-starts (the tutor, the lookahead, the optimal
  teacher) within the tolerance ``tests/test_warm_start.py`` states. On the calibrated
  maze (narrower gaps, 2026-12-06, same command): 1.6 % on average, 7.9 % at worst,
  eps within 0.079, so the stated tolerance is now 8 % and 0.08; one sequence of 8 demos
  outside this benchmark (seed 4) differed on 26 % of the start points at one step.
- pick-and-place: the warm refit lands in another optimum of the likelihood in about
  half the sequences (its objective up to 0.66 nats per sample below the cold fit's)
  and the verdicts then differ on 10.9 % of the plants on average, on 87 % at worst;
  a single warm step from a cold fit (what the lookahead would do) differs on 7.4 % on
  average, 81 % at worst. Pick-and-place fits cold: warm starts would save about 4 ms
  per refit at the price of verdicts that depend on the order of the demos.

Run:  .venv/bin/python benchmarks/warm_vs_cold.py [--seeds 6]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from tutor.tasks import make_task


def compare(name: str, seeds: int, n_demos: int = 10) -> dict:
    task = make_task(name)
    differ, eps_gap, warm_ms, cold_ms, worse = [], [], [], [], []
    for seed in range(seeds):
        rng = np.random.default_rng(seed)
        idx = rng.choice(len(task.test_points), n_demos, replace=False)
        demos = [task.preprocess(task.scripted_demo(int(i), rng)) for i in idx]
        points = task.test_points[idx]
        warm = task.make_learner()
        warm.warm_start = True
        for m in range(1, n_demos + 1):
            frames = [task.frames(c) for c in points[:m]]
            t0 = time.perf_counter()
            warm.fit(demos[:m], frames)
            warm_ms.append(1e3 * (time.perf_counter() - t0))
            cold = task.make_learner()
            cold.warm_start = False
            t0 = time.perf_counter()
            cold.fit(demos[:m], frames)
            cold_ms.append(1e3 * (time.perf_counter() - t0))
            w = task.judge(task.realise(warm), task.test_points).passed
            c = task.judge(task.realise(cold), task.test_points).passed
            differ.append(float((w != c).mean()))
            eps_gap.append(abs(float(w.mean() - c.mean())))
            worse.append(cold.lower_bound_ - warm.lower_bound_)
    return {
        "differ_mean": float(np.mean(differ)),
        "differ_max": float(np.max(differ)),
        "eps_gap_max": float(np.max(eps_gap)),
        "objective_gap_max": float(np.max(worse)),
        "warm_ms": float(np.median(warm_ms)),
        "cold_ms": float(np.median(cold_ms)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=6)
    args = parser.parse_args()
    print(f"warm refit against cold fit, {args.seeds} seeds x 10 demos")
    print(
        "task        verdicts differ: mean   worst   |eps gap| max  objective gap max  "
        "warm ms  cold ms"
    )
    for name in ("maze", "pickplace"):
        r = compare(name, args.seeds)
        print(
            f"{name:10s}  {100 * r['differ_mean']:20.1f}%  {100 * r['differ_max']:5.1f}%  "
            f"{r['eps_gap_max']:13.3f}  {r['objective_gap_max']:17.3f}  {r['warm_ms']:7.1f}  "
            f"{r['cold_ms']:7.1f}"
        )


if __name__ == "__main__":
    main()
