r"""A teaching run: the typed run record kept in step with the session that judges it.

:class:`TeachingRun` is what a tutor, a simulated teacher and the class analysis
drive. Every change goes through it, in this order: the learner and the feedback are
computed first (:class:`~tutor.framework.session.TeachingSession`), then a new
:class:`~tutor.framework.record.RunRecord` replaces the old one with the demo and an
event stamped by the wall clock. A change that fails leaves both as they were.

History is append-only: Undo keeps the demo it takes back (``Attempt.undone``); Reset,
and a Load that replaces the run, close the current attempt and start a new one, and
:meth:`TeachingRun.restore` brings an earlier attempt back as a new one. Nothing a
trainee did is deleted.

A task's protocol subclasses :class:`TeachingRun` and names its experiment; the
experiment's conditions, and the feedback policy of each (what the set :math:`r` of shown
realisations is; see :mod:`tutor.framework.session`), come from the registry
:mod:`tutor.framework.protocol`. A condition in ``"adaptive"`` mode (AF, beyond the
paper) names its selector and k there; each demo's picks are stored in its
``Demo.shown``, so a saved run replays with the same :math:`r` whatever the selector
(even a random one).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import ClassVar

import numpy as np

from ..errors import (
    InvalidFileError,
    InvalidParameterError,
    LimitError,
    TutorError,
    WrongRunError,
)
from ..fileio import read_json, write_json
from ..limits import MAX_DEMOS_PER_RUN
from .feedback import FeedbackPolicy, reveal
from .metrics import rule_of
from .protocol import Condition, Experiment
from .protocol import experiment as registered_experiment
from .record import (
    Attempt,
    Demo,
    Event,
    RunRecord,
    Test,
    Trainee,
    check_given,
    round_recording,
    utc_now,
)
from .session import DemoStep, TeachingSession
from .task import Task

__all__ = ["TeachingRun", "RunOverError"]


class RunOverError(TutorError, RuntimeError):
    """The run is finished (or its time is used up), so it cannot change any more."""


def _floats(a) -> tuple[float, ...]:
    return tuple(np.asarray(a, dtype=float).ravel().tolist())


def _recording(recording) -> np.ndarray:
    """A raw recording as a finite float table (T, C), T, C >= 1, or a named error."""
    try:
        a = np.asarray(recording, dtype=float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InvalidParameterError("a recording must be a table of numbers (T, columns)") from exc
    if a.ndim != 2 or a.size == 0 or not np.isfinite(a).all():
        raise InvalidParameterError(
            f"a recording must be a non-empty table of finite numbers, got shape {a.shape}"
        )
    return a


class TeachingRun:
    """One trainee's run in one condition (see the module docstring).

    Parameters
    ----------
    task : Task
    record : RunRecord
        The run to continue; its current attempt's demos are replayed into the learner.
    clock : callable, optional
        Gives the wall-clock stamp of each event (default :func:`utc_now`).
    selector, k : optional
        An ``"adaptive"`` condition's selector (a name or a
        :class:`~tutor.framework.selectors.Selector`) and k, instead of the ones
        :attr:`adaptive` names for it.
    rng : int, numpy Generator or None
        The random selectors' generator (``"adaptive"`` conditions).

    Raises
    ------
    InvalidFileError
        The record is for another task or condition, or a demo in it cannot be replayed.
    """

    #: the experiment number in the paper (its conditions: :mod:`.protocol`)
    experiment: ClassVar[int] = 0

    def __init__(
        self, task: Task, record: RunRecord, clock=utc_now, *, selector=None, k=None, rng=None
    ):
        self.task = task
        self.clock = clock
        self._adaptive_options = {"selector": selector, "k": k, "rng": rng}
        self._check_record(record)
        self._record = record
        self.session = self._replay(record.current.demos)

    @classmethod
    def fresh_record(
        cls,
        condition: str,
        task: Task,
        trainee: Trainee | None = None,
        run: int = 1,
        practice: bool = False,
        clock=utc_now,
    ) -> RunRecord:
        """The record of a new run: one empty attempt."""
        cls.check_condition(condition)
        trainee = Trainee.from_name() if trainee is None else trainee
        if not isinstance(trainee, Trainee):
            raise InvalidParameterError(f"trainee must be a Trainee, got {trainee!r}")
        if isinstance(run, bool) or not isinstance(run, int) or run < 1:
            raise InvalidParameterError(f"run must be a whole number >= 1, got {run!r}")
        return RunRecord.new(
            cls.experiment,
            task.name,
            condition,
            trainee,
            run=run,
            practice=bool(practice),
            at=clock(),
        )

    @classmethod
    def new(cls, condition: str, task: Task, clock=utc_now, **options):
        """A fresh run (``options``: trainee, run, practice, see :meth:`fresh_record`;
        selector, k, rng, see the class)."""
        adaptive = {key: options.pop(key) for key in ("selector", "k", "rng") if key in options}
        record = cls.fresh_record(condition, task, clock=clock, **options)
        return cls.from_record(task, record, clock, **adaptive)

    @classmethod
    def from_record(cls, task: Task, record: RunRecord, clock=utc_now, **adaptive):
        """Continue the run ``record`` (its current attempt's demos are replayed);
        ``adaptive``: selector, k, rng (see the class)."""
        return cls(task, record, clock, **adaptive)

    @classmethod
    def protocol(cls) -> Experiment:
        """The run's experiment in the registry (its task, conditions and design)."""
        return registered_experiment(cls.experiment)

    @classmethod
    def check_condition(cls, condition) -> str:
        codes = cls.protocol().codes
        if not isinstance(condition, str) or condition not in codes:
            raise InvalidParameterError(
                f"condition must be one of {', '.join(codes)}, got {condition!r}"
            )
        return condition

    def _check_record(self, record: RunRecord) -> None:
        if record.task != self.task.name or record.experiment != self.experiment:
            raise WrongRunError(
                f"this file holds a {record.task!r} run of experiment {record.experiment}, "
                f"not a {self.task.name!r} run of experiment {self.experiment}"
            )
        if record.condition not in self.protocol().codes:
            raise InvalidFileError(
                f"the run's condition {record.condition!r} is not one of "
                f"{', '.join(self.protocol().codes)}"
            )

    # ------------------------------------------------------------ what the run is

    @property
    def record(self) -> RunRecord:
        """The run record as it stands (immutable; replaced by every change)."""
        return self._record

    @property
    def condition(self) -> str:
        return self._record.condition

    @property
    def protocol_condition(self) -> Condition:
        """The run's condition in the registry (:mod:`.protocol`)."""
        return self.protocol().condition(self.condition)

    @property
    def policy(self) -> FeedbackPolicy:
        """The condition's feedback policy (what the teacher is shown)."""
        return self.protocol_condition.policy

    @property
    def feedback(self) -> str:
        """The name of the condition's feedback policy (as the record stores it)."""
        return self.policy.name

    @property
    def attempt(self) -> Attempt:
        """The current attempt."""
        return self._record.current

    @property
    def n_demos(self) -> int:
        return self.session.n_demos

    @property
    def finished(self) -> bool:
        return self._record.finished

    @property
    def score_rule(self) -> str:
        """The scoring rule of the run's experiment (:func:`tutor.framework.metrics.rule_of`)."""
        return rule_of(self.experiment)

    def score(self, target: float = 0.9):
        """The run's score by its own experiment's rule: the one score of a run, shown in
        the after-Finish summary, the results cell, the class analysis, the dashboard and
        the cohort tables alike. ``target`` is Experiment 1's coverage (the paper's 90 %)."""
        return self.session.score(rule=self.score_rule, target=target)

    def study_columns(self) -> dict:
        """The run's own columns in a study's table of runs (none here; a task's run adds
        what its experiment measures)."""
        return {}

    def visibility(self, extra_shown=()):
        """What the trainee may see now (:func:`tutor.framework.feedback.reveal`)."""
        rec = self.session.latest
        shown = () if rec is None else np.r_[rec.shown, np.asarray(extra_shown, dtype=int)]
        return reveal(
            self.feedback,
            len(self.task.test_points),
            shown,
            finished=self.finished,
            practice=self._record.practice,
        )

    def batch(self) -> np.ndarray | None:
        """The conditions shown in ``"batch"`` feedback (override where a task has them)."""
        return None

    def new_session(self) -> TeachingSession:
        """An empty session for this run's feedback mode."""
        policy = self.policy
        batch = self.batch() if policy.needs_batch else None
        if not policy.adaptive:
            return TeachingSession(self.task, feedback=self.feedback, batch=batch)
        selector, k = self.protocol_condition.selector or (None, None)
        options = self._adaptive_options
        return TeachingSession(
            self.task,
            feedback="adaptive",
            selector=selector if options["selector"] is None else options["selector"],
            k=k if options["k"] is None else options["k"],
            rng=self._selector_rng(),
        )

    def _selector_rng(self):
        """The random selectors' generator: the one given, shared by every attempt."""
        if not hasattr(self, "_rng"):
            self._rng = np.random.default_rng(self._adaptive_options["rng"])
        return self._rng

    @property
    def selector(self):
        """The selector of an ``"adaptive"`` condition (None in the others)."""
        return self.session.selector if self.policy.adaptive else None

    @property
    def k(self) -> int | None:
        """How many conditions an ``"adaptive"`` condition shows after each demo."""
        return self.session.k if self.policy.adaptive else None

    def _replay(self, demos) -> TeachingSession:
        if len(demos) > MAX_DEMOS_PER_RUN:
            raise LimitError(
                f"the run holds {len(demos)} demonstrations, more than the "
                f"{MAX_DEMOS_PER_RUN} a run can have, so it is not replayed (was it edited "
                "or made by a program?)"
            )
        session = self.new_session()
        for i, demo in enumerate(demos, start=1):
            try:
                session.add_demo(
                    np.asarray(demo.samples, dtype=float),
                    shown=demo.shown if self.policy.keeps_picks else None,
                    point=None if demo.point is None else np.asarray(demo.point),
                )
            except TutorError as exc:
                raise InvalidFileError(f"demo {i} of the run cannot be replayed: {exc}") from exc
        return session

    def _event(
        self, kind: str, n_demos: int | None = None, detail: str = "", begins: bool = False
    ) -> Event:
        """An event in the current attempt, or (``begins``) in the attempt it begins."""
        n = self.attempt.n_demos if n_demos is None else n_demos
        index = len(self._record.attempts) - (0 if begins else 1)
        return Event(kind, self.clock(), index, n, detail)

    def check_open(self) -> None:
        """Raise :class:`RunOverError` unless demos may still be added (the run is open)."""
        if self.finished:
            self._refuse_finished()

    def _check_room(self, n: int) -> None:
        """Refuse ``n`` more demos when they would take the attempt over the cap."""
        have = self.attempt.n_demos
        if have + n > MAX_DEMOS_PER_RUN:
            adding = "one more" if n == 1 else f"{n} more"
            raise LimitError(
                f"this run holds {have} demonstrations and cannot take {adding}: a run has "
                f"at most {MAX_DEMOS_PER_RUN}. Finish it (or press Reset to begin a new "
                "attempt)"
            )

    @staticmethod
    def _refuse_finished():
        raise RunOverError(
            "this run is finished, so it cannot change any more: start the next run, or "
            "press Reset to begin a new attempt (this one is kept)"
        )

    # ------------------------------------------------------------ teaching

    def add_demo(
        self,
        raw,
        *,
        point=None,
        shown=None,
        seconds: float | None = None,
        followed_rule: bool | None = None,
        chosen_by: str = "",
        mistake: str = "",
        given: str = "",
        recording=None,
    ) -> DemoStep:
        """Add one demonstration; returns the feedback after it.

        ``point`` is the test point it was meant for (read off the demo when
        None); ``shown`` the test points asked to see (SF); ``seconds`` its cost on the
        clock; ``followed_rule`` VR's rule compliance or HF's hint following;
        ``chosen_by`` and ``mistake`` notes on why it was given and what went wrong on
        purpose (simulated teachers, the hand); ``given`` how it was given
        (:data:`~tutor.framework.record.HOW_GIVEN`, "" for not said) and ``recording``
        the raw recording to keep with it (a table of numbers, checked by the caller's
        task; stored rounded, :func:`~tutor.framework.record.round_recording`).

        Raises
        ------
        RunOverError
            The run is finished.
        LimitError
            The attempt already holds :data:`~tutor.limits.MAX_DEMOS_PER_RUN` demos.
        InvalidDemoError, InvalidParameterError
            The demo cannot be used; nothing changed.
        """
        self.check_open()
        self._check_room(1)
        given = check_given(given)
        kept = None if recording is None else round_recording(_recording(recording))
        record = self.session.add_demo(raw, shown=shown, point=point)
        if followed_rule is None:
            followed_rule = self._rule_followed(self.session.latest_demo)
        if self.policy.adaptive:
            shown = record.shown  # the selector's picks, kept so that a replay shows them
        demo = Demo(
            samples=tuple(map(tuple, np.asarray(self.session._demos[-1], float).tolist())),
            point=None if point is None else _floats(self.session.demo_points[-1]),
            shown=None if shown is None else tuple(int(i) for i in np.ravel(shown)),
            seconds=None if seconds is None else float(seconds),
            followed_rule=None if followed_rule is None else bool(followed_rule),
            chosen_by=str(chosen_by),
            mistake=str(mistake or ""),
            given=given,
            recording=kept,
        )
        attempt = replace(self.attempt, demos=(*self.attempt.demos, demo))
        self._record = self._record.with_current(attempt, self._event("add", attempt.n_demos))
        return record

    def _rule_followed(self, demo) -> bool | None:
        """Whether ``demo`` (preprocessed, just added) followed the rule in force when it
        was given; None where the condition has no rule (a run with rules overrides it)."""
        return None

    def add_demos(self, items, detail: str = "") -> int:
        """Add several demos all or nothing (a Load); returns how many were added.

        ``items`` are ``(raw, options)`` pairs, ``options`` a dict of :meth:`add_demo`'s
        keyword arguments (``given`` is "loaded" unless they say otherwise). If one is
        refused, the run is left exactly as it was and the error names the demo.
        """
        self.check_open()
        items = list(items)
        self._check_room(len(items))
        before_record, before_session = self._record, self.session
        trial = self._replay(self.attempt.demos)
        self.session = trial
        try:
            for i, (raw, options) in enumerate(items, start=1):
                try:
                    self.add_demo(raw, **{"given": "loaded", **options})
                except TutorError as exc:
                    where = f"demo {i} of {detail}" if detail else f"demo {i}"
                    raise type(exc)(f"{where}: {exc}") from exc
        except BaseException:
            self._record, self.session = before_record, before_session
            raise
        self._record = self._record.with_current(self.attempt, self._event("load", detail=detail))
        return len(items)

    def undo(self, spent_seconds: float = 0.0) -> DemoStep | None:
        """Take back the latest demo (kept in ``Attempt.undone``); returns the new latest.

        ``spent_seconds`` is clock time the demo used that stays spent (Experiment 2).
        Refused once the run is finished (unless :meth:`_may_undo_finished` allows it: in
        Experiment 2 once after the cap ended the run); a clock that ran out (Experiment
        2) does not stop it, since taking a demo back gives no time back. The robot's
        tests after the demo taken back go with it (they tried what it taught).
        """
        if self._record.finished and not self._may_undo_finished():
            self._refuse_finished()
        if not self.attempt.demos:
            raise InvalidParameterError("there is no demonstration to undo")
        latest = self.session.undo()
        a = self.attempt
        taken = a.demos[-1]
        tests = tuple(t for t in a.tests if t.after_demo < a.n_demos)
        attempt = replace(
            a,
            demos=a.demos[:-1],
            undone=(*a.undone, taken),
            tests=tests,
            other_seconds=a.other_seconds + float(spent_seconds),
        )
        self._record = self._record.with_current(attempt, self._event("undo", attempt.n_demos))
        return latest

    def _may_undo_finished(self) -> bool:
        """Whether :meth:`undo` may take a demo back although the run is finished (never,
        here; Experiment 2 allows one Undo after the cap ended the run)."""
        return False

    def test(self, plants, after_run: bool = False) -> np.ndarray:
        """Record that the robot tried ``plants`` (indices into B^); returns pass/fail."""
        rec = self.session.latest
        if rec is None:
            raise InvalidParameterError("give a demonstration before testing the robot")
        n = len(self.task.test_points)
        idx = tuple(int(p) for p in plants)
        if not idx:
            raise InvalidParameterError(
                f"no {self.task.point_noun} was chosen to test: choose at least one"
            )
        if any(not 0 <= p < n for p in idx):
            raise InvalidParameterError(
                f"{self.task.point_noun_plural} are numbers from 0 to {n - 1}"
            )
        a = self.attempt
        attempt = replace(a, tests=(*a.tests, Test(a.n_demos, idx, bool(after_run))))
        detail = " ".join(map(str, idx))
        self._record = self._record.with_current(attempt, self._event("test", detail=detail))
        return rec.passed[list(idx)]

    def spend(self, seconds: float) -> None:
        """Count clock time besides demos and robot attempts (e.g. setting up a plant)."""
        ok = isinstance(seconds, (int, float, np.integer, np.floating)) and not isinstance(
            seconds, bool
        )
        try:
            ok = ok and bool(float(seconds) >= 0 and np.isfinite(float(seconds)))
        except OverflowError:
            ok = False
        if not ok:
            raise InvalidParameterError(
                f"seconds must be a finite number >= 0, e.g. spend(30); got {seconds!r}"
            )
        a = self.attempt
        attempt = replace(a, other_seconds=a.other_seconds + float(seconds))
        self._record = self._record.with_current(
            attempt, self._event("spend", detail=f"{float(seconds):g}")
        )

    def finish(self, stopped: str = "finish") -> None:
        """End the run; ``stopped`` says why ("finish", "time", or a simulated reason)."""
        if self.attempt.finished:
            return
        attempt = replace(self.attempt, finished=True, stopped=str(stopped))
        self._record = self._record.with_current(attempt, self._event("finish", detail=stopped))

    # ------------------------------------------------------------ attempts

    def reset(self) -> None:
        """Start a new, empty attempt; the current one is kept in the record."""
        self._record = self._record.with_new_attempt(
            Attempt(started=self.clock()), "reset", self._event("reset", 0, begins=True)
        )
        self.session = self.new_session()

    def replace_with(self, other: RunRecord, detail: str = "") -> None:
        """A Load of a run file: its current attempt becomes this run's new attempt.

        Refused (nothing changes) when ``other`` is another experiment, condition or
        run, or when this run is finished; the message names both runs.
        """
        mine = self._record
        if not mine.same_run(other):
            raise WrongRunError(
                f"that file holds {other.trainee.name}'s {other.label}, but this tutor is "
                f"{mine.label}: open it in the matching tutor. Nothing was loaded and this "
                "run's file is untouched."
            )
        if self.finished:
            raise WrongRunError(
                f"this {mine.label} is finished, so {other.trainee.name}'s {other.label} "
                "cannot be loaded into it. Nothing was loaded and its file is untouched; "
                "press Reset first to start a new attempt (this one is kept)."
            )
        session = self._replay(other.current.demos)
        attempt = replace(other.current, started=self.clock(), ended="", finished=False)
        attempt = replace(attempt, stopped="")
        self._record = mine.with_new_attempt(
            attempt, "load", self._event("load", attempt.n_demos, detail, begins=True)
        )
        self.session = session

    def restore(self, index: int) -> None:
        """Bring attempt ``index`` (0-based) back as a new attempt; the current one is kept."""
        attempts = self._record.attempts
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
            raise InvalidParameterError(f"an attempt is a number, got {index!r}")
        if not 0 <= index < len(attempts) - 1:
            raise InvalidParameterError(
                f"there is no earlier attempt {index + 1}; this run has attempts 1 to "
                f"{len(attempts) - 1} before the current one"
            )
        old = attempts[index]
        session = self._replay(old.demos)
        attempt = replace(old, started=self.clock(), ended="")
        self._record = self._record.with_new_attempt(
            attempt,
            "restore",
            self._event("restore", attempt.n_demos, str(index + 1), begins=True),
        )
        self.session = session

    # ------------------------------------------------------------ files

    def to_dict(self) -> dict:
        return self._record.to_dict()

    @classmethod
    def from_dict(cls, data, task: Task, clock=utc_now):
        """Rebuild a run from :meth:`to_dict`'s output (raises InvalidFileError)."""
        return cls.from_record(task, RunRecord.from_dict(data), clock)

    def save(self, path):
        """Write the record atomically (raises SaveError when it cannot be written)."""
        return write_json(path, self.to_dict())

    @classmethod
    def load(cls, path, task: Task, clock=utc_now):
        """The run saved in ``path`` (InvalidFileError naming the file when it is refused:
        unreadable, another run, or events that contradict its demos; it is not changed)."""
        data = read_json(path, "run file")
        try:
            return cls.from_dict(data, task, clock)
        except InvalidFileError as exc:
            raise type(exc)(f"{Path(path).name}: {exc}") from exc
