"""Simulated cohorts: the paper's two experiments rerun with simulated teachers.

Experiment 1 (maze), within subjects: N teachers (paper: 30), each teaches under NF,
VF and VR (in that order, as in the paper; nothing carries over between conditions).
Experiment 2 (pick-and-place), between subjects: N teachers (paper: 36), a quarter
in each of NF, RF, BF and SF (teacher i is in condition ``i // (N / 4)``), three
15-minute runs each. ``conditions=`` adds conditions beyond the paper (e.g.
``("NF", "RF", "BF", "SF", "AF")``, AF the adaptive feedback of
:mod:`tutor.framework.selectors`); teachers are then split evenly over those. The
default is the paper's four.

Reproducibility: each teacher's randomness comes from
``numpy.random.SeedSequence([seed, experiment, teacher, stream])`` (stream 0 draws the
traits, stream k >= 1 the k-th run), so a teacher's numbers do not depend on which
worker process ran them or in what order; results are sorted by teacher. Workers use
one BLAS/OpenMP thread each.

Experiment 2's teachers keep their memory between their three runs (the plants they
saw fail); Experiment 1's start every condition afresh.

Scores: Experiment 1 uses the paper's rule (demos to first reach 90 % coverage, or all
demos; eta there). Experiment 2 uses eta = eps / |b| of the final demonstration set of
each run (the paper gives no 90 % rule for it). Failures are counted on each run's
final demonstration set (see :func:`run_rows`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from contextlib import nullcontext
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..engine import Engine
from ..errors import InvalidParameterError
from ..framework.failures import Thresholds, is_ambiguous
from ..framework.protocol import EXPERIMENTS
from ..framework.protocol import experiment as experiment_of
from ..tasks import make_task
from ..teachers import TEACHERS
from ..teachers.traits import DEFAULT_POPULATION, Population
from .limits import MAX_SEED, MAX_TEACHERS

__all__ = [
    "CohortResult",
    "StudySettings",
    "run_experiment",
    "simulate_teacher",
    "teach_runs",
    "rows_of",
    "check_request",
    "MAX_TEACHERS",
    "min_teachers",
    "check_conditions",
]





def check_conditions(experiment: int, conditions=None) -> tuple[str, ...]:
    """The conditions of a cohort: the paper's by default; Experiment 2 may add AF,
    Experiment 1 VA (beyond the paper: adaptive feedback).

    Raises
    ------
    InvalidParameterError
        Not a sequence of distinct known conditions of the experiment.
    """
    design = experiment_of(experiment)
    if conditions is None:
        return design.paper_codes
    known = design.codes
    if isinstance(conditions, str):
        conditions = (conditions,)
    try:
        chosen = tuple(conditions)
    except TypeError:
        chosen = ()
    if not chosen or len(set(chosen)) != len(chosen) or any(c not in known for c in chosen):
        raise InvalidParameterError(
            f"conditions must be distinct conditions of Experiment {experiment} "
            f"({', '.join(known)}), e.g. {tuple(known)!r}; got {conditions!r}"
        )
    return chosen


def min_teachers(experiment: int, conditions=None) -> int:
    """The smallest cohort whose statistics can be computed.

    Experiment 1 (within subjects, k conditions) needs n >= k: Mauchly's sphericity test
    estimates the (k - 1, k - 1) covariance of the condition contrasts from n - 1 degrees
    of freedom, and with n = k - 1 its correction factor divides by zero. Experiment 2
    (between subjects) needs 2 teachers per condition for a variance within each group.
    """
    k = len(check_conditions(experiment, conditions))
    return k if EXPERIMENTS[experiment].within_subjects else 2 * k


@dataclass(frozen=True)
class StudySettings:
    """Analysis settings of the simulated study (one place).

    Attributes
    ----------
    target : float
        Experiment 1's coverage for the score (the paper's 90 %).
    pickplace_ambiguity : float or None
        delta_a (m) for counting ambiguous pick-and-place demos; None (the default):
        no similarity test, the efficacy change alone, as the paper counted its failure
        table for Experiment 2 ("ambiguous demonstrations are found by considering the
        learner's efficacy as defined by" delta_l <= eps_m - eps_{m-1} <= delta_u). A
        first demo is never ambiguous: there is nothing for it to repeat. Until
        2026-12-07 the cohorts used 3 cm (a demo at the same or the next plant; the
        task's own 1 cm never fires with the kinesthetic demos, two demos of one plant
        being 1.5-2.6 cm apart): 1-15 ambiguous demos per condition in the seed-0
        cohort against the paper's 6-54, 10-78 with the paper's rule.
    pickplace_feasibility : bool
        Whether criterion (i) also checks the arm (the task's ``feasibility="map"``),
        as the paper's B requires. Off: the cohort judges table, tray, grab and
        release only. Measured with the paper's cohort at seed 0: the same numbers
        either way (no realisation failed only because of the arm), 17 s on against
        12 s off.
    maze_blocks : tuple of 4 (float or None), or None
        The maze's two wall blocks (m): reach, low, height and gap of
        :meth:`~tutor.tasks.maze.MazeLayout.with_blocks` (None: the bundled layout's).
        The calibration (:mod:`tutor.study.calibration`) varies them.
    """

    target: float = 0.9
    pickplace_ambiguity: float | None = None
    pickplace_feasibility: bool = True
    maze_blocks: tuple | None = None

    def ambiguity(self, name: str) -> float | None:
        """delta_a for task ``name``'s runs: pick-and-place's setting (inf: no
        similarity test), else None (the task's own)."""
        if name != "pickplace":
            return None
        return math.inf if self.pickplace_ambiguity is None else self.pickplace_ambiguity

    def task_options(self, name: str) -> dict:
        """The options a cohort builds task ``name`` with (:func:`tutor.tasks.make_task`)."""
        if name == "maze" and self.maze_blocks is not None:
            from ..tasks.maze import load_layout

            return {"layout": load_layout().with_blocks(*self.maze_blocks)}
        feasibility = "map" if self.pickplace_feasibility else None
        return {"pickplace": {"feasibility": feasibility}}.get(name, {})


@dataclass
class CohortResult:
    """What a simulated cohort produced.

    Attributes
    ----------
    experiment : int
    seed : int
    runs : pandas.DataFrame
        One row per teacher, condition and run: scores, failures and the teacher's traits.
    demos : pandas.DataFrame
        One row per demonstration in each final set (efficacy after it, delta,
        similarity, correct or not, ambiguous or not, how its place was chosen).
    """

    experiment: int
    seed: int
    runs: pd.DataFrame
    demos: pd.DataFrame
    settings: StudySettings = field(default_factory=StudySettings)


def check_request(experiment, n=None, seed=0, conditions=None) -> tuple[int, int, int]:
    """Validate (experiment, n, seed); returns them with n defaulted to the paper's.

    ``conditions`` (Experiment 2, see :func:`check_conditions`) changes how many
    teachers there must be: a multiple of the number of conditions, 2 each at least.
    """
    if isinstance(experiment, bool) or experiment not in EXPERIMENTS:
        raise InvalidParameterError(
            f"experiment must be 1 (maze) or 2 (pick-and-place), got {experiment!r}"
        )
    spec = EXPERIMENTS[experiment]
    chosen = check_conditions(experiment, conditions)
    n = spec.n_teachers if n is None and conditions is None else n
    if n is None:  # the paper's 9 per condition
        n = spec.n_teachers // len(spec.paper_codes) * len(chosen)
    if not isinstance(n, int | np.integer) or isinstance(n, bool):
        raise InvalidParameterError(f"the number of teachers must be an integer, got {n!r}")
    k, smallest = len(chosen), min_teachers(experiment, chosen)
    if n > MAX_TEACHERS:
        raise InvalidParameterError(
            f"Experiment {experiment} can simulate at most {MAX_TEACHERS} teachers (100 times "
            f"the paper's cohort), got n = {n}; give a smaller n (the paper used {spec.n_teachers})"
        )
    if spec.within_subjects and n < smallest:
        raise InvalidParameterError(
            f"Experiment {experiment} needs at least {smallest} teachers for its statistics "
            f"(the sphericity test of its {k} conditions), got n = {n}; the paper used "
            f"{spec.n_teachers}"
        )
    if not spec.within_subjects and (n < smallest or n % k):
        raise InvalidParameterError(
            f"Experiment {experiment} needs a multiple of {k} teachers, at least {smallest} (2 "
            f"per condition), got n = {n}; the paper used {spec.n_teachers} for its "
            f"{len(spec.paper_codes)}"
        )
    if (
        not isinstance(seed, int | np.integer)
        or isinstance(seed, bool)
        or not 0 <= seed <= MAX_SEED
    ):
        raise InvalidParameterError(
            f"the seed must be a whole number from 0 to {MAX_SEED}, got {seed!r}"
        )
    return int(experiment), int(n), int(seed)


def teacher_rng(seed: int, experiment: int, teacher: int, stream: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([seed, experiment, teacher, stream]))


# ---------------------------------------------------------------- one teacher (in a worker)

_TASKS: dict = {}


def cohort_task(name: str, settings: StudySettings):
    key = (name, settings.pickplace_feasibility, settings.maze_blocks)
    if key not in _TASKS:
        _TASKS[key] = make_task(name, **settings.task_options(name))
    return _TASKS[key]


def run_rows(run, base: dict, ambiguity: float | None, target: float):
    """Summarise one finished run: one row for ``runs`` and its rows for ``demos``.

    Failures on the final demonstration set b: *errors* are demos that fail the task
    criteria themselves (b not in B); *undemonstrated* is |B^ minus (R^ or b)| after the
    last demo; *ambiguous* counts demos with s(b, b_set) <= delta_a and
    delta_l <= eps_m - eps_{m-1} <= delta_u (re-checked here with ``ambiguity`` as
    delta_a, the task's own when None, no similarity test when inf); a first demo is
    never ambiguous.
    """
    session, attempt = run.session, run.attempt
    history = session.history
    thr = Thresholds()
    delta_a = session.task.ambiguity_distance if ambiguity is None else ambiguity
    demo_rows = []
    for rec, demo in zip(history, attempt.demos, strict=True):
        demo_rows.append(
            {
                **base,
                "demo": rec.n_demos,
                "efficacy": rec.efficacy,
                "delta": rec.delta,
                "similarity": None if np.isinf(rec.similarity) else rec.similarity,
                "correct": rec.demo_passed,
                "ambiguous": rec.demo_passed
                and is_ambiguous(rec.similarity, rec.delta, delta_a, thr),
                "chosen_by": demo.chosen_by,
            }
        )
    last = history[-1]
    # demos to the target coverage (a column of its own, whatever the experiment)
    sc = session.score(rule="target", target=target)
    eta = run.score(target).efficiency  # the run's one score, by its experiment's rule
    row = {
        **base,
        "n_demos": last.n_demos,
        "efficacy": last.efficacy,
        "eta": eta,
        "demos_to_target": sc.n_demos,
        "eta_target": sc.efficiency,
        "reached_target": sc.reached,
        "errors": sum(not r.demo_passed for r in history),
        "undemonstrated": last.n_undemonstrated,
        "ambiguous": sum(d["ambiguous"] for d in demo_rows),
        "slips": sum(bool(d.mistake) for d in (*attempt.demos, *attempt.undone)),
        "retries": len(attempt.undone),
        "why_stopped": attempt.stopped,
    }
    return row, demo_rows


def teach_runs(
    experiment: int,
    teacher: int,
    seed: int,
    n: int,
    population: Population = DEFAULT_POPULATION,
    settings: StudySettings = StudySettings(),
    conditions=None,
):
    """One simulated teacher's runs, in the order they are taught.

    Yields ``(traits, number, run)``: the teacher's
    :class:`~tutor.teachers.traits.TeacherTraits`, the run's number and the finished
    :class:`~tutor.framework.run.TeachingRun` (Experiment 1: NF, VF, VR, each run 1;
    Experiment 2: runs 1-3 of the teacher's condition, ``teacher // (n / k)`` of the k
    ``conditions``, by default the paper's four).
    """
    chosen = check_conditions(experiment, conditions)
    traits = population.sample(teacher_rng(seed, experiment, teacher, 0))
    spec = EXPERIMENTS[experiment]
    model = TEACHERS[spec.task](traits, cohort_task(spec.task, settings))
    if spec.within_subjects:
        for k, cond in enumerate(chosen, start=1):
            yield traits, 1, model.teach(cond, teacher_rng(seed, experiment, teacher, k))
    else:
        per = n // len(chosen)
        cond = chosen[teacher // per]
        for k in range(1, spec.runs + 1):
            yield traits, k, model.teach(cond, teacher_rng(seed, experiment, teacher, k))


def rows_of(run, base: dict, settings: StudySettings = StudySettings()):
    """:func:`run_rows` of a run with the study's settings, plus the run's own columns
    (``study_columns``: VR's rule compliance in the maze, the clock's seconds in
    pick-and-place)."""
    ambiguity = settings.ambiguity(run.task.name)
    row, demo_rows = run_rows(run, base, ambiguity, settings.target)
    row.update(run.study_columns())
    return row, demo_rows


def simulate_teacher(
    experiment: int,
    teacher: int,
    seed: int,
    n: int,
    population: Population = DEFAULT_POPULATION,
    settings: StudySettings = StudySettings(),
    conditions=None,
):
    """Simulate one teacher of a cohort end to end; returns (run rows, demo rows)."""
    rows, demo_rows = [], []
    runs = teach_runs(experiment, teacher, seed, n, population, settings, conditions)
    for traits, number, run in runs:
        trait_cols = {f"trait_{k}": v for k, v in traits.to_dict().items() if k != "plan_focus"}
        base = {"teacher": teacher, "condition": run.condition, "run": number}
        row, drows = rows_of(run, base, settings)
        rows.append({**row, **trait_cols})
        demo_rows += drows
    return rows, demo_rows


# ---------------------------------------------------------------- a cohort


def _teacher_job(job):
    """One teacher of a cohort (a worker's job): :func:`simulate_teacher` of its args."""
    return simulate_teacher(*job)


def run_experiment(
    experiment: int,
    seed: int = 0,
    n: int | None = None,
    workers: int | None = None,
    progress: bool | Callable = True,
    population: Population = DEFAULT_POPULATION,
    settings: StudySettings = StudySettings(),
    conditions=None,
    scheduler: str | None = None,
    engine: Engine | None = None,
) -> CohortResult:
    """Simulate a whole cohort of Experiment 1 or 2.

    Parameters
    ----------
    experiment : {1, 2}
    seed : int
        >= 0; the same seed gives the same numbers (whatever ``workers`` is).
    n : int, optional
        Number of teachers (default the paper's: 30 and 36).
    workers : int, optional
        Processes to use (default: the machine's cores, at most ``n``); 1 runs in this
        process. Teachers go to the workers in batches (:class:`tutor.engine.Engine`).
    progress : bool
        Show a tqdm progress bar (one step per teacher).
    population : Population
    settings : StudySettings
    conditions : sequence of str, optional
        Experiment 2's conditions (default the paper's NF, RF, BF, SF; AF may be added,
        see :func:`check_conditions`). ``n`` then defaults to 9 per condition.
    scheduler : str, optional
        Run on a Dask cluster: ``"auto"`` (a local one) or ``"tcp://HOST:PORT"``
        (:class:`tutor.engine.Engine`); the same numbers as the process pool.
    engine : Engine, optional
        An engine already started (several cohorts on one cluster, e.g. robustness):
        ``workers`` and ``scheduler`` are then its own, and it stays open.

    Returns
    -------
    CohortResult
    """
    experiment, n, seed = check_request(experiment, n, seed, conditions)
    chosen = check_conditions(experiment, conditions)
    if workers is None:
        workers = min(os.cpu_count() or 1, n)
    if not isinstance(workers, int) or isinstance(workers, bool) or workers < 1:
        raise InvalidParameterError(f"workers must be a whole number >= 1, got {workers!r}")
    workers = min(workers, n)  # a process per teacher at most: never fork idle ones
    bar = None
    if progress:
        from tqdm.auto import tqdm

        tqdm.monitor_interval = 0  # no monitor thread in a process that forks workers
        bar = tqdm(total=n, desc=f"Experiment {experiment}", unit="teacher")
    jobs = [(experiment, i, seed, n, population, settings, conditions) for i in range(n)]
    try:
        with Engine(workers, scheduler) if engine is None else nullcontext(engine) as running:
            taught = running.map(
                _teacher_job, jobs, step=None if bar is None else lambda k: bar.update(k - bar.n)
            )
    finally:
        if bar is not None:
            bar.close()
    results = dict(enumerate(taught))
    rows = [r for i in sorted(results) for r in results[i][0]]
    demo_rows = [r for i in sorted(results) for r in results[i][1]]
    runs = pd.DataFrame(rows)
    demos = pd.DataFrame(demo_rows)
    order = list(chosen)
    for frame in (runs, demos):
        frame["condition"] = pd.Categorical(frame["condition"], categories=order, ordered=True)
    runs = runs.sort_values(["teacher", "run", "condition"], kind="stable").reset_index(drop=True)
    return CohortResult(experiment, seed, runs, demos, settings)
