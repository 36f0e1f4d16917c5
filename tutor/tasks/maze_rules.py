"""The rule guidance of Experiment 1's VR condition (Sena & Howard, "Experiment 1").

The paper's three rules, applied to the test start points B^ and the latest R^:

1. provide one demonstration, starting from anywhere in the start zone;
2. provide demonstrations within 4 cm of the starting point of the first
   demonstration, until it is surrounded by successful (green) test trajectories;
3. continue providing demonstrations within 4 cm of the starting point of
   successful trajectories, in the area with the greatest number of failed (red)
   trajectories.

"Surrounded by green" is read as: every test start point within 4 cm of the first
demo's start succeeds. For rule 3 the tutor marks the green start point that has the
most red start points within 4 cm of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["RuleAdvice", "advise", "advise_from", "followed", "RULE_RADIUS"]

RULE_RADIUS = 0.04  #: 4 cm


@dataclass(frozen=True)
class RuleAdvice:
    """Where the rules say the next demo should start.

    Attributes
    ----------
    rule : int
        1, 2 or 3 as in the paper; 0 when every test start point already succeeds.
    center : ndarray (2,) or None
        Centre of the circle the next start should lie in (None: anywhere in I).
    radius : float
    message : str
    """

    rule: int
    center: np.ndarray | None
    radius: float
    message: str

    def to_dict(self) -> dict:
        return {
            "rule": self.rule,
            "center": None if self.center is None else self.center.tolist(),
            "radius": self.radius,
            "message": self.message,
        }


def advise(task, session, radius: float = RULE_RADIUS) -> RuleAdvice:
    """The rule that applies now, for a session on a :class:`~tutor.tasks.maze.MazeTask`."""
    record = session.latest
    if record is None:
        return advise_from(task, None, None, radius)
    return advise_from(task, record.passed, task.test_point_of(session.demos[0]), radius)


def advise_from(task, passed, first_start, radius: float = RULE_RADIUS) -> RuleAdvice:
    """The rule for R^'s pass/fail mask ``passed`` (n,) and the first demo's start (2,).

    ``passed`` None means no demo yet.
    """
    if passed is None:
        return RuleAdvice(
            1, None, radius, "Rule 1: give one demonstration, starting anywhere in the start zone."
        )
    starts = task.test_points
    passed = np.asarray(passed, dtype=bool)
    first = np.asarray(first_start, dtype=float)
    near_first = np.linalg.norm(starts - first, axis=1) <= radius
    if not passed[near_first].all():
        return RuleAdvice(
            2,
            first,
            radius,
            "Rule 2: start your next demonstration inside the circle, within 4 cm of where "
            "your first one started, until all the start points around it are green.",
        )
    if passed.all():
        return RuleAdvice(0, None, radius, "Every start point succeeds: you can finish.")
    green, red = starts[passed], starts[~passed]
    reds_near = (np.linalg.norm(green[:, None] - red[None], axis=2) <= radius).sum(axis=1)
    best = np.flatnonzero(reds_near == reds_near.max())
    if reds_near.max() == 0:  # no green point borders red: go towards the nearest red
        gap = np.linalg.norm(green[:, None] - red[None], axis=2).min(axis=1)
        best = np.flatnonzero(gap == gap.min())
    centroid = red.mean(axis=0)
    pick = best[np.argmin(np.linalg.norm(green[best] - centroid, axis=1))]
    return RuleAdvice(
        3,
        green[pick],
        radius,
        "Rule 3: start your next demonstration inside the circle, within 4 cm of a green "
        f"start point, where most start points still fail ({task.describe_where(~passed)}).",
    )


def followed(advice: RuleAdvice, start) -> bool:
    """Whether a demo starting at ``start`` (2,) followed ``advice``."""
    if advice.center is None:
        return True
    return bool(np.linalg.norm(np.asarray(start, float) - advice.center) <= advice.radius + 1e-9)
