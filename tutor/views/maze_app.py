"""The interactive maze tutor: one teaching run of Experiment 1 in one condition.

Conditions (Sena & Howard, "Experiment 1"):

NF  no feedback: r is empty while teaching; the trainee presses *Finish* when they
    think the robot has learned enough, and the picture is then revealed.
VF  visual feedback: R^ (green/red) after every demonstration.
VR  visual feedback and the paper's three rules: the tutor marks the 4 cm circle where
    the rules say the next demo should start and says whether the last one followed them.

Every completed demonstration is saved at once (atomically) to the run's file, so a
crashed or restarted kernel resumes where the trainee was; resuming, the file lock,
loading, undo, reset and finish are shared with the pick-and-place tutor
(:class:`tutor.framework.controller.RunController`, below the views; the shared widgets
are :mod:`tutor.views.app`'s).
"""

from __future__ import annotations

import html

import ipywidgets as w
import numpy as np

from ..errors import InvalidPayloadError, TutorError
from ..framework.wording import percent
from ..paper import PAPER_MEDIAN_ETA
from ..payloads import check_stroke
from ..runtime import headless
from ..tasks.maze import MazeTask
from ..tasks.maze_run import MazeRun
from ..tasks.optimal_reference import optimal_reference
from .app import TutorApp, guarded
from .sketchpad import Sketchpad, layout_spec
from .style import prose
from .text import compose, finish_summary, optimal_sentence

__all__ = ["MazeTutor", "PAPER_MEDIAN_ETA", "compare_runs", "plot_runs"]


class MazeTutor(TutorApp):
    """Sketchpad, live panel and buttons for one run.

    Parameters
    ----------
    condition : {"NF", "VF", "VR", "VA"}
        VA (beyond the paper): only the k start points a selector picks are shown.
    run_file : path, optional
        Where the run autosaves; an existing file of the same run is resumed.
    task : MazeTask, optional
    width_px : int
        Width of the drawing area in pixels.
    trainee : str, optional
        The trainee's name (default ``JUPYTERHUB_USER`` on a hub, else "trainee").
    practice : bool
        Mark the run as practice (the class analysis leaves it out).
    """

    demo_columns = ("t", "x", "y")
    undo_note = ""  # the redrawn sketchpad shows what was taken back

    def __init__(
        self,
        condition: str = "VF",
        run_file=None,
        task=None,
        width_px: int = 360,
        trainee=None,
        practice: bool = False,
    ):
        task = MazeTask() if task is None else task
        super().__init__(MazeRun, condition, task, run_file, trainee, practice=practice)
        self.pad = Sketchpad(maze=layout_spec(self.task.layout), width_px=width_px)
        self.panel = w.HTML(layout=w.Layout(width="380px"))
        self.buttons = {
            name: w.Button(description=name, layout=w.Layout(width="86px"))
            for name in ("Undo", "Reset", "Save", "Finish")
        }
        self.buttons["Reset"].tooltip = "Start a new attempt (asks to confirm; nothing is deleted)"
        self.buttons["Undo"].on_click(lambda _: self.undo())
        self.buttons["Reset"].on_click(lambda _: self.request_reset())
        self.buttons["Save"].on_click(lambda _: self.save())
        self.buttons["Finish"].on_click(lambda _: self.finish())
        self._common_widgets()
        self.pad.observe(self._on_stroke, names="stroke_count")
        self.widget = w.HBox(
            [
                self.pad,
                w.VBox(
                    [
                        w.HBox([*self.buttons.values(), self.upload]),
                        w.HBox([self.attempts, self.bring_back, self.retry]),
                        self.panel,
                        self.status,
                    ]
                ),
            ]
        )
        self.widget.add_class("lfd-maze-tutor")
        self.refresh()

    # ---------------------------------------------------------------- state

    @property
    def compliance(self) -> list[bool]:
        """VR: whether each demo followed the rules in force when it was given."""
        return self.run.compliance

    # ---------------------------------------------------------------- actions

    @guarded
    def _on_stroke(self, change) -> None:
        """A stroke arrived from the page: checked (:func:`.payloads.check_stroke`) before
        it is added; one that is not a list of points is said in the panel."""
        try:
            raw = check_stroke(self.pad.stroke)
        except InvalidPayloadError as exc:
            self.controller.say(f"That stroke was not used: {exc}")
            return
        self._add(raw)

    @guarded
    def add(self, raw) -> None:
        """Add one demonstration (what a finished stroke does)."""
        self._add(raw)

    def _add(self, raw) -> None:
        if self.controller.refuse_if_read_only():
            return
        if self.finished:
            self.controller.say(
                "This run is finished, so that stroke was not used. Press Reset to teach "
                "again (this run is kept)."
            )
            return
        advice = self.run.advice() if self.run.protocol_condition.rules else None
        try:
            record = self.run.add_demo(raw)
        except TutorError as exc:
            self.controller.say(f"That stroke was not used: {exc}")
            return
        self.controller.say(self._rule_note(advice, record.n_demos))
        self.controller.autosave()

    def _rule_note(self, advice, n_demos: int) -> str:
        """VR: whether demo ``n_demos`` followed the rule ``advice`` gave before it ("" in
        the other conditions)."""
        if advice is None:
            return ""
        if advice.rule == 0:
            return (
                f"Every start point already succeeded before demo {n_demos}: "
                "you could have finished."
            )
        if not self.run.attempt.demos[-1].followed_rule:
            start = self.task.test_point_of(self.session.demos[-1])
            gap = np.linalg.norm(start - advice.center)
            return (
                f"Demo {n_demos} did not follow rule {advice.rule}: it started "
                f"{100 * gap:.1f} cm from the circle's centre (stay within 4 cm)."
            )
        return f"Demo {n_demos} followed rule {advice.rule}."

    # ---------------------------------------------------------------- display

    def refresh(self) -> None:
        """Redraw the sketchpad and the panel from the run."""
        s, rec = self.session, self.session.latest
        vis = self.run.visibility()
        rule = None
        if self.run.protocol_condition.rules and not self.finished:
            advice = self.run.advice()
            if advice.center is not None:
                rule = {"center": advice.center.tolist(), "radius": advice.radius}
        if rec is None or not len(vis.shown):
            note = (
                "No feedback in this run: press Finish when you are done."
                if self.run.policy.silent and not vis.everything
                else ""
            )
            self.pad.show(s.demos, rule_circle=rule, note=note)
        else:
            self.pad.show(
                s.demos, s.realisations, rec.passed, vis.shown, rule, causes=rec.causes
            )
        self.pad.enabled = not self.finished and not self.read_only
        for name in ("Undo", "Reset", "Finish", "Save"):
            self.buttons[name].disabled = self.read_only
        self.panel.value = prose(self._panel_html(vis))
        self._refresh_common()

    def _panel_html(self, vis) -> str:
        s, rec = self.session, self.session.latest
        practice = " &middot; practice run" if self.record.practice else ""
        parts = [
            f"<b>Condition {self.condition}</b>{practice} &middot; demonstrations: {s.n_demos}"
        ]
        rule = None
        if self.run.protocol_condition.rules and not self.finished:
            rule = self.run.advice().message
        lines = compose(
            self.task, rec, vis, s.history, rule_message=rule, finished=self.finished
        )
        parts.append(
            "<ul class='lfd-feedback'>"
            + "".join(f"<li>{html.escape(x)}</li>" for x in lines)
            + "</ul>"
        )
        if self.finished and s.n_demos:
            paper = paper_condition(self.condition)
            summary = finish_summary(self.run, PAPER_MEDIAN_ETA[paper], "median", paper)
            parts.append(
                f"<div class='lfd-score'><b>Finished.</b> {html.escape(summary)}</div>"
            )
        parts.append(self.message_html())
        return "".join(parts)

    def autoplay(self, demos, finish: bool = True) -> None:
        """Headless runs only (``TUTOR_HEADLESS=1``): feed ``demos`` as strokes, then finish.

        Does nothing when a person runs the notebook, and nothing on a run that was
        already finished (e.g. resumed).
        """
        if not headless() or self.finished:
            return
        for demo in demos:
            self.pad.draw(demo)
        if finish:
            self.finish()


def paper_condition(condition: str) -> str:
    """The paper's condition a maze run is compared with: its own, or for VA (beyond the
    paper, adaptive feedback) VF (:mod:`tutor.framework.protocol`)."""
    return MazeRun.protocol().condition(condition).paper_code


def compare_runs(tutors) -> str:
    """The trainee's eta per condition beside the paper's medians, with an honest reading.

    Parameters
    ----------
    tutors : sequence of MazeTutor
        The runs (typically NF, VF and VR).
    """
    rows, eta = [], {}
    for t in tutors:
        if t.session.n_demos == 0:
            rows.append(f"{t.condition}: no demonstrations yet")
            continue
        score = t.run.score()  # the run's own experiment's rule, as after Finish
        eta[t.condition] = score.efficiency
        reach = (
            f"90 % after {score.n_demos} demos"
            if score.reached
            else f"90 % not reached ({score.efficacy:.0%} after {score.n_demos} demos)"
        )
        rows.append(
            f"{t.condition}: η = {percent(score.efficiency)} ({reach}); "
            f"paper's median {percent(PAPER_MEDIAN_ETA[paper_condition(t.condition)])}"
        )
    text = "\n".join(rows)
    if eta:
        text += "\n" + optimal_sentence(tutors[0].task)
    exp = MazeRun.protocol()
    nf, with_feedback = exp.without_feedback, exp.with_feedback
    if {nf, *with_feedback} <= eta.keys():
        feedback_best = max(eta[c] for c in with_feedback)
        if eta[nf] < feedback_best:
            text += (
                "\n\nAs in the paper, you taught more efficiently when you could see what the "
                f"robot had learned ({feedback_best / max(eta[nf], 1e-9):.1f} times your {nf} "
                "efficiency; the paper's median trainee gained about 1.8 times)."
            )
        else:
            text += (
                "\n\nUnlike the paper's median trainee, feedback did not make your teaching more "
                "efficient: 7 of the paper's 30 trainees also did well without feedback."
            )
    text += (
        "\n\nA caution: this is one person and one attempt per condition, always in the order "
        "NF, VF, VR, so practice helps the later runs too; the paper needed 30 trainees to "
        "show the effect (F(2,58) = 7.95, p = 0.001) and found VF and VR alike (p = 0.80)."
    )
    return text


def plot_runs(tutors, ax=None):
    """Bar chart of the trainee's eta per condition with the paper's medians marked, and
    the optimal teacher's eta (the best possible) as a dashed line."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 3.5))
    names = [t.condition for t in tutors]
    mine = [100 * t.run.score().efficiency if t.session.n_demos else 0.0 for t in tutors]
    x = np.arange(len(names))
    ax.bar(x, mine, width=0.55, color="#1f4e9c", label="you")
    ax.scatter(
        x,
        [100 * PAPER_MEDIAN_ETA[n] for n in names],
        marker="_",
        s=900,
        linewidths=3,
        color="#d95f02",
        label="paper's median",
        zorder=3,
    )
    best = optimal_reference("maze")
    if best is not None and best.best_eta is not None:
        ax.axhline(
            100 * best.best_eta,
            color="#2ca02c",
            linestyle="--",
            label=f"optimal teacher ({best.n_demos} demos)",
            zorder=2,
        )
    ax.set_xticks(x, names)
    ax.set_ylabel("teaching efficiency η (%)")
    ax.legend(frameon=False)
    return ax
