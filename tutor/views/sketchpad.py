"""The maze sketchpad: an anywidget on which the teacher draws demonstrations.

The stroke is drawn in the browser as it happens and reaches Python once, on
release, as ``stroke`` (a list of [t, x, y] in seconds and metres); the picture
(the maze, R^ green/red, the demos b in blue, numbered, and an optional rule circle)
is redrawn by the browser when Python updates the traits. Setting ``stroke`` from
Python has the same effect as drawing, which is how headless runs feed demos.
"""

from __future__ import annotations

from pathlib import Path

import anywidget
import numpy as np
import traitlets

__all__ = ["Sketchpad", "layout_spec"]

#: samples per realisation sent to the browser (R^ has 140 of them)
BROWSER_SAMPLES = 50


def layout_spec(layout) -> dict:
    """The maze geometry as the browser needs it (metres)."""

    def box(b):
        return {"x": [b.x0, b.x1], "y": [b.y0, b.y1], "name": b.name}

    return {
        "workspace": box(layout.workspace),
        "start_zone": box(layout.start_zone),
        "obstacles": [box(o) for o in layout.obstacles],
        "target": {"center": layout.target_center.tolist(), "diameter": layout.target_diameter},
    }


def _thin(paths: np.ndarray, n: int = BROWSER_SAMPLES) -> list:
    """Paths (B, T, 2) down-sampled to n points each, rounded to 0.1 mm, as lists."""
    paths = np.asarray(paths)
    if paths.size == 0:
        return []
    idx = np.unique(np.linspace(0, paths.shape[1] - 1, n).round().astype(int))
    return np.round(paths[:, idx], 4).tolist()


class Sketchpad(anywidget.AnyWidget):
    """Canvas for drawing maze demonstrations and showing the feedback picture."""

    _esm = Path(__file__).parent / "static" / "sketchpad.js"

    layout = traitlets.Dict().tag(sync=True)
    width_px = traitlets.Int(360).tag(sync=True)
    demos = traitlets.List().tag(sync=True)
    realisations = traitlets.List().tag(sync=True)
    passed = traitlets.List().tag(sync=True)
    shown = traitlets.List().tag(sync=True)
    rule_circle = traitlets.Dict(allow_none=True, default_value=None).tag(sync=True)
    note = traitlets.Unicode("").tag(sync=True)
    enabled = traitlets.Bool(True).tag(sync=True)
    stroke = traitlets.List().tag(sync=True)
    stroke_count = traitlets.Int(0).tag(sync=True)
    render_id = traitlets.Int(0).tag(sync=True)

    def show(self, demos, realisations=None, passed=None, shown=(), rule_circle=None, note=""):
        """Update the whole picture in one message.

        Parameters
        ----------
        demos : sequence of ndarray (T, 3)
        realisations : ndarray (n, T, 2), optional
        passed : ndarray of bool (n,), optional
        shown : sequence of int
            Indices of the realisations to draw (r).
        rule_circle : dict with "center" (2,) and "radius", optional
        note : str
        """
        with self.hold_sync():
            self.demos = _thin(np.array([d[:, 1:] for d in demos])) if len(demos) else []
            self.realisations = [] if realisations is None else _thin(realisations)
            self.passed = [] if passed is None else [bool(p) for p in passed]
            self.shown = [int(i) for i in shown]
            self.rule_circle = rule_circle
            self.note = note
            self.render_id = self.render_id + 1

    def draw(self, demo) -> None:
        """Feed a stroke (T, 3) from Python exactly as if it had been drawn."""
        self.stroke = np.asarray(demo, dtype=float).tolist()
        self.stroke_count = self.stroke_count + 1
