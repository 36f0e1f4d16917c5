"""Simulated teachers of Experiment 1 (the maze): NF, VF and VR.

One :class:`MazeTeacher` (one person, one set of traits) teaches under each condition;
the condition changes only what they are shown after each demo:

NF  nothing (r empty): the teacher follows their own plan and stops when their prior
    says the robot has had enough demos.
VF  the whole picture R^ (green/red): they aim at the densest red region, with human
    imprecision, as often as they heed the picture (``heed``; otherwise their own plan),
    and stop when the picture looks green enough to them.
VR  the same picture and the paper's three rules (:mod:`tutor.tasks.maze_rules`):
    they start each demo inside the rule's 4 cm circle, aiming at red inside it.

The belief and stopping rules are the shared ones of :mod:`tutor.teachers.model`.
A demonstration is a stroke through the maze's gaps from the chosen start
(:meth:`~tutor.tasks.maze.MazeLayout.reference_path`) with the teacher's hand wobble;
a slip cuts an obstacle's corner (an incorrect demo).
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from ..tasks.maze import MazeTask
from ..tasks.maze_rules import advise_from, followed
from ..tasks.maze_run import MazeRun
from .model import SIMULATED, TeacherModel, simulated_clock
from .traits import TeacherTraits

__all__ = ["MazeTeacher", "SLIP_SHIFTS"]

#: how a slip bends the stroke: guide point index -> shift (m); each cuts an obstacle corner
SLIP_SHIFTS = {0: (-0.05, 0.03), 2: (0.05, 0.03)}
RATE_HZ = 80.0  #: the paper's tracker rate


class MazeTeacher:
    """One simulated teacher on the maze.

    Parameters
    ----------
    traits : TeacherTraits
    task : MazeTask, optional
    """

    def __init__(self, traits: TeacherTraits, task: MazeTask | None = None):
        self.traits = traits
        self.task = MazeTask() if task is None else task

    def stroke(self, start, rng, slip: bool = False) -> np.ndarray:
        """A recorded demonstration from ``start``: (t in s, x, y in m) at 80 Hz."""
        lay = self.task.layout
        duration = rng.uniform(2.0, 3.5)
        guides = lay.guide_points.copy()
        if slip:
            k = int(rng.choice(list(SLIP_SHIFTS)))
            guides[k] += np.asarray(SLIP_SHIFTS[k]) * rng.uniform(0.9, 1.1)
        return lay.hand_stroke(start, rng, duration, jitter=self.traits.motor_noise,
                               tremor=self.traits.motor_noise / 2, guides=guides,
                               rate_hz=RATE_HZ)

    def teach(self, condition: str, rng, **adaptive) -> MazeRun:
        """Teach one run under ``condition``; returns the finished run.

        VA (beyond the paper) is read as VF is, on the k start points shown
        (``adaptive``: ``selector=``, ``k=``; the random selectors draw from a generator
        spawned from ``rng``).

        Its record tells the story: each demo's ``chosen_by`` (how its start was chosen:
        "plan", "red", "rule 0".."rule 3"), ``mistake`` ("slip" when the hand slipped)
        and, in VR, ``followed_rule``; the attempt's ``stopped`` is "satisfied" or
        "patience". Maze teachers never take a demo back (the paper's maze protocol has
        no undo).
        """
        spec = MazeRun.protocol().condition(condition)
        policy = spec.policy
        if adaptive and not policy.adaptive:
            raise InvalidParameterError(
                f"selector= and k= are only for the adaptive conditions, not {condition}"
            )
        task, t = self.task, self.traits
        rng = np.random.default_rng(rng)
        if policy.adaptive:
            adaptive["rng"] = rng.spawn(1)[0]
        zone, margin = task.layout.start_zone, 0.001
        lower = np.array([zone.x0 + margin, zone.y0 + margin])
        upper = np.array([zone.x1 - margin, zone.y1 - margin])
        model = TeacherModel(t, rng, task.test_points, lower, upper, "maze")
        run = MazeRun.new(
            condition, task, trainee=SIMULATED, clock=simulated_clock, **adaptive
        )
        session = run.session
        first_start = None
        while True:
            m = session.n_demos
            advice = None
            if spec.rules:
                rec = session.latest
                advice = advise_from(task, None if rec is None else rec.passed, first_start)
                start, why = self._follow(model, advice)
            else:
                start, why = model.next_target(avoid=np.flatnonzero(model.belief.demonstrated))
            slip = model.slips()
            record = run.add_demo(
                self.stroke(start, rng, slip),
                followed_rule=None if advice is None else followed(advice, start),
                chosen_by=why,
                mistake="slip" if slip else "",
                given="simulated",
            )
            session = run.session
            if first_start is None:
                first_start = np.asarray(start, float)
            own = task.nearest_test_point(start)
            model.belief.demonstrate(own)
            model.belief.observe(record.shown, record.passed[record.shown])
            if model.satisfied(m + 1):
                run.finish("satisfied")
                break
            if session.n_demos >= t.patience:
                run.finish("patience")
                break
        return run

    @staticmethod
    def _follow(model: TeacherModel, advice):
        """VR: a start inside the rule's circle, aimed at its worst red region (as in VF)."""
        if advice.center is None:  # rule 1 (anywhere) or everything green
            start, _ = model.next_target(avoid=np.flatnonzero(model.belief.demonstrated))
            return start, f"rule {advice.rule}"
        inside = np.linalg.norm(model.points - advice.center, axis=1) <= advice.radius
        # not reading the picture this time: the rule's circle itself, around its centre
        worst = model.belief.worst_region(within=inside) if model.heeds() else None
        target = advice.center if worst is None else worst
        start = model.aim(target, center=advice.center, radius=advice.radius)
        return start, f"rule {advice.rule}"
