r"""The teacher model shared by both tasks: interpretation omega and demonstration Omega.

Sena & Howard, "Modelling the Teacher": the teacher forms an estimate of what the robot
can do, :math:`\tilde R = \omega(r, Q)`, from the realisations r they are shown and
their human factors Q, and chooses the next demonstration
:math:`b_{m+1} = \Omega(\tilde R, \tilde B, b_m, Q)`.

The simulated teacher's :math:`\tilde R` is a belief, per test point of B^, that the
robot succeeds there (:class:`Belief`). It is built by the same rules in every
test point (the rules are in :meth:`Belief.estimate`):

1. **Prior** (Q): before any evidence, the teacher believes the robot can do the task
   everywhere once it has had ``enough_demos`` demonstrations (``enough_maze`` or
   ``enough_pickplace``), and nowhere before.
2. **Own demos**: the robot can do what it was shown (demonstrated test points pass).
3. **What was seen** (r): a realisation seen passing makes the teacher believe its
   neighbours pass too (within :data:`NEAR` of the grid's width), and so does every
   test point *between* seen successes (inside their convex hull); a realisation
   seen failing marks its neighbourhood as failing. What was seen last wins over
   the prior; the latest sight of a test point replaces earlier ones, and a
   demonstration at a failure counts, for the teacher, as having mended it.

The demonstration function (:class:`TeacherModel`) then picks where the next
demonstration goes, again by one rule for every condition:

a. (pick-and-place) if the robot was just seen failing at the plant the teacher
   demonstrated, or seeing it there makes them notice their demo went to another
   plant (``notice_rate``), they take the demo back and show it again (at most
   twice in a row);
b. otherwise, if some realisation is remembered failing, they aim at the densest
   failing region (with their aiming imprecision ``aim_sd``), unless this time they
   go by their own plan regardless (chance 1 - ``heed``);
c. otherwise they follow their own plan of where demos should go (their idea of B,
   :math:`\tilde B`: around ``plan_focus`` with scatter ``plan_spread_*``, weighing
   ``plan_choices_*`` places and taking the one farthest from their demos), now and then
   repeating a demo on purpose (``repeat_rate``).

Between runs (Experiment 2) the teacher remembers where they saw the robot fail and
starts the next run's plan there: r can change Q (the paper's hypothesis H4).

They stop when the share of B^ they believe succeeds reaches ``satisfaction``, when
``patience`` runs out, or (pick-and-place) when the 15-minute clock does.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import Delaunay, QhullError

from ..framework.record import Trainee
from .traits import TeacherTraits

__all__ = ["Belief", "TeacherModel", "NEAR", "CLUSTER", "SIMULATED", "simulated_clock"]

#: who teaches a simulated run (its record names no person)
SIMULATED = Trainee("simulated teacher", "simulated")


def simulated_clock() -> str:
    """The stamp of every event of a simulated run: fixed, so a seed gives the same record."""
    return "2000-01-01T00:00:00.000Z"

#: a success (failure) seen at one test point is believed to hold this close to it
#: (fraction of the width of B^: 2.3 cm in the maze, about one plant in the tray)
NEAR = 0.12
#: radius of the "region" a teacher sees as one red cluster (fraction of the width)
CLUSTER = 0.2


class Belief:
    r"""The teacher's estimate :math:`\tilde R` of where the robot succeeds.

    Parameters
    ----------
    points : ndarray (n, 2)
        Where the test points of B^ lie, in the task's units (metres).
    width : float
        The width of B^ in the same units (distances are taken relative to it).
    enough_demos : int
        The prior: how many demos the teacher believes are enough.
    """

    def __init__(self, points, width: float, enough_demos: int):
        self.points = np.asarray(points, dtype=float)
        self.width = float(width)
        self.enough_demos = int(enough_demos)
        n = len(self.points)
        #: last sight of each test point: -1 never seen, 0 seen failing, 1 seen passing
        self.seen = np.full(n, -1, dtype=np.int8)
        #: test points the teacher has demonstrated (and not taken back)
        self.demonstrated = np.zeros(n, dtype=bool)
        #: every test point seen failing, in the order first seen (what they may remember)
        self.failures_seen: list[int] = []
        gap = self.points[:, None, :] - self.points[None, :, :]
        self._near = np.linalg.norm(gap, axis=2) <= NEAR * self.width + 1e-12

    def demonstrate(self, index: int) -> None:
        """The teacher demonstrated test point ``index``: failures seen near it count as fixed.

        (Until they see the robot again there: a demo where it failed is meant to mend it.)
        """
        self.demonstrated[index] = True
        self.seen[self._near[index] & (self.seen == 0)] = -1

    def observe(self, shown, passed) -> None:
        """Remember what the robot was seen doing at the test points ``shown``."""
        shown = np.asarray(shown, dtype=int)
        passed = np.asarray(passed, dtype=bool)
        self.seen[shown] = passed.astype(np.int8)
        for index in shown[~passed]:
            if int(index) not in self.failures_seen:
                self.failures_seen.append(int(index))

    def estimate(self, n_demos: int) -> np.ndarray:
        r"""R~: bool (n,), whether the teacher believes the robot succeeds at each test point."""
        belief = np.full(len(self.points), n_demos >= self.enough_demos)
        belief |= self.demonstrated
        ok = self.seen == 1
        if ok.any():
            belief |= self._near[ok].any(axis=0)
            belief |= self._between(ok)
        bad = self.seen == 0
        if bad.any():
            belief &= ~self._near[bad].any(axis=0)
        belief[ok] = True
        return belief

    def coverage(self, n_demos: int) -> float:
        """The share of B^ the teacher believes the robot can do."""
        return float(self.estimate(n_demos).mean())

    def _between(self, ok) -> np.ndarray:
        pts = self.points[ok]
        if len(pts) < 3:
            return np.zeros(len(self.points), dtype=bool)
        try:
            hull = Delaunay(pts)
        except QhullError:  # collinear: no area between them
            return np.zeros(len(self.points), dtype=bool)
        return hull.find_simplex(self.points, tol=1e-9) >= 0

    def worst_region(self, within=None) -> np.ndarray | None:
        """Where the picture looks worst: a large red region away from the demos, or None.

        Each test point seen failing scores the number of failures within
        :data:`CLUSTER` of it, weighted by how far it is from the nearest demo (up to
        CLUSTER away): a person goes where much is red *and* nothing was shown yet.
        Returns the centre of the failures around the best-scoring one. ``within``
        (bool mask over B^) limits where the teacher looks (e.g. a rule's circle).
        """
        failing = self.seen == 0
        if within is not None:
            failing &= np.asarray(within, dtype=bool)
        bad = np.flatnonzero(failing)
        if bad.size == 0:
            return None
        pts = self.points[bad]
        close = np.linalg.norm(pts[:, None] - pts[None], axis=2) <= CLUSTER * self.width
        score = close.sum(axis=1).astype(float)
        if self.demonstrated.any():
            shown = self.points[self.demonstrated]
            gap = np.linalg.norm(pts[:, None] - shown[None], axis=2).min(axis=1)
            score *= 0.25 + np.minimum(gap / (CLUSTER * self.width), 1.0)
        best = int(np.argmax(score))
        return pts[close[best]].mean(axis=0)


class TeacherModel:
    """What a simulated teacher does regardless of the task: plan, aim, believe, stop.

    Parameters
    ----------
    traits : TeacherTraits
    rng : numpy Generator
        The teacher's own randomness (hand, aim, slips, plan).
    points : ndarray (n, 2)
        Where the test points lie (task units).
    lower, upper : array-like (2,)
        Corners of the region the teacher may start demos in (task units).
    task : {"maze", "pickplace"}
        Which of the traits' per-task values apply: the prior count
        (``enough_*``), how widely their own plan scatters demos (``plan_spread_*``, unit
        box) and how many plan places they weigh for the next demo, taking the one
        farthest from the demos already given (``plan_choices_*``).
    """

    def __init__(self, traits: TeacherTraits, rng, points, lower, upper, task: str):
        self.traits = traits
        self.spread = traits.plan_spread(task)
        self.choices = traits.plan_choices(task)
        enough_demos = traits.enough_demos(task)
        self.rng = rng
        self.points = np.asarray(points, dtype=float)
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.width = float(self.upper[0] - self.lower[0])
        self.belief = Belief(self.points, self.width, enough_demos)
        #: test points to demonstrate first, remembered from an earlier run
        self.lessons: list[int] = []

    # ------------------------------------------------------------- Omega pieces

    def plan_point(self, avoid=()) -> np.ndarray:
        """The next demo from the teacher's own plan (their B~ and habits).

        First the places remembered from an earlier run (:attr:`lessons`) not yet
        demonstrated; else, with chance ``repeat_rate``, one of the demos already given
        (``avoid``) again; else a point around ``plan_focus``: with ``choices`` > 1 the
        one of that many farthest from the demos given, otherwise the first (redrawn up to
        three times if it lands on a demonstrated test point).
        """
        t = self.traits
        avoid = [int(i) for i in avoid]
        while self.lessons:
            index = self.lessons.pop(0)
            if index not in avoid:
                return self.points[index].copy()
        if avoid and self.rng.random() < t.repeat_rate:
            return self.points[int(self.rng.choice(avoid))].copy()
        if self.choices > 1 and avoid:
            # weigh a few places and take the one farthest from the demos given so far
            unit = np.clip(
                np.asarray(t.plan_focus) + self.rng.normal(0, self.spread, (self.choices, 2)), 0, 1
            )
            places = self.lower + unit * (self.upper - self.lower)
            given = self.points[avoid]
            gap = np.linalg.norm(places[:, None] - given[None], axis=2).min(axis=1)
            return places[int(np.argmax(gap))]
        point = None
        for _ in range(4):  # otherwise people do not mean to repeat a demo exactly
            unit = np.clip(np.asarray(t.plan_focus) + self.rng.normal(0, self.spread, 2), 0, 1)
            point = self.lower + unit * (self.upper - self.lower)
            if not avoid or self.nearest(point) not in avoid:
                break
        return point

    def aim(self, point, center=None, radius=None) -> np.ndarray:
        """Where a demo aimed at ``point`` starts: imprecise, inside the region (and circle)."""
        got = np.asarray(point, float) + self.rng.normal(0, self.traits.aim_sd * self.width, 2)
        if center is not None:
            center = np.asarray(center, float)
            gap = got - center
            dist = float(np.linalg.norm(gap))
            if dist > radius:
                got = center + gap * (radius / dist) * 0.98
        return np.clip(got, self.lower, self.upper)

    def nearest(self, point) -> int:
        return int(np.argmin(np.linalg.norm(self.points - np.asarray(point, float), axis=1)))

    def next_target(self, avoid=()) -> tuple[np.ndarray, str]:
        """Rules (b) and (c): aim at the worst region seen, else follow the plan."""
        worst = self.belief.worst_region()
        if worst is not None and self.heeds():
            return self.aim(worst), "red"
        return self.aim(self.plan_point(avoid)), "plan"

    def heeds(self) -> bool:
        """Whether this time the teacher chooses from the picture (chance ``heed``; a
        teacher who always heeds draws nothing, so their run is as before the trait)."""
        return self.traits.heed >= 1.0 or bool(self.rng.random() < self.traits.heed)

    def satisfied(self, n_demos: int) -> bool:
        """Whether the teacher believes the robot now does enough of the task."""
        return self.belief.coverage(n_demos) >= self.traits.satisfaction - 1e-12

    def slips(self) -> bool:
        """Whether this demonstration goes wrong (a slip the teacher does not intend)."""
        return bool(self.rng.random() < self.traits.slip_rate)
