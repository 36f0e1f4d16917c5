"""Compile the tutor's numba kernels once, so a trainee's first demo does not wait for them.

numba compiles each kernel (the learner's EM, the feasibility map, the pick-and-place
criteria: see tutor/compiled.py) on its first call, about 7 s in all on a 2-core
machine, and caches the machine code for later processes. scripts/lab.sh runs this in
the background as JupyterLab starts, and binder/postBuild when the image is built;
with the cache already written it takes about a second.

Run:  .venv/bin/python scripts/warm_kernels.py
"""

from __future__ import annotations

import time

import numpy as np

from tutor.framework import TeachingSession
from tutor.tasks.maze import MazeTask
from tutor.tasks.pickplace import PickPlaceTask
from tutor.workers import one_blas_thread


def main() -> None:
    t0 = time.perf_counter()
    one_blas_thread()
    rng = np.random.default_rng(0)
    maze = MazeTask()
    session = TeachingSession(maze)
    for start in maze.test_points[:2]:
        session.add_demo(maze.layout.reference_path(start, rng), point=start)
    tray = PickPlaceTask()
    session = TeachingSession(tray)
    for plant in (0, 50):
        session.add_demo(tray.demonstrate(plant, rng), point=tray.test_points[plant])
    print(f"lfd-tutor: compiled kernels ready ({time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
