r"""How often would Experiment 2's conclusions come out again with 9 new teachers each?

Experiment 2 of Sena & Howard compares four groups of only nine teachers (three runs
each). Its conclusions about the failure counts (section "Evaluation": BF has the
fewest ambiguous demos and the most undemonstrated states, RF the fewest
demonstration errors) rest on sums over 27 runs, and one teacher's run can swing such
a sum by a hundred undemonstrated states (a run that ends with too few demos leaves
most of the 100 plants failing). This module asks how stable each conclusion is.

**Replication rate.** Draw nine teachers per condition *with replacement* from a
cohort (a teacher keeps their three runs together), recompute the conclusion, repeat
``n_boot`` times: the share of draws in which it holds. It estimates the chance that a
new study with nine teachers per condition, drawn from the same population, finds it.

**Against the paper's means.** ``match_paper=True`` first rescales every condition's
teachers so that the condition's total (errors, undemonstrated states, ambiguous demos)
or mean (eta) equals the paper's, keeping the spread between teachers that the
simulation shows. The rates then say how often a study whose true means *are* the
paper's would reproduce the paper's own conclusions with nine teachers per condition.
Where the simulation's total is zero but the paper's is not, no rescaling exists and
the rate is NaN.

Notation: eta is teaching efficiency (efficacy / number of demos); the counts are
those of :func:`tutor.study.stats.failure_table`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.stats import binom

from .. import paper
from ..errors import InvalidParameterError
from ..framework.protocol import EXPERIMENTS
from .stats import experiment2_ranking

__all__ = ["teacher_totals", "replication_rates", "chance_of_at_least"]

COUNTS = ("errors", "undemonstrated", "ambiguous")
CONDITIONS = EXPERIMENTS[2].paper_codes
#: the conclusions a bootstrap can recompute (the ANOVA is not redone per draw)
CONCLUSIONS = ("BF best", "BF fewest ambiguous", "BF most undemonstrated", "RF fewest errors")


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
    need = {"teacher", "condition", "eta", *COUNTS}
    missing = need - set(runs.columns)
    if missing:
        raise InvalidParameterError(
            f"runs lacks the columns {sorted(missing)}; pass the runs frame of an "
            "Experiment 2 cohort (run_experiment(2, ...).runs)"
        )
    conds = set(runs["condition"].astype(str))
    if conds != set(CONDITIONS):
        raise InvalidParameterError(
            f"replication rates need Experiment 2's conditions {CONDITIONS}, got {sorted(conds)}"
        )
    data = runs.assign(condition=runs["condition"].astype(str))
    grouped = data.groupby(["teacher", "condition"])
    out = grouped[list(COUNTS)].sum().join(grouped["eta"].mean()).reset_index("condition")
    return out.reset_index(drop=True)


def _scaled(values: np.ndarray, target: float) -> np.ndarray:
    total = values.sum()
    if total > 0:
        return values * (target / total)
    return values if target == 0 else np.full_like(values, np.nan)


def replication_rates(
    runs: pd.DataFrame, n_boot: int = 2000, seed: int = 0, match_paper: bool = False
) -> pd.Series:
    """Share of bootstrap cohorts (9 teachers per condition, resampled) where each holds.

    Parameters
    ----------
    runs : DataFrame
        The ``runs`` frame of an Experiment 2 cohort.
    n_boot : int
        Number of resampled cohorts (>= 100).
    seed : int
        Seed of the resampling (the same seed gives the same rates).
    match_paper : bool
        Rescale each condition to the paper's totals and means first (see the module
        docstring).

    Returns
    -------
    Series
        Index :data:`CONCLUSIONS`, values in [0, 1] (NaN where no rescaling exists).
    """
    if not isinstance(n_boot, (int, np.integer)) or n_boot < 100:
        raise InvalidParameterError(f"n_boot must be an integer >= 100, got {n_boot!r}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InvalidParameterError(f"seed must be an integer >= 0, got {seed!r}")
    table = teacher_totals(runs)
    rng = np.random.default_rng(seed)
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
    rates = {
        k: float("nan") if np.isnan(measures[uses[k]]).any() else float(holds[k].mean())
        for k in CONCLUSIONS
    }
    return pd.Series(rates, name="replication rate")


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
