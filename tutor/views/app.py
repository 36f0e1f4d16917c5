"""The base of both tutors' views: the controls every tutor has, drawn from its controller.

:class:`TutorApp` holds what :class:`~tutor.views.maze_app.MazeTutor` and
:class:`~tutor.views.pickplace_app.PickPlaceTutor` show alike: the Load button, the
earlier attempts and *Bring back*, *Try again* and the status line. The run itself, its
file and lock, resume, autosave, load, undo, reset, bring back, finish and the message
are the :class:`~tutor.framework.controller.RunController`'s (see there for what each
does): the widgets forward their events to it and draw its state. No exception leaves a
button (:func:`guarded`).
"""

from __future__ import annotations

import functools
import html
import logging
from pathlib import Path

import ipywidgets as w

from ..framework import RunRecord, TeachingRun
from ..framework.controller import RESET_CONFIRM_SECONDS, UNDO_NOTE, RunController
from ..workers import one_blas_thread
from .uploads import Upload, on_upload

__all__ = ["TutorApp", "RESET_CONFIRM_SECONDS", "guarded"]

log = logging.getLogger(__name__)


def guarded(method):
    """Run a tutor action so that no exception leaves it: errors become panel messages
    (:meth:`RunController.failed <tutor.framework.controller.RunController.failed>`), and
    the view is redrawn."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        result = None
        try:
            result = method(self, *args, **kwargs)
        except Exception as exc:  # a bug must not cost the trainee their run
            self.controller.failed(exc, method.__name__)
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
    run_file : path or None
        Where the run autosaves; an existing file of the same run is resumed.
    trainee : str, optional
        The trainee's name (default ``JUPYTERHUB_USER`` on a hub, else "trainee").
    run : int
        The run number (Experiment 2 has three per trainee).
    practice : bool
        A practice run: recorded as such, so the class analysis leaves it out.

    Attributes
    ----------
    controller : RunController
        The run and every action on it; the view's properties (``run``, ``message``,
        ``read_only``, ...) are its.
    """

    #: the columns of a demonstration file, time first (subclasses set them)
    demo_columns: tuple[str, ...] = ()
    #: what Undo says (subclasses may say more, or nothing)
    undo_note: str = UNDO_NOTE
    #: ``load_items(run, demos, name)`` for a loaded file's demos (None: no options)
    load_items = None

    def __init__(
        self,
        run_class: type[TeachingRun],
        condition: str,
        task,
        run_file=None,
        trainee=None,
        run: int = 1,
        practice: bool = False,
    ):
        one_blas_thread()  # the learner's small products run faster on one BLAS thread
        self.controller = RunController(
            run_class,
            condition,
            task,
            run_file,
            trainee,
            run,
            practice,
            demo_columns=self.demo_columns,
            load_items=self.load_items,
            undo_note=self.undo_note,
            on_change=self._redraw,
        )

    # ------------------------------------------------------------ the controller's state

    run_class = property(lambda self: self.controller.run_class)
    task = property(lambda self: self.controller.task)
    trainee = property(lambda self: self.controller.trainee)
    run_file = property(lambda self: self.controller.run_file)
    read_only = property(lambda self: self.controller.read_only)
    unsaved = property(lambda self: self.controller.unsaved)

    @property
    def run(self) -> TeachingRun:
        return self.controller.run

    @property
    def condition(self) -> str:
        return self.controller.condition

    @property
    def session(self):
        """The teaching session of the current attempt (demos, learner, feedback)."""
        return self.controller.session

    @property
    def record(self) -> RunRecord:
        return self.controller.record

    @property
    def finished(self) -> bool:
        return self.controller.finished

    @property
    def message(self) -> str:
        """What the panel says (the controller's; :meth:`RunController.say
        <tutor.framework.controller.RunController.say>` sets it)."""
        return self.controller.message

    @message.setter
    def message(self, text: str) -> None:
        self.controller.say(text)

    def tell(self, text: str) -> None:
        """Say ``text`` in the panel now (what an upload's report does)."""
        self.controller.say(text)
        self.refresh()

    def _redraw(self) -> None:
        """The controller changed on its own (a newer tutor took the run): redraw, if
        the widgets are made yet."""
        if hasattr(self, "widget"):
            self.refresh()

    # ------------------------------------------------------------ actions (forwarded)

    @guarded
    def save(self, path=None) -> Path | None:
        """Save the run (to its file by default, or to ``path``); returns the path written.

        A read-only view saves nothing: LockError when the run's file cannot be locked,
        SessionInUseError when another tutor holds it (shown in the panel).
        """
        return self.controller.save(path)

    @guarded
    def undo(self) -> None:
        """Take back the latest demonstration (kept in the record)."""
        self.controller.undo()

    @guarded
    def request_reset(self) -> None:
        """What the Reset button does: the first click asks, a second within 5 s resets."""
        self.controller.request_reset()

    @guarded
    def reset(self) -> None:
        """Start a new, empty attempt; the current one is kept (see :meth:`restore`)."""
        self.controller.reset()

    @guarded
    def restore(self, attempt: int) -> None:
        """Bring back earlier attempt number ``attempt`` (1-based) as a new attempt."""
        self.controller.restore(attempt)

    @guarded
    def finish(self) -> None:
        """End the run and show the paper's score."""
        self.controller.finish()

    @guarded
    def load(self, path, name: str | None = None) -> None:
        """Load a file (:meth:`RunController.load
        <tutor.framework.controller.RunController.load>`); ``name`` is the file as the
        trainee knows it, for an upload."""
        self.controller.load(path, name)

    @guarded
    def try_again(self) -> None:
        """A read-only view tries once more to take its run's file (and reloads it)."""
        self.controller.try_again()

    def close(self) -> None:
        """Save and let go of the run's file (another tutor may then open it); this view
        is read-only afterwards."""
        self.controller.close()

    # ------------------------------------------------------------ shared widgets

    def _common_widgets(self) -> None:
        """Upload, attempts chooser and status line, wired to the controller."""
        self.upload = Upload(
            accept=".json,.csv",
            multiple=False,
            description="Load file",
            tooltip="Add demonstrations from a .json or .csv file, or open a saved run",
            layout=w.Layout(width="120px"),
        )
        self.upload.observe(on_upload(self.load, self.tell), names="value")
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

    @guarded
    def _on_bring_back(self) -> None:
        self.controller.bring_back(self.attempts.value)

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
        self.status.value = (
            f"<span class='lfd-status'>{html.escape(self.trainee.name)} &middot; "
            f"{self._file_state()}</span>"
        )

    def _file_state(self) -> str:
        """Where the run is saved, as the status line says it (HTML)."""
        if self.read_only and self.controller.lock_problem is not None:
            return "read-only (its file cannot be locked)"
        if self.read_only:
            return "read-only (open in another tutor)"
        if self.run_file is None:
            return "not saved to a file"
        if self.unsaved:
            return f"<b>not saved yet</b> to {html.escape(self.run_file.name)}"
        return f"saved to {html.escape(self.run_file.name)}"

    def message_html(self) -> str:
        if not self.message:
            return ""
        return f"<div class='lfd-message' role='status'>{html.escape(self.message)}</div>"

    def refresh(self) -> None:  # pragma: no cover - subclasses draw
        raise NotImplementedError

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
