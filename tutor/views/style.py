"""Colours and small helpers shared by the pictures of :mod:`tutor.views`.

The colours are colour-blind friendly (ColorBrewer "Dark2" green/orange and a
dark blue): a realisation that meets the task criteria is green, one that does
not is orange-red, the teacher's demos are blue.
"""

from __future__ import annotations

import matplotlib.pyplot as plt

__all__ = [
    "PASS",
    "FAIL",
    "DEMO",
    "INCORRECT",
    "AMBIGUOUS",
    "OBSTACLE",
    "START_ZONE",
    "TARGET",
    "new_axes",
]

PASS = "#1b9e77"  #: realisation in B (meets the criteria), covered test condition
FAIL = "#d95f02"  #: realisation not in B, undemonstrated test condition
DEMO = "#1f4e9c"  #: the teacher's demonstrations b
INCORRECT = "#c0142b"  #: incorrect demonstration marker (red)
AMBIGUOUS = "#e69f00"  #: ambiguous demonstration marker (orange)
OBSTACLE = "#4d4d4d"  #: obstacle blocks (dark grey)
START_ZONE = "#d9e6f2"  #: start zone I (light blue-grey)
TARGET = "#7570b3"  #: the target beta (purple: neither pass nor fail)


def new_axes(ax=None, figsize=(5.0, 4.0)):
    """Return ``ax``, or the Axes of a new figure of ``figsize`` inches when it is None."""
    if ax is None:
        _, ax = plt.subplots(figsize=figsize)
    return ax
