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

from ..errors import InvalidParameterError
from ..framework.protocol import EXPERIMENTS
from ..teachers.traits import DEFAULT_POPULATION, Population, TeacherTraits
from ..workers import one_blas_thread, process_pool
from .cohort import StudySettings, _rng, _task, rows_of
from .limits import MAX_SEEDS, MAX_TEACHERS

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

#: the study's analysis settings (the cohort's defaults)
SETTINGS = StudySettings()
#: the experiment whose teachers, task and clock the study uses (pick-and-place)
EXPERIMENT = 2
#: the cohort sizes the full study accepts (the paper's 36 to 60)
TEACHERS_RANGE = (36, 60)


@dataclass(frozen=True)
class Policy:
    """How a teacher is taught in one arm of the study.

    Attributes
    ----------
    name : str
        The arm's label (a key of :data:`POLICIES`).
    condition : str
        The Experiment 2 condition the runs are in ("BF", "AF" or "HF").
    selector : str, optional
        AF's selector (a key of :data:`tutor.framework.selectors.SELECTORS`).
    k : int, optional
        AF's plants shown after each demo.
    compliance : float, optional
        HF: the probability that the teacher follows the hint (replaces the trait).
    reference : bool
        Kept for reference only (the oracle): not a policy a real robot could follow.
    description : str
    """

    name: str
    condition: str
    selector: str | None = None
    k: int | None = None
    compliance: float | None = None
    reference: bool = False
    description: str = ""

    @property
    def spec(self):
        """The arm's condition in the registry (:mod:`tutor.framework.protocol`)."""
        return EXPERIMENTS[2].condition(self.condition)

    @property
    def hinted(self) -> bool:
        """The arm's teachers are offered the next-demo hint (HF)."""
        return self.spec.hinted

    @property
    def options(self) -> dict:
        """The keyword arguments of ``PickPlaceTeacher.teach`` for this arm."""
        if self.spec.policy.adaptive:
            return {"selector": self.selector, "k": self.k}
        return {}

    def traits(self, traits: TeacherTraits) -> TeacherTraits:
        """The teacher's traits in this arm (HF replaces ``compliance``, nothing else)."""
        if self.compliance is None:
            return traits
        return dataclasses.replace(traits, compliance=self.compliance)


def _af(name: str, selector: str, k: int, text: str, reference: bool = False) -> Policy:
    return Policy(name, "AF", selector=selector, k=k, reference=reference, description=text)


#: every policy the study knows (name -> Policy)
POLICIES: dict[str, Policy] = {
    p.name: p
    for p in (
        Policy("BF", "BF", description="the paper's batch: four corners and the centre"),
        _af("KC5", "farthest", 5, "farthest point, 5 plants (BF's cost)"),
        _af("KC2", "farthest", 2, "farthest point, 2 plants"),
        _af("DIS2", "disagreement", 2, "frame disagreement and distance, 2 plants"),
        _af("DIS5", "disagreement", 5, "frame disagreement and distance, 5 plants (AF)"),
        _af("RAND2", "random", 2, "2 plants at random (the control)"),
        _af("RAND5", "random", 5, "5 plants at random (the control)"),
        _af("ORC2", "failures", 2, "the oracle: 2 plants the robot fails at", reference=True),
        Policy("HF0.5", "HF", compliance=0.5, description="next-demo hint, followed half the time"),
        Policy("HF1", "HF", compliance=1.0, description="next-demo hint, always followed"),
    )
}
#: the issue's arms, in the order they are reported (HF only where available)
DEFAULT_POLICIES = ("BF", "KC5", "KC2", "DIS2", "RAND2", "ORC2", "HF0.5", "HF1")
#: the arms rerun under the teacher-model variants: BF and the pilot's best (two arms, so
#: that four variants fit beside the main study on the shared machine)
ROBUSTNESS_POLICIES = ("BF", "DIS2")
#: the baseline every delta is taken against
BASELINE = "BF"

#: teacher-model variants for the robustness check (name -> Population)
VARIANTS: dict[str, Population] = {
    "less patient": dataclasses.replace(DEFAULT_POPULATION, patience_low=4, patience_high=8),
    "noisier aim": dataclasses.replace(DEFAULT_POPULATION, aim_low=0.06, aim_high=0.15),
    "more repeats": dataclasses.replace(DEFAULT_POPULATION, repeat_a=4.0, repeat_b=6.0),
    "fewer believed enough": dataclasses.replace(
        DEFAULT_POPULATION, enough_median_pickplace=4.0, satisfaction_low=0.85,
        satisfaction_high=0.95,
    ),
}
#: the main study's population
DEFAULT_VARIANT = "default"
#: seeds per teacher-model variant in the full study (see StudyPlan.variant_seeds)
VARIANT_SEEDS = 3


def is_secondary(policy: str) -> bool:
    """The oracle (reference only) and the HF arms: run on fewer seeds when the plan says."""
    p = POLICIES[policy]
    return p.reference or p.hinted


def policy_available(policy: Policy) -> bool:
    """Whether this tutor can teach ``policy`` (HF needs the HF condition and the
    ``compliance`` trait, added beside this study)."""
    if policy.condition not in EXPERIMENTS[2].codes:
        return False
    if policy.compliance is not None:
        return "compliance" in {f.name for f in dataclasses.fields(TeacherTraits)}
    return True


def available_policies(names=DEFAULT_POLICIES) -> tuple[str, ...]:
    """The names among ``names`` this tutor can teach (in order)."""
    return tuple(n for n in names if policy_available(POLICIES[n]))


@dataclass(frozen=True)
class StudyPlan:
    """How big the study is (validated by :func:`check_plan`).

    Attributes
    ----------
    n : int
        Teachers per seed (36-60; the quick plan fewer).
    runs : int
        Runs per teacher (the paper's 3).
    seeds : int
        Seeds 0 .. seeds - 1 of the main study (the claims are stated over them).
    policies : tuple of str
        The arms (keys of :data:`POLICIES`; BF must be one).
    variants : tuple of str
        Teacher-model variants (keys of :data:`VARIANTS`) for the robustness check.
    variant_seeds : int
        Seeds per variant (0: no robustness check).
    variant_policies : tuple of str
        The arms rerun under each variant (BF must be one).
    n_boot : int
        Bootstrap draws of every CI and replication rate.
    hf_teachers : int or None
        The HF arms teach only teachers 0 .. hf_teachers - 1 of each seed (None: all,
        the default). The hint's lookahead refits the learner for up to 12 candidate
        plants before every demo, so an HF run costs about 0.7 s against 0.1 s for the
        others (``benchmarks/bench_adaptive.py``); fewer HF teachers make a quicker
        study, their deltas paired with BF on the same teachers.
    secondary_seeds : int or None
        The oracle and the HF arms run on seeds 0 .. secondary_seeds - 1 only (None: all
        seeds, the default).
    quick : bool
        The test switch's plan (smaller sizes allowed; not a result).
    """

    n: int = 36
    runs: int = 3
    seeds: int = 10
    policies: tuple = DEFAULT_POLICIES
    variants: tuple = tuple(VARIANTS)
    variant_seeds: int = VARIANT_SEEDS
    variant_policies: tuple = ROBUSTNESS_POLICIES
    n_boot: int = 2000
    hf_teachers: int | None = None
    secondary_seeds: int | None = None
    quick: bool = False

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


#: the test switch's plan: 4 teachers x 1 run x 2 seeds in every arm, one variant on one
#: seed (a check that everything runs and is written, not a result)
QUICK = StudyPlan(
    n=4, runs=1, seeds=2, variants=("less patient",), variant_seeds=1,
    variant_policies=("BF", "KC2"), n_boot=200, hf_teachers=2, secondary_seeds=None,
    quick=True,
)


#: how a bad ``hf_teachers`` is named in its error (it is also the CLI's --hf-teachers)
HF_TEACHERS_NAME = "the HF teachers per seed (--hf-teachers, at most --n)"


def _whole(value, name: str, low: int, high: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise InvalidParameterError(f"{name} must be a whole number, got {value!r}")
    if value < low or (high is not None and value > high):
        span = f">= {low}" if high is None else f"from {low} to {high}"
        raise InvalidParameterError(f"{name} must be {span}, got {value}")
    return int(value)


def _names(names, known: dict, what: str) -> tuple[str, ...]:
    if isinstance(names, str):
        names = (names,)
    chosen = tuple(names)
    unknown = [n for n in chosen if n not in known]
    if not chosen or unknown or len(set(chosen)) != len(chosen):
        raise InvalidParameterError(
            f"{what} must be distinct names from {', '.join(known)}; got {names!r}"
        )
    return chosen


def check_plan(plan: StudyPlan) -> StudyPlan:
    """Validate a plan; drop the arms this tutor cannot teach (HF before it lands).

    Raises
    ------
    InvalidParameterError
        A size out of range, an unknown arm or variant, or no BF arm.
    """
    if not isinstance(plan, StudyPlan):
        raise InvalidParameterError(f"plan must be a StudyPlan, got {plan!r}")
    low, high = (2, MAX_TEACHERS) if plan.quick else TEACHERS_RANGE
    n = _whole(plan.n, "the number of teachers (--n)", low, high)
    runs = _whole(plan.runs, "runs", 1, 10)
    seeds = _whole(plan.seeds, "the number of seeds (--seeds)", 2, MAX_SEEDS)
    policies = _names(plan.policies, POLICIES, "policies")
    variant_policies = _names(plan.variant_policies, POLICIES, "variant_policies")
    variants = _names(plan.variants, VARIANTS, "variants") if plan.variants else ()
    for what, arms in (("policies", policies), ("variant_policies", variant_policies)):
        if BASELINE not in arms:
            raise InvalidParameterError(
                f"{what} must include {BASELINE}: every delta is taken against it"
            )
    return dataclasses.replace(
        plan,
        n=n,
        runs=runs,
        seeds=seeds,
        policies=available_policies(policies),
        variants=variants,
        variant_seeds=_whole(plan.variant_seeds, "variant_seeds", 0, MAX_SEEDS),
        variant_policies=available_policies(variant_policies),
        n_boot=_whole(plan.n_boot, "n_boot", 100, 100_000),
        hf_teachers=None if plan.hf_teachers is None
        else _whole(plan.hf_teachers, HF_TEACHERS_NAME, 2, n),
        secondary_seeds=None if plan.secondary_seeds is None
        else _whole(plan.secondary_seeds, "secondary_seeds", 2, MAX_SEEDS),
    )


# ---------------------------------------------------------------- one arm of one teacher


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
    traits = policy.traits(population.sample(_rng(seed, EXPERIMENT, teacher, 0)))
    task = _task("pickplace", settings)
    model = PickPlaceTeacher(traits, task)
    trait_cols = {f"trait_{k}": v for k, v in traits.to_dict().items() if k != "plan_focus"}
    rows, curve = [], []
    for number in range(1, runs + 1):
        rng = _rng(seed, EXPERIMENT, teacher, number)
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


def _job(job):
    """One unit of work in a worker: (variant, seed, teacher, policy, runs, settings)."""
    variant, seed, teacher, policy, runs, settings = job
    population = DEFAULT_POPULATION if variant == DEFAULT_VARIANT else VARIANTS[variant]
    rows, curve = teach_policy(policy, seed, teacher, runs, population, settings)
    for r in (*rows, *curve):
        r["variant"] = variant
    return job[:4], rows, curve


# ---------------------------------------------------------------- the whole study


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
    plan: StudyPlan = StudyPlan(),
    workers: int | None = None,
    progress: bool | Callable = True,
    settings: StudySettings = SETTINGS,
    checkpoint=None,
) -> StudyResult:
    """Simulate the study on ``workers`` processes (default: every core).

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
        if workers == 1 or not jobs:
            one_blas_thread()
            for job in jobs:
                keep(*_job(job))
        else:
            with process_pool(workers) as pool:
                for key, rows, curve in pool.map(_job, jobs, chunksize=2):
                    keep(key, rows, curve)
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
