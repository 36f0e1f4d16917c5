"""The start forms: taking part in an experiment without editing any code.

A trainee types their name, (Experiment 2) picks the condition their educator gave them,
ticks *practice run* if they only want to try the tutor, and presses **Start**. The form
then shows the runs one after another, each beginning with its condition's short
instruction and worked example (:mod:`tutor.views.worked_example`):

- Experiment 1 (:func:`maze_experiment`): NF, then VF, then VR, the paper's order. Each
  run appears when the previous one is finished, so the NF run is taught before the
  trainee has ever seen what the robot learns (as in the paper); finished runs stay on
  the page, with what they revealed.
- Experiment 2 (:func:`tutor.views.start_pickplace.pick_and_place_experiment`): runs 1,
  2 and 3 in the chosen condition, one after another in the same way; its form (the
  condition, the hand, the class plan) is in :mod:`tutor.views.start_pickplace`.

When every run is finished the trainee's scores are shown beside the paper's.

Run files go to ``tutor.runtime.trainee_dir(name)``: ``NF.json``, ``VF.json``,
``VR.json`` and ``pickplace_<condition>_run<k>.json`` (practice runs get the prefix
``practice_``, so they never mix with the counted ones). A run file that exists is
resumed, so running the cell again after a restart carries on where the trainee was.

For an educator (e.g. a workshop), from the environment of the notebook server:

``TUTOR_TRAINEE``
    The trainee's name (see :func:`tutor.runtime.default_trainee`); the name field is
    then locked. Without it, ``JUPYTERHUB_USER`` is the default on a hub. Otherwise a
    trainee must type a name: a blank one is refused, so that the runs of everyone who
    leaves it blank never mix under one made-up name.
``TUTOR_CONDITION``, ``TUTOR_CLASS_PLAN``, ``TUTOR_HAND``
    Experiment 2's condition, class plan and hand: see :mod:`tutor.views.start_pickplace`.
``TUTOR_HEADLESS=1``
    Automated runs: the form starts itself and feeds the bundled demonstrations to every
    run (:meth:`StartForm.autoplay`), under the name set as above or else the one
    ``autoplay`` is given (:data:`HEADLESS_TRAINEE` by default).

Stable CSS classes for browser tests: ``lfd-start-form`` (the whole form),
``lfd-start-name``, ``lfd-start-condition``, ``lfd-start-condition-prompt`` (what it says
while none is chosen), ``lfd-start-hand`` (the guided-hand checkbox),
``lfd-start-practice``, ``lfd-start-go`` (the Start button),
``lfd-start-confirm`` (*Start anyway*, shown only while a warning waits for it),
``lfd-start-note`` and ``lfd-start-results``.
"""

from __future__ import annotations

import html
import unicodedata
from pathlib import Path

import ipywidgets as w

from ..errors import InvalidParameterError, TutorError
from ..framework.protocol import run_file_name
from ..payloads import check_text, safely
from ..runtime import (
    default_trainee,
    env_text,
    headless,
    normalise_name,
    trainee_dir,
    trainee_key,
)
from ..tasks.maze_run import PHASE_ORDER
from .style import prose
from .worked_example import instruction_widget

__all__ = [
    "StartForm",
    "MazeExperiment",
    "maze_experiment",
    "MAZE_AUTOPLAY",
    "HEADLESS_TRAINEE",
]

#: headless runs (TUTOR_HEADLESS=1): the name their runs are recorded under when none is
#: set (given to :meth:`StartForm.autoplay`; a person's blank name is refused instead)
HEADLESS_TRAINEE = "headless trainee"
#: what the form says when Start is pressed with a blank name and none is set
TYPE_A_NAME = (
    "Type your name first, then press Start: your runs are saved under it (a blank name "
    "is not used, so that your runs never mix with those of others who left it blank)."
)
#: headless runs: the bundled demonstration set fed to a maze phase, by whether its
#: condition shows the robot's attempts (a teacher who sees nothing leaves states
#: undemonstrated; one who sees them fills the gaps)
MAZE_AUTOPLAY = {"silent": "maze_undemonstrated", "shown": "maze_good"}

class StartForm:
    """Name, condition, practice and Start; then the experiment's runs one after another.

    Subclasses say which runs there are (:meth:`plan`), how to build one
    (:meth:`make_tutor`), what headless runs feed it (:meth:`autoplay_one`) and how the
    results read (:meth:`results`).

    Parameters
    ----------
    start : bool, optional
        Start at once (default: only in headless runs, ``TUTOR_HEADLESS=1``, which then
        also feed the bundled demonstrations to every run).

    Attributes
    ----------
    widget : ipywidgets.VBox
        The form and, below it, the runs.
    tutors : list
        The runs' tutors built so far, in order.
    trainee : str or None
        The name the runs are recorded under (None until Start).
    """

    experiment = 0
    title = ""

    def __init__(self, start: bool | None = None):
        self.tutors: list = []
        self.trainee: str | None = None
        self.folder: Path | None = None
        self.practice_run = False
        self.problem: str | None = None
        fixed_name = env_text("TUTOR_TRAINEE")
        self.name = w.Text(
            value=fixed_name,
            placeholder=default_trainee() or "your name, e.g. Mai Anh",
            description="Your name",
            disabled=bool(fixed_name),
            layout=w.Layout(width="320px"),
            # The name reaches the kernel when the field is left (the click on Start
            # leaves it first) or Enter is pressed, not at every keystroke: ipywidgets
            # holds back a model's updates while one is in flight and sends them when the
            # kernel is idle, but a button's click is sent at once, so a name typed fast
            # and followed by Start reached the kernel cut short ("voila-" for "voila-bf")
            # and the runs went to another trainee's folder.
            continuous_update=False,
        )
        self.name.add_class("lfd-start-name")
        self.practice = w.Checkbox(
            value=False,
            description="Practice run (you see everything; not counted in the class results)",
            indent=False,
            layout=w.Layout(width="520px"),
        )
        self.practice.add_class("lfd-start-practice")
        self.go = w.Button(description="Start", button_style="primary", icon="play")
        self.go.add_class("lfd-start-go")
        self.go.on_click(lambda _: self._safely(self.start))
        #: what the warning waiting for a confirmation was about (see :meth:`start`)
        self._confirming: tuple | None = None
        self.confirm = w.Button(
            description="Start anyway",
            button_style="warning",
            tooltip="Start although the note above warns you",
            layout=w.Layout(display="none"),
        )
        self.confirm.add_class("lfd-start-confirm")
        self.confirm.on_click(lambda _: self._safely(self.start))
        self.note = w.HTML()
        self._note_lines: list[str] = []  # the note's lines (HTML)
        self.note.add_class("lfd-start-note")
        self.results_box = w.Output()
        self.results_box.add_class("lfd-start-results")
        self.stage = w.VBox()
        self._name_note = (
            "Your name was set by your educator (TUTOR_TRAINEE)." if fixed_name else ""
        )
        self._extra_fields = self._condition_fields()
        self._show_notes()
        self.name.observe(lambda _: self._safely(self._name_changed), names="value")
        self.name.observe(lambda _: self._withdraw_warning(), names="value")
        self.practice.observe(lambda _: self._withdraw_warning(), names="value")
        form = w.VBox(
            [
                w.HTML(f"<b>{html.escape(self.title)}</b>"),
                self.name,
                *self._extra_fields,
                self.practice,
                w.HBox([self.go, self.confirm]),
                self.note,
            ]
        )
        self.widget = w.VBox([form, self.stage, self.results_box])
        self.widget.add_class("lfd-start-form")
        if start is None:
            start = headless()
        if start and headless():
            self.autoplay()
        elif start:
            self.start()

    # ---------------------------------------------------------------- the form

    def _condition_fields(self) -> list:
        """Extra widgets of the form (Experiment 2: the condition)."""
        return []

    def _notes(self) -> list[str]:
        """What the note under the form says before Start (one line each)."""
        return [self._name_note] if self._name_note else []

    def _show_notes(self) -> None:
        self._note_lines = [html.escape(n, quote=False) for n in self._notes()]
        self._render_note()

    def _render_note(self) -> None:
        self.note.value = prose("<br>".join(self._note_lines)) if self._note_lines else ""

    def add_note(self, text: str) -> None:
        """Add a line to what the note under the form says."""
        self._note_lines.append(html.escape(text, quote=False))
        self._render_note()

    def _name_changed(self) -> None:
        """The trainee typed in the name field (before Start: Experiment 2's plan follows)."""

    def typed_name(self) -> str:
        """The name the form would start with: the one typed, else the one set for the
        trainee (``TUTOR_TRAINEE``, or ``JUPYTERHUB_USER`` on a hub).

        Raises
        ------
        InvalidPayloadError
            The field's value, as the page sent it, is not text or is far too long.
        InvalidParameterError
            The field is blank and no name is set (:data:`TYPE_A_NAME`).
        """
        typed = check_text(self.name.value, "your name")
        if "".join(c for c in typed if unicodedata.category(c) != "Cf").strip():
            return typed  # not blank once invisible marks (zero-width spaces) are dropped
        fallback = default_trainee()
        if fallback is None:
            raise InvalidParameterError(TYPE_A_NAME)
        return fallback

    @property
    def condition(self) -> str | None:
        """The chosen condition (Experiment 2), None for Experiment 1."""
        return None

    def _lock_form(self) -> None:
        self._withdraw_warning()
        fields = [self.name, self.practice, self.go, self.confirm, *self._extra_fields]
        while fields:
            field = fields.pop()
            if field.has_trait("disabled"):  # (a note has nothing to lock)
                field.disabled = True
            elif field.has_trait("children"):  # a row of fields
                fields.extend(field.children)

    def _safely(self, action) -> None:
        """Run what a click or a keystroke asked for; an error is said in the form's note,
        never raised out of the widget's callback."""
        safely(action, lambda text: self._say(text, problem=True))

    def _say(self, text: str, problem: bool = False) -> None:
        self.problem = text if problem else None
        style = ' style="color:#b00020"' if problem else ""
        self._note_lines = [f"<span{style}>{html.escape(text, quote=False)}</span>"]
        self._render_note()

    def start(self) -> None:
        """What Start does: check the name, then show the first run that is not finished.

        A wrong name (blank with none set, control characters, too long) or condition is
        said in the form and nothing starts. A warning (:meth:`warning`, e.g. runs in
        another condition) is said and nothing starts either, until the trainee confirms:
        *Start anyway*, or Start pressed again with the same name, condition and practice.
        """
        if self.trainee is not None:
            return
        try:
            self.check_blocked()
            name = normalise_name(self.typed_name())
            self.check_ready(name)
            warning = None if self.practice.value else self.warning(name)
            asked = (trainee_key(name), self.condition, bool(self.practice.value), warning)
            if warning is not None and self._confirming != asked:
                self._say(warning, problem=True)
                self._confirming = asked
                self.confirm.layout.display = None
                return
            folder = trainee_dir(name)
        except TutorError as exc:
            self._say(str(exc), problem=True)
            return
        self.trainee, self.folder = name, folder
        self.practice_run = bool(self.practice.value)
        self._lock_form()
        what = "a practice run" if self.practice_run else "counted runs"
        self._say(
            f"Welcome, {name}. These are {what}; they are saved in {folder.resolve()} after "
            "every step, so you can close the notebook and carry on later."
        )
        self._advance()

    def check_blocked(self) -> None:
        """Raise a TutorError when the form cannot start whatever the name (Experiment 2:
        a wrong TUTOR_CONDITION or class plan, for the educator to fix): said before a
        missing name, so that the trainee is not asked to type one in vain."""

    def check_ready(self, name: str) -> None:
        """Raise a TutorError when the form cannot start for ``name`` (Experiment 2: no
        condition); may settle what the runs need (Experiment 2: the plan's condition)."""

    def warning(self, name: str) -> str | None:
        """What ``name`` must confirm before counted runs start, or None (Experiment 2:
        counted runs in another condition)."""
        return None

    def _withdraw_warning(self) -> None:
        """The name, condition or practice changed: a warning given before no longer
        stands (Start checks again), and its *Start anyway* goes."""
        if self._confirming is None:
            return
        self._confirming = None
        self.confirm.layout.display = "none"
        if self.trainee is None:
            self._show_notes()

    # ---------------------------------------------------------------- the runs

    def plan(self) -> list[dict]:
        """The runs in order: dicts with ``condition``, ``run`` and ``label``."""
        raise NotImplementedError

    def make_tutor(self, step: dict, path: Path):
        """The tutor of one run, saving to ``path``."""
        raise NotImplementedError

    @property
    def current(self):
        """The tutor being taught now (None before Start or when all are finished)."""
        if self.tutors and not self.tutors[-1].finished:
            return self.tutors[-1]
        return None

    @property
    def finished(self) -> bool:
        """True when every run of the experiment is finished."""
        return len(self.tutors) == len(self.plan()) and all(t.finished for t in self.tutors)

    def _advance(self) -> None:
        """Show the next run while the last one shown is finished (resumed runs may be)."""
        steps = self.plan()
        while len(self.tutors) < len(steps) and (not self.tutors or self.tutors[-1].finished):
            step = steps[len(self.tutors)]
            path = self.folder / run_file_name(
                self.experiment, step["condition"], step["run"], self.practice_run
            )
            tutor = self.make_tutor(step, path)
            self.tutors.append(tutor)
            for button in tutor.buttons.values():
                button.on_click(lambda _: self._safely(self._after_click))
            header = w.HTML(f"<h3>{html.escape(step['label'])}</h3>")
            intro = self.instruction(step)
            self.stage.children = (*self.stage.children, header, intro, tutor.widget)
        if self.finished:
            self._show_results()

    def instruction(self, step: dict):
        """The instruction and worked example shown above the run of ``step``."""
        return instruction_widget(self.experiment, step["condition"], self.practice_run)

    def _after_click(self) -> None:
        if self.tutors and self.tutors[-1].finished:
            self._advance()

    def _show_results(self) -> None:
        self.results_box.clear_output()
        with self.results_box:
            self.show_results()

    def show_results(self) -> None:
        """Display the trainee's scores beside the paper's (into the results area)."""
        print(self.results())

    def results(self) -> str:
        """The trainee's results beside the paper's, once every run is finished."""
        raise NotImplementedError

    def not_yet(self) -> str:
        """What the results say before every run is finished."""
        done = sum(t.finished for t in self.tutors)
        if self.trainee is None:
            return (
                "Not started yet: type your name above and press Start. Your results appear "
                "there when every run is finished (or run this cell again then)."
            )
        return (
            f"{done} of {len(self.plan())} runs are finished: finish them all, then run this "
            "cell again."
        )

    # ---------------------------------------------------------------- headless runs

    def autoplay(self, name: str = HEADLESS_TRAINEE) -> None:
        """Headless runs only (``TUTOR_HEADLESS=1``): feed each run its bundled demos.

        Starts the form first if needed: under the name typed or set for the trainee,
        else under ``name``, which the field then shows. Does nothing when a person runs
        the notebook, and skips runs that are already finished.
        """
        if not headless():
            return
        if self.trainee is None and not self.name.value.strip() and default_trainee() is None:
            self.name.value = name
        self.start()
        if self.trainee is None:  # the form refused to start and says why
            raise InvalidParameterError(self.problem or "the form did not start")
        while self.current is not None:
            tutor = self.current
            self.autoplay_one(tutor)
            if not tutor.finished:
                raise InvalidParameterError(
                    f"the bundled demonstrations did not finish the {tutor.condition} run: "
                    f"{tutor.message}"
                )
            self._advance()

    def autoplay_one(self, tutor) -> None:
        raise NotImplementedError

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


class MazeExperiment(StartForm):
    """Experiment 1 for one trainee: NF, VF, VR (see the module docstring)."""

    experiment = 1
    title = "Experiment 1: teach the robot the maze, three times"

    def plan(self) -> list[dict]:
        return [
            {"condition": c, "run": 1, "label": f"Run {k} of 3 · {c}"}
            for k, c in enumerate(PHASE_ORDER, start=1)
        ]

    def make_tutor(self, step: dict, path: Path):
        from .maze_app import MazeTutor

        return MazeTutor(
            step["condition"], run_file=path, trainee=self.trainee, practice=self.practice_run
        )

    def autoplay_one(self, tutor) -> None:
        from ..demofiles import bundled_demos

        silent = tutor.run.protocol_condition.policy.silent
        tutor.autoplay(bundled_demos(MAZE_AUTOPLAY["silent" if silent else "shown"]))

    def show_results(self) -> None:
        import matplotlib.pyplot as plt
        from IPython.display import display

        from .maze_app import plot_runs

        fig, ax = plt.subplots(figsize=(5, 3.5))
        plot_runs(self.tutors, ax=ax)
        display(fig)
        plt.close(fig)
        print(self.results())

    def results(self) -> str:
        from .maze_app import compare_runs

        if not self.finished:
            return self.not_yet()
        return compare_runs(self.tutors)


def maze_experiment(start: bool | None = None) -> MazeExperiment:
    """The start form of Experiment 1 (the maze): name, practice, Start; then NF, VF, VR."""
    return MazeExperiment(start=start)
