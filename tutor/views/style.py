"""Colours, line styles and small helpers shared by the pictures of :mod:`tutor.views`.

Every status has a colour and, where it is drawn as a line, a line style, chosen so
that each pair of statuses differs by at least 30 CIELAB units (CIE76 ΔE*ab) for
normal vision and under simulated protanopia and deuteranopia, and so that pass and
fail also differ in lightness (L* 62 against 22) and in line style (solid against
dashed): they stay apart in greyscale and on a washed-out projector.
``tests/test_palette.py`` checks this.

Words to use for them in prose (notebooks, panel texts):

========================  ==============  ===============================
status                    colour word     drawn as
========================  ==============  ===============================
pass (meets criteria)     green           solid line
fail                      dark red        dashed line
undemonstrated            lavender        dot
incorrect demo            wine            ✗ marker
ambiguous demo            yellow          ◆ marker
demo (the teacher's)      blue            thick solid line, numbered
unknown (not evaluated)   grey            dot
========================  ==============  ===============================
"""

from __future__ import annotations

__all__ = [
    "PASS",
    "FAIL",
    "UNDEMONSTRATED",
    "DEMO",
    "INCORRECT",
    "AMBIGUOUS",
    "UNKNOWN",
    "STATUS_COLOURS",
    "STATUS_WORDS",
    "PASS_DASH",
    "FAIL_DASH",
    "OBSTACLE",
    "START_ZONE",
    "TARGET",
    "RULE",
    "new_axes",
    "PROSE",
    "prose",
]

PASS = "#53a846"  #: realisation in B (meets the criteria), covered test point
FAIL = "#661a05"  #: realisation not in B (fails the criteria)
UNDEMONSTRATED = "#9e8ddb"  #: failing test point that no correct demo covers
DEMO = "#013ad1"  #: the teacher's demonstrations b
INCORRECT = "#821652"  #: incorrect demonstration marker
AMBIGUOUS = "#eed12c"  #: ambiguous demonstration marker
UNKNOWN = "#aaaaaa"  #: not evaluated yet (e.g. a plant before the first demo)

#: the line height of the tutors' text. An ipywidgets HTML widget gives its text the
#: height of one input row (28 px), which spaces a wrapped paragraph a line apart
PROSE = "line-height: 1.4"


def prose(inner: str) -> str:
    """``inner`` (HTML) in a block with :data:`PROSE`'s line height."""
    return f'<div style="{PROSE}">{inner}</div>'


#: every status by name, as the palette test and the browser views read them
STATUS_COLOURS = {
    "pass": PASS,
    "fail": FAIL,
    "undemonstrated": UNDEMONSTRATED,
    "incorrect": INCORRECT,
    "ambiguous": AMBIGUOUS,
    "demo": DEMO,
    "unknown": UNKNOWN,
}

#: the colour word for each status, for prose (see the module docstring's table)
STATUS_WORDS = {
    "pass": "green",
    "fail": "dark red",
    "undemonstrated": "lavender",
    "incorrect": "wine",
    "ambiguous": "yellow",
    "demo": "blue",
    "unknown": "grey",
}

PASS_DASH = "solid"  #: line style of a passing realisation
FAIL_DASH = (0, (4, 2.5))  #: line style of a failing realisation (dashed)

OBSTACLE = "#4d4d4d"  #: obstacle blocks (dark grey)
START_ZONE = "#d9e6f2"  #: start zone I (light blue-grey)
TARGET = "#7570b3"  #: the target beta (purple: neither pass nor fail)
RULE = "#e69f00"  #: VR's rule circle (orange, dashed): where the next demo should start


def new_axes(ax=None, figsize=(5.0, 4.0)):
    """Return ``ax``, or the Axes of a new figure of ``figsize`` inches when it is None."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=figsize)
    return ax
