"""Benchmark the simulated arm (tutor.robot) in the shape of the paper's Experiment 2.

- one full-fidelity realisation check: :meth:`Arm.follow` of a 200-sample path (start
  -> above a plant -> plant -> lift -> over the bin -> release) with IK and a
  collision check at every sample (target <= 50 ms);
- one cold IK solve (start configuration -> a plant), one warm IK solve (5 mm step);
- one collision check (start configuration, scene obstacles);
- the feasibility map judging 100 realisations x 200 samples (target <= 30 ms).

Prints medians and writes them as JSON.

Run:  .venv/bin/python benchmarks/bench_robot.py [--repeats 21] [--out PATH]
"""

from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

from tutor.robot import START_CONFIGURATION, FeasibilityMap, get_arm, scene_obstacles
from tutor.tasks.pickplace import load_scene

DEFAULT_OUT = RESULTS / "bench_robot.json"


def _median_ms(fn, repeats: int) -> float:
    fn()  # warm up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def _realisation(arm, scene, plant: int, T: int = 200):
    """A 200-sample realisation-shaped tool path and hand command."""
    start = arm.fk(START_CONFIGURATION)[0]
    p = scene.plant_positions[plant]
    rel = scene.release_point
    up = np.array([0, 0, 0.12])
    points = np.array([start, p + up, p, p + up, rel + [0, 0, 0.05], rel])
    s = np.linspace(0, len(points) - 1, T)
    k = np.minimum(s.astype(int), len(points) - 2)
    f = s - k
    f = 10 * f**3 - 15 * f**4 + 6 * f**5
    path = (1 - f)[:, None] * points[k] + f[:, None] * points[k + 1]
    grip = ((s >= 2) & (s < 4.9)).astype(float)
    return path, grip


def run(repeats: int = 21) -> dict:
    scene = load_scene()
    arm = get_arm(scene_obstacles(scene))
    fmap = FeasibilityMap.load()
    plant = int(scene.generalisation_indices[0])
    path, grip = _realisation(arm, scene, plant)
    tracking = arm.follow(path, grip)
    assert tracking.ok, tracking.reason
    target = scene.plant_positions[plant]
    q_plant = arm.ik(target).q
    step = target + [0.005, 0, 0]

    rng = np.random.default_rng(0)
    batch = np.array(
        [_realisation(arm, scene, int(i))[0] for i in rng.integers(0, 100, size=100)]
    ) + rng.normal(0, 0.003, size=(100, 200, 3))
    grips = np.tile(grip, (100, 1))

    results = {
        "machine": platform.processor() or platform.machine(),
        "repeats": repeats,
        "median_ms": {
            "follow_200_samples_with_collisions": _median_ms(
                lambda: arm.follow(path, grip), repeats
            ),
            "follow_200_samples_without_collisions": _median_ms(
                lambda: arm.follow(path, grip, check_collisions=False), repeats
            ),
            "ik_cold_start_to_plant": _median_ms(lambda: arm.ik(target), repeats * 5),
            "ik_warm_5mm_step": _median_ms(lambda: arm.ik(step, q_plant), repeats * 5),
            "collision_check": _median_ms(
                lambda: arm.in_collision(START_CONFIGURATION), repeats * 20
            ),
            "map_100x200_points": _median_ms(lambda: fmap.contains(batch), repeats),
            "map_100x200_points_with_hand": _median_ms(
                lambda: fmap.contains(batch, grips), repeats
            ),
        },
        "follow_max_error_m": float(tracking.errors.max()),
        "map_voxels": list(fmap.shape),
        "map_spacing_m": fmap.spacing,
    }
    return results


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=21)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    results = run(args.repeats)
    width = max(map(len, results["median_ms"]))
    print(f"tutor.robot medians over {args.repeats}+ runs ({results['machine']}):")
    for name, ms in results["median_ms"].items():
        print(f"  {name:<{width}}  {ms:9.3f} ms")
    print(f"  follow max tracking error: {1e3 * results['follow_max_error_m']:.3f} mm")
    save(results, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
