r"""A teaching session: demos in, demo steps out (Sena & Howard, sections
"Learning and Teaching Framework" and "Evaluating Teaching").

After each demo the session refits the learner :math:`\lambda` (warm start),
realises the task from every test point in B^ to get R^, judges R^ with the
task's criteria, and reports efficacy eps, efficiency eta, the change in eps, the
set r of realisations the teacher is shown (by feedback mode) and the failures
(incorrect, ambiguous, undemonstrated; see :mod:`tutor.framework.failures`).

The session is the computation only: it holds no file format and no run state. What a
run is (trainee, condition, every attempt and event) lives in its typed record
(:mod:`tutor.framework.record`), and :class:`tutor.framework.run.TeachingRun` keeps the
two in step and saves the record.

Feedback modes (what r is):

``"none"``      r is empty (NF).
``"all"``       r = R^ (the paper's visual feedback, VF/VR).
``"replay"``    r = the realisation for the last demo's own condition (RF).
``"batch"``     r = a fixed subset of B^ after every demo (BF).
``"selected"``  r = the conditions the teacher asks for (SF).
``"adaptive"``  r = k conditions a selector picks after each demo (AF; beyond the paper,
                :mod:`tutor.framework.selectors`).

In ``"adaptive"`` mode the picks are made from the fitted learner, its realisations and
the demos' conditions (the oracle selector also sees the verdict). A replay that passes
the picks recorded when a demo was first given (``add_demo(..., shown=picks)``) shows
them again, so a saved run reads back as it was taught.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidParameterError
from ..tpgmm import check_seed
from .failures import (
    TeachingWarning,
    Thresholds,
    demo_warnings,
    similarity,
    undemonstrated_warning,
)
from .feedback import FEEDBACK_POLICIES
from .metrics import SessionScore, efficacy, efficiency, run_score
from .selectors import DEFAULT_K, DEFAULT_SELECTOR, SelectionContext, check_k, check_selector
from .task import Reason, Task

__all__ = ["DemoStep", "TeachingSession", "FEEDBACK_MODES"]

FEEDBACK_MODES = tuple(FEEDBACK_POLICIES)


@dataclass(frozen=True)
class DemoStep:
    """What the tutor knows after demo number ``n_demos``.

    Arrays are over the test points B^ (length n) unless said otherwise.
    """

    n_demos: int  #: M = |b|
    efficacy: float  #: eps_M
    efficiency: float  #: eta_M = eps_M / M
    delta: float  #: eps_M - eps_{M-1}
    passed: np.ndarray  #: bool (n,): realisation meets the task criteria
    reasons: tuple[str, ...]  #: why each failing realisation fails ("" if it passes)
    demo_passed: bool  #: the demo itself meets the criteria (is in B)
    demo_reason: str  #: why it does not ("" if it does)
    similarity: float  #: s(b, b_set), inf for the first demo
    nearest_demo: int | None  #: 1-based number of the most similar earlier demo
    demonstrated: np.ndarray  #: bool (n,): covered by a correct demo
    undemonstrated: np.ndarray  #: bool (n,): B^ \ (R^ or b)
    shown: np.ndarray  #: int (k,): indices of the conditions in r
    warnings: tuple[TeachingWarning, ...] = field(default=())
    #: the same reasons as data: a tuple of :class:`~tutor.framework.task.Reason` per
    #: realisation (empty if it passes)
    causes: tuple[tuple[Reason, ...], ...] = field(default=())
    demo_causes: tuple[Reason, ...] = field(default=())  #: the demo's own, as data

    @property
    def kinds(self) -> set[str]:
        """The kinds of the warnings of this step."""
        return {w.kind for w in self.warnings}

    @property
    def n_undemonstrated(self) -> int:
        return int(self.undemonstrated.sum())

    def to_dict(self) -> dict:
        """JSON-ready summary (for an educator's export)."""
        return {
            "n_demos": self.n_demos,
            "efficacy": self.efficacy,
            "efficiency": self.efficiency,
            "delta": self.delta,
            "passed": self.passed.astype(int).tolist(),
            "demo_passed": self.demo_passed,
            "demo_reason": self.demo_reason,
            "similarity": None if np.isinf(self.similarity) else self.similarity,
            "nearest_demo": self.nearest_demo,
            "n_undemonstrated": self.n_undemonstrated,
            "shown": self.shown.tolist(),
            "warnings": [w.to_dict() for w in self.warnings],
        }


class TeachingSession:
    """One teacher teaching one task.

    Parameters
    ----------
    task : Task
    learner : TPGMM, optional
        Defaults to ``task.make_learner()``.
    feedback : {"none", "all", "replay", "batch", "selected", "adaptive"}
        What the teacher is shown after each demo (see the module docstring).
    thresholds : Thresholds, optional
        Failure thresholds; defaults documented in :class:`Thresholds`.
    batch : sequence of int, optional
        Indices into ``task.test_points`` shown in ``"batch"`` mode.
    selector : str or Selector, optional
        ``"adaptive"`` mode: a name in :data:`tutor.framework.selectors.SELECTORS`
        (default ``"disagreement"``) or a :class:`~tutor.framework.selectors.Selector`.
    k : int, optional
        ``"adaptive"`` mode: how many conditions are shown after each demo (default 5;
        a k above |B^| shows them all).
    rng : int, numpy Generator or None
        ``"adaptive"`` mode: the generator of the random selectors (seeded from it).
    """

    def __init__(
        self,
        task: Task,
        learner=None,
        feedback: str = "all",
        thresholds: Thresholds | None = None,
        batch=None,
        selector=None,
        k=None,
        rng=None,
    ):
        if not isinstance(feedback, str) or feedback not in FEEDBACK_POLICIES:
            raise InvalidParameterError(
                f"feedback must be one of {', '.join(FEEDBACK_POLICIES)}; got {feedback!r}"
            )
        n = len(task.test_points)
        batch = np.asarray([] if batch is None else batch, dtype=int).ravel()
        policy = FEEDBACK_POLICIES[feedback]
        if policy.needs_batch and batch.size == 0:
            raise InvalidParameterError("feedback='batch' needs batch=[indices of B^ to show]")
        if np.any((batch < 0) | (batch >= n)):
            raise InvalidParameterError(
                f"batch indices must lie in 0..{n - 1}, got {batch.tolist()}"
            )
        self.task = task
        self.feedback = feedback
        #: the feedback policy (:mod:`tutor.framework.feedback`) named by ``feedback``
        self.policy = policy
        self.thresholds = Thresholds() if thresholds is None else thresholds
        self.batch = batch
        if not policy.adaptive and (selector is not None or k is not None):
            raise InvalidParameterError(
                f"selector= and k= are only used with feedback='adaptive', not {feedback!r}"
            )
        self.selector = check_selector(DEFAULT_SELECTOR if selector is None else selector)
        self.k = check_k(DEFAULT_K if k is None else k)
        self.rng = np.random.default_rng(check_seed(rng, "rng"))
        self._fresh_learner = learner if learner is not None else task.make_learner()
        self._demos: list[np.ndarray] = []
        self._demo_points: list[np.ndarray] = []
        self._history: list[DemoStep] = []
        self._learners: list = []
        self._realisations: list[np.ndarray] = []

    # ---------------------------------------------------------------- state

    @property
    def _stacks(self) -> tuple[list, ...]:
        """The per-demo lists, kept the same length."""
        return (self._demos, self._demo_points, self._learners, self._realisations, self._history)

    @property
    def demo_points(self) -> list[np.ndarray]:
        """The test point each demo was given for (copies)."""
        return [c.copy() for c in self._demo_points]

    @property
    def demos(self) -> list[np.ndarray]:
        """The demonstration set b (preprocessed), oldest first (copies)."""
        return [d.copy() for d in self._demos]

    @property
    def latest_demo(self) -> np.ndarray | None:
        """The latest demonstration (preprocessed, a copy), None before the first."""
        return self._demos[-1].copy() if self._demos else None

    @property
    def history(self) -> list[DemoStep]:
        """One record per demo, oldest first."""
        return list(self._history)

    @property
    def latest(self) -> DemoStep | None:
        return self._history[-1] if self._history else None

    @property
    def n_demos(self) -> int:
        return len(self._demos)

    @property
    def learner(self):
        """The learner fitted on the current demos (a fresh one before any demo)."""
        return self._learners[-1] if self._learners else self._fresh_learner

    @property
    def realisations(self) -> np.ndarray | None:
        """R^ after the latest demo: mean trajectories (n, T, d), or None."""
        return self._realisations[-1] if self._realisations else None

    def realisations_at(self, step: int = -1) -> np.ndarray:
        """R^ (n, T, d) after demo ``step + 1`` (an index into :attr:`history`)."""
        if not self._realisations:
            raise InvalidParameterError("no demo yet, so the robot has realised nothing")
        return self._realisations[step]

    def score(self, *, rule: str, target: float = 0.9) -> SessionScore:
        """The session scored by the named rule (``"target"``: demos to first reach
        ``target`` coverage and eta there, Experiment 1; ``"final"``: eta after the last
        demo, Experiment 2).

        The rule has no default: a session does not know its experiment. A run's score
        is :meth:`tutor.framework.run.TeachingRun.score`, by its own experiment's rule.
        """
        return run_score([r.efficacy for r in self._history], rule, target)

    # ---------------------------------------------------------------- teaching

    def add_demo(self, raw, shown=None, point=None) -> DemoStep:
        """Add one demonstration and return the feedback after it.

        Parameters
        ----------
        raw : array-like
            A recording the task's ``preprocess`` accepts (e.g. (T, 3) of t, x, y).
        shown : sequence of int, optional
            In ``"selected"`` mode: the test points the teacher asks to see. In
            ``"adaptive"`` mode: the picks recorded when this demo was first given (a
            replay); None picks them now.
        point : array-like, optional
            The test point the teacher meant to demonstrate (e.g. the plant they chose);
            by default the task reads it off the demo (``task.test_point_of``).

        Raises
        ------
        InvalidDemoError
            The recording cannot be used; the session is left unchanged.
        """
        task = self.task
        demo = task.preprocess(raw)
        point = self._check_point(demo, point)
        selected = self._check_shown(shown)
        replayed = shown is not None
        demos = [*self._demos, demo]
        points = [*self._demo_points, point]
        learner = copy.deepcopy(self.learner)
        learner.fit(demos, [task.frames(c) for c in points])
        record, realisations = self._evaluate(learner, demos, points, selected, replayed)
        self._demos.append(demo)
        self._demo_points.append(point)
        self._learners.append(learner)
        self._realisations.append(realisations)
        self._history.append(record)
        return record

    def undo(self) -> DemoStep | None:
        """Remove the latest demo; returns the record now current (None if no demo is left)."""
        if not self._demos:
            raise InvalidParameterError("there is no demo to undo")
        for stack in self._stacks:
            stack.pop()
        return self.latest

    def remove_demo(self, number: int) -> DemoStep | None:
        """Remove demo ``number`` (1-based) and replay the later ones; returns the new latest.

        Records after the removed demo are recomputed as if it had never been given.
        """
        if not 1 <= number <= self.n_demos:
            raise InvalidParameterError(
                f"there is no demo {number}; demos are numbered 1 to {self.n_demos}"
            )
        if number == self.n_demos:
            return self.undo()
        later = self._demos[number:]
        later_points = self._demo_points[number:]
        shown = [r.shown for r in self._history[number:]]
        for stack in self._stacks:
            del stack[number - 1 :]
        keep = self.policy.keeps_picks  # what was shown stays what was shown
        for demo, point, sel in zip(later, later_points, shown, strict=True):
            self.add_demo(demo, shown=sel if keep else None, point=point)
        return self.latest

    def reset(self) -> None:
        """Remove every demo."""
        for stack in self._stacks:
            stack.clear()

    def _check_shown(self, shown) -> np.ndarray:
        if shown is None:
            return np.zeros(0, dtype=int)
        if not self.policy.keeps_picks:
            raise InvalidParameterError(
                "shown= is only used with feedback='selected' (the conditions asked for) or "
                "'adaptive' (the picks of a replayed demo)"
            )
        idx = np.asarray(shown, dtype=int).ravel()
        n = len(self.task.test_points)
        if np.any((idx < 0) | (idx >= n)):
            raise InvalidParameterError(f"shown indices must lie in 0..{n - 1}")
        return idx

    def _check_point(self, demo, given) -> np.ndarray:
        task = self.task
        if given is None:
            return np.asarray(task.test_point_of(demo), dtype=float)
        expected = np.asarray(task.test_points).shape[1:]
        try:
            point = np.asarray(given, dtype=float)
        except (TypeError, ValueError, OverflowError):
            point = np.full(0, np.nan)
        if point.shape != expected or not np.all(np.isfinite(point)):
            raise InvalidParameterError(
                f"point must be a finite array of shape {expected} like the rows of "
                f"task.test_points, got {given!r}"
            )
        return point

    def _evaluate(self, learner, demos, demo_points, selected, replayed=False):
        task, thr = self.task, self.thresholds
        points = task.test_points
        context = task.criteria_context(demos, np.array(demo_points))
        attempts = task.realise(learner, points)
        verdict = task.judge(attempts, points, context)
        demo = demos[-1]
        own = task.judge_demo(demo, demo_points[-1], context)
        m = len(demos)
        eps = efficacy(verdict.passed)
        previous = self._history[-1].efficacy if self._history else 0.0
        delta = eps - previous
        sim, nearest = similarity(demo, demos[:-1])
        ok = [r.demo_passed for r in self._history] + [bool(own.passed[0])]
        correct = [c for c, good in zip(demo_points, ok, strict=True) if good]
        demonstrated = (
            task.demonstrated(np.array(correct))
            if correct
            else np.zeros(len(points), dtype=bool)
        )
        undemonstrated = ~verdict.passed & ~demonstrated
        if self.policy.adaptive and not replayed:
            selected = self._adaptive_picks(learner, demo_points, attempts, verdict.passed)
        shown = self._shown(demo_points[-1], selected)
        delta_a = thr.ambiguity_distance
        if delta_a is None:
            delta_a = task.ambiguity_distance
        warnings = demo_warnings(
            m,
            demo_passed=bool(own.passed[0]),
            demo_reason=own.reasons[0],
            delta=delta,
            previous=previous,
            similarity=sim,
            nearest=None if nearest < 0 else nearest + 1,
            ambiguity_distance=delta_a,
            thresholds=thr,
            wrong_earlier=[i + 1 for i, r in enumerate(self._history) if not r.demo_passed],
            format_distance=task.format_distance,
        )
        missing = undemonstrated_warning(
            undemonstrated, task.point_noun, task.point_noun_plural, task.describe_where
        )
        if missing is not None:
            warnings.append(missing)
        record = DemoStep(
            n_demos=m,
            efficacy=eps,
            efficiency=efficiency(eps, m),
            delta=delta,
            passed=verdict.passed,
            reasons=verdict.reasons,
            demo_passed=bool(own.passed[0]),
            demo_reason=own.reasons[0],
            causes=verdict.causes,
            demo_causes=own.causes[0],
            similarity=sim,
            nearest_demo=None if nearest < 0 else nearest + 1,
            demonstrated=demonstrated,
            undemonstrated=undemonstrated,
            shown=shown,
            warnings=tuple(warnings),
        )
        return record, attempts

    def _adaptive_picks(self, learner, points, realisations, passed) -> np.ndarray:
        """The selector's k picks after this demo (``"adaptive"`` mode)."""
        context = SelectionContext.of_task(
            self.task, points, learner, realisations=realisations, passed=passed, rng=self.rng
        )
        return self.selector(self.k, context)

    def _shown(self, point, selected) -> np.ndarray:
        """r for this step, from the feedback policy (:mod:`tutor.framework.feedback`)."""
        policy = self.policy
        own = self.task.nearest_test_point(point) if policy.uses_own else -1
        return policy.shown(len(self.task.test_points), own, self.batch, selected)
