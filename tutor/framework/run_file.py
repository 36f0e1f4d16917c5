"""A run's file: the lock that makes a tutor its one writer, and whose run a file holds.

A run file ``VF.json`` is locked through ``.VF.json.lock`` beside it (:mod:`filelock`;
the operating system releases the lock when a kernel dies, so a killed kernel's lock is
taken over safely). Another kernel's lock is waited for a moment
(:data:`LOCK_WAIT_SECONDS`: a reloaded Voila page's old kernel may be shutting down). A
lock that cannot be taken at all (its lock file is a folder or another user's, the folder
is read-only) fails closed: :func:`take_lock` says why in plain words, and the run is
shown read-only (:class:`~tutor.framework.controller.RunController`).

A file is written only when it holds the same run (:func:`not_this_run`): on opening
(resume, Try again) and on Save to a chosen path (:func:`refuse_others_file`).
"""

from __future__ import annotations

import errno
import logging
from pathlib import Path

from ..errors import InvalidFileError, WrongRunError
from ..fileio import read_json
from .record import RunRecord

__all__ = [
    "LOCK_WAIT_SECONDS",
    "lock_path",
    "lock_trouble",
    "not_this_run",
    "refuse_others_file",
    "take_lock",
]

log = logging.getLogger(__name__)

#: seconds a tutor waits for another kernel's lock before it opens read-only
LOCK_WAIT_SECONDS = 2.0


def lock_path(path: Path) -> Path:
    """The lock file of run file ``path``: ``.VF.json.lock`` beside ``VF.json``."""
    return path.with_name(f".{path.name}.lock")


def lock_trouble(lock_file: Path, exc: OSError) -> str:
    """Why the lock file ``lock_file`` cannot be taken, in plain words."""
    name = lock_file.name
    not_yours = (
        f"its lock file {name} or its folder may not be written by you (it may belong to "
        "another user)"
    )
    reasons = {
        errno.EISDIR: f"its lock file {name} is a folder",
        errno.EACCES: not_yours,
        errno.EPERM: not_yours,
        errno.EROFS: "the folder is on a read-only disk",
        errno.ENOTDIR: "part of the path is a file, not a folder",
        errno.EEXIST: "part of the path is a file, not a folder",
        errno.ENOSPC: "the disk is full",
        errno.EDQUOT: "your disk quota is used up",
        errno.ENAMETOOLONG: "its path is too long",
    }
    return reasons.get(exc.errno) or f"{exc.strerror or exc}"


def take_lock(path: Path, wait: float | None = None):
    """Take run file ``path``'s lock: (the held lock, None), or (None, why not).

    Parameters
    ----------
    path : Path
        The run file (its folder is made if missing).
    wait : float, optional
        Seconds to wait for another kernel's lock (default :data:`LOCK_WAIT_SECONDS`).

    Returns
    -------
    tuple
        ``(lock, None)`` when it is held (``lock.release()`` lets go); ``(None, None)``
        when another kernel holds it; ``(None, reason)`` when it cannot be taken at all
        (the reason in plain words, from :func:`lock_trouble`).
    """
    from filelock import FileLock, Timeout

    wait = LOCK_WAIT_SECONDS if wait is None else wait
    where = lock_path(path)
    lock = FileLock(str(where), timeout=wait)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        lock.acquire()
    except Timeout:
        return None, None
    except OSError as exc:  # no lock possible: fail closed (read-only), never open
        log.warning("no lock on %s (%s): read-only", path, exc)
        return None, lock_trouble(where, exc)
    return lock, None


def not_this_run(record: RunRecord, wanted: RunRecord, same_id: bool = False) -> str | None:
    """Why ``record`` (read from a file) is not the run ``wanted``; None when it is.

    Another experiment, task, condition, run number, practice flag or trainee is another
    run. With ``same_id`` (``wanted`` is the run as it stands), another run id (both
    having one) is another run too; without it (``wanted`` is the run a tutor was asked
    for) the id is not compared, since opening a file takes its run over, id and all.
    """
    if not record.same_run(wanted) or record.trainee.key != wanted.trainee.key:
        return (
            f"it holds {record.trainee.name}'s {record.label}, not "
            f"{wanted.trainee.name}'s {wanted.label}"
        )
    ids = (record.run_id, wanted.run_id if same_id else None)
    if None not in ids and ids[0] != ids[1]:
        return (
            f"it holds another {record.label} of {record.trainee.name}'s (run id "
            f"{ids[0][:8]}, this one is {ids[1][:8]})"
        )
    return None


def refuse_others_file(target: Path, mine: RunRecord) -> None:
    """Raise unless ``target`` is new or holds the run ``mine``: a file of another run
    (another condition, trainee or run id) or any other file is never written over."""
    if not target.is_file():  # a new name (or a folder: writing says so)
        return
    fix = (
        f"It is kept untouched: choose another file name for the copy (e.g. "
        f"{target.stem}-copy{target.suffix})."
    )
    try:
        record = RunRecord.from_dict(read_json(target, "file"))
    except InvalidFileError as exc:
        raise InvalidFileError(
            f"Nothing was saved: {target.name} is not a run file of this run ({exc}). {fix}"
        ) from exc
    why = not_this_run(record, mine, same_id=True)
    if why is not None:
        raise WrongRunError(f"Nothing was saved over {target.name}: {why}. {fix}")
