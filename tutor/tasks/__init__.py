"""The paper's two tasks, by name (``Task.name``): :data:`TASKS` and :func:`make_task`.

A task is imported only when it is made: pick-and-place loads the arm's models
(Pinocchio), which the maze never needs.
"""

from __future__ import annotations

from importlib import import_module

from ..errors import InvalidParameterError

__all__ = ["RUNS", "TASKS", "make_task", "run_class"]

#: task name -> (module, class) of its :class:`~tutor.framework.task.Task`
TASKS = {
    "maze": ("tutor.tasks.maze", "MazeTask"),
    "pickplace": ("tutor.tasks.pickplace", "PickPlaceTask"),
}

#: task name -> (module, class) of its :class:`~tutor.framework.run.TeachingRun`
RUNS = {
    "maze": ("tutor.tasks.maze_run", "MazeRun"),
    "pickplace": ("tutor.tasks.pickplace_protocol", "PickPlaceRun"),
}


def _named(registry: dict, name: str, what: str):
    if not isinstance(name, str) or name not in registry:
        raise InvalidParameterError(
            f"there is no {what} called {name!r}: use one of {', '.join(map(repr, registry))}"
        )
    module, cls = registry[name]
    return getattr(import_module(module), cls)


def run_class(name: str):
    """The run class of task ``name`` (a key of :data:`RUNS`)."""
    return _named(RUNS, name, "task")


def make_task(name: str, **options):
    """A new task called ``name`` (a key of :data:`TASKS`), built with ``options``.

    Examples
    --------
    >>> make_task("maze").name
    'maze'
    """
    return _named(TASKS, name, "task")(**options)
