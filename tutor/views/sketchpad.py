"""The maze sketchpad: an anywidget on which the teacher draws demonstrations.

The stroke is drawn in the browser as it happens and reaches Python once, on
release, as ``stroke`` (a list of [t, x, y] in seconds and metres). A stroke can also be
drawn with the keyboard (arrow keys move a cursor, Space places a waypoint, Enter places
the last one and finishes, Backspace takes one back, Escape cancels); it arrives the same
way. Setting ``stroke`` from Python has the same effect as drawing, which is how headless
runs feed demos.

The picture (the maze, the realisations R^ shown, the demos b in blue, numbered, an
optional rule circle, and beside the counts a zoomed view of the target) is redrawn by
the browser when Python updates the traits. Paths travel as float32 bytes (binary
websocket frames, no JSON), and only the traits that changed are sent. A failing
realisation is drawn dashed, with a mark where it went wrong (× where it hit an obstacle
or left the maze, ○ where it ended outside the target), and the causes are counted under
the picture.
"""

from __future__ import annotations

import time
from pathlib import Path
from types import SimpleNamespace

import anywidget
import numpy as np
import traitlets

from ..errors import InvalidParameterError
from . import style
from .maze_reasons import main_causes, reason_summary

__all__ = ["Sketchpad", "layout_spec", "KEYBOARD_HELP", "DISCONNECTED"]

#: samples per realisation sent to the browser (R^ has 200 of them)
BROWSER_SAMPLES = 50

#: what the sketchpad's label tells a screen reader (and the help line shows)
KEYBOARD_HELP = (
    "Maze sketchpad. Draw a demonstration from the start zone to the target with the "
    "mouse, or with the keyboard: arrow keys move the cursor (with Shift, 1 cm steps), "
    "Space places a waypoint, Enter places the last waypoint and finishes the "
    "demonstration, Backspace removes the last waypoint, Escape cancels."
)

#: what a stroke or key press on a sketchpad whose kernel is gone shows
DISCONNECTED = "This tutor is no longer connected: run the cell again."

#: the marks of :mod:`tutor.views.maze_reasons` kinds, as the browser draws them
MARK_CODES = {"obstacle": 1, "outside": 2, "start": 3, "miss": 4, "other": 4}


def layout_spec(layout) -> dict:
    """The maze geometry as the browser needs it (metres)."""

    def box(b):
        return {"x": [b.x0, b.x1], "y": [b.y0, b.y1], "name": b.name, "label": b.label}

    return {
        "workspace": box(layout.workspace),
        "start_zone": box(layout.start_zone),
        "obstacles": [box(o) for o in layout.obstacles],
        "target": {"center": layout.target_center.tolist(), "diameter": layout.target_diameter},
    }


def _thin(paths, n: int = BROWSER_SAMPLES) -> np.ndarray:
    """Paths (B, T, 2) down-sampled to n points each (first and last kept), float32."""
    paths = np.asarray(paths, dtype=float)
    if paths.size == 0:
        return np.zeros((0, n, 2), dtype=np.float32)
    idx = np.unique(np.linspace(0, paths.shape[1] - 1, n).round().astype(int))
    return np.ascontiguousarray(paths[:, idx], dtype=np.float32)


def _unpack(data: bytes, samples: int) -> list:
    """float32 bytes back to nested lists (B, samples, 2)."""
    flat = np.frombuffer(data, dtype=np.float32)
    return flat.reshape(-1, samples, 2).astype(float).tolist() if flat.size else []


class _MazeLayout:
    """The geometry :func:`main_causes` needs, read back from a :func:`layout_spec` dict."""

    def __init__(self, spec: dict):
        self.target_center = np.asarray(spec["target"]["center"], dtype=float)
        self.target_radius = float(spec["target"]["diameter"]) / 2
        self.obstacles = tuple(
            SimpleNamespace(label=o.get("label") or o.get("name") or f"obstacle {i + 1}")
            for i, o in enumerate(spec.get("obstacles", ()))
        )


class Sketchpad(anywidget.AnyWidget):
    """Canvas for drawing maze demonstrations and showing the feedback picture.

    Parameters
    ----------
    maze : dict
        The geometry from :func:`layout_spec`.
    width_px : int
        Width of the drawing area in pixels.
    layout : dict, optional
        The old name of ``maze`` (kept for callers not yet changed). An
        :class:`ipywidgets.Layout` is the widget's layout, as for any widget.
    """

    _esm = Path(__file__).parent / "static" / "sketchpad.js"

    maze = traitlets.Dict().tag(sync=True)
    palette = traitlets.Dict().tag(sync=True)
    help_text = traitlets.Unicode(KEYBOARD_HELP).tag(sync=True)
    disconnected_text = traitlets.Unicode(DISCONNECTED).tag(sync=True)
    width_px = traitlets.Int(360).tag(sync=True)
    samples = traitlets.Int(BROWSER_SAMPLES).tag(sync=True)
    demo_xy = traitlets.Bytes(b"").tag(sync=True)  #: float32 (M, samples, 2)
    real_xy = traitlets.Bytes(b"").tag(sync=True)  #: float32 (n, samples, 2)
    passed = traitlets.List().tag(sync=True)
    shown = traitlets.List().tag(sync=True)
    marks = traitlets.List().tag(sync=True)  #: [x, y, code] per shown failure
    summary = traitlets.Unicode("").tag(sync=True)
    rule_circle = traitlets.Dict(allow_none=True, default_value=None).tag(sync=True)
    note = traitlets.Unicode("").tag(sync=True)
    enabled = traitlets.Bool(True).tag(sync=True)
    #: whatever the page sent as the last stroke, checked by its observer
    #: (:func:`tutor.payloads.check_stroke`), not by the trait, so that a bad one
    #: is said in the panel instead of raising inside the widget's message handler
    stroke = traitlets.Any([]).tag(sync=True)
    stroke_count = traitlets.Int(0).tag(sync=True)
    render_id = traitlets.Int(0).tag(sync=True)
    #: kernel time (ms) from the last stroke's arrival to the picture answering it
    python_ms = traitlets.Float(0.0).tag(sync=True)

    def __init__(self, maze=None, *, layout=None, **kwargs):
        if isinstance(layout, dict):  # the old keyword for the maze geometry
            if maze is not None:
                raise InvalidParameterError(
                    "give the maze geometry once: Sketchpad(maze=layout_spec(...))"
                )
            maze, layout = layout, None
        if maze is None:
            raise InvalidParameterError(
                "the sketchpad needs the maze: Sketchpad(maze=layout_spec(task.layout))"
            )
        if layout is not None:
            kwargs["layout"] = layout
        palette = {
            **style.STATUS_COLOURS,
            "obstacle": style.OBSTACLE,
            "zone": style.START_ZONE,
            "target": style.TARGET,
            "rule": style.RULE,
        }
        super().__init__(maze=maze, palette=palette, **kwargs)
        self._geometry = _MazeLayout(maze)
        self._stroke_at = None
        # registered first, so it runs before the tutor's own observer of the stroke
        self.observe(self._stroke_arrived, names="stroke_count")

    def _stroke_arrived(self, change) -> None:
        self._stroke_at = time.perf_counter()

    # ------------------------------------------------------------ read back

    @property
    def demos(self) -> list:
        """The demos as drawn: (M, samples, 2) nested lists (metres)."""
        return _unpack(self.demo_xy, self.samples)

    @property
    def realisations(self) -> list:
        """The realisations as drawn: (n, samples, 2) nested lists (metres)."""
        return _unpack(self.real_xy, self.samples)

    # ------------------------------------------------------------ update

    def show(
        self,
        demos,
        realisations=None,
        passed=None,
        shown=(),
        rule_circle=None,
        note="",
        causes=None,
    ):
        """Update the picture in one message (traits that did not change are not sent).

        Parameters
        ----------
        demos : sequence of ndarray (T, 3)
        realisations : ndarray (n, T, 2), optional
        passed : ndarray of bool (n,), optional
        shown : sequence of int
            Indices of the realisations to draw (r).
        rule_circle : dict with "center" (2,) and "radius", optional
        note : str
        causes : sequence of tuple of Reason (n,), optional
            Why each realisation fails (empty where it passes), as the task's ``judge``
            gives them (``DemoStep.causes``). With them, each shown failure is
            marked where it went wrong and the causes are counted under the picture.
        """
        shown = [int(i) for i in shown]
        marks, summary = [], ""
        if causes is not None and realisations is not None and shown:
            if len(causes) != len(realisations):
                raise InvalidParameterError(
                    f"causes has {len(causes)} entries for {len(realisations)} "
                    "realisations; give one per realisation (empty where it passes)"
                )
            found = main_causes(realisations, causes, self._geometry)
            for i in shown:
                f = found[i]
                if f.kind != "pass":
                    marks.append([round(f.point[0], 5), round(f.point[1], 5), MARK_CODES[f.kind]])
            summary = reason_summary(found, shown)
        demo_paths = [np.asarray(d)[:, 1:3] for d in demos]
        with self.hold_sync():
            self.demo_xy = b"".join(_thin(p[None]).tobytes() for p in demo_paths)
            self.real_xy = b"" if realisations is None else _thin(realisations).tobytes()
            self.passed = [] if passed is None else [bool(p) for p in passed]
            self.shown = shown
            self.marks = marks
            self.summary = summary
            self.rule_circle = rule_circle
            self.note = note
            if self._stroke_at is not None:
                self.python_ms = round(1000 * (time.perf_counter() - self._stroke_at), 1)
                self._stroke_at = None
            self.render_id = self.render_id + 1

    def draw(self, demo) -> None:
        """Feed a stroke (T, 3) from Python exactly as if it had been drawn."""
        self.stroke = np.asarray(demo, dtype=float).tolist()
        self.stroke_count = self.stroke_count + 1
