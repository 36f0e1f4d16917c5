"""The protocol of Experiment 2 (Sena & Howard): four feedback conditions and the clock.

NF  no feedback while teaching; the teacher may test self-chosen plants after the run.
RF  replay: after each demo the robot replays that same plant (r = the demo's condition).
BF  batch: after each demo the robot performs the five generalisation samples
    (the four corner plants and the centre one).
SF  selected: the teacher chooses when and which plants the robot tries.

Beyond the paper (its open question, choosing r automatically):

AF  adaptive: after each demo the robot tries the k = 5 plants a selector picks from the
    demos and what the robot learnt (by default where the frames' regressions disagree
    most, or far from every demo: :mod:`tutor.framework.selectors`). Same cost as BF.
HF  hint: NF (nothing shown while teaching, totals withheld) plus a next-demo hint,
    the plant the robot would learn most from next by greedy lookahead
    (:meth:`PickPlaceRun.hint`, :mod:`tutor.tasks.hint`). A hint costs no robot time,
    so HF costs what NF costs; each demo records whether it went to the hinted plant
    (``Demo.followed_rule``).

The clock the paper's teachers lived by: a demonstration costs its own duration, every
realisation the robot performs costs 25 s (a real arm is slow), and a teaching run is
capped at 15 minutes. Each trainee does three runs.

The cap, as the paper ran it: a demonstration that cannot finish before 15:00, with the
robot's attempts its condition then shows (RF 1, BF 5, AF k, x 25 s), is not started, and the
run ends with the last complete demonstration. :meth:`PickPlaceRun.demonstrate` refuses
such a demo with a :class:`RunOverError` that says how much time is left (a refusal
changes nothing); the run is over once not even the shortest demonstration fits
(:data:`SHORTEST_DEMO_SECONDS` plus those attempts), and :meth:`PickPlaceRun.finish`
then records it as stopped "time".

The cap's Undo: the demonstration that ended a run by the cap may have lowered the
robot's success, so one Undo of the last demo is allowed after the cap ended the run
(:attr:`PickPlaceRun.cap_undo_left`); its time stays spent and the run stays over.

One voice for the clock: :meth:`PickPlaceRun.clock_state` gives a :class:`ClockState`,
the clock in the whole seconds it is shown in (time used rounded up to a second, so that
used and left add up to the 15 minutes), and every word about the clock comes from it:
the clock line (:meth:`ClockState.line`), the end of a run by the cap
(:meth:`ClockState.cap_message`: which demo would not have fit, when it would have ended
and why), and the refusals (:meth:`ClockState.refusal`, :meth:`ClockState.over`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError, TutorError
from ..framework import RunOverError, TeachingRun
from ..framework.protocol import experiment
from ..framework.record import check_given, utc_now
from .hint import Hint, hint_candidates, next_demo_hint
from .kinesthetic import CARRY_SECONDS, PAUSE_SECONDS, REACH_SECONDS
from .pickplace import PickPlaceTask
from .recording import check_recording

__all__ = [
    "ClockState",
    "Hint",
    "PickPlaceRun",
    "RunOverError",
    "RUNS",
    "SHORTEST_DEMO_SECONDS",
]

#: each trainee teaches three runs in their condition (:mod:`tutor.framework.protocol`)
RUNS = experiment(2).runs
#: The shortest demonstration a person gives (s): the simulated hand's fastest pace
#: (0.85 of the average, less 5 %) over the reach, the transport and both button
#: presses, rounded down. Less time than this (plus the condition's attempts) left
#: ends the run.
SHORTEST_DEMO_SECONDS = float(int(0.8 * (REACH_SECONDS + CARRY_SECONDS + 2 * PAUSE_SECONDS)))


#: the hands whose demo may carry a mistake: the tutor's (asked for in the "mistake"
#: menu) and a simulated teacher's (a slip, noted)
MISTAKEN_HANDS = ("guided", "simulated")


def _setup_seconds(value) -> float:
    """Set-up time before a demo as a finite number >= 0, or a named error."""
    ok = isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)
    try:
        ok = ok and bool(np.isfinite(float(value)) and float(value) >= 0)
    except OverflowError:
        ok = False
    if not ok:
        raise InvalidParameterError(
            f"setup_seconds must be a finite number of seconds >= 0, got {value!r}"
        )
    return float(value)


def clock(seconds: float) -> str:
    """``seconds`` as m:ss (e.g. 65 -> "1:05")."""
    whole = max(0, int(seconds))
    return f"{whole // 60}:{whole % 60:02d}"


def whole_seconds(seconds: float) -> int:
    """``seconds`` rounded up to a whole second, as the clock shows time used (0.2 s used
    is 0:01; a rounding error of a microsecond is no second)."""
    return max(0, math.ceil(float(seconds) - 1e-6))


@dataclass(frozen=True)
class ClockState:
    """The Experiment 2 clock at one moment, in whole seconds, and all its words.

    Made by :meth:`PickPlaceRun.clock_state`; the clock line and every message about the
    cap are read from one of these, so their numbers never disagree.

    Attributes
    ----------
    cap : int
        The run's cap (900 s: the paper's 15 minutes).
    used : int
        Seconds used, rounded up to a whole second, at most ``cap``.
    demos : int
        The demonstrations given in the current attempt.
    demo : int
        Seconds of the next demonstration asked about (rounded up): by default the
        shortest a person gives (:data:`SHORTEST_DEMO_SECONDS`).
    shortest : bool
        ``demo`` is the shortest demonstration (not one that was given).
    attempts : int
        The robot's attempts the condition shows after each demo (RF 1, BF 5, AF k).
    feedback : int
        Their seconds (25 s each).
    fits : bool
        That demonstration and those attempts end by the cap (exactly, not rounded).
    finished : bool
        The trainee finished the run, or it was ended by the cap.
    """

    cap: int
    used: int
    demos: int
    demo: int
    shortest: bool
    attempts: int
    feedback: int
    fits: bool
    finished: bool

    @property
    def left(self) -> int:
        """Seconds left: the cap less the seconds used."""
        return self.cap - self.used

    @property
    def next_demo(self) -> int:
        """The number the next demonstration would have (1 for the first)."""
        return self.demos + 1

    @property
    def needs(self) -> int:
        """Seconds the next demonstration and the attempts after it take."""
        return self.demo + self.feedback

    @property
    def ends(self) -> int:
        """When the next demonstration and its attempts would end (seconds on the clock);
        past the cap whenever they do not fit."""
        ends = self.used + self.needs
        return ends if self.fits else max(ends, self.cap + 1)

    @property
    def minutes(self) -> str:
        """The cap in words, e.g. "15 minutes"."""
        return f"{self.cap / 60:g} minutes"

    def line(self) -> str:
        """The clock line, e.g. "13:41 of 15:00 used, 1:19 left"."""
        return f"{clock(self.used)} of {clock(self.cap)} used, {clock(self.left)} left"

    def _why(self) -> str:
        """E.g. "demo 7 (at least 30 s) and the robot's 5 attempts after it (125 s) would
        have ended at 16:16, past the 15 minutes"."""
        size = f"at least {self.demo} s" if self.shortest else f"about {self.demo} s"
        attempts = "attempt" if self.attempts == 1 else f"{self.attempts} attempts"
        after = f" and the robot's {attempts} after it ({self.feedback} s)" if self.attempts else ""
        return (
            f"demo {self.next_demo} ({size}){after} would have ended at {clock(self.ends)}, "
            f"past the {self.minutes}"
        )

    def cap_message(self) -> str:
        """Why the cap ended the run (or ends it, once Finish run is pressed): which demo
        would not have fit, when it would have ended, and the time used and left."""
        why = self._why()
        demos = f"{self.demos} demo{'' if self.demos == 1 else 's'}"
        ends = "ends here" if self.finished else "is over"
        then = "" if self.finished else ": press Finish run"
        return (
            f"{why[0].upper()}{why[1:]}: the run {ends} with {demos} "
            f"({clock(self.used)} used, {clock(self.left)} left){then}."
        )

    def refusal(self) -> str:
        """A demonstration (of ``demo`` seconds) refused because it would end past the cap;
        nothing changed."""
        return (
            f"Only {clock(self.left)} of the {self.minutes} is left: not enough, since "
            f"{self._why()}, so it was not started ({clock(self.used)} used). A shorter one "
            "may fit; or press Finish run to end the run with your last complete "
            "demonstration"
        )

    def over(self) -> str:
        """What a demonstration asked for after the run is over is told."""
        if self.finished:
            return f"this run is over ({self.line()}): start the next run to go on"
        return (
            f"This run is over: only {clock(self.left)} of the {self.minutes} is left, and "
            f"{self._why()}. Your last complete demonstration counts: press Finish run, "
            "then start the next run"
        )


class PickPlaceRun(TeachingRun):
    """One teaching run of one trainee in one condition, with its clock.

    Make one with ``PickPlaceRun.new(condition, task)`` or, for short,
    ``PickPlaceRun(condition, task)``; resume one with ``PickPlaceRun(task=task,
    record=record)``. The clock is read from the run record: each demo's ``seconds``,
    the robot tests asked for during the run, and ``other_seconds``.

    An AF run takes ``selector=``, ``k=`` and ``rng=`` (the random selectors'
    generator) besides the record options; by default AF shows 5 plants picked by
    frame disagreement (its selector in :mod:`tutor.framework.protocol`). An HF run offers
    :meth:`hint` before each demo.
    """

    experiment = 2

    def __init__(self, condition=None, task: PickPlaceTask | None = None, record=None, **new):
        task = PickPlaceTask() if task is None else task
        clock = new.pop("clock", utc_now)
        adaptive = {key: new.pop(key) for key in ("selector", "k", "rng") if key in new}
        if record is None:
            record = self.fresh_record(condition, task, clock=clock, **new)
        elif condition is not None and condition != record.condition:
            raise InvalidParameterError(f"the record is a {record.condition} run, not {condition}")
        super().__init__(task, record, clock, **adaptive)

    @classmethod
    def new(cls, condition, task, clock=utc_now, **options):
        return cls(condition, task, clock=clock, **options)

    @classmethod
    def from_record(cls, task, record, clock=utc_now, **adaptive):
        return cls(task=task, record=record, clock=clock, **adaptive)

    def batch(self) -> np.ndarray:
        return self.task.scene.generalisation_indices

    # ---------------------------------------------------------------- the clock

    @property
    def cap(self) -> float:
        return self.task.scene.run_seconds

    @property
    def realisation_seconds(self) -> float:
        return self.task.scene.realisation_seconds

    def study_columns(self) -> dict:
        """``seconds``: the run's clock (:attr:`elapsed`)."""
        return {"seconds": self.elapsed}

    @property
    def elapsed(self) -> float:
        """Seconds used: demos, plus 25 s for every realisation shown during the run.

        Also counts :meth:`spend` time and the time of demos taken back with :meth:`undo`.
        """
        a = self.attempt
        shown = sum(len(r.shown) for r in self.session.history)
        tested = sum(len(t.plants) for t in a.tests if not t.after_run)
        robot = self.realisation_seconds * (shown + tested)
        return float(sum(d.seconds or 0.0 for d in a.demos)) + robot + a.other_seconds

    @property
    def remaining(self) -> float:
        return max(0.0, self.cap - self.elapsed)

    @property
    def feedback_seconds(self) -> float:
        """Seconds of the robot's attempts the condition shows after each demo (RF 25, BF
        125, AF 25 k, NF and SF 0: SF's tests are asked for and paid for one by one). The
        oracle selector may show fewer than k (only failures): this is then the most."""
        n = len(self.task.test_points)
        adaptive = min(self.k, n) if self.policy.adaptive else 0
        shown = {"replay": 1, "batch": len(self.batch()), "adaptive": adaptive}
        shown = shown.get(self.feedback, 0)
        return self.realisation_seconds * shown

    def demo_cost(self, seconds: float) -> float:
        """Clock time a demonstration of ``seconds`` takes with the attempts shown after it."""
        return float(seconds) + self.feedback_seconds

    def fits(self, seconds: float) -> bool:
        """A demonstration of ``seconds`` (and the attempts shown after it) ends by the cap."""
        return self.demo_cost(seconds) <= self.remaining + 1e-9

    @property
    def out_of_time(self) -> bool:
        """Not even the shortest demonstration fits in the time left."""
        return not self.fits(SHORTEST_DEMO_SECONDS)

    @property
    def finished(self) -> bool:
        return super().finished or self.out_of_time

    def clock_state(self, seconds: float | None = None) -> ClockState:
        """The clock now, and its words (:class:`ClockState`): the one source of the
        clock line and of every message about the cap.

        ``seconds`` is the next demonstration asked about (default: the shortest one,
        :data:`SHORTEST_DEMO_SECONDS`, which says whether the run is over).
        """
        shortest = seconds is None
        seconds = SHORTEST_DEMO_SECONDS if shortest else float(seconds)
        cap = whole_seconds(self.cap)
        return ClockState(
            cap=cap,
            used=min(whole_seconds(self.elapsed), cap),
            demos=self.attempt.n_demos,
            demo=whole_seconds(seconds),
            shortest=shortest,
            attempts=int(round(self.feedback_seconds / self.realisation_seconds)),
            feedback=whole_seconds(self.feedback_seconds),
            fits=self.fits(seconds),
            finished=super().finished,
        )

    def clock_text(self) -> str:
        """The clock line, e.g. "13:41 of 15:00 used, 1:19 left" (:meth:`ClockState.line`)."""
        return self.clock_state().line()

    def check_open(self) -> None:
        """Raise :class:`RunOverError` (saying why, from the clock) unless the run is open:
        not finished, and the shortest demonstration still fits before the cap."""
        if self.out_of_time or self.finished:
            raise RunOverError(self.clock_state().over())

    def add_demo(self, raw, *, seconds: float | None = None, **options):
        """Add one demonstration (see :meth:`TeachingRun.add_demo`) if it fits the clock.

        Raises
        ------
        RunOverError
            It would not end, with the attempts shown after it, by the 15-minute cap
            (nothing changed); or the run is over.
        """
        self.check_open()
        if seconds is not None and not self.fits(seconds):
            raise RunOverError(self.clock_state(seconds).refusal())
        return super().add_demo(raw, seconds=seconds, **options)

    # ---------------------------------------------------------------- the hint (HF)

    @property
    def hinted(self) -> bool:
        """Whether this run's condition shows the next-demo hint (HF)."""
        return self.protocol_condition.hinted

    def _hint_key(self) -> tuple[int, int, int]:
        """What the hint depends on: the attempt, the demos taken back, the demos."""
        return (len(self.record.attempts), len(self.attempt.undone), self.session.n_demos)

    def hint(self) -> Hint:
        """Where the robot would learn most from next (:func:`tutor.tasks.hint.next_demo_hint`).

        The plant whose careful demo raises eps the most, by greedy lookahead over a
        pruned candidate set (the optimal teacher's first pick before any demo). It is
        kept until the demos change (a demo, Undo, Reset, Load), and costs no time on
        the clock. Any condition may ask; only HF shows it to the trainee.
        """
        key = self._hint_key()
        cached = getattr(self, "_hint", None)
        if cached is None or cached[0] != key:
            cached = (key, next_demo_hint(self.task, self.session))
            self._hint = cached
        return cached[1]

    def _followed_hint(self, plant: int) -> bool | None:
        """Whether ``plant`` is the hinted one; None when no hint could be computed (the
        trainee then had none to follow, and teaching goes on without it).

        After a demo the hint is one of :func:`~tutor.tasks.hint.hint_candidates`, so a
        plant outside them did not follow it, whatever the lookahead would pick: the
        answer is known without the lookahead's refits (what a simulated teacher who
        goes their own way costs).
        """
        try:
            cached = getattr(self, "_hint", None)
            if (cached is None or cached[0] != self._hint_key()) and self.session.n_demos:
                if plant not in hint_candidates(self.task, self.session).tolist():
                    return False
            return plant == self.hint().plant
        except TutorError:
            return None

    # ---------------------------------------------------------------- teaching

    def demonstrate(
        self,
        plant: int,
        raw=None,
        mistake=None,
        rng=None,
        chosen_by: str = "",
        given: str = "guided",
        setup_seconds: float = 0.0,
    ):
        """Give one demonstration to ``plant``: by the trainee's own hand, or guided.

        ``given`` says how (:data:`~tutor.framework.record.HOW_GIVEN`):

        "guided" (the default)
            The tutor guides the arm for the trainee: the demo is generated
            kinesthetically (:meth:`PickPlaceTask.demonstrate`, with ``mistake`` when
            asked for) unless ``raw`` is given.
        "own"
            The trainee's own hand guided the arm: ``raw`` is the recording (T, 5) the
            page sent, checked by :func:`tutor.tasks.recording.check_recording` and kept
            with the demo (``Demo.recording``). No ``mistake``: a grab elsewhere is a
            real demonstration error, judged as such.
        "simulated", "loaded"
            ``raw`` from a simulated teacher or a file (``mistake`` notes a simulated
            hand's slip).

        The demo costs its duration plus ``setup_seconds`` (setting up before it, e.g.
        choosing the plant and taking the handle) on the clock, as one cost.

        In HF it records whether ``plant`` is the hinted one (``Demo.followed_rule``;
        None when no hint could be given); a demo added with :meth:`add_demo` (e.g.
        loaded from a file) records nothing.

        Raises
        ------
        InvalidRecordingError
            An own-hand recording that cannot be a demonstration (nothing changes).
        InvalidParameterError
            An unknown plant, ``given``, a ``mistake`` with an own-hand demo, a missing
            recording, or ``setup_seconds`` not a finite number >= 0.
        RunOverError
            The demonstration (with the attempts the condition shows after it) would not
            end by the cap: it is not started (nothing changes). When not even the
            shortest one fits, the run is over (:attr:`finished`; :meth:`finish` then
            records it as stopped "time") and ends with its last complete demo.
        """
        self.check_open()
        plant = self._check_plant(plant)
        given = check_given(given)
        setup = _setup_seconds(setup_seconds)
        recording = None
        if given == "own":
            if raw is None:
                raise InvalidParameterError(
                    "an own-hand demonstration needs its recording: demonstrate(plant, "
                    'raw=recording, given="own")'
                )
            if mistake:
                raise InvalidParameterError(
                    "an own-hand demonstration takes no mistake= (the trainee's hand makes "
                    'its own): mistakes are for given="guided"'
                )
            raw = recording = check_recording(raw, self.task.scene)
        elif mistake and given not in MISTAKEN_HANDS:
            raise InvalidParameterError(
                f'mistake= is for the tutor\'s hand (given="guided") or a simulated one, not '
                f"given={given!r}"
            )
        if raw is None:
            raw = self.task.demonstrate(plant, rng, mistake=mistake)
        seconds = self.task.duration(raw) + setup
        followed = self._followed_hint(plant) if self.hinted else None
        return self.add_demo(
            raw,
            point=self.task.test_points[plant],
            seconds=seconds,
            followed_rule=followed,
            chosen_by=chosen_by,
            mistake=mistake or "",
            given=given,
            recording=recording,
        )

    def test(self, plants, after_run: bool | None = None) -> np.ndarray:
        """The robot tries ``plants``: SF during the run (25 s each), any condition after it.

        Returns the pass/fail of each tried plant (after the latest demo).
        """
        plants = [self._check_plant(p) for p in np.atleast_1d(plants)]
        after = self.finished
        if not after and not self.policy.teacher_picks:
            raise RunOverError(
                f"in condition {self.condition} the robot can be tested only after the run"
            )
        if self.session.latest is None:
            raise InvalidParameterError("give a demonstration before testing the robot")
        cost = self.realisation_seconds * len(plants)
        if not after and cost > self.remaining:
            raise RunOverError(
                f"testing {len(plants)} plant(s) takes {cost:.0f} s but only "
                f"{self.remaining:.0f} s are left"
            )
        return super().test(plants, after_run=after)

    def finish(self, stopped: str | None = None) -> None:
        """End the run ("time" when the 15 minutes are used up, else "finish")."""
        if stopped is None:
            stopped = "time" if self.out_of_time else "finish"
        super().finish(stopped)

    @property
    def cap_undo_left(self) -> bool:
        """Whether the one Undo allowed after the cap ended the run is still to be used:
        the run was finished by the clock ("time") and no demo was taken back since."""
        a = self.attempt
        if not (a.finished and a.stopped == "time" and a.demos):
            return False
        index = len(self.record.attempts) - 1
        after = False  # the events of this attempt since its finish
        for event in self.record.events:
            if event.attempt == index and event.kind == "finish":
                after = True
            elif after and event.attempt == index and event.kind == "undo":
                return False
        return after

    @property
    def can_undo(self) -> bool:
        """Whether :meth:`undo` would take a demo back now (for the Undo button): a demo
        is left and the run is open, or the cap's one Undo is still to be used."""
        return bool(self.attempt.demos) and (not self.record.finished or self.cap_undo_left)

    def _may_undo_finished(self) -> bool:
        return self.cap_undo_left

    def undo(self):
        """Take back the latest demo; the time it and its realisations took stays spent.

        Once the cap ended the run, one Undo is still allowed (:attr:`cap_undo_left`):
        the run stays over.

        Returns the record now current (None when no demo is left).

        Raises
        ------
        RunOverError
            The run is finished (by the trainee, or by the cap with its Undo used).
        """
        a = self.attempt
        if a.finished and a.stopped == "time" and a.demos and not self.cap_undo_left:
            raise RunOverError(
                "this run was ended by the 15-minute cap and its one Undo is used: the run "
                f"is over ({self.clock_text()}); start the next run to go on"
            )
        rec = self.session.latest
        if rec is None:
            raise InvalidParameterError("there is no demo to undo")
        a = self.attempt
        tests = [t for t in a.tests if t.after_demo == rec.n_demos and not t.after_run]
        spent = (a.demos[-1].seconds or 0.0) + self.realisation_seconds * (
            len(rec.shown) + sum(len(t.plants) for t in tests)
        )
        return super().undo(spent_seconds=spent)

    def _check_plant(self, plant) -> int:
        n = len(self.task.test_points)
        if isinstance(plant, bool):
            raise InvalidParameterError(f"a plant is a number from 0 to {n - 1}, got {plant!r}")
        try:
            index = int(plant)
        except (TypeError, ValueError, OverflowError) as exc:
            raise InvalidParameterError(f"a plant is a number from 0 to {n - 1}") from exc
        if not 0 <= index < n or index != plant:
            raise InvalidParameterError(f"a plant is a number from 0 to {n - 1}, got {plant!r}")
        return index

    # ---------------------------------------------------------------- what the teacher sees

    def tested_plants(self) -> np.ndarray:
        """The plants the trainee asked the robot to try after the latest demo."""
        rec = self.session.latest
        if rec is None:
            return np.zeros(0, dtype=int)
        tests = [t.plants for t in self.attempt.tests if t.after_demo == rec.n_demos]
        return np.array([p for ps in tests for p in ps], dtype=int)

    def shown_plants(self) -> np.ndarray:
        """The plants the robot performed after the latest demo (r), for the picture."""
        rec = self.session.latest
        if rec is None:
            return np.zeros(0, dtype=int)
        return np.unique(np.r_[rec.shown, self.tested_plants()]).astype(int)

    def visibility(self, extra_shown=()):
        """What the trainee may see: r after the latest demo and the plants tested."""
        return super().visibility(np.r_[self.tested_plants(), np.asarray(extra_shown, int)])
