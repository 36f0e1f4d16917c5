"""Helpers shared by the tests: scripted maze demo sets and the session's task objects."""

from __future__ import annotations

import functools
import os
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def maze_demos(layout, n_demos: int, seed: int, jitter: float = 0.004):
    """``n_demos`` scripted demos from random starts, and their frames."""
    rng = np.random.default_rng(seed)
    starts = layout.sample_starts(n_demos, rng)
    demos = [layout.reference_path(s, rng, jitter=jitter) for s in starts]
    return demos, [layout.frames(s) for s in starts]


@functools.cache
def shared_maze_task():
    """The test session's one ``MazeTask()`` (what the ``maze_task`` fixture returns).

    For code that cannot take a fixture (hypothesis tests, cached helpers). Shared
    read-only: a test that changes a task's attributes builds its own task.
    """
    from tutor.tasks.maze import MazeTask

    return MazeTask()


@functools.cache
def shared_pickplace_task():
    """The test session's one ``PickPlaceTask()`` (what the ``pickplace_task`` fixture
    returns); shared read-only like :func:`shared_maze_task`."""
    from tutor.tasks.pickplace import PickPlaceTask

    return PickPlaceTask()
