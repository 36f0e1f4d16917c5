"""The start forms: taking part in an experiment without editing any code.

A trainee types their name, (Experiment 2) picks the condition their educator gave them,
ticks *practice run* if they only want to try the tutor, and presses **Start**. The form
then shows the runs one after another, each beginning with its condition's short
instruction and worked example (:mod:`tutor.views.worked_example`):

- Experiment 1 (:func:`maze_experiment`): NF, then VF, then VR, the paper's order. Each
  run appears when the previous one is finished, so the NF run is taught before the
  trainee has ever seen what the robot learns (as in the paper); finished runs stay on
  the page, with what they revealed.
- Experiment 2 (:func:`pick_and_place_experiment`): runs 1, 2 and 3 in the chosen
  condition, one after another in the same way. The paper's four conditions come first,
  none chosen until the trainee (or the educator) chooses; AF, adaptive feedback, and
  HF, the next-demo hint, are offered
  after them as extra conditions *beyond the paper* (AF: the robot tries the 5 plants
  it picks itself, at BF's cost, :mod:`tutor.framework.selectors`; HF: nothing is shown,
  as in NF, but the tutor names the plant the robot would learn most from next,
  :mod:`tutor.tasks.hint`).

When every run is finished the trainee's scores are shown beside the paper's.

Experiment 2 is between subjects: the class analysis counts one condition per trainee.
When the trainee's folder already holds counted runs in another condition of it, Start
says so ("Ana already has runs in BF (2 finished); ... Start SF anyway?") and the run
starts only once the trainee confirms (the *Start anyway* button, or Start pressed
again with the same name and condition).

Run files go to ``tutor.runtime.session_dir(name)``: ``NF.json``, ``VF.json``,
``VR.json`` and ``pickplace_<condition>_run<k>.json`` (practice runs get the prefix
``practice_``, so they never mix with the counted ones). A run file that exists is
resumed, so running the cell again after a restart carries on where the trainee was.

For an educator (e.g. a workshop), from the environment of the notebook server:

``TUTOR_TRAINEE``
    The trainee's name (see :func:`tutor.runtime.default_trainee`); the name field is
    then locked. Without it, ``JUPYTERHUB_USER`` is the default on a hub. Otherwise a
    trainee must type a name: a blank one is refused, so that the runs of everyone who
    leaves it blank never mix under one made-up name.
``TUTOR_CONDITION``
    Experiment 2's condition (NF, RF, BF or SF; or AF or HF, beyond the paper) for everyone
    on this server; the
    condition buttons are then locked and say why. A value that is not a condition is
    refused with a message. It wins over the class plan.
``TUTOR_CLASS_PLAN``
    A class plan file (CSV or JSON, :mod:`tutor.framework.assignment`) saying which
    trainee teaches in which condition, or "balanced". The condition buttons then show
    the condition of the name in the form (it follows the name once typed: Tab, Enter or
    a click elsewhere), are
    locked, and the note says why ("your educator's class plan assigns you RF"). If the
    trainee's folder already holds counted runs in another condition (the roster changed
    after they started), they carry on in that condition and the note says so. A plan
    that cannot be used is said in the form, and Start waits for the educator to fix it.
``TUTOR_HAND``
    Who moves the arm in Experiment 2 (:mod:`tutor.views.hand`): ``own`` (the default),
    the trainee guides it themself, or ``guided``, the tutor guides it for them. A class
    plan's ``hand`` column wins over it for the trainees it sets; for the others the form
    offers a checkbox, *The tutor guides the arm for me*, ticked when ``TUTOR_HAND`` is
    ``guided``, which the trainee may change. A value that is not a hand is refused with
    a message, and Start waits for the educator to fix it.
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

from ..errors import InvalidParameterError, InvalidPlanError, TutorError
from ..fileio import read_json
from ..framework.assignment import plan_from_env
from ..framework.record import RunRecord
from ..runtime import (
    default_trainee,
    env_text,
    headless,
    normalise_name,
    session_dir,
    sessions_root,
    trainee_key,
)
from ..tasks.maze_run import PHASE_ORDER
from ..tasks.pickplace_protocol import RUNS, PickPlaceRun
from .hand import HAND_SOURCES, HANDS, hand_and_source
from .payloads import check_choice, check_text, safely
from .worked_example import instruction_widget

__all__ = [
    "StartForm",
    "MazeExperiment",
    "PickPlaceExperiment",
    "maze_experiment",
    "pick_and_place_experiment",
    "condition_from_env",
    "run_file_name",
    "counted_runs",
    "MAZE_AUTOPLAY",
    "HEADLESS_TRAINEE",
    "PICKPLACE_AUTOPLAY",
]

#: headless runs (TUTOR_HEADLESS=1): the name their runs are recorded under when none is
#: set (given to :meth:`StartForm.autoplay`; a person's blank name is refused instead)
HEADLESS_TRAINEE = "headless trainee"
#: what the form says when Start is pressed with a blank name and none is set
TYPE_A_NAME = (
    "Type your name first, then press Start: your runs are saved under it (a blank name "
    "is not used, so that your runs never mix with those of others who left it blank)."
)
#: headless runs: the bundled demonstration set fed to each maze phase
MAZE_AUTOPLAY = {"NF": "maze_undemonstrated", "VF": "maze_good", "VR": "maze_good"}
#: headless runs: the plants (and deliberate mistakes) demonstrated in each run
PICKPLACE_AUTOPLAY = {
    1: ([44, 0, 99, 9, 90, 22, 77], {3: "wrong_plant"}),
    2: ([0, 99, 9, 90, 44], {}),
    3: ([0, 99, 90, 9], {}),
}
#: headless runs only: the condition autoplay chooses when nobody else did (a person
#: always chooses: the form preselects none)
HEADLESS_CONDITION = "BF"
#: what the condition chooser says while no condition is chosen
CHOOSE_CONDITION = "Choose your condition"
#: what Start says when pressed before a condition is chosen
NO_CONDITION = "Choose your condition first (the one your educator gave you), then press Start."
#: the start form's checkbox for the guided hand, and the hand each of its values asks for
GUIDED_CHECKBOX = "The tutor guides the arm for me (if you cannot use a mouse or keyboard)"
CHECKBOX_HANDS = {True: "guided", False: "own"}
def condition_from_env() -> str | None:
    """Experiment 2's condition set by the educator in ``TUTOR_CONDITION``, or None.

    Raises
    ------
    InvalidParameterError
        ``TUTOR_CONDITION`` is set but is not one of NF, RF, BF, SF (or AF or HF, beyond
        the paper).
    """
    value = env_text("TUTOR_CONDITION")
    if not value:
        return None
    design = PickPlaceRun.protocol()
    if value.upper() not in design.codes:
        raise InvalidParameterError(
            f"TUTOR_CONDITION is {value!r}, which is not a condition of Experiment 2: set it "
            f"to one of {', '.join(design.paper_codes)} (or {', '.join(design.extra_codes)}, "
            "beyond the paper; or unset it to let trainees choose)."
        )
    return value.upper()


def run_file_name(experiment: int, condition: str, run: int = 1, practice: bool = False) -> str:
    """The file name of a run in the trainee's folder, e.g. ``VF.json``."""
    stem = condition if experiment == 1 else f"pickplace_{condition}_run{run}"
    return f"{'practice_' if practice else ''}{stem}.json"


def counted_runs(name: str, experiment: int = 2) -> dict[str, tuple[int, int]]:
    """The counted runs of ``name`` in ``experiment``, read from their folder.

    Every ``*.json`` file of the trainee's folder (:func:`tutor.runtime.sessions_root`) that
    reads as a :class:`~tutor.framework.RunRecord` of this experiment, of this trainee and
    not a practice run counts, as the class analysis counts it. A file that cannot be read
    is not counted here (the class analysis lists it with the reason).

    Returns
    -------
    dict
        condition -> (runs, finished runs), in the order the conditions were first found
        (files by name).
    """
    key = trainee_key(name)
    folder = sessions_root() / key
    found: dict[str, tuple[int, int]] = {}
    if not folder.is_dir():
        return found
    for path in sorted(folder.glob("*.json")):
        if path.is_symlink() or not path.is_file():
            continue  # a link may point anywhere: the class analysis does not count it
        try:
            record = RunRecord.from_dict(read_json(path, "run file"))
        except TutorError:
            continue
        if record.experiment != experiment or record.practice or record.trainee.key != key:
            continue
        runs, finished = found.get(record.condition, (0, 0))
        found[record.condition] = (runs + 1, finished + int(record.finished))
    return found


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
        self.note.value = "<br>".join(html.escape(n, quote=False) for n in self._notes())

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
        self.note.value = f"<span{style}>{html.escape(text, quote=False)}</span>"

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
            folder = session_dir(name)
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
            step["condition"], session_file=path, trainee=self.trainee, practice=self.practice_run
        )

    def autoplay_one(self, tutor) -> None:
        from ..demofiles import bundled_demos

        tutor.autoplay(bundled_demos(MAZE_AUTOPLAY[tutor.condition]))

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
            return _not_yet(self)
        return compare_runs(self.tutors)


class PickPlaceExperiment(StartForm):
    """Experiment 2 for one trainee: three runs in one condition (see the module docstring).

    Parameters
    ----------
    start : bool, optional
    scene3d : bool or {"auto", "live", "static"}
        Show the robot in 3-D under each run (:class:`tutor.views.scene3d.Scene3D`, in
        this mode; True is "auto"); False: no 3-D view.
    """

    experiment = 2
    title = "Experiment 2: teach the robot arm to pick and place, three times"

    def __init__(self, start: bool | None = None, scene3d=True):
        if scene3d not in (True, False, "auto", "live", "static"):
            raise InvalidParameterError(
                f"scene3d must be True, False or a Scene3D mode ('auto', 'live', 'static'), "
                f"got {scene3d!r}"
            )
        self.scene3d = "auto" if scene3d is True else scene3d
        self._fixed_condition = None
        self._condition_problem = None
        #: the class plan (``TUTOR_CLASS_PLAN``), when one is set and TUTOR_CONDITION is not
        self.class_plan = None
        #: the plan's assignment of the name in the form (None without a plan)
        self.assignment = None
        self.carried_on = None
        self._task = None
        #: the hand the runs use once started (see :attr:`hand`)
        self.started_hand: str | None = None
        super().__init__(start)

    def _condition_fields(self) -> list:
        design = PickPlaceRun.protocol()
        try:
            self._fixed_condition = condition_from_env()
        except InvalidParameterError as exc:
            self._condition_problem = f"{exc} Ask your educator."
        if self._fixed_condition is None and self._condition_problem is None:
            try:
                self.class_plan = plan_from_env(design.paper_codes, hands=HANDS)
            except InvalidPlanError as exc:
                text = str(exc)
                self._condition_problem = f"{text[:1].upper()}{text[1:]} Ask your educator."
        locked = self._fixed_condition is not None or self.class_plan is not None
        self.condition_buttons = w.ToggleButtons(
            options=design.codes,  # the paper's four first
            value=self._fixed_condition,  # None: nothing is preselected
            description="Condition",
            tooltips=[c.tip for c in design.conditions],
            style={"button_width": "56px"},
            disabled=locked,
        )
        self.condition_buttons.add_class("lfd-start-condition")
        self.condition_prompt = w.HTML()
        self.condition_prompt.add_class("lfd-start-condition-prompt")
        self.condition_buttons.observe(lambda _: self._condition_changed(), names="value")
        self.beyond_note = w.HTML(f"<small>{html.escape(design.beyond_note)}</small>")
        self.beyond_note.add_class("lfd-start-beyond")
        self.guided_box = self._hand_field()
        self._follow_plan()
        self._condition_changed()
        return [
            w.HBox([self.condition_buttons, self.condition_prompt]),
            self.beyond_note,
            self.guided_box,
        ]

    # ---------------------------------------------------------------- the hand

    def _hand_field(self) -> w.Checkbox:
        """The guided-hand checkbox, ticked as ``TUTOR_HAND`` (or the default) says."""
        self._hand_problem = None
        try:
            self._unasked_hand = hand_and_source()[0]
        except InvalidParameterError as exc:
            self._hand_problem = f"{exc} Ask your educator."
            self._unasked_hand = hand_and_source(explicit=CHECKBOX_HANDS[False])[0]
        box = w.Checkbox(
            value=next(v for v, code in CHECKBOX_HANDS.items() if code == self._unasked_hand),
            description=GUIDED_CHECKBOX,
            indent=False,
            layout=w.Layout(width="560px"),
        )
        box.add_class("lfd-start-hand")
        if not self.scene3d:  # no 3-D view to guide in: the tutor guides the arm
            box.layout.display = "none"
        box.observe(lambda _: self._withdraw_warning(), names="value")
        return box

    def _plan_hand(self) -> str | None:
        """The hand the class plan sets for the name in the form (None: it sets none)."""
        return None if self.assignment is None else self.assignment.hand

    def _hand_choice(self) -> tuple[str, str]:
        """(hand, source) the runs would use: the plan's, else the checkbox's when the
        trainee changed it, else ``TUTOR_HAND`` or the default."""
        if not self.scene3d:  # made with scene3d=False: there is nothing to guide in
            return "guided", "no-view"
        ticked = CHECKBOX_HANDS[bool(self.guided_box.value)]
        explicit = None if ticked == self._unasked_hand else ticked
        plan_hand = self._plan_hand()
        return hand_and_source(plan_hand, None if plan_hand else explicit)

    @property
    def hand(self) -> str:
        """The hand the runs use (:mod:`tutor.views.hand`): once started, the one they
        started with; before, the one Start would choose."""
        if self.started_hand is not None:
            return self.started_hand
        return self._hand_choice()[0]

    def _asked_hand(self) -> str | None:
        """The hand passed to each run's tutor: the one the trainee or the plan chose;
        None leaves it to the tutor (``TUTOR_HAND``, else the default, as here)."""
        code, source = self._hand_choice()
        return code if source in ("explicit", "plan", "no-view") else None

    def hand_line(self) -> str:
        """The summary's sentence about the hand, e.g. "The tutor guides the arm for you
        (your educator's class plan sets it)."."""
        code, source = self._hand_choice()
        if self.started_hand is not None:
            code = self.started_hand
        return f"{HANDS[code].label} ({HAND_SOURCES[source]})."

    def _show_hand_field(self) -> None:
        """The checkbox shows only while the plan does not set the hand."""
        hidden = self._plan_hand() or not self.scene3d
        self.guided_box.layout.display = "none" if hidden else None

    def _condition_changed(self) -> None:
        """Say "Choose your condition" beside the buttons while none is chosen."""
        chosen = self.condition_buttons.value is not None
        self.condition_prompt.value = "" if chosen else f"<i>{CHOOSE_CONDITION}</i>"
        self._withdraw_warning()

    def _follow_plan(self) -> None:
        """Show the class plan's condition for the name in the form (before Start)."""
        if self.class_plan is None or self.trainee is not None:
            return
        try:
            self.assignment = self.class_plan.assign(self.typed_name())
        except TutorError:  # a name the form will refuse at Start, and say why
            self.assignment = None
            self.condition_buttons.value = None
            self._show_hand_field()
            return
        self.condition_buttons.value = self.assignment.condition
        self._show_hand_field()

    def _name_changed(self) -> None:
        if self.class_plan is not None and self.trainee is None:
            self._follow_plan()
            self._show_notes()

    def _notes(self) -> list[str]:
        notes = super()._notes()
        if self._condition_problem is not None:
            notes.append(self._condition_problem)
        elif self._fixed_condition is not None:
            notes.append(
                f"Your condition, {self._fixed_condition}, was set by your educator "
                "(TUTOR_CONDITION)."
            )
        elif self.class_plan is not None:
            if self.assignment is None:
                notes.append(
                    "Type your name: your educator's class plan then gives your condition."
                )
            else:
                reason = self.assignment.reason
                notes.append(f"{reason[0].upper()}{reason[1:]} (for {self.assignment.trainee}).")
        else:
            notes.append("Choose the condition your educator gave you.")
        if self._hand_problem is not None:
            notes.append(self._hand_problem)
        elif self._plan_hand() or self._hand_choice()[1] == "env":
            notes.append(f"Who moves the arm: {self.hand_line()}")
        return notes

    @property
    def condition(self) -> str | None:
        """The condition chosen (or set by the educator or the plan); None while none is."""
        return self.condition_buttons.value

    def check_blocked(self) -> None:
        for problem in (self._condition_problem, self._hand_problem):
            if problem is not None:
                raise InvalidParameterError(problem)

    def check_ready(self, name: str) -> None:
        if self.class_plan is None:
            if self.condition is None:
                raise InvalidParameterError(NO_CONDITION)
            check_choice(self.condition, "the condition", tuple(self.condition_buttons.options))
            return
        self.assignment = self.class_plan.assign(name)
        condition = self.assignment.condition
        if not self.practice.value:
            started = self.started_conditions(name)
            if started and condition not in started:
                condition = started[0]
                self.carried_on = (
                    f"Your folder already holds runs in {condition}, so you carry on in "
                    f"{condition}; your educator's class plan now assigns you "
                    f"{self.assignment.condition} (was the plan changed?): tell your educator."
                )
        self.condition_buttons.value = condition

    def started_conditions(self, name: str) -> list[str]:
        """The conditions in which ``name``'s folder holds counted (not practice) runs, in
        the experiment's order (:mod:`tutor.framework.protocol`)."""
        found = counted_runs(name, self.experiment)
        return [c for c in PickPlaceRun.protocol().codes if c in found]

    def warning(self, name: str) -> str | None:
        """Counted runs of ``name`` in another condition than the one chosen: the class
        analysis counts one condition per trainee, so the trainee must confirm."""
        found = counted_runs(name, self.experiment)
        codes = PickPlaceRun.protocol().codes
        others = [c for c in codes if c in found and c != self.condition]
        if not others:
            return None
        held = " and ".join(f"{c} ({_runs_said(*found[c])})" for c in others)
        how = "" if self.condition_buttons.disabled else f"; else choose {others[0]}"
        return (
            f"{name} already has runs in {held}; the class analysis counts one condition "
            f"per trainee. Start {self.condition} anyway? If so, press Start anyway (or "
            f"Start again){how}."
        )

    def autoplay(self, name: str = HEADLESS_TRAINEE) -> None:
        """Headless runs only: as :meth:`StartForm.autoplay`, in
        :data:`HEADLESS_CONDITION` when nobody chose a condition."""
        if headless() and self.trainee is None and self.condition is None:
            if self.class_plan is None and not self.condition_buttons.disabled:
                self.condition_buttons.value = HEADLESS_CONDITION
        super().autoplay(name)

    def start(self) -> None:
        if self.trainee is not None:
            return
        self.carried_on = None
        super().start()
        if self.trainee is None:
            return
        if self.carried_on:
            self.note.value += f"<br>{html.escape(self.carried_on, quote=False)}"
        self.note.value += f"<br>{html.escape(self.hand_line(), quote=False)}"

    def _lock_form(self) -> None:
        # settled before the first run is made, so that a later change asks for nothing
        self.started_hand, self._started_ask = self._hand_choice()[0], self._asked_hand()
        super()._lock_form()

    def plan(self) -> list[dict]:
        c = self.condition
        return [
            {"condition": c, "run": k, "label": f"Run {k} of {RUNS} · {c}"}
            for k in range(1, RUNS + 1)
        ]

    def instruction(self, step: dict):
        """The instruction, the worked example and the "Try the controls" step (before the
        first run, and in a practice run, with time to try them)."""
        return instruction_widget(
            self.experiment, step["condition"], self.practice_run, self.hand, step["run"] == 1
        )

    def make_tutor(self, step: dict, path: Path):
        from .pickplace_app import PickPlaceTutor

        scene = task = None
        if self.scene3d:
            from .scene3d import Scene3D

            scene = Scene3D(task=self._task, mode=self.scene3d)
            task = scene.task
        tutor = PickPlaceTutor(
            step["condition"],
            session_file=path,
            task=task if task is not None else self._task,
            trainee=self.trainee,
            run=step["run"],
            seed=step["run"],
            scene3d=scene,
            practice=self.practice_run,
            hand=self._started_ask,
        )
        self._task = tutor.task  # one task (and its arm) for all three runs
        return tutor

    def autoplay_one(self, tutor) -> None:
        plants, mistakes = PICKPLACE_AUTOPLAY[tutor.record.run]
        tutor.autoplay(plants, mistakes=mistakes)

    def save_scene(self, run: int = 1) -> Path | None:
        """Write run ``run``'s 3-D view as one HTML page beside the run file; prints where.

        Returns the path, or None (and says why) when that run has no 3-D view yet.
        """
        if not (isinstance(run, int) and 1 <= run <= len(self.tutors)):
            print(f"Run {run} has not started yet: press Start and teach it first.")
            return None
        tutor = self.tutors[run - 1]
        if tutor.scene3d is None:
            print(f"Run {run} has no 3-D view (the experiment was made with scene3d=False).")
            return None
        stem = Path(tutor.session_file or run_file_name(2, tutor.condition, run)).stem
        saved = tutor.scene3d.save_html(self.folder / f"{stem}_3d.html")
        print(f"Saved {saved} ({saved.stat().st_size / 1e6:.1f} MB)")
        animation = tutor.scene3d.animation
        print(animation.label if animation else "Nothing animated yet.")
        return saved

    def results(self) -> str:
        from .pickplace_app import compare_runs

        if not self.finished:
            return _not_yet(self)
        return compare_runs(self.tutors)


def _runs_said(runs: int, finished: int) -> str:
    """E.g. "2 finished", "1 begun" or "2 finished, 1 begun"."""
    parts = [f"{finished} finished"] if finished else []
    if runs > finished:
        parts.append(f"{runs - finished} begun")
    return ", ".join(parts)


def _not_yet(form: StartForm) -> str:
    done = sum(t.finished for t in form.tutors)
    if form.trainee is None:
        return (
            "Not started yet: type your name above and press Start. Your results appear "
            "there when every run is finished (or run this cell again then)."
        )
    return (
        f"{done} of {len(form.plan())} runs are finished: finish them all, then run this "
        "cell again."
    )


def maze_experiment(start: bool | None = None) -> MazeExperiment:
    """The start form of Experiment 1 (the maze): name, practice, Start; then NF, VF, VR."""
    return MazeExperiment(start=start)


def pick_and_place_experiment(start: bool | None = None, scene3d=True) -> PickPlaceExperiment:
    """The start form of Experiment 2 (pick-and-place): name, condition, practice, Start."""
    return PickPlaceExperiment(start=start, scene3d=scene3d)
