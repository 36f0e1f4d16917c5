r"""One teacher's runs in one arm of the adaptive-feedback study, traced demo by demo.

:func:`teach_policy` teaches a simulated teacher's runs in one arm (:mod:`.adaptive_plan`)
with the study's common random numbers (see :mod:`.adaptive`), on a run that keeps the
study's trace (:class:`TracedRun`: :math:`\varepsilon` against the clock after every demo
and every demo taken back, and the robot's seconds); :func:`arm_job` is the same for one
unit of work in a worker process.
"""

from __future__ import annotations

import time

import numpy as np

from ..teachers.traits import DEFAULT_POPULATION, Population
from .adaptive_plan import DEFAULT_VARIANT, EXPERIMENT, POLICIES, SETTINGS, VARIANTS, Policy
from .cohort import StudySettings, cohort_task, rows_of, teacher_rng

__all__ = ["TracedRun", "teach_policy"]


class TracedRun:
    """Mix-in for a protocol run: ``trace`` holds (event, seconds used, eps, demos) after
    every demo and every demo taken back; ``robot_seconds`` the time of every robot
    attempt during the run (after demos later taken back too)."""

    def _init_trace(self) -> None:
        self.trace: list[tuple[str, float, float, int]] = []
        self.robot_seconds = 0.0

    def _mark(self, event: str) -> None:
        rec = self.session.latest
        eps = 0.0 if rec is None else float(rec.efficacy)
        self.trace.append((event, float(self.elapsed), eps, self.session.n_demos))

    def add_demo(self, raw, *, seconds=None, **options):
        record = super().add_demo(raw, seconds=seconds, **options)
        self.robot_seconds += self.realisation_seconds * len(self.session.latest.shown)
        self._mark("demo")
        return record

    def undo(self):
        out = super().undo()
        self._mark("undo")
        return out

    def test(self, plants, after_run=None):
        during = not self.finished
        passed = super().test(plants, after_run)
        if during:
            self.robot_seconds += self.realisation_seconds * len(np.atleast_1d(plants))
        return passed


def _traced_class():
    from ..tasks.pickplace_protocol import PickPlaceRun

    class TracedPickPlaceRun(TracedRun, PickPlaceRun):
        """A :class:`PickPlaceRun` that keeps the study's trace (see :class:`TracedRun`)."""

        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self._init_trace()

    return TracedPickPlaceRun


def _new_run(policy: Policy, task, rng: np.random.Generator):
    """The traced run ``PickPlaceTeacher.teach`` would have made itself for ``policy``
    (AF's random selectors draw from a generator spawned from the run's, as there)."""
    from ..teachers.model import SIMULATED, simulated_clock

    options = dict(policy.options)
    if policy.spec.policy.adaptive:
        options["rng"] = rng.spawn(1)[0]
    return _traced_class()(
        policy.condition, task, trainee=SIMULATED, clock=simulated_clock, **options
    )


def teach_policy(
    policy: str | Policy,
    seed: int,
    teacher: int,
    runs: int = 3,
    population: Population = DEFAULT_POPULATION,
    settings: StudySettings = SETTINGS,
):
    """One teacher's ``runs`` runs in one arm, with the study's common random numbers.

    Returns
    -------
    rows : list of dict
        One per run: the cohort's columns (:func:`tutor.study.cohort.rows_of`) plus
        ``final_reached`` (eps >= 0.9 at the end), ``robot_seconds``, ``realisations``,
        ``demo_seconds`` (mean duration of the demos kept), ``compute_seconds`` (this
        machine's time to simulate the run: the only column that is not reproducible)
        and the teacher's traits.
    curve : list of dict
        One per demo and per demo taken back: ``step``, ``event``, ``seconds`` (clock
        used after it), ``efficacy`` and ``n_demos`` then.
    """
    from ..teachers.pickplace import PickPlaceTeacher

    policy = POLICIES[policy] if isinstance(policy, str) else policy
    traits = policy.traits(population.sample(teacher_rng(seed, EXPERIMENT, teacher, 0)))
    task = cohort_task("pickplace", settings)
    model = PickPlaceTeacher(traits, task)
    trait_cols = {f"trait_{k}": v for k, v in traits.to_dict().items() if k != "plan_focus"}
    rows, curve = [], []
    for number in range(1, runs + 1):
        rng = teacher_rng(seed, EXPERIMENT, teacher, number)
        started = time.perf_counter()
        run = model.teach(policy.condition, rng, run=_new_run(policy, task, rng))
        compute = time.perf_counter() - started
        base = {"seed": seed, "teacher": teacher, "policy": policy.name, "run": number}
        row, _ = rows_of(run, {**base, "condition": run.condition}, settings)
        demos = [d.seconds for d in run.attempt.demos if d.seconds is not None]
        row.update(
            final_reached=bool(row["efficacy"] >= settings.target),
            robot_seconds=run.robot_seconds,
            realisations=int(round(run.robot_seconds / run.realisation_seconds)),
            demo_seconds=float(np.mean(demos)) if demos else np.nan,
            compute_seconds=compute,
        )
        rows.append({**row, **trait_cols})
        for step, (event, seconds, eps, n_demos) in enumerate(run.trace, start=1):
            curve.append(
                {**base, "step": step, "event": event, "seconds": seconds,
                 "efficacy": eps, "n_demos": n_demos}
            )
        curve.append(
            {**base, "step": len(run.trace) + 1, "event": "end", "seconds": run.elapsed,
             "efficacy": row["efficacy"], "n_demos": row["n_demos"]}
        )
    return rows, curve


def arm_job(job):
    """One unit of work in a worker: (variant, seed, teacher, policy, runs, settings)."""
    variant, seed, teacher, policy, runs, settings = job
    population = DEFAULT_POPULATION if variant == DEFAULT_VARIANT else VARIANTS[variant]
    rows, curve = teach_policy(policy, seed, teacher, runs, population, settings)
    for r in (*rows, *curve):
        r["variant"] = variant
    return job[:4], rows, curve
