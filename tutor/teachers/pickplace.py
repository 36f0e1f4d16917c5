"""Simulated teachers of Experiment 2 (pick-and-place): NF, RF, BF and SF.

One :class:`PickPlaceTeacher` (one person's traits) teaches three runs of
:class:`~tutor.tasks.pickplace_protocol.PickPlaceRun` in their condition. The condition
changes only what they are shown and what that costs on the 15-minute clock:

NF  nothing while teaching: they follow their own plan of plants and stop when their
    prior says the robot has had enough demos (or the time is up).
RF  the robot replays the plant just demonstrated (25 s): a failed replay makes them
    notice a bad demo (e.g. a slip to the wrong plant), take it back and redo it.
BF  the robot tries the four corner plants and the centre one after every demo
    (125 s): they read these five and aim the next demo at a failing one.
SF  they ask the robot to try plants now and then (25 s each), choosing as novices
    do: mostly plants they demonstrated or their neighbours.

Every teacher also spends ``setup_seconds`` per demo (pointing at the plant, the
experimenter setting the target, the arm returning to its start) in every condition.
The belief, aiming and stopping rules are the shared ones of
:mod:`tutor.teachers.model`; there is no condition-specific skill.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from ..tasks.pickplace import PickPlaceTask
from ..tasks.pickplace_protocol import CONDITIONS, PickPlaceRun
from .model import TeacherModel
from .traits import TeacherTraits

__all__ = ["PickPlaceTeacher", "PICKPLACE_CONDITIONS", "NOVICE_TEST_NEAR"]

PICKPLACE_CONDITIONS = tuple(CONDITIONS)
#: SF: share of a novice's test choices that are a demonstrated plant or its neighbour
NOVICE_TEST_NEAR = 0.8


class PickPlaceTeacher:
    """One simulated teacher on the pick-and-place task.

    Parameters
    ----------
    traits : TeacherTraits
    task : PickPlaceTask, optional
    """

    def __init__(self, traits: TeacherTraits, task: PickPlaceTask | None = None):
        self.traits = traits
        self.task = PickPlaceTask() if task is None else task

    # ---------------------------------------------------------------- the hand

    def demonstration(self, plant: int, rng, slip: bool = False) -> np.ndarray:
        """A kinesthetic demo to ``plant`` with this teacher's hand wobble (t, x, y, z, g).

        A slip guides the arm to a neighbouring plant (the paper's demonstration error).
        """
        raw = self.task.demonstrate(plant, rng, mistake="wrong_plant" if slip else None)
        n = len(raw)
        s = np.linspace(0.0, 1.0, n)
        wobble = rng.normal(scale=self.traits.motor_noise, size=(n, 3))
        kernel = np.hanning(21) / np.hanning(21).sum()
        wobble = np.column_stack([np.convolve(wobble[:, j], kernel, mode="same") for j in range(3)])
        raw = raw.copy()
        raw[:, 1:4] += wobble * np.sin(np.pi * s)[:, None]
        return raw

    # ---------------------------------------------------------------- teaching

    def _model(self, rng) -> TeacherModel:
        plants = self.task.conditions[:, :2]
        lo, hi = plants.min(axis=0), plants.max(axis=0)
        return TeacherModel(self.traits, rng, plants, lo, hi, self.traits.enough_pickplace)

    def teach(self, condition: str, rng, run: PickPlaceRun | None = None) -> PickPlaceRun:
        """Teach one 15-minute run under ``condition``; returns the finished run.

        ``run.session.meta`` gains ``targets`` (why each plant was chosen: "plan",
        "red", "retry"), ``slips``, ``retries`` and ``why_stopped`` ("satisfied",
        "patience" or "time").
        """
        if condition not in CONDITIONS:
            raise InvalidParameterError(
                f"pick-and-place condition must be one of {', '.join(CONDITIONS)}, "
                f"got {condition!r}"
            )
        rng = np.random.default_rng(rng)
        t = self.traits
        run = PickPlaceRun(condition, self.task) if run is None else run
        model = self._model(rng)
        meta = run.session.meta
        meta.update(targets=[], slips=0, retries=0)
        retry = None
        why_stopped = "time"
        while not run.finished:
            m = run.session.n_demos
            if retry is not None:
                plant, why = retry, "retry"
            else:
                point, why = model.next_target(avoid=np.flatnonzero(model.belief.demonstrated))
                plant = model.nearest(point)
            run.spend(t.setup_seconds)
            if run.finished:
                break
            slip = model.slips()
            record = run.demonstrate(plant, raw=self.demonstration(plant, rng, slip))
            meta["targets"].append(why)
            meta["slips"] += int(slip)
            model.belief.demonstrated[plant] = True
            model.belief.observe(record.shown, record.passed[record.shown])
            if condition == "SF":
                self._self_test(run, model, rng)
            # (a) the robot fails right at the plant just shown: take it back, show it again
            seen = model.belief.seen[plant]
            if seen == 0 and retry is None:
                run.undo()
                meta["targets"].pop()
                model.belief.demonstrated[plant] = False
                meta["retries"] += 1
                retry = plant
                continue
            retry = None
            if model.satisfied(m + 1):
                why_stopped = "satisfied"
                break
            if run.session.n_demos >= t.patience:
                why_stopped = "patience"
                break
        meta["why_stopped"] = why_stopped
        run.finish()
        return run

    def _self_test(self, run: PickPlaceRun, model: TeacherModel, rng) -> None:
        """SF: maybe ask the robot to try one or two plants, chosen as a novice would."""
        if rng.random() >= self.traits.test_rate:
            return
        k = int(rng.integers(1, 3))
        demonstrated = np.flatnonzero(model.belief.demonstrated)
        rows, cols = self.task.scene.rows, self.task.scene.cols
        plants = []
        for _ in range(k):
            if demonstrated.size and rng.random() < NOVICE_TEST_NEAR:
                r, c = divmod(int(rng.choice(demonstrated)), cols)
                dr, dc = rng.integers(-1, 2, 2)
                plants.append(int(np.clip(r + dr, 0, rows - 1) * cols + np.clip(c + dc, 0, cols - 1)))
            else:
                plants.append(model.nearest(model.plan_point()))
        plants = sorted(set(plants))
        if run.realisation_seconds * len(plants) > run.remaining:
            return
        passed = run.test(plants)
        model.belief.observe(plants, passed)
