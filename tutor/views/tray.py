"""The pick-and-place tutor's tray map: one button per plant, coloured by what the trainee
may see.

Tray colours (as in the paper's good-versus-bad figure): green, the robot succeeds;
dark red ✗, it fails; blue ●, demonstrated; grey, not shown to the trainee (yet).
Status is never shown by colour alone: each plant's glyph and tooltip say it too. HF
marks the hinted plant ★ (its tooltip says so, and its button has the CSS class
``lfd-hint``). The map is laid out as the 3-D view's default camera sees the tray.
"""

from __future__ import annotations

from collections.abc import Callable

import ipywidgets as w
import numpy as np

from ..tasks.pickplace_protocol import PickPlaceRun
from .style import DEMO, FAIL, PASS, UNKNOWN
from .text import HINT_GLYPH, plain_reason

__all__ = ["TrayMap", "tray_status", "set_trait", "STATUS_WORDS"]

TRAY_COLOURS = {"pass": PASS, "fail": FAIL, "demo": DEMO, "unknown": UNKNOWN}
TRAY_GLYPHS = {"pass": "✓", "fail": "✗", "demo": "●", "unknown": ""}
#: glyph colours that stand out on each status colour
TRAY_TEXT = {"pass": "#000000", "fail": "#ffffff", "demo": "#ffffff", "unknown": "#000000"}
STATUS_WORDS = {
    "pass": "the robot succeeds",
    "fail": "the robot fails",
    "demo": "demonstrated",
    "unknown": "not seen yet",
}
#: the frame of the selected plant's button and of the others
SELECTED_BORDER, UNSELECTED_BORDER = "3px solid #111111", "1px solid #ffffff"


def set_trait(obj, name: str, value) -> None:
    """Set a widget trait only when it changes (each change is a message to the browser)."""
    if getattr(obj, name) != value:
        setattr(obj, name, value)


def tray_status(run: PickPlaceRun, reveal: bool = False) -> np.ndarray:
    """Status of each plant as the trainee may see it: pass, fail, demo or unknown (100,).

    Only the plants the condition showed (r, and the plants tested) get pass or fail;
    ``reveal`` (or a finished or practice run) shows every plant.
    """
    status = np.full(len(run.task.test_points), "unknown", dtype=object)
    rec = run.session.latest
    if rec is None:
        return status
    vis = run.visibility()
    if reveal or vis.everything:  # the paper's good-versus-bad picture: demos in blue
        status[:] = np.where(rec.passed, "pass", "fail")
        status[rec.demonstrated] = "demo"
        return status
    status[rec.demonstrated] = "demo"
    # what the robot just tried is shown as it went, even on a demonstrated plant (RF's
    # replay is of the plant just demonstrated)
    status[vis.shown] = np.where(rec.passed[vis.shown], "pass", "fail")
    return status


#: a plant button's cell on the tray map and the gap between cells (px)
CELL_PX, GAP_PX = 28, 2


class TrayMap:
    """The plant buttons and their grid.

    Parameters
    ----------
    task : PickPlaceTask
    on_select : callable
        ``on_select(plant)``, called when a plant's button is clicked.

    Attributes
    ----------
    buttons : list of ipywidgets.Button
        One per plant, in the task's plant order.
    grid : ipywidgets.GridBox
        The buttons with row and column numbers.
    """

    def __init__(self, task, on_select: Callable[[int], None]):
        self.task = task
        rows, cols = task.scene.rows, task.scene.cols
        self.buttons = [
            w.Button(  # made as most plants are first drawn: each change is a message
                description=TRAY_GLYPHS["unknown"],
                tooltip=f"{task.plant_name(i)}: {STATUS_WORDS['unknown']}",
                style={
                    "button_color": TRAY_COLOURS["unknown"],
                    "text_color": TRAY_TEXT["unknown"],
                },
                layout=w.Layout(
                    width=f"{CELL_PX - 2}px",
                    height=f"{CELL_PX - 2}px",
                    padding="0",
                    border=UNSELECTED_BORDER,
                ),
            )
            for i in range(rows * cols)
        ]
        for i, b in enumerate(self.buttons):
            b.on_click(lambda _, i=i: on_select(i))
        self.grid = self._grid(rows, cols)

    def _grid(self, rows: int, cols: int) -> w.GridBox:
        """The plant buttons laid out as the 3-D view's default camera sees the tray: row 1
        (nearest the robot) at the top, column 1 (the robot's right) on the left; rows and
        columns are numbered as in the plants' names."""
        label = {"layout": w.Layout(width=f"{CELL_PX - 2}px", height=f"{CELL_PX - 2}px")}
        cells = [w.HTML("", **label)]
        cells += [w.HTML(f"<center><small>{c + 1}</small></center>", **label) for c in range(cols)]
        for r in range(rows):
            cells.append(w.HTML(f"<center><small>{r + 1}</small></center>", **label))
            cells += [self.buttons[r * cols + c] for c in range(cols)]
        return w.GridBox(
            cells,
            layout=w.Layout(
                grid_template_columns=f"repeat({cols + 1}, {CELL_PX}px)",
                grid_gap=f"{GAP_PX}px",
                # never narrower than its cells, however little room the page leaves
                min_width=f"{self.width_px}px",
            ),
        )

    @property
    def width_px(self) -> int:
        """The grid's width in pixels: a column of row numbers, one column per plant."""
        cols = self.task.scene.cols
        return (cols + 1) * CELL_PX + cols * GAP_PX

    def draw(self, status, rec, selected: int, hinted: int | None = None) -> None:
        """Colour, glyph and tooltip of every plant; exactly one drawn as selected.

        Status is never shown by colour alone: pass ✓, fail ✗, demonstrated ●, not seen
        blank; the tooltip names the plant, its status and, for a shown failure, why.
        The ``hinted`` plant (HF) gets ★ after its glyph, a tooltip that says so and the
        class ``lfd-hint``; its colour and the selected plant's frame are unchanged.
        """
        for i, b in enumerate(self.buttons):
            kind = status[i]
            words = STATUS_WORDS[kind]
            if kind == "fail" and rec is not None:
                words += f": {plain_reason(self.task, rec.causes[i])}"
            if kind in ("pass", "fail") and rec is not None and rec.demonstrated[i]:
                words += " (demonstrated)"
            chosen, hint = i == selected, i == hinted
            if hint:
                words += "; the robot would learn most from here next (hint)"
            tip = f"{self.task.plant_name(i)}: {words}" + (" (selected)" if chosen else "")
            # one message per widget that changed, not one per trait (a burst of hundreds
            # of messages is what a busy page or server falls behind on)
            with b.hold_sync(), b.style.hold_sync(), b.layout.hold_sync():
                set_trait(b.style, "button_color", TRAY_COLOURS[kind])
                set_trait(b.style, "text_color", TRAY_TEXT[kind])
                set_trait(b, "description", TRAY_GLYPHS[kind] + (HINT_GLYPH if hint else ""))
                set_trait(b, "tooltip", tip)
                set_trait(b.layout, "border", SELECTED_BORDER if chosen else UNSELECTED_BORDER)
                for css, on in (("lfd-selected", chosen), ("lfd-hint", hint)):
                    if on:
                        b.add_class(css)
                    else:
                        b.remove_class(css)
