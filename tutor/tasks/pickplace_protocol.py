"""The protocol of Experiment 2 (Sena & Howard): four feedback conditions and the clock.

NF  no feedback while teaching; the teacher may test self-chosen plants after the run.
RF  replay: after each demo the robot replays that same plant (r = the demo's condition).
BF  batch: after each demo the robot performs the five generalisation samples
    (the four corner plants and the centre one).
SF  selected: the teacher chooses when and which plants the robot tries.

The clock the paper's teachers lived by: a demonstration costs its own duration, every
realisation the robot performs costs 25 s (a real arm is slow), and a teaching run is
capped at 15 minutes. Each trainee does three runs.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError, TutorError
from ..framework import TeachingSession
from .pickplace import PickPlaceTask

__all__ = ["CONDITIONS", "PickPlaceRun", "RunOverError"]

CONDITIONS = {"NF": "none", "RF": "replay", "BF": "batch", "SF": "selected"}


class RunOverError(TutorError, RuntimeError):
    """The teaching run has used its 15 minutes or was finished."""


class PickPlaceRun:
    """One teaching run of one trainee in one condition, with its clock.

    Parameters
    ----------
    condition : {"NF", "RF", "BF", "SF"}
    task : PickPlaceTask, optional
    session : TeachingSession, optional
        Resume this session (its ``meta`` holds the clock); a new one otherwise.
    """

    def __init__(self, condition: str, task: PickPlaceTask | None = None, session=None):
        if condition not in CONDITIONS:
            raise InvalidParameterError(
                f"condition must be one of {', '.join(CONDITIONS)}, got {condition!r}"
            )
        self.task = PickPlaceTask() if task is None else task
        self.condition = condition
        if session is None:
            session = TeachingSession(
                self.task,
                feedback=CONDITIONS[condition],
                batch=self.task.scene.generalisation_indices if condition == "BF" else None,
            )
            session.meta.update(condition=condition, demo_seconds=[], tests=[], finished=False)
        self.session = session

    # ---------------------------------------------------------------- the clock

    @property
    def cap(self) -> float:
        return self.task.scene.run_seconds

    @property
    def realisation_seconds(self) -> float:
        return self.task.scene.realisation_seconds

    @property
    def elapsed(self) -> float:
        """Seconds used: demos, plus 25 s for every realisation shown during the run.

        Also counts :meth:`spend` time and the time of demos taken back with :meth:`undo`.
        """
        meta = self.session.meta
        shown = sum(len(r.shown) for r in self.session.history)
        tested = sum(len(t["plants"]) for t in meta["tests"] if not t["after_run"])
        other = float(meta.get("other_seconds", 0.0))
        robot = self.realisation_seconds * (shown + tested)
        return float(sum(meta["demo_seconds"])) + robot + other

    @property
    def remaining(self) -> float:
        return max(0.0, self.cap - self.elapsed)

    @property
    def finished(self) -> bool:
        return bool(self.session.meta["finished"]) or self.remaining <= 0

    def clock_text(self) -> str:
        used, cap = self.elapsed, self.cap
        return f"{int(used // 60)}:{int(used % 60):02d} of {int(cap // 60)}:00 used"

    # ---------------------------------------------------------------- teaching

    def demonstrate(self, plant: int, raw=None, mistake=None, rng=None):
        """Give one demonstration to ``plant`` (recorded, or generated kinesthetically)."""
        if self.finished:
            raise RunOverError(
                "this run is over (15 minutes used or finished): start the next run to go on"
            )
        plant = self._check_plant(plant)
        if raw is None:
            raw = self.task.demonstrate(plant, rng, mistake=mistake)
        record = self.session.add_demo(raw, condition=self.task.conditions[plant])
        self.session.meta["demo_seconds"].append(self.task.duration(raw))
        return record

    def test(self, plants) -> np.ndarray:
        """The robot tries ``plants``: SF during the run (25 s each), any condition after it.

        Returns the pass/fail of each tried plant (after the latest demo).
        """
        plants = [self._check_plant(p) for p in np.atleast_1d(plants)]
        after = self.finished
        if not after and self.condition != "SF":
            raise RunOverError(
                f"in condition {self.condition} the robot can be tested only after the run"
            )
        rec = self.session.latest
        if rec is None:
            raise InvalidParameterError("give a demonstration before testing the robot")
        cost = self.realisation_seconds * len(plants)
        if not after and cost > self.remaining:
            raise RunOverError(
                f"testing {len(plants)} plant(s) takes {cost:.0f} s but only "
                f"{self.remaining:.0f} s are left"
            )
        self.session.meta["tests"].append(
            {"after_demo": rec.n_demos, "plants": plants, "after_run": after}
        )
        return rec.passed[plants]

    def finish(self) -> None:
        self.session.meta["finished"] = True

    def spend(self, seconds: float) -> None:
        """Count time besides demos and realisations (e.g. choosing and setting a plant)."""
        if not seconds >= 0:
            raise InvalidParameterError(f"seconds must be >= 0, got {seconds}")
        meta = self.session.meta
        meta["other_seconds"] = float(meta.get("other_seconds", 0.0)) + float(seconds)

    def undo(self):
        """Take back the latest demo; the time it and its realisations took stays spent.

        Returns the record now current (None when no demo is left).
        """
        s = self.session
        rec = s.latest
        if rec is None:
            raise InvalidParameterError("there is no demo to undo")
        meta = s.meta
        tests = [t for t in meta["tests"] if t["after_demo"] == rec.n_demos and not t["after_run"]]
        spent = meta["demo_seconds"][-1] + self.realisation_seconds * (
            len(rec.shown) + sum(len(t["plants"]) for t in tests)
        )
        meta["tests"] = [t for t in meta["tests"] if t["after_demo"] < rec.n_demos]
        meta["demo_seconds"] = meta["demo_seconds"][:-1]
        self.spend(spent)
        return s.undo()

    def _check_plant(self, plant) -> int:
        n = len(self.task.conditions)
        try:
            index = int(plant)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"a plant is a number from 0 to {n - 1}") from exc
        if not 0 <= index < n or index != plant:
            raise InvalidParameterError(f"a plant is a number from 0 to {n - 1}, got {plant!r}")
        return index

    # ---------------------------------------------------------------- what the teacher sees

    def shown_plants(self) -> np.ndarray:
        """The plants the robot performed after the latest demo (r), for the picture."""
        rec = self.session.latest
        if rec is None:
            return np.zeros(0, dtype=int)
        tests = [t["plants"] for t in self.session.meta["tests"] if t["after_demo"] == rec.n_demos]
        extra = np.array([p for ps in tests for p in ps], dtype=int)
        return np.unique(np.r_[rec.shown, extra]).astype(int)
