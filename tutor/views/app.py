"""The base of both tutors: one run, its file, and the controls every tutor has.

:class:`TutorApp` holds what :class:`~tutor.views.maze_app.MazeTutor` and
:class:`~tutor.views.pickplace_app.PickPlaceTutor` share, so each fix is made once:

- **Resume.** The run's file is read back when the tutor opens. A file that cannot be
  read, or that holds another run (another condition, experiment, run number or
  trainee), is never overwritten: the tutor uses the next free name beside it
  (``NF-2.json``, ``NF-3.json``, ...) and says so.
- **One writer per file.** The tutor that owns a run file holds a lock on it
  (:mod:`filelock`; the operating system releases it when a kernel dies, so a killed
  kernel's lock is taken over safely). A second tutor or kernel on the same file is told
  so in plain words and gets a read-only view. A lock that cannot be taken at all (its
  lock file is a folder or another user's, the folder is read-only) fails closed: the
  run is shown read-only, the panel says why, and Save raises
  :class:`~tutor.errors.LockError`. Nothing is written without the lock.
- **Autosave** after every change, atomically (:func:`tutor.fileio.write_json`). A failed
  save (disk full, no permission, a folder that is a file) keeps everything in memory,
  says so in the panel, and is tried again at the next change or with Save.
- **Load** adds the demos of a demonstration file (all or nothing), or, for a run file of
  the *same* run, makes its demos a new attempt. Another run's file, or a load into a
  finished run, is refused, naming both runs.
- **Undo, Reset, Finish.** Reset asks for a second click within a few seconds; it starts
  a new attempt and keeps the old one, which *Bring back* restores. Nothing a trainee
  did is deleted.
- **No exception leaves a button.** A :class:`~tutor.errors.TutorError` becomes a
  message in the panel; anything else becomes a message that says the work is kept.
"""

from __future__ import annotations

import errno
import functools
import html
import logging
import os
import time
import weakref
from pathlib import Path

import ipywidgets as w
import numpy as np

from ..demofiles import DEMOS_FORMAT, load_demos
from ..errors import (
    InvalidFileError,
    InvalidParameterError,
    LockError,
    SaveError,
    SessionInUseError,
    TutorError,
    WrongRunError,
)
from ..fileio import check_file_name, read_json
from ..framework import RunRecord, TeachingRun, Trainee
from ..framework.record import RECORD_FORMAT
from ..framework.wording import sentence
from .uploads import Upload, on_upload

__all__ = ["TutorApp", "RESET_CONFIRM_SECONDS", "guarded"]

log = logging.getLogger(__name__)

#: a second click on Reset within this many seconds confirms it
RESET_CONFIRM_SECONDS = 5.0
#: seconds a tutor waits for another kernel's lock before it opens read-only
LOCK_WAIT_SECONDS = 2.0
#: the tutor of this kernel that holds each run file (by real path)
_OWNERS: dict[str, weakref.ref] = {}
#: how many sibling names (NF-2.json ...) are tried when a file holds another run
_MAX_SIBLINGS = 50
#: what a refused action says while another tutor holds the run
_IN_USE = (
    "This view is read-only because the run is open in another tutor: nothing was changed. "
    "Use the other one, or close it and run this cell again."
)


def _check_path(path, what: str = "session_file") -> str:
    """``path`` as text, or InvalidParameterError saying what is wrong with it."""
    problem = check_file_name(path)
    if problem is not None:
        raise InvalidParameterError(
            f"{what}: {problem}. Give the file's path as text, e.g. "
            f'{what}=folder / "VF.json", with a shorter name if it is too long'
        )
    return os.fspath(path)


def _lock_trouble(lock_path: Path, exc: OSError) -> str:
    """Why the lock file ``lock_path`` cannot be taken, in plain words."""
    name = lock_path.name
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


def guarded(method):
    """Run a tutor action so that no exception leaves it: errors become panel messages."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        result = None
        try:
            result = method(self, *args, **kwargs)
        except TutorError as exc:
            self.message = str(exc)
        except Exception as exc:  # a bug must not cost the trainee their run
            log.exception("tutor action %s failed", method.__name__)
            self.message = (
                f"Something went wrong inside the tutor ({type(exc).__name__}: {exc}). "
                "Your demonstrations are kept; please tell your educator."
            )
        try:
            self.refresh()
        except Exception:  # drawing must not lose the step either
            log.exception("refreshing the tutor failed")
        return result

    return wrapper


class TutorApp:
    """One teaching run on screen (subclasses add the drawing and the task's controls).

    Parameters
    ----------
    run_class : type of TeachingRun
    condition : str
    task : Task
    session_file : path or None
        Where the run autosaves; an existing file of the same run is resumed.
    trainee : str, optional
        The trainee's name (default ``JUPYTERHUB_USER`` on a hub, else "trainee").
    run : int
        The run number (Experiment 2 has three per trainee).
    practice : bool
        A practice run: recorded as such, so the class analysis leaves it out.
    """

    def __init__(
        self,
        run_class: type[TeachingRun],
        condition: str,
        task,
        session_file=None,
        trainee=None,
        run: int = 1,
        practice: bool = False,
    ):
        run_class.check_condition(condition)
        self.run_class = run_class
        self.task = task
        self.trainee = trainee if isinstance(trainee, Trainee) else Trainee.from_name(trainee)
        self._wanted = {"condition": condition, "run": run, "practice": bool(practice)}
        self.message = ""
        self.read_only = False
        self.unsaved = False
        self._lock = None
        #: why the lock cannot be taken at all (None: it can, or another tutor holds it)
        self._lock_problem: str | None = None
        #: what a refused action says while the view is read-only
        self._refusal = ""
        self._reset_asked = -1e9
        self.session_file = None if session_file is None else Path(_check_path(session_file))
        self.run = self._open()

    # ------------------------------------------------------------ state

    @property
    def condition(self) -> str:
        return self.run.condition

    @property
    def session(self):
        """The teaching session of the current attempt (demos, learner, feedback)."""
        return self.run.session

    @property
    def record(self) -> RunRecord:
        return self.run.record

    @property
    def finished(self) -> bool:
        return self.run.finished

    def _fresh(self) -> TeachingRun:
        return self.run_class.new(
            self._wanted["condition"],
            self.task,
            trainee=self.trainee,
            run=self._wanted["run"],
            practice=self._wanted["practice"],
        )

    def _matches(self, record: RunRecord) -> bool:
        return self._not_this_run(record) is None

    def _not_this_run(self, record: RunRecord, mine: RunRecord | None = None) -> str | None:
        """Why ``record`` (read from a file) is not this tutor's run; None when it is.

        The one check before a file is written: on opening (resume, Try again) and on
        Save to a chosen path. Another experiment, task, condition, run number, practice
        flag or trainee is another run. ``mine`` is the run as it stands: then another run
        id (both having one) is another run too. Without it the run this tutor was asked
        for is compared, since opening a file takes its run over, id and all.
        """
        wanted = self._fresh_record_like() if mine is None else mine
        if not record.same_run(wanted) or record.trainee.key != wanted.trainee.key:
            return (
                f"it holds {record.trainee.name}'s {record.label}, not "
                f"{wanted.trainee.name}'s {wanted.label}"
            )
        ids = (record.run_id, None if mine is None else mine.run_id)
        if None not in ids and ids[0] != ids[1]:
            return (
                f"it holds another {record.label} of {record.trainee.name}'s (run id "
                f"{ids[0][:8]}, this one is {ids[1][:8]})"
            )
        return None

    def _fresh_record_like(self) -> RunRecord:
        return self.run_class.fresh_record(
            self._wanted["condition"],
            self.task,
            trainee=self.trainee,
            run=self._wanted["run"],
            practice=self._wanted["practice"],
        )

    # ------------------------------------------------------------ opening the file

    def _open(self) -> TeachingRun:
        if self.session_file is None:
            return self._fresh()
        notes = []
        path = self.session_file
        for k in range(1, _MAX_SIBLINGS + 1):
            candidate = path if k == 1 else path.with_name(f"{path.stem}-{k}{path.suffix}")
            found, why = self._try_resume(candidate)
            if why is None:
                if candidate != path:
                    notes.append(f"This run is kept in {candidate.name} instead.")
                    self.session_file = candidate
                if notes:
                    self.message = " ".join([*notes, self.message]).strip()
                return found if found is not None else self._fresh()
            notes.append(why)
        self.message = " ".join(notes) + " No free file name was found: this run is not saved."
        self.session_file = None
        return self._fresh()

    def _try_resume(self, path: Path):
        """(run or None, None) when ``path`` can be this tutor's file; (None, why) if not.

        The file is read after its lock is taken, so no other writer can change it
        between the reading and this tutor's first save.
        """
        if path.exists() and not path.is_file():
            return None, f"{path.name} is not a regular file, so it is left alone."
        locked = self._take_lock(path)
        record = None
        if path.exists():
            try:
                record = RunRecord.from_dict(read_json(path, "run file"))
            except InvalidFileError as exc:
                self._release_lock()
                return (
                    None,
                    f"Could not resume from {path.name}: {sentence(exc)} It is kept untouched.",
                )
            why = self._not_this_run(record)
            if why is not None:
                self._release_lock()
                return None, f"Could not resume from {path.name}: {why}; it is kept untouched."
        if not locked:
            return self._read_only_view(path, record), None
        if record is None:
            return None, None
        try:
            run = self.run_class.from_record(self.task, record)
        except InvalidFileError as exc:
            self._release_lock()
            return None, f"Could not resume from {path.name}: {sentence(exc)} It is kept untouched."
        self.message = (
            f"{self.message} Resumed {run.n_demos} demonstration(s) from {path.name}."
            + (" This run is finished." if run.finished else "")
        ).strip()
        return run, None

    def _read_only_view(self, path: Path, record: RunRecord | None) -> TeachingRun:
        if self._lock_problem is not None:
            self._go_read_only(
                f"{path.name} cannot be locked ({self._lock_problem}), so this tutor shows "
                "it read-only: nothing you do here is saved. Ask your educator, or choose "
                "another folder; once it is fixed, press Try again.",
                f"This view is read-only because {path.name} cannot be locked "
                f"({self._lock_problem}): nothing was changed. Ask your educator, or choose "
                "another folder.",
            )
        else:
            self._go_read_only(
                f"{path.name} is open in another tutor (another kernel or browser tab). To "
                "keep that run safe, this view is read-only: nothing you do here is saved. "
                "Close the other one (or restart its kernel), then press Try again.",
                _IN_USE,
            )
        if record is None:
            return self._fresh()
        try:
            return self.run_class.from_record(self.task, record)
        except InvalidFileError:
            return self._fresh()

    @guarded
    def try_again(self) -> None:
        """A read-only view tries once more to take its run's file (and reloads it)."""
        if not self.read_only or self.session_file is None:
            return
        path = self.session_file
        if not self._take_lock(path):
            if self._lock_problem is not None:
                self.message = (
                    f"{path.name} still cannot be locked ({self._lock_problem}). This view "
                    "stays read-only: ask your educator, or choose another folder."
                )
            else:
                self.message = (
                    f"{path.name} is still open in another tutor: close that one (or "
                    "restart its kernel) first. This view stays read-only."
                )
            return
        if path.exists():
            try:
                record = RunRecord.from_dict(read_json(path, "run file"))
                why = self._not_this_run(record)
                if why is not None:
                    raise WrongRunError(why)
                run = self.run_class.from_record(self.task, record)
            except InvalidFileError as exc:
                self._release_lock()
                raise type(exc)(
                    f"Could not take {path.name} back: {sentence(exc)} It is kept untouched "
                    "and this view stays read-only; run the cell again to save this run beside it."
                ) from exc
            self.run = run
        self.read_only = False
        self.message = f"This tutor saves the run to {path.name} again."

    def _take_lock(self, path: Path, wait: float | None = None) -> bool:
        """Hold ``path``'s lock; False when another kernel holds it or it cannot be taken.

        A tutor made earlier in this same kernel on the same file (a cell run again) hands
        its file over: it saves, becomes read-only and says so. Another kernel's lock is
        waited for a moment (a reloaded Voila page's old kernel may be shutting down).
        A lock that cannot be taken at all (an OSError: the lock file is a folder or
        another user's, the folder is read-only) fails closed: False, with the reason in
        ``_lock_problem`` (None when another kernel holds the lock).
        """
        from filelock import FileLock, Timeout

        key = os.path.realpath(path)
        earlier = _OWNERS.get(key)
        owner = earlier() if earlier is not None else None
        if (
            owner is not None
            and owner is not self
            and owner._lock is not None
            and self._matches(owner.record)
        ):
            owner._hand_over()
        wait = LOCK_WAIT_SECONDS if wait is None else wait
        lock_path = path.with_name(f".{path.name}.lock")
        lock = FileLock(str(lock_path), timeout=wait)
        self._lock_problem = None
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            lock.acquire()
        except Timeout:
            return False
        except OSError as exc:  # no lock possible: fail closed (read-only), never open
            self._lock_problem = _lock_trouble(lock_path, exc)
            log.warning("no lock on %s (%s): read-only", path, exc)
            return False
        self._lock = lock
        _OWNERS[key] = weakref.ref(self)
        return True

    def _hand_over(self) -> None:
        """A newer tutor in this kernel takes this one's file: save, let go, say so."""
        self._autosave()
        self._release_lock()
        self._go_read_only(
            "This tutor was replaced by a newer one on the same run (its cell was run "
            "again), which carries on with every demonstration. Use that one; this view is "
            "read-only now.",
            _IN_USE,
        )
        try:
            self.refresh()
        except Exception:  # a view that cannot redraw must not stop the newer tutor
            log.exception("refreshing a replaced tutor failed")

    def _release_lock(self) -> None:
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def close(self) -> None:
        """Save and let go of the run's file (another tutor may then open it); this view
        is read-only afterwards."""
        self._autosave()
        self._release_lock()
        if self.session_file is not None and not self.read_only:
            self._go_read_only(
                "",
                "This tutor was closed, so it is read-only: nothing was changed. Run its "
                "cell again to carry on.",
            )

    def _go_read_only(self, message: str, refusal: str) -> None:
        """Show the run read-only: ``message`` now, ``refusal`` for every refused action."""
        self.read_only = True
        self._refusal = refusal
        if message:
            self.message = message

    def __del__(self):
        try:
            self._release_lock()
        except Exception:  # interpreter shutting down
            pass

    # ------------------------------------------------------------ saving

    def _autosave(self) -> None:
        if self.session_file is None or self.read_only or self._lock is None:
            return
        try:
            self.run.save(self.session_file)
        except SaveError as exc:
            self.unsaved = True
            self.message = (
                f"{self.message} Not saved: {exc} Your demonstrations are kept here and "
                "saving is tried again after the next change (or press Save)."
            ).strip()
        else:
            self.unsaved = False

    def _refuse_if_read_only(self) -> bool:
        if self.read_only:
            self.message = self._refusal
            self.refresh()
        return self.read_only

    def _check_may_save(self) -> None:
        """Raise LockError (the lock cannot be taken) or SessionInUseError (another tutor
        holds the run) when this view is read-only: nothing is saved then."""
        if not self.read_only:
            return
        if self._lock_problem is not None:
            raise LockError(f"Nothing was saved. {self._refusal}")
        raise SessionInUseError(f"Nothing was saved. {self._refusal}")

    # ------------------------------------------------------------ actions

    @guarded
    def save(self, path=None) -> Path | None:
        """Save the run (to its file by default, or to ``path``); returns the path written.

        A read-only view saves nothing: LockError when the run's file cannot be locked,
        SessionInUseError when another tutor holds it (shown in the panel).
        """
        self._check_may_save()
        if path is not None:
            problem = check_file_name(path)
            if problem is not None:
                raise InvalidParameterError(
                    f"Nothing was saved: {problem}. Give the copy's path as text, e.g. "
                    'folder / "VF-copy.json".'
                )
            target = Path(path)
            own = self.session_file is not None and (
                os.path.realpath(target) == os.path.realpath(self.session_file)
            )
            if not own:
                self._refuse_others_file(target)
                self.run.save(target)
                self.message = f"Saved a copy to {target}."
                return target
        if self.session_file is None:
            self.message = "This run has no file to save to (see above)."
            return None
        self.run.save(self.session_file)
        self.unsaved = False
        self.message = f"Saved to {self.session_file}."
        return self.session_file

    def _refuse_others_file(self, target: Path) -> None:
        """Raise unless ``target`` is new or holds this very run: a file of another run
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
        why = self._not_this_run(record, self.record)
        if why is not None:
            raise WrongRunError(f"Nothing was saved over {target.name}: {why}. {fix}")

    @guarded
    def undo(self) -> None:
        """Take back the latest demonstration (kept in the record)."""
        if self._refuse_if_read_only():
            return
        if self.run.n_demos == 0:
            self.message = "There is no demonstration to undo."
            return
        self.run.undo()
        self.message = self._undo_message()
        self._autosave()

    def _undo_message(self) -> str:
        return "Took back the latest demonstration (it stays in the run's history)."

    def request_reset(self) -> None:
        """What the Reset button does: the first click asks, a second within 5 s resets."""
        if self._refuse_if_read_only():
            return
        now = time.monotonic()
        if now - self._reset_asked <= RESET_CONFIRM_SECONDS:
            self._reset_asked = -1e9
            self.reset()
            return
        self._reset_asked = now
        self.message = (
            f"Press Reset again within {RESET_CONFIRM_SECONDS:.0f} seconds to start a new "
            "attempt. This attempt is kept and can be brought back."
        )
        self.refresh()

    @guarded
    def reset(self) -> None:
        """Start a new, empty attempt; the current one is kept (see :meth:`restore`)."""
        if self._refuse_if_read_only():
            return
        kept = self.run.n_demos
        self.run.reset()
        self.message = (
            f"Started attempt {len(self.record.attempts)}. The previous attempt ({kept} "
            "demonstration(s)) is kept: choose it under 'Earlier attempts' to bring it back."
        )
        self._autosave()

    @guarded
    def restore(self, attempt: int) -> None:
        """Bring back earlier attempt number ``attempt`` (1-based) as a new attempt."""
        if self._refuse_if_read_only():
            return
        if isinstance(attempt, bool) or not isinstance(attempt, (int, np.integer)):
            raise InvalidParameterError(
                f"an attempt is a whole number (1 for the first), got {attempt!r}"
            )
        self.run.restore(int(attempt) - 1)
        self.message = (
            f"Brought back attempt {attempt} as attempt {len(self.record.attempts)} "
            f"({self.run.n_demos} demonstration(s))."
        )
        self._autosave()

    @guarded
    def finish(self) -> None:
        """End the run and show the paper's score."""
        if self._refuse_if_read_only():
            return
        if self.run.n_demos == 0:
            self.message = "Give at least one demonstration before finishing."
            return
        self.run.finish()
        self.message = ""
        self._autosave()

    @guarded
    def load(self, path) -> None:
        """Load a file: a demonstration file's demos are added (all or nothing); a run file
        of this same run becomes a new attempt. Anything else is refused, and the run and
        its file are left as they were."""
        if self._refuse_if_read_only():
            return
        problem = check_file_name(path)
        if problem is not None:
            raise InvalidFileError(
                f"Nothing was loaded: {problem}. Choose a .json or .csv file with the Load "
                "button, or give its path as text."
            )
        path = Path(path)
        try:
            self._load(path)
        except TutorError as exc:
            why = str(exc).rstrip()
            why = why if why.endswith((".", "!", "?")) else why + "."
            raise type(exc)(
                f"Nothing was loaded from {path.name}: {why} This run and its file are unchanged."
            ) from exc
        self._autosave()

    def _load(self, path: Path) -> None:
        suffix = path.suffix.lower()
        if suffix == ".csv":
            self._load_demo_file(path)
        elif suffix == ".json":
            data = read_json(path, "file")
            kind = data.get("format") if isinstance(data, dict) else None
            if kind == RECORD_FORMAT or kind == "lfd-tutor-session":
                other = RunRecord.from_dict(data)
                self.run.replace_with(other, detail=path.name)
                self.message = (
                    f"Loaded {self.run.n_demos} demonstration(s) from {path.name} as attempt "
                    f"{len(self.record.attempts)}; the previous attempt is kept."
                )
            elif kind == DEMOS_FORMAT:
                self._load_demo_file(path)
            else:
                raise InvalidFileError(
                    f'it is neither a demonstration file ("format": "{DEMOS_FORMAT}") '
                    f'nor a run file ("format": "{RECORD_FORMAT}")'
                    + (f'; it says "format": {kind!r}.' if kind else ".")
                )
        else:
            raise InvalidFileError("load a .json or .csv file (demonstrations or a saved run).")

    def _load_demo_file(self, path: Path) -> None:
        demos = load_demos(path, columns=self.demo_columns)
        items = self._load_items(demos, path.name)
        n = self.run.add_demos(items, detail=path.name)
        self.message = f"Added {n} demonstration(s) from {path.name}."

    #: the columns of a demonstration file, time first (subclasses set them)
    demo_columns: tuple[str, ...] = ()

    def _load_items(self, demos, name: str):
        """(raw, options) for each demo of a loaded file (subclasses add the condition)."""
        return [(raw, {}) for raw in demos]

    # ------------------------------------------------------------ shared widgets

    def _common_widgets(self) -> None:
        """Upload, attempts chooser and status line, wired to the actions above."""
        self.upload = Upload(
            accept=".json,.csv",
            multiple=False,
            description="Load file",
            tooltip="Add demonstrations from a .json or .csv file, or open a saved run",
            layout=w.Layout(width="120px"),
        )
        self.upload.observe(on_upload(self.load), names="value")
        self.attempts = w.Dropdown(
            options=[],
            description="Earlier attempts",
            style={"description_width": "initial"},
            layout=w.Layout(width="300px", display="none"),
        )
        self.bring_back = w.Button(
            description="Bring back",
            tooltip="Make the chosen earlier attempt the current one (nothing is deleted)",
            layout=w.Layout(width="100px", display="none"),
        )
        self.bring_back.on_click(lambda _: self._on_bring_back())
        self.retry = w.Button(
            description="Try again",
            tooltip="Take the run's file back once the other tutor is closed",
            layout=w.Layout(width="100px", display="none"),
        )
        self.retry.on_click(lambda _: self.try_again())
        self.status = w.HTML()

    def _on_bring_back(self) -> None:
        if self.attempts.value is None:
            self.message = "Choose an earlier attempt in the list first, then press Bring back."
            self.refresh()
            return
        self.restore(self.attempts.value)

    def _refresh_common(self) -> None:
        attempts = self.record.attempts
        earlier = [
            (f"attempt {i}: {a.n_demos} demo(s), {a.ended or 'open'}", i)
            for i, a in enumerate(attempts[:-1], start=1)
        ]
        if len(earlier) != len(self.attempts.options):
            self.attempts.options = earlier
            if earlier:  # a new earlier attempt: offer it, ready to bring back
                self.attempts.value = earlier[-1][1]
        show = "flex" if earlier and not self.read_only else "none"
        self.attempts.layout.display = show
        self.bring_back.layout.display = show
        self.upload.disabled = self.read_only or self.finished
        self.retry.layout.display = "flex" if self.read_only else "none"
        if self.read_only and self._lock_problem is not None:
            state = "read-only (its file cannot be locked)"
        elif self.read_only:
            state = "read-only (open in another tutor)"
        elif self.session_file is None:
            state = "not saved to a file"
        elif self.unsaved:
            state = f"<b>not saved yet</b> to {html.escape(self.session_file.name)}"
        else:
            state = f"saved to {html.escape(self.session_file.name)}"
        self.status.value = (
            f"<span class='lfd-status'>{html.escape(self.trainee.name)} &middot; {state}</span>"
        )

    def message_html(self) -> str:
        if not self.message:
            return ""
        return f"<div class='lfd-message' role='status'>{html.escape(self.message)}</div>"

    def refresh(self) -> None:  # pragma: no cover - subclasses draw
        raise NotImplementedError

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
