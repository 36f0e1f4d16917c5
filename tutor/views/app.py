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
  so in plain words and gets a read-only view.
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
from ..errors import InvalidFileError, InvalidParameterError, SaveError, TutorError
from ..fileio import check_file_name, read_json
from ..framework import RunRecord, TeachingRun, Trainee
from ..framework.record import RECORD_FORMAT
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


def _check_path(path, what: str = "session_file") -> str:
    """``path`` as text, or InvalidParameterError saying what is wrong with it."""
    problem = check_file_name(path)
    if problem is not None:
        raise InvalidParameterError(
            f"{what}: {problem}. Give the file's path as text, e.g. "
            f'{what}=folder / "VF.json", with a shorter name if it is too long'
        )
    return os.fspath(path)


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
        mine = self._fresh_record_like()
        return record.same_run(mine) and record.trainee.key == self.trainee.key

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
                return None, f"Could not resume from {path.name}: {exc}. It is kept untouched."
            if not self._matches(record):
                self._release_lock()
                return None, (
                    f"Could not resume from {path.name}: it holds "
                    f"{record.trainee.name}'s {record.label}, not "
                    f"{self.trainee.name}'s {self._fresh_record_like().label}; it is kept "
                    "untouched."
                )
        if not locked:
            return self._read_only_view(path, record), None
        if record is None:
            return None, None
        try:
            run = self.run_class.from_record(self.task, record)
        except InvalidFileError as exc:
            self._release_lock()
            return None, f"Could not resume from {path.name}: {exc}. It is kept untouched."
        self.message = (
            f"{self.message} Resumed {run.n_demos} demonstration(s) from {path.name}."
            + (" This run is finished." if run.finished else "")
        ).strip()
        return run, None

    def _read_only_view(self, path: Path, record: RunRecord | None) -> TeachingRun:
        self.read_only = True
        self.message = (
            f"{path.name} is open in another tutor (another kernel or browser tab). To "
            "keep that run safe, this view is read-only: nothing you do here is saved. "
            "Close the other one (or restart its kernel), then press Try again."
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
            self.message = (
                f"{path.name} is still open in another tutor: close that one (or restart "
                "its kernel) first. This view stays read-only."
            )
            return
        self.read_only = False
        if path.exists():
            self.run = self.run_class.from_record(
                self.task, RunRecord.from_dict(read_json(path, "run file"))
            )
        self.message = f"This tutor saves the run to {path.name} again."

    def _take_lock(self, path: Path, wait: float | None = None) -> bool:
        """Hold ``path``'s lock; False when another kernel holds it.

        A tutor made earlier in this same kernel on the same file (a cell run again) hands
        its file over: it saves, becomes read-only and says so. Another kernel's lock is
        waited for a moment (a reloaded Voila page's old kernel may be shutting down).
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
        lock = FileLock(str(path.with_name(f".{path.name}.lock")), timeout=wait)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            lock.acquire()
        except Timeout:
            return False
        except OSError as exc:  # no lock possible (read-only folder): saving will say so
            log.warning("no lock on %s: %s", path, exc)
            return True
        self._lock = lock
        _OWNERS[key] = weakref.ref(self)
        return True

    def _hand_over(self) -> None:
        """A newer tutor in this kernel takes this one's file: save, let go, say so."""
        self._autosave()
        self._release_lock()
        self.read_only = True
        self.message = (
            "This tutor was replaced by a newer one on the same run (its cell was run "
            "again), which carries on with every demonstration. Use that one; this view is "
            "read-only now."
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
        """Save and let go of the run's file (another tutor may then open it)."""
        self._autosave()
        self._release_lock()

    def __del__(self):
        try:
            self._release_lock()
        except Exception:  # interpreter shutting down
            pass

    # ------------------------------------------------------------ saving

    def _autosave(self) -> None:
        if self.session_file is None or self.read_only:
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
            self.message = (
                "This view is read-only because the run is open in another tutor: nothing "
                "was changed. Use the other one, or close it and run this cell again."
            )
            self.refresh()
        return self.read_only

    # ------------------------------------------------------------ actions

    @guarded
    def save(self, path=None) -> Path | None:
        """Save the run (to its file by default, or to ``path``); returns the path written."""
        if path is not None:
            target = Path(path)
            self.run.save(target)
            self.message = f"Saved a copy to {target}."
            return target
        if self._refuse_if_read_only():
            return None
        if self.session_file is None:
            self.message = "This run has no file to save to (see above)."
            return None
        self.run.save(self.session_file)
        self.unsaved = False
        self.message = f"Saved to {self.session_file}."
        return self.session_file

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
                f"Nothing was loaded from {path.name}: {why} This run and its file are "
                "unchanged."
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
                    f"it is neither a demonstration file (\"format\": \"{DEMOS_FORMAT}\") "
                    f"nor a run file (\"format\": \"{RECORD_FORMAT}\")"
                    + (f"; it says \"format\": {kind!r}." if kind else ".")
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
        if self.read_only:
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
