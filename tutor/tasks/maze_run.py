"""One run of Experiment 1 (Sena & Howard, "Experiment 1"): the maze under NF, VF or VR.

NF  no feedback: r is empty while teaching; the picture is revealed after Finish.
VF  visual feedback: r = R^ (every test start point's realisation) after every demo.
VR  visual feedback and the paper's three rules (:mod:`tutor.tasks.maze_rules`); each
    demo's compliance with the rule in force is kept in the run record.

Trainees do the three conditions in the paper's order, NF, VF, VR.

Beyond the paper (not in the paper's order, never by default):

VA  visual feedback, adaptive: after every demo the robot shows only the k = 5 start
    points a selector picks (:mod:`tutor.framework.selectors`) instead of all 140, and
    withholds the totals, as the paper's BF does on the tray.
"""

from __future__ import annotations

import numpy as np

from ..framework import TeachingRun
from ..framework.protocol import experiment
from ..framework.session import DemoStep
from .maze_rules import RuleAdvice, advise, followed

__all__ = ["MazeRun", "PHASE_ORDER"]

#: the paper's order of the three phases (its conditions: :mod:`tutor.framework.protocol`)
PHASE_ORDER = experiment(1).paper_codes


class MazeRun(TeachingRun):
    """A maze run (see the module docstring); ``MazeRun.new("VF", MazeTask())``."""

    experiment = 1
    #: (session, its latest record, the advice): the rule worked out for the next demo
    _advice = None
    #: the rule in force while a demo is being added (VR), else None
    _rule_in_force = None

    def advice(self) -> RuleAdvice:
        """VR: the rule that applies to the next demo (worked out once per step: the
        stroke's check, the picture's circle and the panel's words all read it)."""
        cached = self._advice
        if cached is not None and cached[0] is self.session and cached[1] is self.session.latest:
            return cached[2]
        advice = advise(self.task, self.session)
        self._advice = (self.session, self.session.latest, advice)
        return advice

    def add_demo(self, raw, **options) -> DemoStep:
        """Add a demo; in VR its compliance with the rule in force is recorded.

        ``given`` (how it was given) is "drawn" unless the options say otherwise: a
        maze demo is a stroke drawn on the sketchpad.
        """
        options.setdefault("given", "drawn")
        rules = self.protocol_condition.rules and options.get("followed_rule") is None
        self._rule_in_force = self.advice() if rules else None
        try:
            return super().add_demo(raw, **options)
        finally:
            self._rule_in_force = None

    def _rule_followed(self, demo) -> bool | None:
        rule = self._rule_in_force
        return None if rule is None else followed(rule, self.task.test_point_of(demo))

    def study_columns(self) -> dict:
        """``followed_rules``: the share of demos that followed VR's rule (NaN in a
        condition without the rule, or before any demo)."""
        compliance = self.compliance
        rules = self.protocol_condition.rules and compliance
        return {"followed_rules": float(np.mean(compliance)) if rules else np.nan}

    @property
    def compliance(self) -> list[bool]:
        """VR: whether each demo of the current attempt followed its rule."""
        return [bool(d.followed_rule) for d in self.attempt.demos if d.followed_rule is not None]
