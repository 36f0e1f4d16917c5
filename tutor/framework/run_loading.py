"""What a loaded file does to a run: its demos are added, or its run becomes an attempt.

A ``.csv`` file, or a ``.json`` file saying ``"format": "lfd-tutor-demos"``, is a
demonstration file: its demos are added to the run, all or nothing
(:func:`tutor.demofiles.load_demos`). A ``.json`` run file (``"format": "lfd-tutor-run"``)
of the same run becomes a new attempt, the previous one kept
(:meth:`~tutor.framework.run.TeachingRun.replace_with` refuses another run's file).
Anything else is refused with :class:`~tutor.errors.InvalidFileError`.
:meth:`tutor.framework.controller.RunController.load` says what happened.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..demofiles import DEMOS_FORMAT, load_demos
from ..errors import InvalidFileError
from ..fileio import read_json
from .record import RECORD_FORMAT, RunRecord

__all__ = ["load_into", "plain_items"]


def plain_items(run, demos, name: str):
    """(raw, options) for each demo of a loaded file: no options."""
    return [(raw, {}) for raw in demos]


def load_into(run, path: Path, shown: str, columns, load_items: Callable = plain_items) -> str:
    """Load ``path`` into ``run``; returns what the panel says about it.

    Parameters
    ----------
    run : TeachingRun
    path : Path
        A ``.json`` or ``.csv`` file; its name is recorded in the run's history.
    shown : str
        The file as the trainee knows it (an upload is stored under a safe name).
    columns : tuple of str
        The columns of a demonstration file, time first.
    load_items : callable
        ``load_items(run, demos, shown)``: (raw, options) for each demo.

    Raises
    ------
    TutorError
        The file is refused (the run is unchanged).
    """
    suffix = path.suffix.lower()
    if suffix == ".csv":
        return _add_demos(run, path, shown, columns, load_items)
    if suffix != ".json":
        raise InvalidFileError("load a .json or .csv file (demonstrations or a saved run).")
    data = read_json(path, "file")
    kind = data.get("format") if isinstance(data, dict) else None
    if kind == RECORD_FORMAT or kind == "lfd-tutor-session":
        run.replace_with(RunRecord.from_dict(data), detail=path.name)
        return (
            f"Loaded {run.n_demos} demonstration(s) from {shown} as attempt "
            f"{len(run.record.attempts)}; the previous attempt is kept."
        )
    if kind == DEMOS_FORMAT:
        return _add_demos(run, path, shown, columns, load_items)
    raise InvalidFileError(
        f'it is neither a demonstration file ("format": "{DEMOS_FORMAT}") '
        f'nor a run file ("format": "{RECORD_FORMAT}")'
        + (f'; it says "format": {kind!r}.' if kind else ".")
    )


def _add_demos(run, path: Path, shown: str, columns, load_items: Callable) -> str:
    demos = load_demos(path, columns=columns)
    n = run.add_demos(load_items(run, demos, shown), detail=path.name)
    return f"Added {n} demonstration(s) from {shown}."
