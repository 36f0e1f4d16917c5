"""Shared fixtures."""

from __future__ import annotations

import pytest

from tests.helpers import shared_maze_task, shared_pickplace_task
from tutor.tasks.maze import load_layout


@pytest.fixture(scope="session")
def layout():
    return load_layout()


@pytest.fixture(scope="session")
def maze_task():
    """The maze task, ``MazeTask()``, built once for the whole test session.

    Shared by every test that asks for it, so it is read-only: a test that changes a
    task's attributes (or monkeypatches them) builds its own ``MazeTask()`` instead.
    """
    return shared_maze_task()


@pytest.fixture(scope="session")
def pickplace_task():
    """The pick-and-place task, ``PickPlaceTask()`` (feasibility map included), built
    once for the whole test session.

    Shared read-only like ``maze_task``: a test that changes a task's attributes builds
    its own ``PickPlaceTask()`` instead.
    """
    return shared_pickplace_task()


@pytest.fixture
def person(tmp_path, monkeypatch):
    """A person at the notebook (not headless, no trainee, condition or class plan set),
    whose runs are saved under tmp_path/sessions."""
    for var in (
        "TUTOR_HEADLESS",
        "TUTOR_TRAINEE",
        "TUTOR_CONDITION",
        "TUTOR_CLASS_PLAN",
        "TUTOR_HAND",
        "JUPYTERHUB_USER",
    ):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("TUTOR_RUNS_DIR", str(tmp_path / "sessions"))
    return monkeypatch
