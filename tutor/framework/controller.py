"""The run controller: one teaching run, its file, and what every tutor's controls do.

:class:`RunController` sits below the views: both tutors
(:class:`~tutor.views.maze_app.MazeTutor`, :class:`~tutor.views.pickplace_app.PickPlaceTutor`)
make one and forward their buttons to it, so each fix is made once. The views draw its
state (the run, :attr:`~RunController.read_only`, :attr:`~RunController.unsaved`, the
message) and nothing else.

- **Resume.** The run's file is read back when the tutor opens. A file that cannot be
  read, or that holds another run (another condition, experiment, run number or
  trainee), is never overwritten: the tutor uses the next free name beside it
  (``NF-2.json``, ``NF-3.json``, ...) and says so.
- **One writer per file.** The tutor that owns a run file holds a lock on it
  (:mod:`tutor.framework.run_file`; the operating system releases it when a kernel dies,
  so a killed kernel's lock is taken over safely). A second tutor or kernel on the same
  file is told so in plain words and gets a read-only view. A lock that cannot be taken
  at all (its lock file is a folder or another user's, the folder is read-only) fails
  closed: the run is shown read-only, the panel says why, and Save raises
  :class:`~tutor.errors.LockError`. Nothing is written without the lock.
- **Autosave** after every change, atomically (:func:`tutor.fileio.write_json`). A failed
  save (disk full, no permission, a folder that is a file) keeps everything in memory,
  says so in the panel, and is tried again at the next change or with Save.
- **Load** adds the demos of a demonstration file (all or nothing), or, for a run file of
  the *same* run, makes its demos a new attempt. Another run's file, or a load into a
  finished run, is refused, naming both runs. An uploaded file is named as the trainee
  knows it (``load(path, name)``), not by the name it was stored under.
- **Undo, Reset, Finish.** Reset asks for a second click within a few seconds; it starts
  a new attempt and keeps the old one, which *Bring back* restores. Nothing a trainee
  did is deleted.
- **One message.** What the panel says is :attr:`RunController.message`, set only by
  :meth:`RunController.say`. No exception leaves a button (the views'
  :func:`~tutor.views.app.guarded`): :meth:`RunController.failed` turns a
  :class:`~tutor.errors.TutorError` into its message, and anything else into a message
  that says the work is kept.
"""

from __future__ import annotations

import logging
import os
import time
import weakref
from collections.abc import Callable
from pathlib import Path

import numpy as np

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
from .record import RunRecord, Trainee
from .run import TeachingRun
from .run_file import not_this_run, refuse_others_file, take_lock
from .run_loading import load_into, plain_items
from .wording import sentence

__all__ = ["RunController", "RESET_CONFIRM_SECONDS", "UNDO_NOTE"]

log = logging.getLogger(__name__)

#: a second click on Reset within this many seconds confirms it
RESET_CONFIRM_SECONDS = 5.0
#: what Undo says by default
UNDO_NOTE = "Took back the latest demonstration (it stays in the run's history)."
#: the controller of this kernel that holds each run file (by real path)
_OWNERS: dict[str, weakref.ref] = {}
#: how many sibling names (NF-2.json ...) are tried when a file holds another run
_MAX_SIBLINGS = 50
#: what a refused action says while another tutor holds the run
_IN_USE = (
    "This view is read-only because the run is open in another tutor: nothing was changed. "
    "Use the other one, or close it and run this cell again."
)


def _nothing_loaded(exc: TutorError) -> TutorError:
    """``exc``, marked as a refused load that already says "Nothing was loaded" (a page
    that reports it reads the mark, not the words)."""
    exc.nothing_loaded = True
    return exc


def _check_path(path, what: str = "run_file") -> str:
    """``path`` as text, or InvalidParameterError saying what is wrong with it."""
    problem = check_file_name(path)
    if problem is not None:
        raise InvalidParameterError(
            f"{what}: {problem}. Give the file's path as text, e.g. "
            f'{what}=folder / "VF.json", with a shorter name if it is too long'
        )
    return os.fspath(path)


class RunController:
    """One teaching run, its file and its lock, and the actions on it; no widgets.

    Parameters
    ----------
    run_class : type of TeachingRun
    condition : str
    task : Task
    run_file : path or None
        Where the run autosaves; an existing file of the same run is resumed.
    trainee : str or Trainee, optional
        The trainee (default ``JUPYTERHUB_USER`` on a hub, else "trainee").
    run : int
        The run number (Experiment 2 has three per trainee).
    practice : bool
        A practice run: recorded as such, so the class analysis leaves it out.
    demo_columns : tuple of str
        The columns of a demonstration file, time first.
    load_items : callable, optional
        ``load_items(run, demos, name)``: (raw, options) for each demo of a loaded file
        (the pick-and-place tutor adds each demo's plant); by default no options.
    undo_note : str
        What Undo says after taking a demonstration back.
    on_change : callable, optional
        Called when the state changes outside an action of this view: a newer tutor in
        the same kernel took the run over (the view redraws).
    """

    #: what the panel says (set only by :meth:`say`)
    _message: str = ""

    def __init__(
        self,
        run_class: type[TeachingRun],
        condition: str,
        task,
        run_file=None,
        trainee=None,
        run: int = 1,
        practice: bool = False,
        *,
        demo_columns: tuple[str, ...] = (),
        load_items: Callable | None = None,
        undo_note: str = UNDO_NOTE,
        on_change: Callable[[], None] | None = None,
    ):
        run_class.check_condition(condition)
        self.run_class = run_class
        self.task = task
        self.trainee = trainee if isinstance(trainee, Trainee) else Trainee.from_name(trainee)
        self.demo_columns = tuple(demo_columns)
        self._load_items = plain_items if load_items is None else load_items
        self.undo_note = undo_note
        self.on_change = on_change
        self._wanted = {"condition": condition, "run": run, "practice": bool(practice)}
        self.read_only = False
        self.unsaved = False
        self._lock = None
        #: why the lock cannot be taken at all (None: it can, or another tutor holds it)
        self.lock_problem: str | None = None
        #: what a refused action says while the view is read-only
        self._refusal = ""
        self._reset_asked = -1e9
        self.run_file = None if run_file is None else Path(_check_path(run_file))
        self.run = self._open()

    # ------------------------------------------------------------ the message

    @property
    def message(self) -> str:
        """What the panel says now (set by :meth:`say`)."""
        return self._message

    def say(self, text: str) -> None:
        """Make ``text`` what the panel says: the one place the message is set."""
        self._message = text

    def failed(self, exc: Exception, action: str) -> None:
        """Say what went wrong in ``action``: a TutorError's own words; for anything else
        (a bug), that the demonstrations are kept."""
        if isinstance(exc, TutorError):
            self.say(str(exc))
            return
        log.error("tutor action %s failed", action, exc_info=exc)
        self.say(
            f"Something went wrong inside the tutor ({type(exc).__name__}: {exc}). "
            "Your demonstrations are kept; please tell your educator."
        )

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

    def _not_this_run(self, record: RunRecord) -> str | None:
        """Why ``record`` (read from a file) is not the run this tutor was asked for
        (:func:`~tutor.framework.run_file.not_this_run`); None when it is."""
        return not_this_run(record, self._fresh_record_like())

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
        if self.run_file is None:
            return self._fresh()
        notes = []
        path = self.run_file
        for k in range(1, _MAX_SIBLINGS + 1):
            candidate = path if k == 1 else path.with_name(f"{path.stem}-{k}{path.suffix}")
            found, why = self._try_resume(candidate)
            if why is None:
                if candidate != path:
                    notes.append(f"This run is kept in {candidate.name} instead.")
                    self.run_file = candidate
                if notes:
                    self.say(" ".join([*notes, self.message]).strip())
                return found if found is not None else self._fresh()
            notes.append(why)
        self.say(" ".join(notes) + " No free file name was found: this run is not saved.")
        self.run_file = None
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
                self.release_lock()
                return (
                    None,
                    f"Could not resume from {path.name}: {sentence(exc)} It is kept untouched.",
                )
            why = self._not_this_run(record)
            if why is not None:
                self.release_lock()
                return None, f"Could not resume from {path.name}: {why}; it is kept untouched."
        if not locked:
            return self._read_only_view(path, record), None
        if record is None:
            return None, None
        try:
            run = self.run_class.from_record(self.task, record)
        except InvalidFileError as exc:
            self.release_lock()
            return None, f"Could not resume from {path.name}: {sentence(exc)} It is kept untouched."
        resumed = (
            f"{self.message} Resumed {run.n_demos} demonstration(s) from {path.name}."
            + (" This run is finished." if run.finished else "")
        )
        self.say(resumed.strip())
        return run, None

    def _read_only_view(self, path: Path, record: RunRecord | None) -> TeachingRun:
        if self.lock_problem is not None:
            self._go_read_only(
                f"{path.name} cannot be locked ({self.lock_problem}), so this tutor shows "
                "it read-only: nothing you do here is saved. Ask your educator, or choose "
                "another folder; once it is fixed, press Try again.",
                f"This view is read-only because {path.name} cannot be locked "
                f"({self.lock_problem}): nothing was changed. Ask your educator, or choose "
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

    def try_again(self) -> None:
        """A read-only view tries once more to take its run's file (and reloads it)."""
        if not self.read_only or self.run_file is None:
            return
        path = self.run_file
        if not self._take_lock(path):
            if self.lock_problem is not None:
                self.say(
                    f"{path.name} still cannot be locked ({self.lock_problem}). This view "
                    "stays read-only: ask your educator, or choose another folder."
                )
            else:
                self.say(
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
                self.release_lock()
                raise type(exc)(
                    f"Could not take {path.name} back: {sentence(exc)} It is kept untouched "
                    "and this view stays read-only; run the cell again to save this run beside it."
                ) from exc
            self.run = run
        self.read_only = False
        self.say(f"This tutor saves the run to {path.name} again.")

    # ------------------------------------------------------------ the lock

    def _take_lock(self, path: Path, wait: float | None = None) -> bool:
        """Hold ``path``'s lock; False when another kernel holds it or it cannot be taken.

        A tutor made earlier in this same kernel on the same file (a cell run again) hands
        its file over: it saves, becomes read-only and says so. Another kernel's lock is
        waited for a moment (:func:`~tutor.framework.run_file.take_lock`). A lock that
        cannot be taken at all fails closed: False, with the reason in
        :attr:`lock_problem` (None when another kernel holds the lock).
        """
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
        lock, self.lock_problem = take_lock(path, wait)
        if lock is None:
            return False
        self._lock = lock
        _OWNERS[key] = weakref.ref(self)
        return True

    def _hand_over(self) -> None:
        """A newer tutor in this kernel takes this one's file: save, let go, say so."""
        self.autosave()
        self.release_lock()
        self._go_read_only(
            "This tutor was replaced by a newer one on the same run (its cell was run "
            "again), which carries on with every demonstration. Use that one; this view is "
            "read-only now.",
            _IN_USE,
        )
        if self.on_change is not None:
            try:
                self.on_change()
            except Exception:  # a view that cannot redraw must not stop the newer tutor
                log.exception("refreshing a replaced tutor failed")

    def release_lock(self) -> None:
        """Let go of the run file's lock (if held)."""
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def close(self) -> None:
        """Save and let go of the run's file (another tutor may then open it); this view
        is read-only afterwards."""
        self.autosave()
        self.release_lock()
        if self.run_file is not None and not self.read_only:
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
            self.say(message)

    def __del__(self):
        try:
            self.release_lock()
        except Exception:  # interpreter shutting down
            pass

    # ------------------------------------------------------------ saving

    def autosave(self) -> None:
        """Save the run to its file after a change; a failure is said, never raised."""
        if self.run_file is None or self.read_only or self._lock is None:
            return
        try:
            self.run.save(self.run_file)
        except SaveError as exc:
            self.unsaved = True
            why = (
                f"{self.message} Not saved: {exc} Your demonstrations are kept here and "
                "saving is tried again after the next change (or press Save)."
            )
            self.say(why.strip())
        else:
            self.unsaved = False

    def refuse_if_read_only(self) -> bool:
        """True (and the refusal said) when this view is read-only and may change nothing."""
        if self.read_only:
            self.say(self._refusal)
        return self.read_only

    def _check_may_save(self) -> None:
        """Raise LockError (the lock cannot be taken) or SessionInUseError (another tutor
        holds the run) when this view is read-only: nothing is saved then."""
        if not self.read_only:
            return
        if self.lock_problem is not None:
            raise LockError(f"Nothing was saved. {self._refusal}")
        raise SessionInUseError(f"Nothing was saved. {self._refusal}")

    def save(self, path=None) -> Path | None:
        """Save the run (to its file by default, or to ``path``); returns the path written.

        A read-only view saves nothing: LockError when the run's file cannot be locked,
        SessionInUseError when another tutor holds it.
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
            own = self.run_file is not None and (
                os.path.realpath(target) == os.path.realpath(self.run_file)
            )
            if not own:
                refuse_others_file(target, self.record)
                self.run.save(target)
                self.say(f"Saved a copy to {target}.")
                return target
        if self.run_file is None:
            self.say("This run has no file to save to (see above).")
            return None
        self.run.save(self.run_file)
        self.unsaved = False
        self.say(f"Saved to {self.run_file}.")
        return self.run_file

    # ------------------------------------------------------------ actions

    def undo(self) -> None:
        """Take back the latest demonstration (kept in the record)."""
        if self.refuse_if_read_only():
            return
        if self.run.n_demos == 0:
            self.say("There is no demonstration to undo.")
            return
        self.run.undo()
        self.say(self.undo_note)
        self.autosave()

    def request_reset(self) -> None:
        """What the Reset button does: the first click asks, a second within 5 s resets."""
        if self.refuse_if_read_only():
            return
        now = time.monotonic()
        if now - self._reset_asked <= RESET_CONFIRM_SECONDS:
            self._reset_asked = -1e9
            self.reset()
            return
        self._reset_asked = now
        self.say(
            f"Press Reset again within {RESET_CONFIRM_SECONDS:.0f} seconds to start a new "
            "attempt. This attempt is kept and can be brought back."
        )

    def reset(self) -> None:
        """Start a new, empty attempt; the current one is kept (see :meth:`restore`)."""
        if self.refuse_if_read_only():
            return
        kept = self.run.n_demos
        self.run.reset()
        self.say(
            f"Started attempt {len(self.record.attempts)}. The previous attempt ({kept} "
            "demonstration(s)) is kept: choose it under 'Earlier attempts' to bring it back."
        )
        self.autosave()

    def restore(self, attempt: int) -> None:
        """Bring back earlier attempt number ``attempt`` (1-based) as a new attempt."""
        if self.refuse_if_read_only():
            return
        if isinstance(attempt, bool) or not isinstance(attempt, (int, np.integer)):
            raise InvalidParameterError(
                f"an attempt is a whole number (1 for the first), got {attempt!r}"
            )
        self.run.restore(int(attempt) - 1)
        self.say(
            f"Brought back attempt {attempt} as attempt {len(self.record.attempts)} "
            f"({self.run.n_demos} demonstration(s))."
        )
        self.autosave()

    def bring_back(self, attempt: int | None) -> None:
        """What *Bring back* does with the attempt chosen in the list (None: none chosen)."""
        if attempt is None:
            self.say("Choose an earlier attempt in the list first, then press Bring back.")
            return
        self.restore(attempt)

    def finish(self, needs_demos: bool = True) -> None:
        """End the run (the paper's score is then shown).

        ``needs_demos``: a run without demonstrations is not finished (Experiment 1);
        Experiment 2's trainee may end a run whenever they like.
        """
        if self.refuse_if_read_only():
            return
        if needs_demos and self.run.n_demos == 0:
            self.say("Give at least one demonstration before finishing.")
            return
        self.run.finish()
        self.say("")
        self.autosave()

    def load(self, path, name: str | None = None) -> None:
        """Load a file: a demonstration file's demos are added (all or nothing); a run file
        of this same run becomes a new attempt. Anything else is refused, and the run and
        its file are left as they were.

        ``name`` is the file as the trainee knows it (an upload is stored under a safe
        name); by default the file's own name.
        """
        if self.refuse_if_read_only():
            return
        problem = check_file_name(path)
        if problem is not None:
            raise _nothing_loaded(InvalidFileError(
                f"Nothing was loaded: {problem}. Choose a .json or .csv file with the Load "
                "button, or give its path as text."
            ))
        path = Path(path)
        shown = path.name if name is None else name
        try:
            self.say(load_into(self.run, path, shown, self.demo_columns, self._load_items))
        except TutorError as exc:
            why = str(exc).rstrip()
            if shown != path.name:  # the readers name the stored file: name the trainee's
                why = why.replace(path.name, shown)
            why = why if why.endswith((".", "!", "?")) else why + "."
            raise _nothing_loaded(type(exc)(
                f"Nothing was loaded from {shown}: {why} This run and its file are unchanged."
            )) from exc
        self.autosave()
