r"""Calibrating the simulated teachers (and the maze's free geometry) to the paper's people.

The simulated teachers of :mod:`tutor.teachers` draw their human factors Q from a
:class:`~tutor.teachers.traits.Population`; the maze's two blocks are ours to size
(the paper gives X, I, the target and "two obstacle blocks"). This module fits both to
the paper's results by simulation-based inference, and checks the fit on results it did
not see.

**Free parameters** :math:`\theta` (:data:`PARAMETERS`, a registry: name -> prior and
where it goes). Nothing is per condition: one population and one maze serve every
condition of both experiments. A maze the learner is unsteady on (one more demo where
the robot fails can cost a third of its efficacy: :mod:`tutor.study.steadiness`) is
kept out: it simulates nothing and lies far from the paper.

**Summary statistics** :math:`s(\theta)` (:data:`STATISTICS`): what the paper reports
that a simulated cohort can give back. The *fitted* ones are Experiment 1 (the three
median :math:`\eta`, the number of NF teachers who did well, the ANOVA's F) and
Experiment 2's NF condition (mean and third-run :math:`\eta`, its failure counts); the
*held-out* ones are the rest of Experiment 2 (RF, BF and SF: mean and third-run
:math:`\eta`, the failure table). Counts are scaled to the paper's group sizes.

**Method: ABC-SMC** (approximate Bayesian computation by sequential Monte Carlo,
Beaumont et al. 2009, with `pyabc <https://pyabc.readthedocs.io>`_). The simulator has
no likelihood we can write down, a run of it is a whole cohort (seconds), and the
parameters mix counts, rates and a length. ABC-SMC needs only simulations and returns a
weighted sample of the posterior :math:`p(\theta \mid d(s(\theta), s_{paper}) \le
\epsilon_t)`, with a shrinking tolerance :math:`\epsilon_t`: exactly what the
posterior predictive check needs. (Bayesian optimisation of the same distance with
optuna would find its minimum with fewer runs, but gives a point, not a posterior.)
The distance is

.. math::

    d(s, s^*) = \Big( \sum_{j \in \text{fitted}} \big( (s_j - s^*_j) / \sigma_j \big)^2
    \Big)^{1/2}

with :math:`\sigma_j` written next to each statistic (the size of a difference that
matters: a quarter of the paper's value for the rates, more for the noisier counts).

**On the executor.** Each simulated study spreads its teachers over the
:class:`tutor.engine.Engine` (a local process pool, or a Dask cluster with
``scheduler=``), so a calibration scales out like the cohorts do, and gives the same
numbers on any executor for the same seed.

**Validation.** :func:`predictive` draws parameter sets from the posterior, simulates
both experiments in full with fresh seeds and gives every statistic's 90 % posterior
predictive interval; :func:`report` says, statistic by statistic, whether the paper's
value lies inside it, separately for the fitted and the held-out ones.

Command line: ``lfd-tutor calibrate --out DIR`` (``--quick`` for a reduced budget).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .. import paper
from ..engine import Engine
from ..errors import InvalidFileError, InvalidParameterError
from ..fileio import atomic_write_text
from ..tasks.maze import load_layout
from ..teachers.traits import DEFAULT_POPULATION, Population
from .cohort import StudySettings, run_experiment
from .steadiness import steadiness_of_blocks

__all__ = [
    "Parameter",
    "Statistic",
    "PARAMETERS",
    "STATISTICS",
    "Budget",
    "QUICK_BUDGET",
    "FULL_BUDGET",
    "Calibration",
    "from_history",
    "bundled_blocks",
    "apply",
    "summary_statistics",
    "simulate",
    "distance",
    "calibrate",
    "predictive",
    "report",
    "refine",
    "save",
    "load",
]


# ---------------------------------------------------------------- parameters


@dataclass(frozen=True)
class Parameter:
    """One free parameter: a uniform prior on [low, high] (on the log scale if ``log``).

    ``put(population, settings, value)`` returns the population and study settings with
    the value in place.
    """

    name: str
    low: float
    high: float
    why: str
    put: Callable = field(repr=False, compare=False)
    log: bool = False

    def to_unit(self, value: float) -> float:
        """The value's place in the prior's range, 0 .. 1."""
        if self.log:
            return (math.log(value) - math.log(self.low)) / (
                math.log(self.high) - math.log(self.low)
            )
        return (value - self.low) / (self.high - self.low)

    def from_unit(self, u: float) -> float:
        """The value at place ``u`` (0 .. 1) of the prior's range."""
        if self.log:
            return math.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low)))
        return self.low + u * (self.high - self.low)


def _field(name: str):
    def put(population, settings, value):
        return dataclasses.replace(population, **{name: float(value)}), settings

    return put


def _block(index: int):
    def put(population, settings, value):
        blocks = list(settings.maze_blocks or (None,) * 4)
        blocks[index] = float(value)
        return population, dataclasses.replace(settings, maze_blocks=tuple(blocks))

    return put


#: the narrowest gap between the blocks the calibration draws (m)
NARROWEST_GAP = 0.025


def _gap_share(population, settings, value):
    layout = load_layout()
    now = list(settings.maze_blocks or (None,) * 4)
    known = layout.blocks
    low = known["low"] if now[1] is None else now[1]
    height = known["height"] if now[2] is None else now[2]
    highest = layout.target_center[1] - layout.target_radius - 0.03 - 1e-9  # block 2's top
    room = max(0.0, highest - low - 2 * height - NARROWEST_GAP)
    now[3] = NARROWEST_GAP + float(value) * room
    return population, dataclasses.replace(settings, maze_blocks=tuple(now))


def _uniform_around(low: str, high: str, width: float, floor: float = 0.0,
                    ceiling: float = math.inf):
    """A uniform of fixed ``width`` around the value (its middle), clipped to
    ``floor`` .. ``ceiling``: the population's ``low`` and ``high`` fields."""
    def put(population, settings, value):
        value = float(value)
        lo, hi = max(floor, value - width / 2), min(ceiling, value + width / 2)
        return dataclasses.replace(population, **{low: lo, high: hi}), settings

    return put


def _beta_mean(a: str, b: str, concentration: float):
    def put(population, settings, value):
        value = float(value)
        return dataclasses.replace(
            population, **{a: concentration * value, b: concentration * (1 - value)}
        ), settings

    return put


#: the free parameters (name -> Parameter), with their priors and why
PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in (
        Parameter(
            "maze_reach", 0.12, 0.17,
            "how far each maze block juts in (m): from 12 cm (an 8 cm side gap) to 17 cm "
            "(a 3 cm gap, which a hand still passes in one stroke); a first calibration "
            "with 10-16 cm piled its particles at 16 cm. Mazes the learner is unsteady "
            "on (from about 16 cm) simulate nothing: tutor.study.steadiness",
            _block(0),
        ),
        Parameter(
            "maze_low", 0.075, 0.11,
            "where block 1 starts (m, its lower edge): from 1.5 cm above the start zone "
            "(the paths must turn at once) to 11 cm (so two blocks at their highest and "
            "the narrowest gap still fit below the target)",
            _block(1),
        ),
        Parameter(
            "maze_height", 0.02, 0.05,
            "each block's height (m): from a thin wall to 5 cm (block 1 at its lowest, "
            "two 5 cm blocks and the narrowest gap still end 3 cm below the target)",
            _block(2),
        ),
        Parameter(
            "maze_gap_share", 0.0, 1.0,
            "the gap between block 1's top and block 2's bottom, as a share of the room "
            "there is: 0 is the narrowest a hand passes (2.5 cm), 1 puts block 2 3 cm "
            "below the target; so every draw is a maze a hand can pass",
            _gap_share,
        ),
        Parameter(
            "enough_median_maze", 2.0, 9.0,
            "the demos a novice believes the maze needs: from 2 (the paper: unguided "
            "teachers 'underestimate') to 9 (more than its optimal teacher needs)",
            _field("enough_median_maze"),
        ),
        Parameter(
            "spread_median_maze", 0.08, 0.5,
            "how widely a novice's own maze demos scatter (unit box): from clustered to "
            "half the start zone; log scale",
            _field("spread_median_maze"), log=True,
        ),
        Parameter(
            "satisfaction_low", 0.7, 0.97,
            "the lowest share of B^ a teacher must believe works before stopping (the "
            "highest is 1)",
            _field("satisfaction_low"),
        ),
        Parameter(
            "aim_high", 0.04, 0.15,
            "the least precise aim in the population (unit box, standard deviation; the "
            "most precise is 0.02)",
            _field("aim_high"),
        ),
        Parameter(
            "enough_median_pickplace", 4.0, 11.0,
            "the demos a novice believes pick-and-place needs (the paper's NF numbers "
            "imply about 7)",
            _field("enough_median_pickplace"),
        ),
        Parameter(
            "spread_median_pickplace", 0.2, 0.8,
            "how widely a novice's own plants scatter over the tray (unit box); log scale",
            _field("spread_median_pickplace"), log=True,
        ),
        Parameter(
            "repeat_mean", 0.03, 0.35,
            "the mean chance that a demo repeats one already given (beta, concentration "
            "10): the paper's ambiguous demos",
            _beta_mean("repeat_a", "repeat_b", 10.0),
        ),
        Parameter(
            "slip_mean", 0.005, 0.08,
            "the mean chance that a demo slips (beta, concentration 50): the paper's "
            "demonstration errors",
            _beta_mean("slip_a", "slip_b", 50.0),
        ),
        Parameter(
            "setup_middle", 30.0, 110.0,
            "seconds per pick-and-place demo besides the motion (uniform, 50 s wide, "
            "around this middle)",
            _uniform_around("setup_low", "setup_high", 50.0),
        ),
        Parameter(
            "heed_middle", 0.0, 1.0,
            "how often a teacher shown failures chooses the next demo from the picture "
            "rather than from their own plan (uniform, 0.5 wide around this middle, "
            "clipped to 0-1; the hand-set model's teachers always do)",
            _uniform_around("heed_low", "heed_high", 0.5, ceiling=1.0),
        ),
    )
}


def apply(theta: dict, population: Population = DEFAULT_POPULATION,
          settings: StudySettings | None = None) -> tuple[Population, StudySettings]:
    """The population and settings with the parameters ``theta`` (name -> value) in place.

    Raises
    ------
    InvalidParameterError
        An unknown name, or a value outside its prior's range.
    """
    settings = StudySettings() if settings is None else settings
    for name, value in theta.items():
        if name not in PARAMETERS:
            raise InvalidParameterError(
                f"unknown calibration parameter {name!r}; known: {', '.join(PARAMETERS)}"
            )
        p = PARAMETERS[name]
        value = float(value)
        if not (p.low - 1e-12 <= value <= p.high + 1e-12):
            raise InvalidParameterError(
                f"{name} must be from {p.low:g} to {p.high:g} (its prior), got {value!r}"
            )
        population, settings = p.put(population, settings, value)
    return population, settings


# ---------------------------------------------------------------- statistics


@dataclass(frozen=True)
class Statistic:
    """One summary statistic: the paper's value, a scale, fitted or held out."""

    name: str
    experiment: int
    value: float
    scale: float
    fitted: bool
    what: str


def _statistics() -> dict[str, Statistic]:
    e1, e2 = paper.EXPERIMENT_1, paper.EXPERIMENT_2
    out = []
    for c, v in e1["median_eta"].items():
        out.append(Statistic(f"median eta {c}", 1, v, v / 4, True, f"Exp 1 median eta, {c}"))
    out.append(Statistic(
        "NF did well", 1, e1["did_well_without_feedback"], 3.0, True,
        "Exp 1 NF teachers reaching 90 % (of 30)",
    ))
    out.append(Statistic("F", 1, e1["anova"]["F"], 3.0, True, "Exp 1 repeated-measures F"))
    for c in paper.PICKPLACE_CONDITIONS:
        fitted = c == "NF"
        out.append(Statistic(
            f"mean eta {c}", 2, e2["mean_eta"][c], e2["mean_eta"][c] / 4, fitted,
            f"Exp 2 mean eta over runs, {c}",
        ))
        out.append(Statistic(
            f"third-run eta {c}", 2, e2["third_run_eta"][c], e2["third_run_eta"][c] / 4,
            fitted, f"Exp 2 mean eta of the third run, {c}",
        ))
        for kind, scale in (("errors", 3.0), ("undemonstrated", 150.0), ("ambiguous", 15.0)):
            out.append(Statistic(
                f"{kind} {c}", 2, e2["failures"][kind][c], scale, fitted,
                f"Exp 2 {kind} (27 runs), {c}",
            ))
    return {s.name: s for s in out}


#: the summary statistics (name -> Statistic), fitted and held out
STATISTICS: dict[str, Statistic] = _statistics()


def summary_statistics(exp1: pd.DataFrame | None, exp2: pd.DataFrame | None) -> dict:
    """The statistics a cohort's ``runs`` give (Experiment 1's and/or Experiment 2's).

    Counts are scaled to the paper's groups (30 teachers in Experiment 1, 9 teachers x
    3 runs per condition in Experiment 2), so a smaller simulated cohort is comparable.
    """
    out = {}
    if exp1 is not None:
        from .stats import experiment1_stats

        grouped = exp1.groupby("condition")["eta"]
        for c, v in grouped.median().items():
            out[f"median eta {c}"] = float(v)
        nf = exp1[exp1.condition == "NF"]
        out["NF did well"] = float(nf.reached_target.mean() * paper.MAZE_N_TEACHERS)
        try:
            out["F"] = float(experiment1_stats(exp1)["anova"]["F"])
        except Exception:  # noqa: BLE001 - a degenerate cohort (every eta equal) has no F
            out["F"] = math.nan
    if exp2 is not None:
        per = paper.PICKPLACE_N_TEACHERS // len(paper.PICKPLACE_CONDITIONS) * paper.PICKPLACE_N_RUNS
        for c, group in exp2.groupby("condition"):
            out[f"mean eta {c}"] = float(group.eta.mean())
            out[f"third-run eta {c}"] = float(group[group.run == group.run.max()].eta.mean())
            for kind in ("errors", "undemonstrated", "ambiguous"):
                out[f"{kind} {c}"] = float(group[kind].sum() * per / len(group))
    return out


def distance(stats: dict, names=None) -> float:
    """The scaled Euclidean distance of ``stats`` to the paper's values, over ``names``
    (default: the fitted statistics); a missing or NaN statistic counts as 4 scales off."""
    names = [n for n, s in STATISTICS.items() if s.fitted] if names is None else names
    total = 0.0
    for n in names:
        s, v = STATISTICS[n], stats.get(n, math.nan)
        z = 4.0 if v is None or not math.isfinite(v) else (v - s.value) / s.scale
        total += z * z
    return math.sqrt(total)


# ---------------------------------------------------------------- the simulator


@dataclass(frozen=True)
class Budget:
    """How much a calibration simulates.

    Attributes
    ----------
    population_size : int
        Particles per ABC-SMC generation.
    generations : int
        ABC-SMC generations (tolerances). Three by default: on 2026-12-06 they took
        60 + 122 + 143 + 426 = 751 studies (pyabc's first prior sample, then acceptance
        rates of 49, 42 and 14 %) in 59 minutes on the pool of 2; at 14 % and falling,
        a fourth would take more than an hour more.
    n1, n2 : int
        Teachers in each simulated Experiment 1 cohort, and Experiment 2 NF teachers
        (the fit); the predictive check simulates the paper's sizes unless ``quick``.
    draws : int
        Posterior draws of the predictive check.
    quick : bool
        The test switch: smaller cohorts in the predictive check too; not a result.
    max_simulations : int
        ABC-SMC starts no further generation once this many studies are simulated
        (pyabc's ``max_total_nr_simulations``: the generation under way finishes). Later
        generations reject more draws; this keeps a run with more generations asked for
        near an hour on 2 cores (about 5 s per study on the pool of 2).
    """

    population_size: int = 60
    generations: int = 3
    n1: int = 30
    n2: int = 9
    draws: int = 20
    quick: bool = False
    max_simulations: int = 720

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


#: the test switch's budget: a check that everything runs and is written, not a result
QUICK_BUDGET = Budget(population_size=6, generations=2, n1=3, n2=2, draws=3, quick=True)
#: the budget of the bundled calibration
FULL_BUDGET = Budget()


def simulate(theta: dict, seed: int, n1: int, n2: int, engine: Engine,
             experiment2_conditions=("NF",)) -> dict:
    """The summary statistics of one simulated study at ``theta``.

    Experiment 1 with ``n1`` teachers and Experiment 2 with ``n2`` teachers in each of
    ``experiment2_conditions`` (the fit uses NF alone; the predictive check all four).
    A maze the learner is unsteady on (:mod:`tutor.study.steadiness`) simulates nothing
    and gives no statistics, so the distance puts it far from the paper.
    """
    population, settings = apply(theta)
    if settings.maze_blocks is not None and not steadiness_of_blocks(
        tuple(settings.maze_blocks)
    ).steady:
        return {}  # a maze the learner is unsteady on: every statistic missing, far away
    exp1 = run_experiment(1, seed=seed, n=n1, population=population, settings=settings,
                          progress=False, engine=engine).runs
    conditions = tuple(experiment2_conditions)
    exp2 = run_experiment(2, seed=seed, n=n2 * len(conditions), population=population,
                          settings=settings, conditions=conditions, progress=False,
                          engine=engine).runs
    return summary_statistics(exp1, exp2)


# ---------------------------------------------------------------- ABC-SMC


@dataclass
class Calibration:
    """What :func:`calibrate` found.

    Attributes
    ----------
    particles : DataFrame
        The last generation's parameter sets (one column per parameter) and ``weight``.
    generations : DataFrame
        Per generation: ``epsilon`` (the tolerance), ``particles``, ``simulations``
        (generation 0's count includes pyabc's first sample of the prior, which sets
        its tolerance, so the column sums to every study simulated).
    budget : Budget
    seconds : float
        Wall time of the ABC-SMC.
    seed : int
    where : str
        The executor it ran on.
    chosen : dict or None
        The bundled point, once :func:`refine` has chosen it: the posterior particle
        whose fresh-seed studies come closest to the paper on average.
    refined : DataFrame or None
        :func:`refine`'s table: per candidate particle, its parameters, its ABC
        distance and its mean distance over the fresh seeds.
    """

    particles: pd.DataFrame
    generations: pd.DataFrame
    budget: Budget
    seconds: float
    seed: int
    where: str = ""
    chosen: dict | None = None
    refined: pd.DataFrame | None = None

    def quantile(self, name: str, q: float) -> float:
        """The posterior's weighted ``q`` quantile of parameter ``name``."""
        w = self.particles["weight"].to_numpy()
        v = self.particles[name].to_numpy()
        order = np.argsort(v)
        cum = np.cumsum(w[order]) / w.sum()
        return float(v[order][min(np.searchsorted(cum, q), len(v) - 1)])

    def point(self) -> dict:
        """The posterior's weighted median of each parameter."""
        return {name: self.quantile(name, 0.5) for name in PARAMETERS}

    def bundled(self) -> dict:
        """The point the tutor bundles: :func:`refine`'s choice, else :meth:`point`."""
        return dict(self.chosen) if self.chosen is not None else self.point()

    def draw(self, k: int, rng) -> list[dict]:
        """``k`` parameter sets drawn from the posterior (by weight, with replacement)."""
        w = self.particles["weight"].to_numpy()
        rows = rng.choice(len(w), size=k, p=w / w.sum())
        return [{n: float(self.particles[n].iloc[r]) for n in PARAMETERS} for r in rows]


def _check_budget(budget) -> Budget:
    if not isinstance(budget, Budget):
        raise InvalidParameterError(f"budget must be a Budget, got {budget!r}")
    lows = {"population_size": 2, "generations": 1, "n1": 3, "n2": 2, "draws": 2,
            "max_simulations": 2}
    for name, low in lows.items():
        v = getattr(budget, name)
        if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= 100_000:
            raise InvalidParameterError(
                f"the budget's {name} must be a whole number from {low} to 100000, got {v!r}"
            )
    return budget


def calibrate(budget: Budget = FULL_BUDGET, seed: int = 0, workers=None, scheduler=None,
              folder=None, progress: bool = True) -> Calibration:
    """Fit :data:`PARAMETERS` to the fitted :data:`STATISTICS` by ABC-SMC.

    Every simulation gets its own seed from ``seed`` and a running count, so a
    calibration reruns to the same posterior on any executor. pyabc keeps its history in
    an SQLite file in ``folder`` (a temporary folder by default); the result is read
    back as numbers only.
    """
    import tempfile

    import pyabc

    budget = _check_budget(budget)
    names = list(PARAMETERS)
    prior = pyabc.Distribution(**{
        n: pyabc.RV("uniform", 0.0, 1.0) for n in names  # on the unit scale of each prior
    })
    counter = iter(range(10**9))
    observed = {n: s.value for n, s in STATISTICS.items() if s.fitted}

    with Engine(workers, scheduler) as engine:
        def model(par):
            theta = {n: PARAMETERS[n].from_unit(min(max(float(par[n]), 0.0), 1.0))
                     for n in names}
            run_seed = seed * 100_000 + next(counter)
            stats = simulate(theta, run_seed % (2**31), budget.n1, budget.n2, engine)
            return {n: stats.get(n, math.nan) for n in observed}

        def dist(x, x0):
            return distance(x, list(observed))

        # pyabc draws its particles with numpy's global generator
        np.random.seed(seed)  # noqa: NPY002
        abc = pyabc.ABCSMC(
            model, prior, dist, population_size=budget.population_size,
            sampler=pyabc.sampler.SingleCoreSampler(check_max_eval=False),
        )
        with tempfile.TemporaryDirectory() as tmp:
            where_db = Path(folder or tmp)
            where_db.mkdir(parents=True, exist_ok=True)
            db = where_db / HISTORY
            db.unlink(missing_ok=True)
            abc.new(f"sqlite:///{db}", observed)
            abc.run(max_nr_populations=budget.generations,
                    max_total_nr_simulations=budget.max_simulations)
            return from_history(where_db, budget, seed, engine.where)


#: pyabc's history of a calibration (an SQLite file of numbers), in its out folder
HISTORY = "calibration_history.db"


def from_history(folder, budget: Budget = FULL_BUDGET, seed: int = 0,
                 where: str = "") -> Calibration:
    """The calibration in pyabc's history in ``folder``, as of its last whole generation.

    :func:`calibrate` ends here; so can a run that was stopped (a kill, a crash, a
    machine needed back): ``lfd-tutor calibrate --from-history`` finishes it from its
    last generation (``budget`` and ``seed`` as the run was started with).

    Raises
    ------
    InvalidFileError
        No history in the folder, or one without a whole generation.
    """
    import pyabc

    db = Path(folder) / HISTORY
    if not db.is_file():
        raise InvalidFileError(
            f"{db}: no calibration history here; `lfd-tutor calibrate --out {folder}` "
            "writes one"
        )
    history = pyabc.History(f"sqlite:///{db}", _id=1)
    pops = history.get_all_populations()
    if history.max_t < 0:
        raise InvalidFileError(
            f"{db}: the calibration stopped before its first generation; start it again"
        )
    names = list(PARAMETERS)
    frame, weights = history.get_distribution()
    distances = history.get_weighted_distances()["distance"].to_numpy()
    particles = pd.DataFrame({
        n: [PARAMETERS[n].from_unit(min(max(float(u), 0.0), 1.0)) for u in frame[n]]
        for n in names
    })
    particles["weight"] = np.asarray(weights, dtype=float)
    particles["distance"] = np.asarray(distances, dtype=float)
    done = pops[pops.t <= history.max_t]
    gens = done[done.t >= 0][["t", "epsilon", "particles", "samples"]].rename(
        columns={"t": "generation", "samples": "simulations"}
    ).reset_index(drop=True)
    gens.loc[0, "simulations"] += int(done[done.t < 0].samples.sum())  # the calibration sample
    seconds = float(done.wall_time.sum())
    return Calibration(particles, gens, budget, seconds, int(seed), where)


# ---------------------------------------------------------------- the bundled point


def refine(calibration: Calibration, candidates: int = 6, seeds: int = 3, seed: int = 2,
           workers=None, scheduler=None) -> Calibration:
    """Choose the bundled point among the posterior's best particles.

    The posterior of a small ABC-SMC budget is wide, and its marginal medians
    (:meth:`Calibration.point`) need not be a population that fits: the maze's
    difficulty turns sharply with the blocks' reach, so a median of reaches can be a
    maze easier than any good particle's. So the ``candidates`` particles of the last
    generation with the smallest ABC distance each simulate ``seeds`` further studies
    with fresh seeds (the same seeds for every candidate: common random numbers), and
    the one whose mean distance to the paper is smallest becomes ``chosen``, among
    those whose maze, rounded to the millimetre as it is bundled
    (:func:`bundled_blocks`), still passes the steadiness check (a maze at the edge of
    the check can fall over it when rounded; on 2026-12-06 the closest candidate's
    did, median fall 0.157 against 0.15).
    """
    parts = calibration.particles
    if "distance" not in parts:
        raise InvalidParameterError(
            "this calibration has no particle distances (written by an older version); "
            "rerun lfd-tutor calibrate"
        )
    best = parts.nsmallest(min(candidates, len(parts)), "distance")
    budget = calibration.budget
    names = [n for n, st in STATISTICS.items() if st.fitted]
    rows = []
    with Engine(workers, scheduler) as engine:
        for _, particle in best.iterrows():
            theta = {n: float(particle[n]) for n in PARAMETERS}
            d = [
                distance(simulate(theta, 2 * 10**6 + seed * 1000 + k, budget.n1, budget.n2,
                                  engine), names)
                for k in range(seeds)
            ]
            steady = steadiness_of_blocks(bundled_blocks(theta))
            rows.append({**theta, "abc_distance": float(particle["distance"]),
                         "mean_distance": float(np.mean(d)),
                         "fall_as_bundled": steady.median_fall,
                         "steady_as_bundled": steady.steady})
    table = pd.DataFrame(rows)
    # the maze as bundled (to the mm) must pass the check the calibration applies
    pool = table[table.steady_as_bundled] if table.steady_as_bundled.any() else table
    top = table.loc[pool.mean_distance.idxmin()]
    table["chosen"] = table.index == top.name
    chosen = {n: float(top[n]) for n in PARAMETERS}
    return dataclasses.replace(calibration, chosen=chosen, refined=table)


def bundled_blocks(theta: dict) -> tuple[float, float, float, float]:
    """The maze's blocks as ``scripts/apply_calibration.py`` bundles a point ``theta``:
    the parameters to 4 decimals, the blocks (reach, low, height, gap) to the millimetre."""
    _, settings = apply({k: round(float(v), 4) for k, v in theta.items()})
    return tuple(round(float(v), 3) for v in settings.maze_blocks)


# ---------------------------------------------------------------- validation


def predictive(calibration: Calibration, seed: int = 1, workers=None,
               scheduler=None, at_point: bool = False) -> pd.DataFrame:
    """Posterior predictive statistics: one row per posterior draw, every statistic.

    With ``at_point`` every row is the bundled point (:meth:`Calibration.bundled`) with
    its own fresh seed instead: what the bundled population itself predicts.

    Each draw simulates Experiment 1 and all four conditions of Experiment 2 at the
    paper's sizes (the quick budget's small ones when ``budget.quick``), with fresh
    seeds (``seed`` x 1000 + draw, never used by the fit).
    """
    budget = calibration.budget
    rng = np.random.default_rng(np.random.SeedSequence([seed, 7]))
    thetas = calibration.draw(budget.draws, rng) if not at_point else (
        [calibration.bundled()] * budget.draws
    )
    n1 = budget.n1 if budget.quick else paper.MAZE_N_TEACHERS
    n2 = budget.n2 if budget.quick else paper.PICKPLACE_N_TEACHERS // 4
    rows = []
    with Engine(workers, scheduler) as engine:
        for k, theta in enumerate(thetas):
            stats = simulate(theta, 10**6 + seed * 1000 + k, n1, n2, engine,
                             experiment2_conditions=paper.PICKPLACE_CONDITIONS)
            rows.append({"draw": k, **theta, **stats})
    return pd.DataFrame(rows)


def recheck(folder, seed: int = 0, workers=None, scheduler=None, draws: int | None = None):
    """The predictive checks of the calibration saved in ``folder`` run again with the
    code as it is now (its posterior, refine table and bundled point kept), e.g. after a
    change in how a statistic is counted; writes the files back into ``folder``.

    ``draws`` (optional) replaces the budget's number of predictive draws: the ends of
    a 90 % interval over 20 draws are their second smallest and second largest values,
    so more draws give the interval more exactly (the posterior is the same).

    Returns ``(calibration, table, paths)``; the fresh seeds are those of the run that
    wrote the folder with ``seed`` (:func:`predictive` with ``seed + 1``).
    """
    found, _, _ = load(folder)
    note = "; predictive checks rerun (lfd-tutor calibrate --recheck)"
    if not found.where.endswith(note):
        found = dataclasses.replace(found, where=found.where + note)
    if draws is not None:
        budget = _check_budget(dataclasses.replace(found.budget, draws=draws))
        found = dataclasses.replace(found, budget=budget)
    predicted, at_point = (
        predictive(found, seed=seed + 1, workers=workers, scheduler=scheduler, at_point=point)
        for point in (False, True)
    )
    table = report(found, predicted, point_predicted=at_point)
    paths = save(found, predicted, table, folder, point_predicted=at_point)
    return found, table, paths


def _intervals(predicted: pd.DataFrame | None, name: str, level: float):
    lo_q, hi_q = (1 - level) / 2, 1 - (1 - level) / 2
    if predicted is None or name not in predicted or predicted[name].dropna().empty:
        return math.nan, math.nan, math.nan
    values = predicted[name].dropna()
    return tuple(float(values.quantile(q)) for q in (lo_q, 0.5, hi_q))


def report(calibration: Calibration, predicted: pd.DataFrame, level: float = 0.9,
           point_predicted: pd.DataFrame | None = None) -> pd.DataFrame:
    """Each statistic's paper value, posterior predictive median and ``level`` interval,
    and whether the paper's value lies inside (one row per statistic); with
    ``point_predicted`` (:func:`predictive` ``at_point``), the same for the bundled point
    in the ``point_*`` columns."""
    rows = []
    for name, s in STATISTICS.items():
        low, median, high = _intervals(predicted, name, level)
        p_low, p_median, p_high = _intervals(point_predicted, name, level)
        rows.append({
            "statistic": name, "fitted": s.fitted, "paper": s.value, "median": median,
            "low": low, "high": high, "inside": bool(low <= s.value <= high),
            "point_median": p_median, "point_low": p_low, "point_high": p_high,
            "point_inside": bool(p_low <= s.value <= p_high),
        })
    return pd.DataFrame(rows)


def format_report(calibration: Calibration, table: pd.DataFrame) -> str:
    """The calibration report in plain text."""
    b = calibration.budget
    lines = [
        "Calibration of the simulated teachers and the maze (ABC-SMC, pyabc)",
        f"budget: {b.population_size} particles x {b.generations} generations, Exp 1 "
        f"cohorts of {b.n1}, Exp 2 NF groups of {b.n2}; {b.draws} predictive draws"
        + (" (quick: not a result)" if b.quick else ""),
        f"simulated studies: {int(calibration.generations.simulations.sum())}, "
        f"{calibration.seconds:.0f} s on {calibration.where}",
        "tolerance per generation: "
        + ", ".join(f"{e:.2f}" for e in calibration.generations.epsilon),
        "",
        "posterior (weighted median; 5 % .. 95 %)"
        + ("; the bundled point, chosen by refine:" if calibration.chosen else ":"),
    ]
    point, bundled = calibration.point(), calibration.bundled()
    for name, p in PARAMETERS.items():
        lo, hi = calibration.quantile(name, 0.05), calibration.quantile(name, 0.95)
        chosen = f"; bundled {bundled[name]:.4g}" if calibration.chosen else ""
        lines.append(f"  {name}: {point[name]:.4g} ({lo:.4g} .. {hi:.4g}){chosen}; prior "
                     f"{'log-' if p.log else ''}uniform {p.low:g} .. {p.high:g}")
    if calibration.refined is not None:
        r = calibration.refined
        lines += ["", f"the bundled point: of the {len(r)} particles of the last generation "
                      "closest to the paper, the one whose fresh-seed studies come closest "
                      "on average and whose maze, to the mm, is steady (distance: ABC's, "
                      "mean over the fresh seeds; the maze's median fall):"]
        for k, row in r.iterrows():
            chosen = row["chosen"] if "chosen" in r else k == r.mean_distance.idxmin()
            mark = "  <- bundled" if chosen else ""
            if "steady_as_bundled" in r:
                mark = (f", fall {row.fall_as_bundled:.2f}"
                        + ("" if row.steady_as_bundled else " (unsteady)") + mark)
            lines.append(f"    particle {k}: {row.abc_distance:.2f}, {row.mean_distance:.2f}"
                         + mark)
    checks = [("", "posterior predictive (draws from the posterior)")]
    if "point_inside" in table and table.point_median.notna().any():
        checks.append(("point_", "the bundled point (fresh seeds)"))
    for prefix, title in checks:
        lines += ["", f"{title}: statistic: paper, median [90 % interval], inside?"]
        for fitted, kind in ((True, "fitted"), (False, "held out")):
            lines.append(f"  {kind}:")
            for r in table[table.fitted == fitted].to_dict(orient="records"):
                lines.append(
                    f"    {r['statistic']}: {r['paper']:.4g}, {r[prefix + 'median']:.4g} "
                    f"[{r[prefix + 'low']:.4g}, {r[prefix + 'high']:.4g}] "
                    f"{'yes' if r[prefix + 'inside'] else 'NO'}"
                )
        held = table[~table.fitted][prefix + "inside"]
        share = held.mean() if len(held) else math.nan
        lines.append(f"  held-out statistics inside their 90 % interval: {int(held.sum())} "
                     f"of {len(held)} ({share:.0%}; target at least 80 %)")
    return "\n".join(lines)


def save(calibration: Calibration, predicted: pd.DataFrame, table: pd.DataFrame, out,
         point_predicted: pd.DataFrame | None = None) -> dict:
    """Write the posterior, the predictive draws, the report and the bundled point."""
    from .report import check_out_dir

    out = check_out_dir(out)
    paths = {
        "posterior": out / "calibration_posterior.csv",
        "generations": out / "calibration_generations.csv",
        "predictive": out / "calibration_predictive.csv",
        "report": out / "calibration_report.txt",
        "summary": out / "calibration_summary.json",
    }
    atomic_write_text(paths["posterior"], calibration.particles.to_csv(index=False))
    atomic_write_text(paths["generations"], calibration.generations.to_csv(index=False))
    atomic_write_text(paths["predictive"], predicted.to_csv(index=False))
    if point_predicted is not None:
        paths["point predictive"] = out / "calibration_point_predictive.csv"
        atomic_write_text(paths["point predictive"], point_predicted.to_csv(index=False))
    if calibration.refined is not None:
        paths["refined"] = out / "calibration_refined.csv"
        atomic_write_text(paths["refined"], calibration.refined.to_csv(index=False))
    atomic_write_text(paths["report"], format_report(calibration, table) + "\n")
    held = table[~table.fitted]
    summary = {
        "point": calibration.point(),
        "chosen": calibration.chosen,
        "budget": calibration.budget.to_dict(),
        "seed": calibration.seed,
        "seconds": calibration.seconds,
        "where": calibration.where,
        "simulations": int(calibration.generations.simulations.sum()),
        "statistics": table.to_dict(orient="records"),
        "held_out_inside": float(held.inside.mean()),
        "held_out_inside_at_point": float(held.point_inside.mean())
        if point_predicted is not None else None,
    }
    atomic_write_text(paths["summary"], json.dumps(summary, indent=2, default=float) + "\n")
    return paths


#: the bundled calibration: the files :func:`save` wrote for the bundled population and maze
BUNDLED_FOLDER = ("calibration",)


def load(folder=None) -> tuple[Calibration, pd.DataFrame, pd.DataFrame]:
    """A calibration as :func:`save` wrote it: ``(calibration, predicted, table)``.

    ``folder`` defaults to the bundled calibration (``tutor/assets/calibration``), the one
    the bundled population (:data:`~tutor.teachers.traits.DEFAULT_POPULATION`) and maze
    come from. Numbers only (CSV and JSON), never a pickle.

    Raises
    ------
    InvalidFileError
        A file is missing or is not what :func:`save` writes.
    """
    from ..errors import InvalidFileError
    from ..resources import asset

    where = Path(folder) if folder is not None else asset(*BUNDLED_FOLDER)
    try:
        summary = json.loads((where / "calibration_summary.json").read_text(encoding="utf-8"))
        particles = pd.read_csv(where / "calibration_posterior.csv")
        gens = pd.read_csv(where / "calibration_generations.csv")
        predicted = pd.read_csv(where / "calibration_predictive.csv")
        table = pd.DataFrame(summary["statistics"])
        budget = Budget(**summary["budget"])
        refined_path = where / "calibration_refined.csv"
        refined = pd.read_csv(refined_path) if refined_path.exists() else None
        chosen = summary.get("chosen")
        found = Calibration(particles, gens, budget, float(summary["seconds"]),
                            int(summary["seed"]), str(summary.get("where", "")),
                            None if chosen is None else {k: float(v) for k, v in chosen.items()},
                            refined)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InvalidFileError(
            f"{where} does not hold a calibration as `lfd-tutor calibrate --out` writes it "
            f"({type(exc).__name__}: {exc}); rerun the command into that folder"
        ) from None
    missing = [n for n in (*PARAMETERS, "weight") if n not in particles]
    if missing or not {"statistic", "fitted", "paper", "low", "high", "inside"} <= set(table):
        raise InvalidFileError(
            f"{where}: the calibration files lack {missing or 'report columns'}; they were "
            "written by another version: rerun `lfd-tutor calibrate --out` into that folder"
        )
    for column in ("fitted", "inside", "point_inside"):
        if column in table:
            table[column] = table[column].astype(bool)
    return found, predicted, table
