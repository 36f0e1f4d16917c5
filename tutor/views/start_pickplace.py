"""Experiment 2's start form (pick-and-place): the condition, the hand, the class plan.

:func:`pick_and_place_experiment` makes a :class:`~tutor.views.start.StartForm` for runs
1, 2 and 3 in the chosen condition. The paper's four conditions come first, none chosen
until the trainee (or the educator) chooses; the conditions beyond the paper (AF,
adaptive feedback: the robot tries the 5 plants it picks itself, at BF's cost; HF, the
next-demo hint: nothing is shown, as in NF, but the tutor names the plant the robot would
learn most from next) follow, all as the registry lists them
(:mod:`tutor.framework.protocol`).

Experiment 2 is between subjects: the class analysis counts one condition per trainee.
When the trainee's folder already holds counted runs in another condition of it, Start
says so ("Ana already has runs in BF (2 finished); ... Start SF anyway?") and the run
starts only once the trainee confirms (the *Start anyway* button, or Start pressed
again with the same name and condition).

For an educator, from the environment of the notebook server:

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
"""

from __future__ import annotations

import html
from pathlib import Path

import ipywidgets as w

from ..errors import InvalidParameterError, InvalidPlanError, TutorError
from ..fileio import read_json
from ..framework.assignment import plan_from_env
from ..framework.protocol import run_file_name
from ..framework.record import RunRecord
from ..payloads import check_choice
from ..runtime import env_text, headless, runs_root, trainee_key
from ..tasks.pickplace_protocol import RUNS, PickPlaceRun
from .hand import HAND_SOURCES, HANDS, hand_and_source
from .start import HEADLESS_TRAINEE, StartForm
from .style import PROSE
from .worked_example import instruction_widget

__all__ = [
    "PickPlaceExperiment",
    "pick_and_place_experiment",
    "condition_from_env",
    "counted_runs",
    "PICKPLACE_AUTOPLAY",
]

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


def counted_runs(name: str, experiment: int = 2) -> dict[str, tuple[int, int]]:
    """The counted runs of ``name`` in ``experiment``, read from their folder.

    Every ``*.json`` file of the trainee's folder (:func:`tutor.runtime.runs_root`) that
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
    folder = runs_root() / key
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
        self.beyond_note = w.HTML(
            f'<div style="font-size: 90%; {PROSE}">{html.escape(design.beyond_note)}</div>'
        )
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
            self.add_note(self.carried_on)
        self.add_note(self.hand_line())

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
            run_file=path,
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
        stem = Path(tutor.run_file or run_file_name(2, tutor.condition, run)).stem
        saved = tutor.scene3d.save_html(self.folder / f"{stem}_3d.html")
        print(f"Saved {saved} ({saved.stat().st_size / 1e6:.1f} MB)")
        animation = tutor.scene3d.animation
        print(animation.label if animation else "Nothing animated yet.")
        return saved

    def results(self) -> str:
        from .pickplace_app import compare_runs

        if not self.finished:
            return self.not_yet()
        return compare_runs(self.tutors)


def _runs_said(runs: int, finished: int) -> str:
    """E.g. "2 finished", "1 begun" or "2 finished, 1 begun"."""
    parts = [f"{finished} finished"] if finished else []
    if runs > finished:
        parts.append(f"{runs - finished} begun")
    return ", ".join(parts)


def pick_and_place_experiment(start: bool | None = None, scene3d=True) -> PickPlaceExperiment:
    """The start form of Experiment 2 (pick-and-place): name, condition, practice, Start."""
    return PickPlaceExperiment(start=start, scene3d=scene3d)
