"""How steady is the learner on a maze of given blocks? (a check before bundling a maze)

A guided teacher (each demo from the failing start point farthest from their earlier
demos, recorded as the bundled demo sets are: 80 Hz, hand tremor) gives ``--demos``
demos on the maze with the given blocks. Per seed it reports the demos needed to first
reach 90 % coverage and the deepest fall of efficacy after that (the best so far minus
the lowest later value): a maze on which one more demo where the robot fails can take
efficacy from 97 % to 72 % teaches a trainee the wrong lesson, whatever the simulated
cohorts' medians say.

Run:  .venv/bin/python scripts/maze_fragility.py --blocks 0.13,0.10,0.03,0.05 --blocks ...
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_maze_demo_sets import recording  # noqa: E402

from tutor.framework import TeachingSession  # noqa: E402
from tutor.tasks.maze import MazeTask, load_layout  # noqa: E402


def guided_path(layout, seed: int, demos: int) -> list[float]:
    """Efficacy after each of ``demos`` guided demos."""
    rng = np.random.default_rng([seed, 11])
    task = MazeTask(layout)
    session = TeachingSession(task)
    zone = layout.start_zone
    low = np.array([zone.x0, zone.y0]) + 0.004
    high = np.array([zone.x1, zone.y1]) - 0.004
    start, path = np.array([0.03, 0.03]), []
    for _ in range(demos):
        r = session.add_demo(recording(layout, start, rng))
        path.append(float(r.efficacy))
        fail = task.test_points[~r.passed]
        if len(fail) == 0:
            break
        mine = np.array([task.test_point_of(d) for d in session.demos])
        far = np.linalg.norm(fail[:, None] - mine[None], axis=2).min(axis=1)
        start = np.clip(fail[np.argmax(far)], low, high)
    return path


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--blocks", action="append", required=True,
                        help="reach,low,height,gap in metres (repeat for several mazes)")
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--demos", type=int, default=8)
    args = parser.parse_args(argv)
    for text in args.blocks:
        blocks = [float(v) for v in text.split(",")]
        layout = load_layout().with_blocks(*blocks)
        needed, falls = [], []
        for seed in range(args.seeds):
            path = guided_path(layout, seed, args.demos)
            reached = [k for k, e in enumerate(path) if e >= 0.9]
            needed.append(reached[0] + 1 if reached else None)
            best = np.maximum.accumulate(path)
            falls.append(float(np.max(best - np.asarray(path))))
        got = [n for n in needed if n is not None]
        print(f"blocks {text}: 90 % reached in {len(got)} of {args.seeds} seeds "
              f"(demos {needed}); deepest fall after the best so far: median "
              f"{np.median(falls):.0%}, worst {max(falls):.0%}", flush=True)


if __name__ == "__main__":
    main()
