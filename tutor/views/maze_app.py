"""The interactive maze tutor: one teaching run of Experiment 1 in one condition.

Conditions (Sena & Howard, "Experiment 1"):

NF  no feedback: r is empty while teaching; the trainee presses *Finish* when they
    think the robot has learned enough, and the picture is then revealed.
VF  visual feedback: R^ (green/red) after every demonstration.
VR  visual feedback and the paper's three rules: the tutor marks the 4 cm circle where
    the rules say the next demo should start and says whether the last one followed them.

Every completed demonstration is saved at once (atomically) to the run's session file,
so a crashed or restarted kernel resumes where the trainee was.
"""

from __future__ import annotations

import html
from pathlib import Path

import ipywidgets as w
import numpy as np

from ..demofiles import load_demos
from ..errors import InvalidFileError, TutorError
from ..framework import TeachingSession
from ..runtime import headless
from ..tasks.maze import MazeTask
from ..tasks.maze_rules import advise, followed
from .sketchpad import Sketchpad, layout_spec
from .text import session_report, summary
from .uploads import on_upload

__all__ = ["MazeTutor", "CONDITIONS", "PAPER_MEDIAN_ETA", "compare_runs", "plot_runs"]

CONDITIONS = {"NF": "none", "VF": "all", "VR": "all"}
PAPER_MEDIAN_ETA = {"NF": 0.076, "VF": 0.134, "VR": 0.14}


class MazeTutor:
    """Sketchpad, live panel and buttons for one run.

    Parameters
    ----------
    condition : {"NF", "VF", "VR"}
    session_file : path, optional
        Where the run autosaves; an existing file is resumed.
    task : MazeTask, optional
    width_px : int
        Width of the drawing area in pixels.
    """

    def __init__(self, condition: str = "VF", session_file=None, task=None, width_px: int = 360):
        if condition not in CONDITIONS:
            raise TutorError(f"condition must be one of {', '.join(CONDITIONS)}, got {condition!r}")
        self.task = MazeTask() if task is None else task
        self.condition = condition
        self.session_file = None if session_file is None else Path(session_file)
        self.message = ""
        self._autosave_ok = True
        self.session = self._resume()

        self.pad = Sketchpad(layout=layout_spec(self.task.layout), width_px=width_px)
        self.panel = w.HTML(layout=w.Layout(width="380px"))
        self.buttons = {
            name: w.Button(description=name, layout=w.Layout(width="86px"))
            for name in ("Undo", "Reset", "Save", "Finish")
        }
        self.upload = w.FileUpload(accept=".json,.csv", multiple=False, description="Load")
        self.buttons["Undo"].on_click(lambda _: self.undo())
        self.buttons["Reset"].on_click(lambda _: self.reset())
        self.buttons["Save"].on_click(lambda _: self.save())
        self.buttons["Finish"].on_click(lambda _: self.finish())
        self.upload.observe(on_upload(self.load), names="value")
        self.pad.observe(self._on_stroke, names="stroke_count")
        self.widget = w.HBox(
            [
                self.pad,
                w.VBox([w.HBox([*self.buttons.values(), self.upload]), self.panel]),
            ]
        )
        self.widget.add_class("lfd-maze-tutor")
        self.refresh()

    # ---------------------------------------------------------------- state

    @property
    def finished(self) -> bool:
        return bool(self.session.meta.get("finished", False))

    @property
    def compliance(self) -> list[bool]:
        """VR: whether each demo followed the rules in force when it was given."""
        return list(self.session.meta.get("followed_rules", []))

    def _new_session(self) -> TeachingSession:
        s = TeachingSession(self.task, feedback=CONDITIONS[self.condition])
        s.meta.update(condition=self.condition, finished=False, followed_rules=[])
        return s

    def _resume(self) -> TeachingSession:
        path = self.session_file
        if path is None or not path.exists():
            return self._new_session()
        try:
            session = TeachingSession.load(path, self.task)
        except InvalidFileError as exc:
            self._autosave_ok = False  # never overwrite a file we could not read
            self.message = (
                f"Could not resume from {path.name}: {exc}. Starting afresh; this run will not "
                "be saved over that file (use Save after choosing another file)."
            )
            return self._new_session()
        if session.meta.get("condition", self.condition) != self.condition:
            self._autosave_ok = False
            self.message = (
                f"{path.name} holds a {session.meta.get('condition')} run, not {self.condition}; "
                "starting afresh without touching it."
            )
            return self._new_session()
        self.message = f"Resumed {session.n_demos} demonstration(s) from {path.name}."
        return session

    # ---------------------------------------------------------------- actions

    def _on_stroke(self, change) -> None:
        self.add(np.asarray(self.pad.stroke, dtype=float))

    def add(self, raw) -> None:
        """Add one demonstration (what a finished stroke does)."""
        if self.finished:
            self.message = "This run is finished; press Reset to teach again."
            self.refresh()
            return
        advice = advise(self.task, self.session) if self.condition == "VR" else None
        try:
            record = self.session.add_demo(raw)
        except TutorError as exc:
            self.message = f"That stroke was not used: {exc}"
            self.refresh()
            return
        self.message = ""
        if advice is not None:
            start = self.task.condition_of(self.session.demos[-1])
            ok = followed(advice, start)
            self.session.meta["followed_rules"] = [*self.compliance, ok]
            if advice.rule == 0:
                self.message = (
                    f"Every start point already succeeded before demo {record.n_demos}: "
                    "you could have finished."
                )
            elif not ok:
                gap = np.linalg.norm(start - advice.center)
                self.message = (
                    f"Demo {record.n_demos} did not follow rule {advice.rule}: it started "
                    f"{100 * gap:.1f} cm from the circle's centre (stay within 4 cm)."
                )
            else:
                self.message = f"Demo {record.n_demos} followed rule {advice.rule}."
        self._autosave()
        self.refresh()

    def undo(self) -> None:
        if self.session.n_demos == 0 or self.finished:
            return
        self.session.undo()
        if self.condition == "VR":
            self.session.meta["followed_rules"] = self.compliance[: self.session.n_demos]
        self.message = ""
        self._autosave()
        self.refresh()

    def reset(self) -> None:
        self.session = self._new_session()
        self.message = "Started again."
        self._autosave()
        self.refresh()

    def finish(self) -> None:
        """End the run: NF reveals the picture; every condition shows the paper's score."""
        if self.session.n_demos == 0:
            self.message = "Give at least one demonstration before finishing."
        else:
            self.session.meta["finished"] = True
            self.message = ""
            self._autosave()
        self.refresh()

    def save(self, path=None) -> Path | None:
        """Save the run (to ``session_file`` by default); returns the path written."""
        path = Path(path) if path is not None else self.session_file
        if path is None:
            path = Path("sessions") / f"maze_{self.condition}.json"
            self.session_file = path
        self.session.save(path)
        self._autosave_ok = True
        self.message = f"Saved to {path}."
        self.refresh()
        return path

    def load(self, path) -> None:
        """Load a session file, or add the demos of a demonstration file (JSON/CSV)."""
        path = Path(path)
        try:
            if path.suffix.lower() == ".json" and '"lfd-tutor-session"' in path.read_text()[:200]:
                self.session = TeachingSession.load(path, self.task)
                self.message = f"Loaded {self.session.n_demos} demonstration(s)."
            else:
                demos = load_demos(path)
                trial = TeachingSession.from_dict(self.session.to_dict(), self.task)
                for i, demo in enumerate(demos, start=1):
                    try:
                        trial.add_demo(demo)
                    except TutorError as exc:
                        raise InvalidFileError(f"demo {i} of {path.name}: {exc}") from exc
                trial.meta = self.session.meta
                self.session = trial
                self.message = f"Added {len(demos)} demonstration(s) from {path.name}."
        except (InvalidFileError, OSError, UnicodeDecodeError) as exc:
            self.message = f"Nothing was loaded: {exc}"
            self.refresh()
            return
        self._autosave()
        self.refresh()

    def _autosave(self) -> None:
        if self.session_file is not None and self._autosave_ok:
            self.session.save(self.session_file)

    # ---------------------------------------------------------------- display

    def refresh(self) -> None:
        """Redraw the sketchpad and the panel from the session."""
        s, rec = self.session, self.session.latest
        reveal = self.condition != "NF" or self.finished
        rule = None
        if self.condition == "VR" and not self.finished:
            advice = advise(self.task, s)
            if advice.center is not None:
                rule = {"center": advice.center.tolist(), "radius": advice.radius}
        if rec is None or not reveal:
            note = "" if reveal else "No feedback in this run: press Finish when you are done."
            self.pad.show(s.demos, rule_circle=rule, note=note)
        else:
            shown = np.arange(len(rec.passed)) if self.finished else rec.shown
            self.pad.show(s.demos, s.realisations, rec.passed, shown, rule)
        self.pad.enabled = not self.finished
        self.panel.value = self._panel_html(reveal)

    def _panel_html(self, reveal: bool) -> str:
        s, rec = self.session, self.session.latest
        parts = [f"<b>Condition {self.condition}</b> &middot; demonstrations: {s.n_demos}"]
        if rec is not None and reveal:
            parts.append(
                f"<div class='lfd-metrics'>efficacy ε = <b>{rec.efficacy:.0%}</b> "
                f"({100 * rec.delta:+.0f}) &middot; "
                f"efficiency η = <b>{rec.efficiency:.1%}</b></div>"
            )
            lines = summary(rec).splitlines()[1:]
            parts.append(
                "<ul>" + "".join(f"<li>{html.escape(x[2:])}</li>" for x in lines) + "</ul>"
            )
        if self.condition == "VR" and not self.finished:
            parts.append(f"<div><i>{html.escape(advise(self.task, s).message)}</i></div>")
        if self.finished:
            score = s.score()
            parts.append(
                f"<div class='lfd-score'><b>Finished.</b> {html.escape(session_report(s))} "
                f"(paper's median for {self.condition}: "
                f"{PAPER_MEDIAN_ETA[self.condition]:.1%}; you used {score.n_demos} "
                "demonstration(s) to get there)</div>"
            )
        if self.message:
            parts.append(f"<div class='lfd-message'>{html.escape(self.message)}</div>")
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

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


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
        score = t.session.score()
        eta[t.condition] = score.efficiency
        reach = (
            f"90 % after {score.n_demos} demos"
            if score.reached
            else f"90 % not reached ({score.efficacy:.0%} after {score.n_demos} demos)"
        )
        rows.append(
            f"{t.condition}: eta = {score.efficiency:.1%} ({reach}); "
            f"paper's median {PAPER_MEDIAN_ETA[t.condition]:.1%}"
        )
    text = "\n".join(rows)
    if {"NF", "VF", "VR"} <= eta.keys():
        feedback_best = max(eta["VF"], eta["VR"])
        if eta["NF"] < feedback_best:
            text += (
                "\n\nAs in the paper, you taught more efficiently when you could see what the "
                f"robot had learned ({feedback_best / max(eta['NF'], 1e-9):.1f} times your NF "
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
    """Bar chart of the trainee's eta per condition with the paper's medians marked."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 3.5))
    names = [t.condition for t in tutors]
    mine = [100 * t.session.score().efficiency if t.session.n_demos else 0.0 for t in tutors]
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
    ax.set_xticks(x, names)
    ax.set_ylabel("teaching efficiency η (%)")
    ax.legend(frameon=False)
    return ax
