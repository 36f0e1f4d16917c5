r"""The adaptive-feedback study: does choosing :math:`r` automatically beat BF?

Sena & Howard end on an open problem: choosing the set :math:`r` of realisations the
robot shows after a demo automatically and economically (their BF fixed the four corner
plants and the centre by hand). This study puts the selectors of
:mod:`tutor.framework.selectors` (and, where the tutor has it, the next-demo hint HF)
to the test with the simulated teachers of Experiment 2, on the paper's 15-minute clock.

Policies (:data:`POLICIES`, a registry: name -> how a teacher is taught)

========= ============================================================================
BF        the paper's batch feedback: the four corners and the centre (125 s a demo)
KC5, KC2  farthest point (k-centre), k = 5 (BF's cost) and k = 2
DIS2      frame disagreement and distance, k = 2 (DIS5 is AF's default, optional)
RAND2     k = 2 plants at random (the control; RAND5 optional)
ORC2      the oracle: 2 plants the robot fails at (reference only, no real robot can)
HF0.5/HF1 the next-demo hint, followed with probability 0.5 and 1 (the teachers'
          ``compliance``): only when the tutor has the HF condition
========= ============================================================================

Nothing is tuned per policy: every policy uses the selectors' and the teachers' defaults.

**Common random numbers.** For a seed and a teacher index, every policy gets the same
traits (``population.sample(SeedSequence([seed, 2, teacher, 0]))``, exactly as the
cohort of :mod:`tutor.study.cohort` draws them) and the same generator for each run
(``SeedSequence([seed, 2, teacher, run])``). Each policy gets its own fresh
:class:`~tutor.teachers.pickplace.PickPlaceTeacher`, which keeps its memory between its
three runs as in the cohort. A teacher of the cohort in BF (teachers 18-26 of 36) thus
gives the same runs as this study's BF arm for that teacher (``tests`` check it).

**What is measured per run** (one row of :attr:`StudyResult.runs`): the final efficacy
:math:`\varepsilon` at the end of the 900 s run, whether 0.9 was reached (at some demo,
and at the end), undemonstrated plants at the end, demos, the paper's
:math:`\eta = \varepsilon / |b|` and :math:`\eta_{0.9}` (Experiment 1's rule: demos to
first reach 0.9), robot seconds (every realisation shown or tested during the run x
25 s, those of demos taken back included) and the clock used; and (in
:attr:`StudyResult.curves`) :math:`\varepsilon` against the clock after every demo and
every demo taken back. The statistics are in :mod:`tutor.study.adaptive_stats`, the
report, figure and files in :mod:`tutor.study.adaptive_report`.

**Robustness.** The same comparison under teacher-model variants (:data:`VARIANTS`:
less patient, noisier aim, more repeats, fewer demos believed enough), on fewer seeds.

The arms, variants and plan are in :mod:`tutor.study.adaptive_plan`, one teacher's runs
in one arm in :mod:`tutor.study.adaptive_arm`; this module runs the whole study
(:func:`run_study`) and every name above is importable from here.

Command line: ``lfd-tutor adaptive --seeds 10 --out DIR`` (``--quick`` for a reduced
run).
"""

from __future__ import annotations

import dataclasses
import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..engine import Engine
from .adaptive_arm import TracedRun, arm_job, teach_policy
from .adaptive_plan import (
    DEFAULT_POLICIES,
    DEFAULT_VARIANT,
    EXPERIMENT,
    POLICIES,
    QUICK,
    ROBUSTNESS_POLICIES,
    SETTINGS,
    TEACHERS_RANGE,
    VARIANTS,
    Policy,
    StudyPlan,
    _whole,
    available_policies,
    check_plan,
    is_secondary,
    policy_available,
)
from .cohort import StudySettings

__all__ = [
    "Policy",
    "POLICIES",
    "DEFAULT_POLICIES",
    "VARIANTS",
    "ROBUSTNESS_POLICIES",
    "StudyPlan",
    "StudyResult",
    "QUICK",
    "TracedRun",
    "available_policies",
    "check_plan",
    "policy_available",
    "is_secondary",
    "teach_policy",
    "run_study",
    "EXPERIMENT",
    "TEACHERS_RANGE",
]


@dataclass
class StudyResult:
    """What the study produced.

    Attributes
    ----------
    plan : StudyPlan
        The plan as run (HF arms dropped when the tutor lacks them).
    runs : DataFrame
        One row per variant, seed, teacher, policy and run (see :func:`teach_policy`);
        the main study is ``variant == "default"``.
    curves : DataFrame
        The per-demo curves (same keys plus ``step``).
    missing : tuple of str
        Arms asked for that this tutor cannot teach (e.g. HF before it lands).
    seconds : float
        Wall time of the simulation (of this call, when it resumed a checkpoint).
    settings : StudySettings
    resumed : int
        Jobs (one teacher's runs in one arm) read back from a checkpoint.
    """

    plan: StudyPlan
    runs: pd.DataFrame
    curves: pd.DataFrame
    missing: tuple = ()
    seconds: float = 0.0
    settings: StudySettings = SETTINGS
    resumed: int = 0

    @property
    def main(self) -> pd.DataFrame:
        """The main study's runs (the default population)."""
        return self.runs[self.runs.variant == DEFAULT_VARIANT]


def jobs_of(plan: StudyPlan, settings: StudySettings = SETTINGS) -> list[tuple]:
    """Every unit of work of a (checked) plan: one teacher's runs in one arm."""
    def teachers(policy: str) -> range:
        hinted = POLICIES[policy].hinted and plan.hf_teachers is not None
        return range(plan.hf_teachers if hinted else plan.n)

    def seeds(policy: str) -> range:
        few = is_secondary(policy) and plan.secondary_seeds is not None
        return range(min(plan.secondary_seeds, plan.seeds) if few else plan.seeds)

    jobs = [
        (DEFAULT_VARIANT, s, t, p, plan.runs, settings)
        for p in plan.policies
        for s in seeds(p)
        for t in teachers(p)
    ]
    jobs += [
        (v, s, t, p, plan.runs, settings)
        for v in plan.variants
        for s in range(plan.variant_seeds)
        for p in plan.variant_policies
        for t in teachers(p)
    ]
    return jobs


def _python(value):
    """numpy scalars as Python numbers (for JSON)."""
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to a checkpoint")


class _Checkpoint:
    """Finished jobs appended to a JSON-lines file as they come, so an interrupted study
    resumes where it stopped.

    The first line names the plan and the settings. A job's numbers depend only on its
    key (variant, seed, teacher, arm), the runs per teacher and the settings, so any plan
    with the same runs and settings reuses every job it shares (e.g. ``--seeds 7`` after
    an interrupted ``--seeds 10``); otherwise the file starts over.
    """

    def __init__(self, path, plan: StudyPlan, settings: StudySettings):
        import json
        from pathlib import Path

        self.path = Path(path)
        self.head = {"plan": plan.to_dict(), "settings": dataclasses.asdict(settings)}
        self.head = json.loads(json.dumps(self.head))  # tuples as lists, as read back
        self.done: dict = {}
        if self.path.is_file():
            lines = self.path.read_text().splitlines()
            try:
                same = bool(lines) and self._same(json.loads(lines[0]))
                if same:
                    for line in lines[1:]:
                        item = json.loads(line)
                        self.done[tuple(item["key"])] = (item["rows"], item["curve"])
            except (ValueError, KeyError, TypeError):  # a torn last line: keep what parsed
                same = bool(self.done)
            if not same:
                self.done = {}
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fresh = self.path.with_name(self.path.name + ".new")  # replaced whole, never torn
        self.file = fresh.open("w")
        self.file.write(json.dumps(self.head) + "\n")
        for key, (rows, curve) in self.done.items():
            self._write(key, rows, curve)
        self.file.close()
        os.replace(fresh, self.path)
        self.file = self.path.open("a")

    def _same(self, head) -> bool:
        """Whether a checkpoint's jobs hold this plan's numbers (runs and settings)."""
        mine = self.head
        return head["plan"]["runs"] == mine["plan"]["runs"] and head["settings"] == mine[
            "settings"
        ]

    def _write(self, key, rows, curve) -> None:
        import json

        item = {"key": list(key), "rows": rows, "curve": curve}
        self.file.write(json.dumps(item, default=_python) + "\n")
        self.file.flush()

    def add(self, key, rows, curve) -> None:
        self.done[key] = (rows, curve)
        self._write(key, rows, curve)

    def close(self) -> None:
        self.file.close()


def run_study(
    plan: StudyPlan = StudyPlan(),  # noqa: B008 - a frozen dataclass, a safe default
    workers: int | None = None,
    progress: bool | Callable = True,
    settings: StudySettings = SETTINGS,
    checkpoint=None,
    scheduler: str | None = None,
) -> StudyResult:
    """Simulate the study on ``workers`` processes (default: every core), or on a Dask
    cluster (``scheduler``: ``"auto"`` or ``"tcp://HOST:PORT"``, :class:`tutor.engine.Engine`).

    The numbers depend on the plan and the seeds only, not on ``workers``, the order
    the work is done in, or a resumed ``checkpoint``.

    Parameters
    ----------
    checkpoint : path, optional
        A JSON-lines file each finished job is appended to; a study interrupted with the
        same plan resumes from it (its jobs are not simulated again).

    Raises
    ------
    InvalidParameterError
        A bad plan (:func:`check_plan`) or ``workers``.
    """
    asked = tuple(dict.fromkeys((*plan.policies, *plan.variant_policies)))
    plan = check_plan(plan)
    missing = tuple(p for p in asked if p not in (*plan.policies, *plan.variant_policies))
    if workers is None:
        workers = os.cpu_count() or 1
    workers = _whole(workers, "workers", 1, 256)
    order = [job[:4] for job in jobs_of(plan, settings)]
    saved = None if checkpoint is None else _Checkpoint(checkpoint, plan, settings)
    done = {} if saved is None else saved.done
    resumed = len(done)
    # the main arms seed by seed (an interrupted study has whole seeds of them), then the
    # secondary arms, the variants last; the slow HF jobs first among the secondary
    jobs = sorted(
        (j for j in jobs_of(plan, settings) if j[:4] not in done),
        key=lambda j: (
            j[0] != DEFAULT_VARIANT, is_secondary(j[3]), j[1], not POLICIES[j[3]].hinted
        ),
    )
    bar = None
    if progress:
        from tqdm.auto import tqdm

        tqdm.monitor_interval = 0
        bar = tqdm(total=len(order), initial=resumed, desc="adaptive study", unit="teacher-arm")
    started = time.perf_counter()

    def keep(key, rows, curve):
        if saved is None:
            done[key] = (rows, curve)
        else:
            saved.add(key, rows, curve)
        if bar is not None:
            bar.update(1)

    try:
        with Engine(workers, scheduler) as engine:
            for _, (key, rows, curve) in engine.results(arm_job, jobs):
                keep(key, rows, curve)  # each kept (and checkpointed) as it arrives
    finally:
        if bar is not None:
            bar.close()
        if saved is not None:
            saved.close()
    seconds = time.perf_counter() - started
    runs = pd.DataFrame([r for key in order for r in done[key][0]])
    curves = pd.DataFrame([r for key in order for r in done[key][1]])
    front = ["variant", "seed", "teacher", "policy", "run"]
    runs = runs[front + [c for c in runs.columns if c not in front]]
    curves = curves[front + [c for c in curves.columns if c not in front]]
    return StudyResult(plan, runs, curves, missing, seconds, settings, resumed)
