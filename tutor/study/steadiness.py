r"""Is the learner steady on a maze? A check on a maze's geometry before it is used.

The paper's lesson is that a demonstration where the robot fails helps it. On some
geometries this learner is *unsteady*: with narrow gaps between the blocks and the walls,
one more demonstration where the robot failed can take efficacy from 97 % down to 72 %,
and a trainee would learn the opposite lesson. Such a maze also looks "hard" to simulated
novices for the wrong reason, so the calibration (:mod:`tutor.study.calibration`) keeps
away from it.

**The check.** A guided teacher gives ``demos`` demonstrations: the first from a fixed
start, each next one from the failing start point farthest from their earlier demos,
each a scripted stroke through the gaps with a careful hand's jitter (3 mm). Over
``seeds`` such teachers it records the demos needed to first reach 90 % coverage and the
*deepest fall*

.. math::

    f = \max_m \big( \max_{j \le m} \varepsilon_j - \varepsilon_m \big),

the most efficacy lost below the best reached so far. The maze is steady when the median
of :math:`f` over the teachers is at most :data:`MAX_FALL`.

Measured on 2026-12-06 (``scripts/maze_fragility.py``, 6 seeds, 8 demos): the bundled
maze (13 cm blocks) and 15 cm blocks are steady (no fall; 90 % in 3 demos); 16 cm blocks
4.5 cm high and 16.9 cm blocks 3.3 cm high fall by a median of 51 % and 35 %.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..framework import TeachingSession
from ..tasks.maze import MazeTask, load_layout

__all__ = ["Steadiness", "steadiness", "steadiness_of_blocks", "MAX_FALL"]

#: the largest median fall of efficacy a maze may show and still count as steady
MAX_FALL = 0.15
#: the careful hand's jitter of the guide points (m)
JITTER = 0.003


@dataclass(frozen=True)
class Steadiness:
    """What :func:`steadiness` found.

    Attributes
    ----------
    needed : tuple
        Per teacher, the demos needed to first reach 90 % (None: not within the demos).
    falls : tuple of float
        Per teacher, the deepest fall of efficacy below the best so far.
    """

    needed: tuple
    falls: tuple

    @property
    def median_fall(self) -> float:
        return float(np.median(self.falls))

    @property
    def steady(self) -> bool:
        return self.median_fall <= MAX_FALL


def _guided_efficacy(task: MazeTask, seed: int, demos: int) -> list[float]:
    layout = task.layout
    rng = np.random.default_rng([seed, 11])
    session = TeachingSession(task)
    zone = layout.start_zone
    low = np.array([zone.x0, zone.y0]) + 0.004
    high = np.array([zone.x1, zone.y1]) - 0.004
    start, path = np.array([0.03, 0.03]), []
    for _ in range(demos):
        stroke = layout.reference_path(start, rng, jitter=JITTER)
        r = session.add_demo(stroke)
        path.append(float(r.efficacy))
        fail = task.test_points[~r.passed]
        if len(fail) == 0:
            break
        mine = np.array([task.test_point_of(d) for d in session.demos])
        far = np.linalg.norm(fail[:, None] - mine[None], axis=2).min(axis=1)
        start = np.clip(fail[np.argmax(far)], low, high)
    return path


def steadiness(layout=None, seeds: int = 6, demos: int = 8) -> Steadiness:
    """The steadiness check on ``layout`` (default: the bundled maze)."""
    task = MazeTask(load_layout() if layout is None else layout)
    needed, falls = [], []
    for seed in range(seeds):
        path = np.asarray(_guided_efficacy(task, seed, demos))
        reached = np.flatnonzero(path >= 0.9)
        needed.append(int(reached[0]) + 1 if len(reached) else None)
        falls.append(float(np.max(np.maximum.accumulate(path) - path)))
    return Steadiness(tuple(needed), tuple(falls))


@lru_cache(maxsize=256)
def steadiness_of_blocks(blocks: tuple) -> Steadiness:
    """:func:`steadiness` of the bundled maze with its blocks set to ``blocks`` (reach,
    low, height, gap), remembered per geometry (a calibration asks again and again)."""
    return steadiness(load_layout().with_blocks(*blocks))
