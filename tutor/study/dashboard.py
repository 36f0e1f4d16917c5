"""The educator's class dashboard (notebook 05, also a Voila app).

It points at the class folder, reads every trainee's runs (:func:`.classroom.read_class`;
a trainee's zip in the folder is read as their folder), saying how far it has got, and
shows, beside the paper's numbers and a simulated class of the same size
(:func:`.class_report.analyse_class`):

- how many trainees and runs are counted, and when it was last refreshed;
- the class's η per condition beside the paper's and the simulation's, and the figure;
- the paper's tests on the class (or why the class is too small for them), and each
  condition beyond the paper against the one it is compared with;
- the trainees still to finish (or on the class plan without any run yet);
- every file not counted, with the reason.

**Refresh** reads the folder again (only files that changed are read and replayed), and
*Refresh every N s* does it by itself while the notebook runs. **Save the results**
writes what ``lfd-tutor class --out`` writes, to a folder beside the class folder.

The class folder is, in order: the ``folder`` argument, ``TUTOR_CLASS_DIR`` in the
environment (the hub kit sets it for the educator), or the tutor's own runs folder
(:func:`tutor.runtime.runs_root`, where trainees' runs go on one machine). With
``TUTOR_HEADLESS=1`` and no folder given, the dashboard shows a simulated class
(:func:`.simulated_class.write_simulated_class`), as a rehearsal would.

Stable CSS classes for browser tests: ``lfd-class-dashboard``, ``lfd-class-folder``,
``lfd-class-experiment``, ``lfd-class-refresh``, ``lfd-class-auto``,
``lfd-class-status``, ``lfd-class-beside``, ``lfd-class-figure``, ``lfd-class-tests``,
``lfd-class-trainees``, ``lfd-class-problems``, ``lfd-class-save``, ``lfd-class-rehearse``.
"""

from __future__ import annotations

import asyncio
import base64
import html
import io
import numbers
import os
import tempfile
import time
from pathlib import Path

import ipywidgets as w

from ..errors import InvalidParameterError, TutorError
from ..fileio import check_path_length
from ..framework.protocol import EXPERIMENTS
from ..framework.wording import percent, plural
from ..payloads import check_choice, check_text, safely
from ..runtime import headless, runs_root
from .class_report import (
    BESIDE_LEGEND,
    analyse_class,
    as_sentence,
    beyond_lines,
    class_figure,
    paper_runs,
    save_class,
)
from .classroom import read_class
from .report import OUT_ROOM
from .tables import has_no_number, readable_label, readable_table

__all__ = ["ClassDashboard", "class_dashboard", "CLASS_DIR_ENV", "default_class_folder"]

#: the environment variable naming the class folder (set for the educator by deploy/)
CLASS_DIR_ENV = "TUTOR_CLASS_DIR"
#: the shortest and longest automatic refresh interval, seconds
REFRESH_RANGE = (10, 600)


def default_class_folder() -> Path:
    """``TUTOR_CLASS_DIR``, or else the tutor's runs folder."""
    value = os.environ.get(CLASS_DIR_ENV, "").strip()
    return check_path_length(value, CLASS_DIR_ENV) if value else runs_root()


#: how every text block of the dashboard wraps: between words only (JupyterLab gives a
#: ``<pre>`` in an output ``word-break: break-all``, which cut "finished" into "finishe d");
#: a word too long for the line by itself (a long path) may still break
WRAP_WORDS = "word-break:normal;overflow-wrap:break-word;hyphens:manual"


def _table(frame, legend: str = "") -> str:
    """A small accessible HTML table (header cells, a caption-free plain style), its cells
    as a person reads them (:func:`.tables.readable_table`: η in %, a dash for none), and
    under it ``legend`` when a cell has no number."""
    table = readable_table(frame)
    out = table.to_html(classes="lfd-class-table", border=0, escape=True)
    out = f'<div style="{WRAP_WORDS}">{out}</div>'
    if legend and has_no_number(table):
        out += f'<p class="lfd-class-legend" style="{WRAP_WORDS}">{html.escape(legend)}</p>'
    return out


def _list(items: list[str], empty: str) -> str:
    if not items:
        return f'<p style="{WRAP_WORDS}">{html.escape(empty)}</p>'
    return f'<ul style="{WRAP_WORDS}">' + "".join(f"<li>{i}</li>" for i in items) + "</ul>"


def check_board_options(experiment, refresh_seconds):
    """(experiment, refresh_seconds) checked: 1 or 2, and None or whole seconds in
    :data:`REFRESH_RANGE` (raises InvalidParameterError naming the allowed values)."""
    if isinstance(experiment, bool) or experiment not in (1, 2):
        raise InvalidParameterError(
            f"experiment must be 1 (maze) or 2 (pick-and-place), got {experiment!r}"
        )
    if refresh_seconds is None:
        return int(experiment), None
    low, high = REFRESH_RANGE
    whole = (
        not isinstance(refresh_seconds, bool)
        and isinstance(refresh_seconds, numbers.Real)
        and refresh_seconds == refresh_seconds  # not nan
        and float(refresh_seconds).is_integer()
    )
    if not whole or not low <= refresh_seconds <= high:
        raise InvalidParameterError(
            f"refresh_seconds must be None (no automatic refresh) or whole seconds from "
            f"{low} to {high}, got {refresh_seconds!r}"
        )
    return int(experiment), int(refresh_seconds)


class ClassDashboard:
    """The dashboard's widgets and what they do (see the module docstring).

    Parameters
    ----------
    folder : path, optional
        The class folder (default :func:`default_class_folder`).
    experiment : {1, 2}
    refresh_seconds : int, optional
        Start refreshing by itself every so many seconds (10-600).
    """

    def __init__(self, folder=None, experiment: int = 1, refresh_seconds: int | None = None):
        experiment, refresh_seconds = check_board_options(experiment, refresh_seconds)
        self._cache: dict = {}
        self._said_at = 0.0  # when the status last said how far a read has got
        self._timer = None
        self._rehearsing = False
        self.result = None
        self.analysis = None
        self.folder = w.Text(
            value=str(default_class_folder() if folder is None else folder),
            description="Class folder",
            continuous_update=False,  # read when the educator presses Enter or leaves it
            layout=w.Layout(width="auto"),  # the row, less its margins
            style={"description_width": "initial"},
        )
        self.folder.add_class("lfd-class-folder")
        self.experiment = w.ToggleButtons(
            options=[("Experiment 1 (maze)", 1), ("Experiment 2 (pick-and-place)", 2)],
            value=experiment,
            tooltips=["NF, VF, VR for every trainee", "NF, RF, BF or SF, three runs each"],
            style={"button_width": "230px"},
        )
        self.experiment.add_class("lfd-class-experiment")
        self.refresh_button = w.Button(description="Refresh", icon="refresh")
        self.refresh_button.add_class("lfd-class-refresh")
        self.auto = w.Checkbox(
            value=False, description="Refresh every", indent=False, layout=w.Layout(width="auto")
        )
        self.auto.add_class("lfd-class-auto")
        self.seconds = w.BoundedIntText(
            value=30, min=REFRESH_RANGE[0], max=REFRESH_RANGE[1], description="seconds",
            layout=w.Layout(width="140px"), style={"description_width": "initial"},
            tooltip="seconds between automatic refreshes (10-600)",
        )
        self.save_button = w.Button(description="Save the results", icon="save")
        self.save_button.add_class("lfd-class-save")
        self.rehearse_button = w.Button(
            description="Try a simulated class",
            tooltip="write a class of simulated trainees (30 for Experiment 1, 36 for "
            "Experiment 2) to a temporary folder and show it",
        )
        self.rehearse_button.add_class("lfd-class-rehearse")
        self.status = w.HTML()
        self.status.add_class("lfd-class-status")
        self.beside = w.HTML()
        self.beside.add_class("lfd-class-beside")
        self.figure = w.HTML(layout=w.Layout(width="100%", max_width="1100px"))
        self.figure.add_class("lfd-class-figure")
        self.figure_caption = w.HTML()
        self.tests = w.HTML()
        self.tests.add_class("lfd-class-tests")
        self.trainees = w.HTML()
        self.trainees.add_class("lfd-class-trainees")
        self.problems = w.HTML()
        self.problems.add_class("lfd-class-problems")
        # every click and change from the page goes through safely(): nothing raises out
        self.refresh_button.on_click(lambda _: self._safely(self.refresh))
        self.experiment.observe(lambda _: self._safely(self.refresh), "value")
        self.folder.observe(lambda _: self._safely(self._folder_changed), "value")
        self.auto.observe(lambda _: self._safely(lambda: self._auto(self.auto.value)), "value")
        self.save_button.on_click(lambda _: self._safely(self.save))
        self.rehearse_button.on_click(lambda _: self._safely(self.rehearse))
        self.widget = w.VBox(
            [
                self.folder,
                self.experiment,
                w.HBox(
                    [
                        self.refresh_button,
                        self.auto,
                        self.seconds,
                        self.save_button,
                        self.rehearse_button,
                    ],
                    layout=w.Layout(align_items="center", grid_gap="8px"),  # CSS gap (flex too)
                ),
                self.status,
                w.HTML("<h3>The class beside the paper</h3>"),
                self.beside,
                self.figure,
                self.figure_caption,
                w.HTML("<h3>The paper's tests</h3>"),
                self.tests,
                w.HTML("<h3>Trainees still to finish</h3>"),
                self.trainees,
                w.HTML("<h3>Files not counted</h3>"),
                self.problems,
            ]
        )
        self.widget.add_class("lfd-class-dashboard")
        self.refresh()
        if refresh_seconds is not None:
            self.seconds.value = int(refresh_seconds)
            self.auto.value = True

    # ------------------------------------------------------------ reading

    def _say(self, text: str, problem: bool = False) -> None:
        colour = "#8b0000" if problem else "inherit"
        self.status.value = (
            f'<p role="status" aria-live="polite" style="color:{colour};{WRAP_WORDS}">'
            f"{text}</p>"
        )

    def _safely(self, action) -> None:
        safely(action, lambda text: self._say(html.escape(text), problem=True))

    def class_folder(self) -> Path:
        """The folder in the folder field (``.`` when it is blank).

        Raises
        ------
        InvalidPayloadError
            The field's value, as the page sent it, is not text or is far too long.
        InvalidParameterError
            A name in it, or the whole path, is too long for the file system.
        """
        text = check_text(self.folder.value, "the class folder").strip() or "."
        return check_path_length(text, "the class folder")

    def refresh(self) -> None:
        """Read the class folder again and redraw everything (errors are said in words)."""
        started = self._said_at = time.perf_counter()
        try:
            folder = self.class_folder()
            experiment = check_choice(self.experiment.value, "the experiment", (1, 2))
            self.result = read_class(
                folder, experiment, cache=self._cache, progress=self._reading
            )
            self.analysis = analyse_class(self.result)
        except TutorError as exc:
            self.result = self.analysis = None
            self._clear()
            self._say(html.escape(str(exc)), problem=True)
            return
        except Exception as exc:  # noqa: BLE001 - a widget callback must not raise
            self.result = self.analysis = None
            self._clear()
            self._say(
                "The class could not be read because of an error in the tutor "
                f"({html.escape(type(exc).__name__)}: {html.escape(str(exc))}). Please "
                "report it; the trainees' files are untouched.",
                problem=True,
            )
            return
        self._draw(time.perf_counter() - started)

    def _reading(self, done: int, total: int) -> None:
        """Say how many files are read so far (at most twice a second)."""
        now = time.perf_counter()
        if done < total and now - self._said_at < 0.5:
            return
        self._said_at = now
        self._say(f"Reading the class: {done} of {plural(total, 'file')}…")

    def _folder_changed(self) -> None:
        if not self._rehearsing:
            self.refresh()

    def _clear(self) -> None:
        for part in (self.beside, self.tests, self.trainees, self.problems, self.figure_caption):
            part.value = ""
        self.figure.value = ""
        self.figure.layout.display = "none"

    def _draw(self, seconds: float) -> None:
        result, analysis = self.result, self.analysis
        trainees = result.trainees
        n_counted = int((trainees.counted_runs > 0).sum()) if len(trainees) else 0
        stamp = time.strftime("%H:%M:%S")
        if not result.files and not len(trainees):
            self._clear()
            self._say(
                f"No run files in {html.escape(result.source)} yet. Trainees' runs appear "
                "here as they save them; press Refresh (or tick Refresh every) to look "
                "again, or try a simulated class."
            )
            return
        others = len(result.other_experiment)
        aside = (
            f" {others} files of Experiment {3 - result.experiment} are set aside (choose "
            "that experiment above to see them)."
            if others
            else ""
        )
        self._say(
            f"<b>{plural(len(result.runs), 'run')}</b> counted from "
            f"<b>{plural(n_counted, 'trainee')}</b> "
            f"in {html.escape(result.source)}; {len(result.not_counted)} files not "
            f"counted.{aside} Read at {stamp} in {seconds:.1f} s."
            + html.escape(f" {result.cannot_read_note}".rstrip())
            + "".join(f" {html.escape(as_sentence(n))}" for n in result.notes)
        )
        if result.runs.empty:
            self.beside.value = "<p>No finished run of this experiment yet.</p>"
            self.figure.layout.display = "none"
            self.figure_caption.value = ""
        elif paper_runs(result.runs, result.experiment).empty:  # runs beyond the paper only
            self.beside.value = _table(analysis["beside"], BESIDE_LEGEND)
            self.figure.layout.display = "none"
            self.figure_caption.value = ""
        else:
            self.beside.value = _table(analysis["beside"], BESIDE_LEGEND)
            fig = class_figure(result, analysis)
            buffer = io.BytesIO()
            fig.savefig(buffer, format="png", dpi=90)
            import matplotlib.pyplot as plt

            plt.close(fig)
            png = base64.b64encode(buffer.getvalue()).decode("ascii")
            self.figure.value = (
                f'<img src="data:image/png;base64,{png}" style="width:100%" alt="'
                + html.escape(self._figure_text(), quote=True)
                + '">'
            )
            self.figure.layout.display = ""
            self.figure_caption.value = (
                f'<p style="{WRAP_WORDS}"><i>{html.escape(self._caption())}</i></p>'
            )
        self.tests.value = self._tests_html()
        lacking = trainees[~trainees.complete] if len(trainees) else trainees
        self.trainees.value = _list(
            [
                f"<b>{html.escape(t.trainee)}</b> ({html.escape(t.trainee_key)}): "
                f"{html.escape(t.missing)}"
                for _, t in lacking.iterrows()
            ],
            "Every trainee has finished every run.",
        )
        self.problems.value = _list(
            [
                f"<b>{html.escape(f.file)}</b>: {html.escape(f.kind)} — {html.escape(f.reason)}"
                for f in result.not_counted
            ],
            "Every run file of this experiment was counted.",
        )

    def _caption(self) -> str:
        """The figure's caption, from what its η panel draws (:func:`.figures.eta_caption`)."""
        from .figures import eta_caption  # matplotlib only once there is a figure

        reference = self.analysis["simulated"]["runs"]
        what = eta_caption(self.result.experiment, "trainees", reference)
        return f"The class's η per condition. {what[0].upper()}{what[1:]}."

    def _figure_text(self) -> str:
        """The figure in words (its alternative text): η per condition, class and paper."""
        from .figures import PLOT_KINDS

        beside = self.analysis["beside"]
        measure = readable_label(self.analysis["measure"])
        kind = "Box plots" if PLOT_KINDS[self.result.experiment] == "box" else "Bar charts"
        parts = [
            f"{c}: class {percent(row.iloc[1])}, paper {percent(row.iloc[2])}"
            for c, row in beside.iterrows()
            if row.iloc[0]
        ]
        return f"{kind} of the class's η per condition; {measure}: " + "; ".join(parts)

    def _tests_html(self) -> str:
        from .class_report import tested_lines

        parts = []
        for who, label in (("class", "This class"), ("simulated", "Simulated, same size")):
            lines = tested_lines(self.analysis[who], self.result.experiment, label)
            if who == "class":  # the conditions beyond the paper, each against its own
                lines += beyond_lines(self.analysis["beyond"])
            parts.append(  # lines kept as they are, wrapped between words (no <pre>)
                f'<div class="lfd-class-lines" style="white-space:pre-wrap;{WRAP_WORDS};'
                'font-family:var(--jp-code-font-family, monospace)">'
                + html.escape("\n".join(lines))
                + "</div>"
            )
        return "".join(parts)

    # ------------------------------------------------------------ refreshing by itself

    def _auto(self, on: bool) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if on:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:
                try:
                    loop = asyncio.get_event_loop_policy().get_event_loop()
                except RuntimeError:
                    loop = None
            if loop is None or not loop.is_running():
                self.auto.value = False
                self._say(
                    "Refreshing by itself needs a running notebook (JupyterLab or Voila): "
                    "press Refresh instead.",
                    problem=True,
                )
                return
            self._timer = loop.call_later(self.seconds.value, self._tick)

    def _tick(self) -> None:
        self._timer = None
        if not self.auto.value:
            return
        self.refresh()
        self._auto(True)

    # ------------------------------------------------------------ files

    def results_folder(self) -> Path:
        """Where Save writes: ``<class folder>_results`` beside the class folder."""
        folder = self.class_folder().resolve()
        return check_path_length(
            folder.parent / f"{folder.name}_results", "the results folder", room=OUT_ROOM
        )

    def save(self) -> None:
        """Write the class's CSV, JSON, report and figure (as ``lfd-tutor class --out``)."""
        if self.result is None:
            self._say("There is nothing to save: the class could not be read.", problem=True)
            return
        try:
            out = self.results_folder()
            paths = save_class(self.result, self.analysis, out)
        except TutorError as exc:
            self._say(html.escape(str(exc)), problem=True)
            return
        self._say(f"Saved {len(paths)} files in {html.escape(str(out))}.")

    def rehearse(self, n: int = 30) -> Path:
        """Show a class of ``n`` simulated trainees (2 runs unfinished, 3 files spoiled)."""
        from .simulated_class import write_simulated_class

        folder = Path(tempfile.mkdtemp(prefix="lfd-simulated-class-")) / "class"
        spec = EXPERIMENTS[self.experiment.value]
        n = n if spec.within_subjects else spec.n_teachers  # Experiment 2: 4 conditions of 9
        self._say(f"Writing a simulated class ({plural(n, 'trainee')})…")
        write_simulated_class(folder, self.experiment.value, n, seed=1, unfinished=2, damaged=3)
        self._rehearsing = True  # one read, not one for the new folder and one here
        try:
            self.folder.value = str(folder)
        finally:
            self._rehearsing = False
        self.refresh()
        return folder


def class_dashboard(folder=None, experiment: int = 1, refresh_seconds: int | None = None):
    """Build and show the dashboard (notebook 05); returns the :class:`ClassDashboard`.

    With ``TUTOR_HEADLESS=1`` and no ``folder`` (and no ``TUTOR_CLASS_DIR``), it shows a
    simulated class instead of an empty runs folder.
    """
    from IPython.display import display

    rehearse = folder is None and headless() and not os.environ.get(CLASS_DIR_ENV, "").strip()
    board = ClassDashboard(folder, experiment, refresh_seconds)
    if rehearse:
        board.rehearse()
    display(board.widget)
    return board
