"""Benchmark the arm following the trainee's hand (tutor.robot.follow.HandFollower).

One step = clamp the handle, warm-started IK (gripper down), fingers, collision check,
placements of the visual links: what the kernel does for every handle move. The handle
is driven along scripted own-hand recordings (tutor.tasks.recording.steady_hand) to the
plants 11, 18, 45, 81 and 88 at 40 samples a second, plus a drag below the table and
one out of reach. Target: well under 5 ms a step.

Prints the median and p90 step time and writes them as JSON.

Run:  .venv/bin/python benchmarks/bench_follow.py [--repeats 3] [--out PATH]
"""

from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

from tutor.robot.follow import HandFollower
from tutor.tasks.pickplace import PickPlaceTask
from tutor.tasks.recording import steady_hand

DEFAULT_OUT = RESULTS / "bench_follow.json"
PLANTS = (11, 18, 45, 81, 88)


def _paths(task) -> list[np.ndarray]:
    """Handle paths (T, 4) of x, y, z, g: five own-hand demos and two hostile drags."""
    paths = [steady_hand(task, p, rng=i)[:, 1:] for i, p in enumerate(PLANTS)]
    s = np.linspace(0, 1, 80)[:, None]
    below = np.array([0.3, 0.2, 0.2]) + s * np.array([0.2, -0.1, -0.5])
    far = np.array([0.4, 0.0, 0.3]) + s * np.array([0.8, 0.0, 0.2])
    paths += [np.column_stack([p, np.zeros(len(p))]) for p in (below, far)]
    return paths


def run(repeats: int = 3) -> dict:
    task = PickPlaceTask()
    follower = HandFollower.for_scene(task.scene)
    paths = _paths(task)
    times, by_kind = [], {"own_hand": [], "below_table": [], "out_of_reach": []}
    kinds = ["own_hand"] * len(PLANTS) + ["below_table", "out_of_reach"]
    follower.step(paths[0][1, :3], 0.0)  # warm up
    for _ in range(repeats):
        for kind, path in zip(kinds, paths, strict=True):
            follower.reset()
            for x, y, z, g in path:
                t0 = time.perf_counter()
                follower.step((x, y, z), g)
                dt = time.perf_counter() - t0
                times.append(dt)
                by_kind[kind].append(dt)
    ms = 1e3 * np.asarray(times)
    return {
        "machine": platform.processor() or platform.machine(),
        "repeats": repeats,
        "steps": int(ms.size),
        "step_median_ms": float(np.median(ms)),
        "step_p90_ms": float(np.percentile(ms, 90)),
        "step_max_ms": float(ms.max()),
        "median_ms_by_path": {k: 1e3 * float(np.median(v)) for k, v in by_kind.items()},
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    r = run(args.repeats)
    print(f"HandFollower.step over {r['steps']} steps ({r['machine']}):")
    print(
        f"  median {r['step_median_ms']:.3f} ms, p90 {r['step_p90_ms']:.3f} ms, "
        f"max {r['step_max_ms']:.3f} ms (target well under 5 ms)"
    )
    for kind, value in r["median_ms_by_path"].items():
        print(f"  {kind:<13} median {value:.3f} ms")
    save(r, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
