"""Measure the tracking controller's control cost for each task (issue 22).

For r in powers of ten, the robot's attempts (:meth:`tutor.framework.Task.realise`)
after each demo of the task's bundled correct demo set: efficacy against the plain
regression's, and the peak speed of the moving coordinates (metres per movement; a
movement lasts 1 time unit). The bundled ``control_cost`` is one power of ten inside the
lossless range: the largest r such that it and every smaller r lose nothing against the
regression once the correct set has 3 demos, divided by 10 as a margin for a novice's
looser demos (wider covariances loosen the tracking). The gentlest controller that
still follows the demos where they agree, with room to spare.

    python scripts/choose_control_cost.py
"""

from __future__ import annotations

import dataclasses

import numpy as np

from tutor.demofiles import load_demos
from tutor.framework.session import TeachingSession
from tutor.resources import asset
from tutor.tasks.maze import MazeTask, load_layout
from tutor.tasks.pickplace import PickPlaceTask, load_scene

COSTS = (1e-8, 1e-6, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)
SETS = {"maze": "demos/maze_good.json", "pickplace": "demos/pickplace_corners.json"}


def _tasks(name):
    if name == "maze":
        layout = load_layout()
        return {r: MazeTask(dataclasses.replace(layout, control_cost=r)) for r in COSTS}
    scene = load_scene()
    return {r: PickPlaceTask(dataclasses.replace(scene, control_cost=r)) for r in COSTS}


def main() -> None:
    for name, path in SETS.items():
        tasks = _tasks(name)
        task = tasks[COSTS[0]]
        demos = load_demos(asset(path)).demos
        session = TeachingSession(task)
        print(f"\n{name}: eps (peak speed) after each demo of {path}")
        print("  M  regression  " + "  ".join(f"r={r:<11.0e}" for r in COSTS))
        lossy = set()
        for m, demo in enumerate(demos, 1):
            session.add_demo(demo)
            learner = session.learner
            mean = learner.reproduce_batch(task.frame_batch(task.test_points), task.times)[0]
            plain = task.judge(mean, task.test_points).passed.mean()
            cells = []
            for r, t in tasks.items():
                path_ = t.realise(learner)
                eps = t.judge(path_, t.test_points).passed.mean()
                n = t.moving_dims or path_.shape[-1]
                speed = np.linalg.norm(np.diff(path_[..., :n], axis=1), axis=-1).max()
                speed /= t.times[1] - t.times[0]
                cells.append(f"{eps:.2f} ({speed:5.1f})")
                if m >= 3 and eps < plain:
                    lossy.add(r)
            print(f"{m:3d}  {plain:10.2f}  " + "  ".join(f"{c:13s}" for c in cells))
        edge = max(r for r in COSTS if not any(c <= r for c in lossy))
        print(f"  lossless up to r = {edge:.0e}; control_cost = {edge / 10:.0e}")


if __name__ == "__main__":
    main()
