"""Simulated teachers of Experiment 2 (pick-and-place): NF, RF, BF and SF (and AF, HF).

One :class:`PickPlaceTeacher` (one person's traits) teaches three runs of
:class:`~tutor.tasks.pickplace_protocol.PickPlaceRun` in their condition. The condition
changes only what they are shown and what that costs on the 15-minute clock:

NF  nothing while teaching: they follow their own plan of plants and stop when their
    prior says the robot has had enough demos (or the time is up); after the run they
    may try a few plants of their choice.
RF  the robot replays the plant just demonstrated (25 s): a failed replay makes them
    notice a bad demo (e.g. a slip to the wrong plant), take it back and redo it
    (at most twice in a row). The same rule holds in every condition, but only RF
    always shows the demonstrated plant.
BF  the robot tries the four corner plants and the centre one after every demo
    (125 s): they read these five and aim the next demo at a failing one.
SF  they ask the robot to try plants now and then (25 s each), choosing as novices
    do: mostly plants they demonstrated or their neighbours.
AF  (beyond the paper) the robot tries the k plants a selector picks after every demo
    (25 s each): they read them exactly as BF's five (same belief, same aiming at a
    failing one, same traits); only which plants are shown differs.
HF  (beyond the paper) nothing is shown, as in NF, but before each demo the tutor
    names the plant the robot would learn most from next (:meth:`PickPlaceRun.hint`):
    with chance ``compliance`` they demonstrate it, otherwise the plant they would
    have chosen in NF. They stop as in NF (their prior; nothing shown) and test a few
    plants after the run as NF does.

Between runs a teacher remembers the plants they saw the robot fail at (during the
run, or for NF in the tests they choose after it) and starts the next run's plan there.

Every teacher also spends ``setup_seconds`` per demo (pointing at the plant, the
experimenter setting the target, the arm returning to its start) in every condition.
The belief, aiming and stopping rules are the shared ones of
:mod:`tutor.teachers.model`; there is no condition-specific skill.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from ..tasks.pickplace import PickPlaceTask
from ..tasks.pickplace_protocol import PickPlaceRun
from .model import SIMULATED, TeacherModel, simulated_clock
from .traits import TeacherTraits

__all__ = ["PickPlaceTeacher", "NOVICE_TEST_NEAR", "MAX_RETRIES"]
#: SF: share of a novice's test choices that are a demonstrated plant or its neighbour
NOVICE_TEST_NEAR = 0.8
#: how many times in a row a teacher redoes a demo the robot was seen failing
MAX_RETRIES = 2


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
        #: plants seen failing in the previous run: the next run's plan starts there
        self.lessons: list[int] = []

    # ---------------------------------------------------------------- the hand

    def demonstration(self, plant: int, rng, slip: bool = False) -> np.ndarray:
        """A kinesthetic demo to ``plant`` (t, x, y, z, g).

        The hand's variability is the task's own model of a person guiding the arm
        (:meth:`~tutor.tasks.pickplace.PickPlaceTask.demonstrate`); ``motor_noise`` is
        not added on top (it would push correct grabs past half a plant's pitch). A
        slip guides the arm to a neighbouring plant (the paper's demonstration error).
        """
        return self.task.demonstrate(plant, rng, mistake="wrong_plant" if slip else None)

    # ---------------------------------------------------------------- teaching

    def _model(self, rng) -> TeacherModel:
        plants = self.task.test_points[:, :2]
        lo, hi = plants.min(axis=0), plants.max(axis=0)
        return TeacherModel(self.traits, rng, plants, lo, hi, "pickplace")

    def teach(
        self, condition: str, rng, run: PickPlaceRun | None = None, **adaptive
    ) -> PickPlaceRun:
        """Teach one 15-minute run under ``condition``; returns the finished run.

        ``adaptive`` (AF only): ``selector=`` and ``k=`` instead of AF's defaults. The
        random selectors draw from a generator spawned from ``rng`` (the teacher's own
        draws are unchanged by it).

        HF: before each demo the teacher asks ``run.hint()`` and follows it with chance
        ``traits.compliance`` (one draw from ``rng``); a hinted demo's ``chosen_by`` is
        "hint", and every HF demo's ``followed_rule`` says whether it went to the hinted
        plant.

        Its record tells the story: each demo's ``chosen_by`` (why the plant was chosen:
        "plan", "red", "retry", "hint") and ``mistake`` ("wrong_plant" when the hand
        slipped), the undo events (retries) and the attempt's ``stopped`` ("satisfied",
        "patience" or "time").
        """
        spec = PickPlaceRun.protocol().condition(condition)
        if adaptive and not spec.policy.adaptive:
            raise InvalidParameterError(
                f"selector= and k= are only for the adaptive conditions, not {condition}"
            )
        rng = np.random.default_rng(rng)
        t = self.traits
        if run is None:
            if spec.policy.adaptive:
                adaptive["rng"] = rng.spawn(1)[0]
            run = PickPlaceRun(
                condition, self.task, trainee=SIMULATED, clock=simulated_clock, **adaptive
            )
        model = self._model(rng)
        model.lessons = list(self.lessons)
        hinted = spec.hinted
        retry, tries = None, 0
        why_stopped = "time"
        while not run.finished:
            m = run.session.n_demos
            if retry is not None:
                plant, why = retry, "retry"
            elif hinted and rng.random() < t.compliance:
                plant, why = run.hint().plant, "hint"
            else:
                point, why = model.next_target(avoid=np.flatnonzero(model.belief.demonstrated))
                plant = model.nearest(point)
            run.spend(t.setup_seconds)
            if run.finished:
                break
            slip = model.slips()
            raw = self.demonstration(plant, rng, slip)
            if not run.fits(self.task.duration(raw)):
                break  # as the paper ran it: a demo that cannot end by 15:00 is not started
            record = run.demonstrate(
                plant,
                raw=raw,
                chosen_by=why,
                mistake="wrong_plant" if slip else None,
                given="simulated",
            )
            model.belief.demonstrate(plant)
            model.belief.observe(record.shown, record.passed[record.shown])
            fresh = set(record.shown.tolist())
            if spec.policy.teacher_picks:
                fresh |= self._self_test(run, model, rng)
            # (a) watching the robot do the plant just shown: it fails, or the teacher
            # notices their demo went to another plant: take it back, show it again
            noticed = slip and rng.random() < t.notice_rate
            failed = model.belief.seen[plant] == 0
            if plant in fresh and (failed or noticed) and tries < MAX_RETRIES:
                run.undo()
                model.belief.demonstrated[plant] = False
                retry, tries = plant, tries + 1
                continue
            retry, tries = None, 0
            if model.satisfied(m + 1):
                why_stopped = "satisfied"
                break
            if run.session.n_demos >= t.patience:
                why_stopped = "patience"
                break
        run.finish(why_stopped)
        if spec.policy.silent and run.session.n_demos:
            # NF (and HF): self-chosen realisations only after the run, as novices do
            self._self_test(run, model, rng, always=True)
        self.lessons = list(model.belief.failures_seen)
        return run

    def _self_test(self, run: PickPlaceRun, model: TeacherModel, rng, always=False) -> set[int]:
        """Maybe ask the robot to try one or two plants, chosen as a novice would.

        SF during the run (with chance ``test_rate``); NF after it (``always``).
        Returns the plants tried (empty when none).
        """
        if not always and rng.random() >= self.traits.test_rate:
            return set()
        k = int(rng.integers(1, 3))
        demonstrated = np.flatnonzero(model.belief.demonstrated)
        rows, cols = self.task.scene.rows, self.task.scene.cols
        plants = []
        for _ in range(k):
            if demonstrated.size and rng.random() < NOVICE_TEST_NEAR:
                r, c = divmod(int(rng.choice(demonstrated)), cols)
                dr, dc = rng.integers(-1, 2, 2)
                r, c = np.clip(r + dr, 0, rows - 1), np.clip(c + dc, 0, cols - 1)
                plants.append(int(r * cols + c))
            else:
                plants.append(model.nearest(model.plan_point()))
        plants = sorted(set(plants))
        if not run.finished and run.realisation_seconds * len(plants) > run.remaining:
            return set()
        passed = run.test(plants)
        model.belief.observe(plants, passed)
        return set(plants)
