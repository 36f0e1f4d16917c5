r"""How often would the paper's conclusions come out again with a new set of teachers?

Experiment 2 of Sena & Howard compares four groups of only nine teachers (three runs
each). Its conclusions about the failure counts (section "Evaluation": BF has the
fewest ambiguous demos and the most undemonstrated states, RF the fewest
demonstration errors) rest on sums over 27 runs, and one teacher's run can swing such
a sum by a hundred undemonstrated states (a run that ends with too few demos leaves
most of the 100 plants failing). Experiment 1's rest on paired t-tests over 30
teachers. This module asks how stable each conclusion is.

**Replication rate.** Draw the experiment's teachers again *with replacement* from a
cohort (nine per condition in Experiment 2, a teacher keeping their three runs
together; thirty in Experiment 1, a teacher keeping their three conditions together),
recompute the conclusion, repeat ``n_boot`` times: the share of draws in which it
holds. It estimates the chance that a new study of the paper's size, drawn from the
same population, finds it.

**Against the paper's levels.** ``match_paper=True`` first rescales every condition's
teachers so that the condition's summary equals the paper's, keeping the relative
spread between teachers that the simulation shows: in Experiment 2 the total (errors,
undemonstrated states, ambiguous demos) or mean (eta), in Experiment 1 the median eta
(the only level the paper gives). The rates then say how often a study whose true
levels *are* the paper's would reproduce the paper's own conclusions. Where the
simulation's summary is zero but the paper's is not, no rescaling exists and the rate
is NaN.

The conclusions recomputed per draw (the ANOVAs are not redone):

.. math::

    \text{Experiment 1: } \tilde\eta_{NF} < \tilde\eta_{VF},\;
    \tilde\eta_{NF} < \tilde\eta_{VR} \text{ (with } p_{bonf} < 0.05\text{)},\;
    p_{bonf}(VF, VR) \ge 0.05,\; \text{and all three together};

    \text{Experiment 2: BF best, BF fewest ambiguous, BF most undemonstrated, RF fewest
    errors, and the four together.}

Notation: eta is teaching efficiency (efficacy / number of demos), :math:`\tilde\eta`
a median; the counts are those of :func:`tutor.study.stats.failure_table`.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
from scipy.stats import binom, ttest_rel

from .. import paper
from ..errors import InvalidParameterError
from ..framework.protocol import EXPERIMENTS
from .stats import experiment1_holds, experiment2_ranking

__all__ = ["teacher_totals", "replication_rates", "chance_of_at_least", "CONCLUSIONS"]

COUNTS = ("errors", "undemonstrated", "ambiguous")
CONDITIONS = EXPERIMENTS[2].paper_codes
#: experiment -> the conclusions a bootstrap recomputes (the ANOVA is not redone per
#: draw), the last of them all the others holding together
CONCLUSIONS = {
    1: ("NF<VF", "NF<VR", "VF~VR", "all three"),
    2: ("BF best", "BF fewest ambiguous", "BF most undemonstrated", "RF fewest errors",
        "all four"),
}


def _check_runs(runs: pd.DataFrame, experiment: int, need: set) -> pd.DataFrame:
    """``runs`` with string conditions, after checking it is ``experiment``'s frame."""
    missing = need - set(runs.columns)
    what = f"run_experiment({experiment}, ...).runs"
    if missing:
        raise InvalidParameterError(
            f"runs lacks the columns {sorted(missing)}; pass the runs frame of an "
            f"Experiment {experiment} cohort ({what})"
        )
    codes = EXPERIMENTS[experiment].paper_codes
    conds = set(runs["condition"].astype(str))
    if conds != set(codes):
        raise InvalidParameterError(
            f"replication rates need Experiment {experiment}'s conditions {codes}, got "
            f"{sorted(conds)}; pass {what}"
        )
    return runs.assign(condition=runs["condition"].astype(str))


def teacher_totals(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per Experiment 2 teacher: condition, summed counts and mean eta.

    Parameters
    ----------
    runs : DataFrame
        The ``runs`` frame of an Experiment 2 :class:`~tutor.study.cohort.CohortResult`.

    Returns
    -------
    DataFrame (n_teachers, 5)
        Columns ``condition``, ``errors``, ``undemonstrated``, ``ambiguous`` (sums over
        the teacher's runs) and ``eta`` (mean over them).
    """
    data = _check_runs(runs, 2, {"teacher", "condition", "eta", *COUNTS})
    grouped = data.groupby(["teacher", "condition"])
    out = grouped[list(COUNTS)].sum().join(grouped["eta"].mean()).reset_index("condition")
    return out.reset_index(drop=True)


def _scaled(values: np.ndarray, target: float, summary=np.sum) -> np.ndarray:
    """``values`` times the factor that makes ``summary(values)`` equal ``target``."""
    now = summary(values)
    if now > 0:
        return values * (target / now)
    return values if target == 0 else np.full_like(values, np.nan)


def _check_bootstrap(n_boot, seed) -> np.random.Generator:
    if not isinstance(n_boot, (int, np.integer)) or n_boot < 100:
        raise InvalidParameterError(f"n_boot must be an integer >= 100, got {n_boot!r}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InvalidParameterError(f"seed must be an integer >= 0, got {seed!r}")
    return np.random.default_rng(seed)


def _rates1(runs: pd.DataFrame, rng: np.random.Generator, n_boot: int,
            match_paper: bool) -> dict:
    """Experiment 1: thirty teachers drawn again, each keeping their three conditions."""
    data = _check_runs(runs, 1, {"teacher", "condition", "eta"})
    codes = EXPERIMENTS[1].paper_codes
    wide = data.pivot_table(index="teacher", columns="condition", values="eta")
    wide = wide.reindex(columns=list(codes)).dropna()
    if len(wide) < 3:
        raise InvalidParameterError(
            f"replication rates need at least 3 teachers who taught {', '.join(codes)}, "
            f"got {len(wide)}"
        )
    values = wide.to_numpy(float)  # (n, 3)
    if match_paper:
        target = paper.EXPERIMENT_1["median_eta"]
        values = np.column_stack([
            _scaled(values[:, j], target[c], np.median) for j, c in enumerate(codes)
        ])
    if np.isnan(values).any():
        return dict.fromkeys(CONCLUSIONS[1], float("nan"))
    idx = rng.integers(0, len(values), size=(n_boot, len(values)))
    picked = values[idx]  # (n_boot, n, 3)
    column = {c: picked[..., j] for j, c in enumerate(codes)}
    pairs = tuple(paper.EXPERIMENT_1["pairwise_p"])
    with np.errstate(divide="ignore", invalid="ignore"), warnings.catch_warnings():
        # draws with (nearly) no spread: NaN p, read as "not shown", as pingouin gives
        warnings.simplefilter("ignore", RuntimeWarning)
        p_unc = {(a, b): ttest_rel(column[a], column[b], axis=1).pvalue for a, b in pairs}
    p_bonf = {k: np.minimum(1.0, v * len(pairs)) for k, v in p_unc.items()}
    holds = experiment1_holds({c: np.median(v, axis=1) for c, v in column.items()}, p_bonf)
    holds["all three"] = np.logical_and.reduce(list(holds.values()))
    return {k: float(v.mean()) for k, v in holds.items()}


def _rates2(runs: pd.DataFrame, rng: np.random.Generator, n_boot: int,
            match_paper: bool) -> dict:
    """Experiment 2: nine teachers per condition drawn again, keeping their runs."""
    table = teacher_totals(runs)
    ref = paper.EXPERIMENT_2
    # draws[c]: (n_boot, 4) sums of errors, undemonstrated, ambiguous and mean eta
    draws = {}
    for c in CONDITIONS:
        rows = table[table.condition == c]
        cols = {k: rows[k].to_numpy(float) for k in (*COUNTS, "eta")}
        if match_paper:
            targets = {k: ref["failures"][k][c] for k in COUNTS}
            targets["eta"] = ref["mean_eta"][c] * len(rows)  # a mean: scale its sum
            cols = {k: _scaled(v, targets[k]) for k, v in cols.items()}
        values = np.column_stack(list(cols.values()))  # (n_c, 4)
        idx = rng.integers(0, len(values), size=(n_boot, len(values)))
        picked = values[idx]  # (n_boot, n_c, 4)
        draws[c] = np.concatenate([picked[..., :3].sum(axis=1), picked[..., 3:].mean(axis=1)], 1)
    stack = np.stack([draws[c] for c in CONDITIONS])  # (4 conditions, n_boot, 4 measures)
    measures = {k: stack[..., j] for j, k in enumerate((*COUNTS, "eta"))}
    holds = experiment2_ranking(CONDITIONS, **measures)
    uses = {
        "BF best": "eta",
        "BF fewest ambiguous": "ambiguous",
        "BF most undemonstrated": "undemonstrated",
        "RF fewest errors": "errors",
    }
    unknown = {k for k, m in uses.items() if np.isnan(measures[m]).any()}
    rates = {k: float("nan") if k in unknown else float(holds[k].mean()) for k in uses}
    together = np.logical_and.reduce([holds[k] for k in uses])
    rates["all four"] = float("nan") if unknown else float(together.mean())
    return rates


#: experiment -> how a bootstrap redraws its teachers and recomputes its conclusions
_RATES = {1: _rates1, 2: _rates2}


def replication_rates(
    runs: pd.DataFrame, experiment: int, n_boot: int = 2000, seed: int = 0,
    match_paper: bool = False,
) -> pd.Series:
    """Share of bootstrap cohorts (the paper's size, resampled) where each conclusion holds.

    Parameters
    ----------
    runs : DataFrame
        The ``runs`` frame of an Experiment ``experiment`` cohort.
    experiment : {1, 2}
    n_boot : int
        Number of resampled cohorts (>= 100).
    seed : int
        Seed of the resampling (the same seed gives the same rates).
    match_paper : bool
        Rescale each condition to the paper's levels first (see the module docstring).

    Returns
    -------
    Series
        Index ``CONCLUSIONS[experiment]``, values in [0, 1] (NaN where no rescaling
        exists).
    """
    if isinstance(experiment, bool) or experiment not in _RATES:
        raise InvalidParameterError(f"experiment must be 1 or 2, got {experiment!r}")
    rng = _check_bootstrap(n_boot, seed)
    rates = _RATES[experiment](runs, rng, n_boot, match_paper)
    return pd.Series(rates, name="replication rate").reindex(list(CONCLUSIONS[experiment]))


def chance_of_at_least(k: int, n: int, rate: float) -> float:
    """Chance that a conclusion holding in a share ``rate`` of cohorts holds in >= k of n.

    E.g. the issue's bar "in at least 8 of 10 seeds" for a conclusion whose
    replication rate is 0.78 is met with chance ``chance_of_at_least(8, 10, 0.78)``
    (about 0.6).
    """
    if not (0 <= k <= n):
        raise InvalidParameterError(f"need 0 <= k <= n, got k={k}, n={n}")
    if not np.isfinite(rate):
        return float("nan")
    if not 0 <= rate <= 1:
        raise InvalidParameterError(f"rate must be in [0, 1], got {rate}")
    return float(binom.sf(k - 1, n, rate))
