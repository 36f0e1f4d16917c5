"""The interactive pick-and-place tutor: one teaching run of Experiment 2.

The trainee clicks a plant on the tray map, then demonstrates the pick and place in one
of two ways (the *hand*, :mod:`tutor.views.hand`):

- **their own hand** (the default): *Guide the arm* arms a handle on the gripper in the
  3-D view; the trainee drags it (or uses the keys or a gamepad) to the plant, closes the
  hand, carries the plant to the bin, opens the hand and presses Enter. The arm follows
  the handle through the task's inverse kinematics (:class:`tutor.robot.follow.HandFollower`)
  and the page sends the whole recording once, at the end
  (:meth:`tutor.views.scene3d.Scene3D.start_guide`). The plant selected before guiding
  is the plant meant; a grab elsewhere is the trainee's own demonstration error. Its real
  duration and the set-up time count on the clock.
- **the tutor guides the arm for you**: *Demonstrate* has the tutor move the arm there as
  a person guiding it by hand would (:mod:`tutor.tasks.kinesthetic`), optionally with a
  mistake, to see what it does. For trainees who cannot use a pointer, for simulated
  teachers, and where an educator chooses it (``TUTOR_HAND=guided`` or the class plan).

What the robot then shows depends on the condition (NF, RF, BF, SF; and, beyond the
paper, AF, whose picks the tray map shows as it shows BF's batch, and HF, NF with a
next-demo hint; see :mod:`tutor.tasks.pickplace_protocol`), and the clock counts the
teaching time the paper's trainees had (15 minutes; 25 s per robot attempt).

The tray map (:mod:`tutor.views.tray`) colours the plants as in the paper's
good-versus-bad figure; HF marks the hinted plant ★, and the hint is also said in words.
Loading a file, undo, reset, bring back, finish, the run's file and its lock, and the
message are the run controller's (:class:`tutor.framework.controller.RunController`);
which plant a loaded demo is for is :mod:`tutor.views.pickplace_files`'.
"""

from __future__ import annotations

import contextlib
import html
import logging
import time

import ipywidgets as w
import numpy as np

from ..errors import InvalidParameterError, TutorError
from ..framework.wording import percent, plural
from ..paper import PAPER_MEAN_ETA, PAPER_THIRD_RUN_ETA
from ..payloads import check_choice
from ..robot.follow import HandFollower
from ..runtime import headless
from ..tasks.pickplace import PickPlaceTask
from ..tasks.pickplace_protocol import PickPlaceRun
from ..tasks.recording import steady_hand
from .app import TutorApp, guarded
from .hand import HANDS, choose_hand, controls_html
from .pickplace_files import plant_items
from .style import prose
from .text import compose, finish_summary, hint_sentence, optimal_sentence
from .tray import STATUS_WORDS, TrayMap, set_trait, tray_status

__all__ = [
    "PickPlaceTutor",
    "tray_status",
    "compare_runs",
    "paper_condition",
    "STATUS_WORDS",
    "PAPER_MEAN_ETA",
    "PAPER_THIRD_RUN_ETA",
]

log = logging.getLogger(__name__)

#: a click that arrives this soon after a demo ended is the second half of a double click
DOUBLE_CLICK_SECONDS = 0.4
#: the own hand's button, and its label while guiding
GUIDE, CANCEL_GUIDE = "Guide the arm", "Cancel guiding"
#: seconds a scripted (headless) trainee takes to set up before the first move
SCRIPTED_SETUP_SECONDS = 2.0
MISTAKES = {"no mistake": None, "wrong plant": "wrong_plant", "sloppy grab": "sloppy_grab"}


class PickPlaceTutor(TutorApp):
    """Tray map, controls, clock and panel for one run (the 3-D view is optional).

    Parameters
    ----------
    condition : {"NF", "RF", "BF", "SF", "AF", "HF"}
    run_file : path, optional
        Autosave after every demonstration; an existing file of the same run is resumed.
    task : PickPlaceTask, optional
    scene3d : object with ``update(run, status)``, optional
        A 3-D view (e.g. :class:`tutor.views.scene3d.Scene3D`) refreshed after each step.
    seed : int, optional
        Seed of the simulated hand's variability.
    trainee : str, optional
        The trainee's name (default ``JUPYTERHUB_USER`` on a hub, else "trainee").
    run : int
        Which of the trainee's three runs this is (1, 2 or 3).
    practice : bool
        Mark the run as practice (the class analysis leaves it out).
    hand : {"own", "guided"}, optional
        How the trainee demonstrates (:func:`tutor.views.hand.choose_hand`: this, else
        ``TUTOR_HAND``, else their own hand). The own hand needs a 3-D view that can be
        guided (``scene3d`` with ``start_guide``); without one the tutor guides the arm,
        and says so.

    Examples
    --------
    >>> from tutor.views.pickplace_app import PickPlaceTutor
    >>> tutor = PickPlaceTutor("BF", hand="guided", seed=0)
    >>> tutor.select(44); tutor.demonstrate()
    >>> tutor.run.n_demos
    1
    """

    demo_columns = ("t", "x", "y", "z", "g")
    undo_note = "Took back the latest demonstration (its time stays used; it stays in the history)."
    load_items = staticmethod(plant_items)

    def __init__(
        self,
        condition="BF",
        run_file=None,
        task=None,
        scene3d=None,
        seed=None,
        trainee=None,
        run: int = 1,
        practice: bool = False,
        hand: str | None = None,
    ):
        task = PickPlaceTask() if task is None else task
        super().__init__(PickPlaceRun, condition, task, run_file, trainee, run, practice)
        self.scene3d = scene3d
        self.hand, hand_note = self._hand_for(hand, scene3d)
        self._guide_plant: int | None = None  # the plant meant while the trainee guides
        self._follower: HandFollower | None = None
        self.rng = np.random.default_rng(seed)
        self.selected = 44
        self.tray_map = TrayMap(self.task, on_select=self.select)
        self.plant_buttons = self.tray_map.buttons
        self.tray = self.tray_map.grid
        self.mistake = w.Dropdown(
            options=list(MISTAKES),
            value="no mistake",
            description="Mistake",  # the select's accessible name (axe: select-name)
            style={"description_width": "initial"},
            layout=w.Layout(width="190px"),
        )
        self.buttons = {
            name: w.Button(description=name, layout=w.Layout(width="120px"))
            for name in (GUIDE, "Demonstrate", "Test plant", "Undo", "Finish run", "Reset")
        }
        self.buttons[GUIDE].layout.width = "150px"
        self.buttons[GUIDE].icon = "hand-paper-o"
        self.buttons[GUIDE].add_class("lfd-guide-button")
        self.buttons[GUIDE].tooltip = "Guide the arm yourself in the 3-D view (Enter ends)"
        self.buttons[GUIDE].on_click(lambda _: self.guide())
        self.buttons["Demonstrate"].tooltip = "The tutor guides the arm to the selected plant"
        self.buttons["Reset"].tooltip = "Start a new attempt (asks to confirm; nothing is deleted)"
        self._demo_ended = -1e9
        self.buttons["Demonstrate"].on_click(lambda _: self._on_demonstrate())
        self.buttons["Test plant"].on_click(lambda _: self.test())
        self.buttons["Undo"].on_click(lambda _: self.undo())
        self.buttons["Finish run"].on_click(lambda _: self.finish())
        self.buttons["Reset"].on_click(lambda _: self.request_reset())
        self._common_widgets()
        self.clock = w.HTML()
        self.panel = w.HTML(layout=w.Layout(width="420px"))
        self.how = w.HTML(controls_html(self.hand))
        self.how.add_class("lfd-controls")
        self.demo_row = w.HBox(self._demo_controls())
        controls = w.VBox(
            [
                self.demo_row,
                self.how,
                w.HBox(
                    [
                        self.buttons["Test plant"],
                        self.buttons["Undo"],
                        self.buttons["Finish run"],
                        self.buttons["Reset"],
                    ]
                ),
                w.HBox([self.attempts, self.bring_back, self.retry]),
                self.clock,
                self.panel,
                self.status,
            ]
        )
        self.widget = w.HBox(
            [
                w.VBox(
                    [
                        w.HTML(
                            "<b>Tray</b>, seen as in the 3-D view: the robot stands behind "
                            "row 1, at the top"
                        ),
                        self.tray,
                    ],
                    # the map keeps its width (11 cells of 28 px and their gaps): squeezed by
                    # the controls beside it, it hid columns 9 and 10 behind them
                    layout=w.Layout(flex="0 0 auto", width=f"{self.tray_map.width_px + 8}px"),
                ),
                controls,
            ]
        )
        view3d = getattr(scene3d, "widget", None)
        if view3d is not None:  # the 3-D view under the tray map and the controls
            self.widget = w.VBox([self.widget, view3d])
        self.widget.add_class("lfd-pickplace-tutor")
        if hand_note:
            self.controller.say(hand_note)
        self.refresh()

    # ---------------------------------------------------------------- the hand

    @staticmethod
    def _hand_for(hand, scene3d) -> tuple[str, str]:
        """The hand this tutor uses, and a note when it cannot be the one asked for."""
        code = choose_hand(explicit=hand)
        if HANDS[code].trainee_moves and not callable(getattr(scene3d, "start_guide", None)):
            note = (
                ""
                if hand is None and scene3d is None  # a tray-only tutor: nothing to guide in
                else "This tutor has no 3-D view to guide the arm in, so the tutor guides "
                "the arm for you: click a plant, then Demonstrate."
            )
            return "guided", note
        return code, ""

    def _demo_controls(self) -> list:
        """The row that gives a demonstration: the hand's own controls, then Upload."""
        if HANDS[self.hand].mistake_menu:
            return [self.buttons["Demonstrate"], self.mistake, self.upload]
        return [self.buttons[GUIDE], self.upload]

    @property
    def guiding(self) -> bool:
        """Whether the trainee is guiding the arm right now (between Guide and Enter)."""
        return self._guide_plant is not None

    @guarded
    def guide(self) -> None:
        """Start guiding the arm to the selected plant (own hand); pressed again, cancel.

        The 3-D view arms its handle; the demonstration arrives when the trainee presses
        Enter there (:meth:`_guided`), as the whole recording.
        """
        if self.controller.refuse_if_read_only():
            return
        if self.guiding:
            self.scene3d.stop_guide()
            self._guide_plant = None
            self.controller.say("Guiding cancelled: nothing was recorded and no time was used.")
            return
        if not HANDS[self.hand].trainee_moves:
            raise InvalidParameterError(
                "this tutor uses the guided hand: click a plant, then Demonstrate"
            )
        self.run.check_open()
        if self._follower is None:
            self._follower = HandFollower.for_scene(self.task.scene)
        plant = self.selected
        self.scene3d.start_guide(
            self._follower, on_end=self._guided, on_cancel=self._guide_cancelled
        )
        self._guide_plant = plant
        self.controller.say(
            f"Guide the arm to {self.task.plant_name(plant)} in the 3-D view: close the hand "
            "on the plant, carry it over the bin, open the hand, then press Enter "
            "(Escape cancels)."
        )

    @guarded
    def _guided(self, end) -> None:
        """The page sent the trainee's recording (a :class:`~tutor.views.scene_guide.GuideEnd`):
        one demonstration to the plant selected when guiding began."""
        plant, self._guide_plant = self._guide_plant, None
        if plant is None:
            return  # a late end after a cancel: nothing is meant by it
        finished = self.run.attempt.finished
        with self._busy("The robot is learning from your demonstration…"):
            self.run.demonstrate(plant, raw=end.raw, given="own", setup_seconds=end.setup_seconds)
        self.controller.say("")
        self._close_if_out_of_time()
        if self.run.attempt.finished != finished or self.message == "":
            self.controller.autosave()

    @guarded
    def _guide_cancelled(self) -> None:
        if self._guide_plant is not None:
            self._guide_plant = None
            self.controller.say("Guiding cancelled: nothing was recorded and no time was used.")

    def guide_as_steady_hand(self, plant: int | None = None, rng=None) -> None:
        """A scripted trainee guides the arm to ``plant`` (default: the selected one).

        It goes the whole way a person's does: Guide, moves the page sends, the recording
        at Enter (:func:`tutor.tasks.recording.steady_hand`, a steady hand at a person's
        pace). For headless runs and tests; a trainee uses the 3-D view.
        """
        if plant is not None:
            self.select(plant)
        self.guide()
        if not self.guiding:
            return  # refused (the message says why)
        raw = np.ascontiguousarray(
            steady_hand(self.task, self.selected, self.rng if rng is None else rng), float
        )
        for seq, row in enumerate(raw[:: max(1, len(raw) // 8)], start=1):
            x, y, z, g = (float(v) for v in row[1:])
            self.scene3d.receive(
                {"type": "guide-move", "seq": seq, "x": x, "y": y, "z": z, "g": g}, []
            )
        end = {"type": "guide-end", "n": len(raw), "setup": SCRIPTED_SETUP_SECONDS}
        self.scene3d.receive(end, [raw.tobytes()])

    def _busy(self, text: str):
        """A context in which the 3-D view says ``text`` (:meth:`Scene3D.busy`), for a step
        that takes a while; nothing without a view."""
        busy = getattr(self.scene3d, "busy", None)
        return busy(text) if callable(busy) else contextlib.nullcontext()

    # ---------------------------------------------------------------- actions

    def select(self, plant: int) -> None:
        if self.guiding and int(plant) != self._guide_plant:
            self.controller.say(
                f"You are guiding the arm to {self.task.plant_name(self._guide_plant)}: "
                f"press Enter in the 3-D view to end, or {CANCEL_GUIDE}, before choosing "
                "another plant."
            )
        else:
            self.selected = int(plant)
        self.refresh()

    def _on_demonstrate(self) -> None:
        """The Demonstrate button: busy while the demo runs; a double click gives one demo."""
        if time.monotonic() - self._demo_ended < DOUBLE_CLICK_SECONDS:
            return  # the second click of a double click, queued while the first ran
        button = self.buttons["Demonstrate"]
        button.disabled, button.description, button.icon = True, "Working…", "spinner"
        try:
            self.demonstrate()
        finally:
            button.description, button.icon = "Demonstrate", ""
            button.disabled = self.run.finished or self.read_only
            self._demo_ended = time.monotonic()

    @guarded
    def demonstrate(self, plant=None, mistake=None) -> None:
        """Demonstrate to ``plant`` (default: the selected one); the mistake chooser goes
        back to "no mistake" afterwards."""
        if self.controller.refuse_if_read_only():
            return
        if self.guiding:
            raise InvalidParameterError(
                "you are guiding the arm: press Enter in the 3-D view to end that "
                "demonstration first (or cancel it)"
            )
        plant = self.selected if plant is None else plant
        if mistake is None:  # the chooser's value, as the page set it
            mistake = MISTAKES[check_choice(self.mistake.value, "the mistake", tuple(MISTAKES))]
        finished = self.run.attempt.finished
        try:
            with self._busy("The robot is learning from the demonstration…"):
                self.run.demonstrate(plant, mistake=mistake, rng=self.rng, given="guided")
            self.controller.say("")
        except TutorError as exc:
            self.controller.say(str(exc))
        self.mistake.value = "no mistake"
        self._close_if_out_of_time()
        if self.run.attempt.finished != finished or self.message == "":
            self.controller.autosave()

    def _close_if_out_of_time(self) -> None:
        """The paper's cap: when not even the shortest demonstration fits in the time
        left, the run ends with the last complete demo (recorded as stopped "time"). The
        panel then says why, from the same clock state as the clock line (:meth:`refresh`)."""
        if self.run.out_of_time and not self.run.attempt.finished:
            self.run.finish("time")

    def capped(self) -> bool:
        """Whether the cap ends this run: not even the shortest demonstration fits, and the
        trainee did not finish it before (a run finished by "time", or one resumed over)."""
        attempt = self.run.attempt
        return self.run.out_of_time and attempt.stopped in ("", "time")

    @guarded
    def test(self, plants=None) -> None:
        if self.controller.refuse_if_read_only():
            return
        plants = [self.selected] if plants is None else list(plants)
        ok = self.run.test(plants)
        names = ", ".join(
            f"{self.task.plant_name(p)}: {'success' if o else 'fails'}"
            for p, o in zip(plants, ok, strict=True)
        )
        self.controller.say(f"The robot tried {names}.")
        self.controller.autosave()

    @guarded
    def finish(self) -> None:
        self.controller.finish(needs_demos=False)

    def autoplay(self, plants, mistakes=None) -> None:
        """Headless runs only (TUTOR_HEADLESS=1): demonstrate ``plants`` then finish.

        With the own hand a scripted steady hand guides the arm through the 3-D view's
        guide (:meth:`guide_as_steady_hand`); ``mistakes`` (index -> mistake) are the
        guided hand's.
        """
        if not headless() or self.run.finished:
            return
        mistakes = mistakes or {}
        for i, plant in enumerate(plants):
            if self.run.finished:
                break
            if HANDS[self.hand].trainee_moves:
                self.guide_as_steady_hand(plant)
            else:
                self.demonstrate(plant, mistake=mistakes.get(i))
        self.finish()

    # ---------------------------------------------------------------- display

    def _refresh_guide(self) -> None:
        """The Guide button: "Cancel guiding" while guiding; off when the run is over."""
        button = self.buttons[GUIDE]
        set_trait(button, "description", CANCEL_GUIDE if self.guiding else GUIDE)
        set_trait(button, "icon", "stop" if self.guiding else "hand-paper-o")
        set_trait(button, "disabled", (self.run.finished and not self.guiding) or self.read_only)
        if self.guiding:
            button.add_class("lfd-guiding")
        else:
            button.remove_class("lfd-guiding")

    def current_hint(self):
        """HF's next-demo hint while the run is open (None in the other conditions, once
        finished, or when it cannot be computed: the panel then says why)."""
        run = self.run
        if not run.hinted or run.finished:
            return None
        try:
            return run.hint()
        except TutorError as exc:
            self.controller.say(f"No hint this time: {exc}")
        except Exception as exc:  # the hint is an extra: it must not cost the trainee the run
            log.exception("the next-demo hint failed")
            self.controller.say(
                f"No hint this time: something went wrong inside the tutor "
                f"({type(exc).__name__}). Your demonstrations are kept; carry on without it."
            )
        return None

    def refresh(self) -> None:
        run, rec = self.run, self.run.session.latest
        status = tray_status(run, reveal=run.finished)
        hint = self.current_hint()
        self.tray_map.draw(status, rec, self.selected, None if hint is None else hint.plant)
        sf_or_after = run.policy.teacher_picks or run.finished
        busy = self.guiding  # while guiding, only Cancel guiding (and Enter) act
        self.buttons["Test plant"].disabled = (
            not sf_or_after or rec is None or self.read_only or busy
        )
        self.buttons["Demonstrate"].disabled = run.finished or self.read_only or busy
        # after the cap ended a run, its last demo may still be taken back once
        self.buttons["Undo"].disabled = not run.can_undo or self.read_only or busy
        for name in ("Finish run", "Reset"):
            self.buttons[name].disabled = self.read_only or busy
        self._refresh_guide()
        timing = run.clock_state()  # the clock line and the cap's words: one state
        self.clock.value = f"<b>Time</b>: {html.escape(timing.line())}"
        vis = run.visibility()
        practice = " &middot; practice run" if self.record.practice else ""
        parts = [
            f"<b>Condition {run.condition}</b>{practice} &middot; run {self.record.run} "
            f"&middot; demonstrations: {run.session.n_demos}"
            f" &middot; selected: {self.task.plant_name(self.selected)}"
        ]
        demo = run.attempt.demos[-1] if run.attempt.demos else None
        lines = compose(
            self.task,
            rec,
            vis,
            run.session.history,
            generated=demo is not None and demo.given == "guided",
            mistake=demo.mistake if demo is not None else "",
            finished=run.finished,
            rule_message=None if hint is None else hint_sentence(self.task, hint.plant),
        )
        parts.append(
            "<ul class='lfd-feedback'>"
            + "".join(f"<li>{html.escape(x)}</li>" for x in lines)
            + "</ul>"
        )
        if run.finished and rec is not None:
            paper = paper_condition(run.condition)
            summary = finish_summary(run, PAPER_MEAN_ETA[paper], "mean over three runs", paper)
            parts.append(f"<div class='lfd-score'><b>Run over.</b> {html.escape(summary)}</div>")
        if self.capped():
            parts.append(
                f"<div class='lfd-cap' role='status'>{html.escape(timing.cap_message())}</div>"
            )
        parts.append(self.message_html())
        self.panel.value = prose("".join(parts))
        self._refresh_common()
        if self.guiding:  # a file loaded mid-guide would interleave two demonstrations
            self.upload.disabled = True
        if self.scene3d is not None:
            self.scene3d.update(run, status)


def paper_condition(condition: str) -> str:
    """The paper's condition a run's score is compared with: its own; for AF (beyond the
    paper) BF, which shows as many robot attempts and so costs the same time; for HF
    (beyond the paper) NF, which shows nothing either and lacks only the hint
    (:mod:`tutor.framework.protocol`)."""
    return PickPlaceRun.protocol().condition(condition).paper_code


def compare_runs(tutors) -> str:
    """The trainee's η over their runs beside the paper's means for the condition.

    Each run's η is its own score (:meth:`tutor.framework.run.TeachingRun.score`, the
    paper's Experiment 2 rule: ε after the last demo / the demos given), the number the
    after-Finish summary shows.
    """
    lines, etas = [], []
    for i, t in enumerate(tutors, start=1):
        if t.run.n_demos == 0:
            lines.append(f"Run {i}: no demonstrations yet")
            continue
        score = t.run.score()
        etas.append(score.efficiency)
        lines.append(
            f"Run {i} ({t.run.condition}): η = {percent(score.efficiency)} (the robot "
            f"succeeds at {score.efficacy:.0%} of the plants after "
            f"{plural(score.n_demos, 'demo')}; {t.run.clock_text()})"
        )
    if not etas:
        return "\n".join(lines)
    spec = tutors[0].run.protocol_condition
    own, cond = spec.code, spec.paper_code
    beyond = "" if spec.paper else f" ({own} is beyond the paper; {cond} {spec.compared_why})"
    lines.append(
        f"\nYour mean η: {percent(np.mean(etas))}. The paper's 9 trainees in {cond}{beyond}: "
        f"mean {percent(PAPER_MEAN_ETA[cond])} over the runs, "
        f"{percent(PAPER_THIRD_RUN_ETA[cond])} in the third."
    )
    best = optimal_sentence(tutors[0].task)
    if best:
        lines.append(best)
    lines.append(
        "The paper found batch feedback (BF: the five sample plants after every demo) best, "
        "about 1.7 times the others, because it shows how the robot generalises; replays (RF) "
        "mostly catch wrong-plant demos, and novices choose uninformative tests (SF). One "
        "trainee's three runs cannot show that: the paper compared 36 people."
    )
    return "\n".join(lines)
