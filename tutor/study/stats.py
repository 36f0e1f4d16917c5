"""Statistics of the simulated cohorts, done as the paper did them (pingouin).

Experiment 1: a repeated-measures ANOVA of eta over the three conditions with
Mauchly's sphericity test (Greenhouse-Geisser corrected p reported when sphericity is
violated), then pairwise comparisons (paired t-tests, Bonferroni corrected).
Experiment 2: a mixed ANOVA (between: condition; within: run), then pairwise
comparisons of the teachers' mean eta between conditions (Welch t-tests, Bonferroni);
the failure-count table. :func:`conclusions` checks the paper's findings on a result.

Every function takes the ``runs`` frame of :class:`~tutor.study.cohort.CohortResult`.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import paper
from ..paper import PICKPLACE_BEST, PICKPLACE_CONDITIONS

__all__ = [
    "experiment1_stats",
    "experiment2_stats",
    "failure_table",
    "relative_improvement",
    "conclusions",
    "experiment1_holds",
    "experiment2_ranking",
    "summary_table",
    "describe",
    "compare_two",
    "Analysis",
    "ANALYSES",
]

ALPHA = 0.05


def _pg():
    import pingouin as pg

    return pg


def _col(frame: pd.DataFrame, *names):
    """The first of ``names`` present in ``frame`` (pingouin renamed columns over versions)."""
    for name in names:
        if name in frame.columns:
            return name
    return None


def _pairwise(frame: pd.DataFrame, **kwargs) -> pd.DataFrame:
    pg = _pg()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = pg.pairwise_tests(data=frame, padjust="bonf", **kwargs)
    p_unc = _col(res, "p_unc", "p-unc")
    p_corr = _col(res, "p_corr", "p-corr")
    out = pd.DataFrame(
        {
            "A": res["A"],
            "B": res["B"],
            "T": res["T"],
            "p_unc": res[p_unc],
            "p_bonf": res[p_corr] if p_corr else res[p_unc],
        }
    )
    return out.reset_index(drop=True)


def _clean(frame: pd.DataFrame) -> pd.DataFrame:
    out = frame.copy()
    out["condition"] = out["condition"].astype(str)
    return out


def experiment1_stats(runs: pd.DataFrame) -> dict:
    """Repeated-measures ANOVA, sphericity and pairwise tests of eta (Experiment 1).

    Returns
    -------
    dict
        ``anova`` (F, ddof1, ddof2, p, p_gg, sphericity_W, sphericity_p,
        sphericity_ok), ``pairwise`` (DataFrame A, B, T, p_unc, p_bonf), ``medians``,
        ``means``, ``demos`` (mean demos per condition), ``efficacy`` (mean and sd).
    """
    pg = _pg()
    data = _clean(runs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        aov = pg.rm_anova(
            data=data,
            dv="eta",
            within="condition",
            subject="teacher",
            correction=True,
            detailed=True,
        )
        sph = pg.sphericity(data=data, dv="eta", within="condition", subject="teacher")
    row = aov.iloc[0]
    p = float(row[_col(aov, "p_unc", "p-unc")])
    gg = _col(aov, "p_GG_corr", "p-GG-corr")
    p_gg = float(row[gg]) if gg and pd.notna(row[gg]) else p
    sph_ok = bool(sph.spher) if hasattr(sph, "spher") else bool(sph[0])
    w_stat = float(sph.W) if hasattr(sph, "W") else float(sph[1])
    sph_p = float(sph.pval) if hasattr(sph, "pval") else float(sph[-1])
    anova = {
        "F": float(row["F"]),
        "ddof1": int(row["DF"]),
        "ddof2": int(aov.iloc[1]["DF"]),
        "p": p,
        "p_gg": p_gg,
        "sphericity_W": w_stat,
        "sphericity_p": sph_p,
        "sphericity_ok": sph_ok,
        "p_used": p if sph_ok else p_gg,
    }
    pairs = _pairwise(data, dv="eta", within="condition", subject="teacher")
    return {"anova": anova, "pairwise": pairs, **describe(runs, 1)}


def _describe1(data: pd.DataFrame, grouped) -> dict:
    return {
        "medians": grouped["eta"].median().to_dict(),
        "means": grouped["eta"].mean().to_dict(),
        "demos": grouped["n_demos"].mean().to_dict(),
        "efficacy_mean": grouped["efficacy"].mean().to_dict(),
        "efficacy_sd": grouped["efficacy"].std().to_dict(),
        "reached_target": grouped["reached_target"].sum().astype(int).to_dict(),
    }


def _describe2(data: pd.DataFrame, grouped) -> dict:
    return {
        "means": grouped["eta"].mean().to_dict(),
        "by_run": data.pivot_table(index="condition", columns="run", values="eta", aggfunc="mean"),
        "demos": grouped["n_demos"].mean().to_dict(),
        "efficacy_mean": grouped["efficacy"].mean().to_dict(),
        "seconds": grouped["seconds"].mean().to_dict() if "seconds" in data else {},
    }


def describe(runs: pd.DataFrame, experiment: int) -> dict:
    """The per-condition numbers of a cohort, which need no test (any size, one run too).

    Experiment 1: ``medians``, ``means`` (of eta), ``demos`` (mean demos),
    ``efficacy_mean``, ``efficacy_sd``, ``reached_target`` (runs that reached 90 %).
    Experiment 2: ``means`` (of eta), ``by_run`` (mean eta per condition and run),
    ``demos``, ``efficacy_mean``, ``seconds`` (mean clock seconds).
    """
    data = _clean(runs)
    return ANALYSES[experiment].describe(data, data.groupby("condition", sort=False))


def experiment2_stats(runs: pd.DataFrame) -> dict:
    """Mixed ANOVA (condition x run), pairwise tests and means of eta (Experiment 2)."""
    pg = _pg()
    data = _clean(runs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        aov = pg.mixed_anova(
            data=data, dv="eta", within="run", between="condition", subject="teacher"
        )
        try:
            sph = pg.sphericity(data=data, dv="eta", within="run", subject="teacher")
            sph_p = float(sph.pval) if hasattr(sph, "pval") else float(sph[-1])
        except (ValueError, np.linalg.LinAlgError):
            sph_p = float("nan")
    pcol = _col(aov, "p_unc", "p-unc")
    table = {}
    for _, r in aov.iterrows():
        key = {"condition": "condition", "run": "run", "Interaction": "interaction"}[r["Source"]]
        table[key] = {
            "F": float(r["F"]),
            "ddof1": int(r["DF1"]),
            "ddof2": int(r["DF2"]),
            "p": float(r[pcol]),
        }
    table["sphericity_p"] = sph_p
    per_teacher = data.groupby(["teacher", "condition"], as_index=False)["eta"].mean()
    pairs = _pairwise(per_teacher, dv="eta", between="condition", parametric=True)
    return {"anova": table, "pairwise": pairs, **describe(runs, 2)}


def failure_table(runs: pd.DataFrame) -> pd.DataFrame:
    """Total failures per condition over all teachers and runs (the paper's table).

    Rows: demonstration errors, undemonstrated states, ambiguous demonstrations;
    columns: the conditions.
    """
    data = _clean(runs)
    order = list(dict.fromkeys(data["condition"]))
    sums = data.groupby("condition")[["errors", "undemonstrated", "ambiguous"]].sum()
    return sums.loc[order].T.astype(int)


def _relative1(stats: dict) -> dict:
    med = stats["medians"]
    nf = med["NF"] if med["NF"] > 0 else np.nan
    return {"VF/NF": med["VF"] / nf, "VR/NF": med["VR"] / nf}


def _relative2(stats: dict) -> dict:
    means, best = stats["means"], PICKPLACE_BEST
    rest = [c for c in PICKPLACE_CONDITIONS if c != best]
    others = np.mean([means[c] for c in rest])
    third = stats["by_run"][stats["by_run"].columns.max()]
    others3 = np.mean([third[c] for c in rest])
    return {"mean": means[best] / others, "third run": third[best] / others3}


def relative_improvement(stats: dict, experiment: int) -> dict:
    """The paper's relative improvements, from :func:`experiment1_stats` or ``2``."""
    return ANALYSES[experiment].relative(stats)


def _p(pairs: pd.DataFrame, a: str, b: str) -> float:
    hit = pairs[((pairs.A == a) & (pairs.B == b)) | ((pairs.A == b) & (pairs.B == a))]
    return float(hit["p_bonf"].iloc[0]) if len(hit) else float("nan")


def experiment1_holds(medians: dict, p_bonf: dict) -> dict:
    """Experiment 1's conclusions from its medians and Bonferroni-corrected p values.

    Parameters
    ----------
    medians : dict
        Condition (``NF``, ``VF``, ``VR``) -> median eta: floats, or arrays of one
        shape (e.g. one entry per bootstrap draw).
    p_bonf : dict
        ``(a, b)`` for each of ``("NF", "VF")``, ``("NF", "VR")`` and ``("VF", "VR")``
        -> the paired t-test's Bonferroni p, of the same shape. NaN (no spread to test)
        makes every conclusion about that pair false.

    Returns
    -------
    dict of bool (ndarray of bool for arrays)
        ``NF<VF``, ``NF<VR`` (median lower and p < 0.05) and ``VF~VR`` (p >= 0.05).
    """
    med = {c: np.asarray(v, dtype=float) for c, v in medians.items()}
    p = {k: np.asarray(v, dtype=float) for k, v in p_bonf.items()}
    return {
        "NF<VF": (med["NF"] < med["VF"]) & (p["NF", "VF"] < ALPHA),
        "NF<VR": (med["NF"] < med["VR"]) & (p["NF", "VR"] < ALPHA),
        "VF~VR": p["VF", "VR"] >= ALPHA,
    }


def _conclusions1(runs: pd.DataFrame, st: dict) -> dict:
    pairs = st["pairwise"]
    held = experiment1_holds(
        st["medians"], {(a, b): _p(pairs, a, b) for a, b in paper.EXPERIMENT_1["pairwise_p"]}
    )
    return {k: bool(v) for k, v in held.items()}


def _conclusions2(runs: pd.DataFrame, st: dict) -> dict:
    fail = failure_table(runs)
    conds = list(fail.columns)
    measures = {k: fail.loc[k].to_numpy(float) for k in ("errors", "undemonstrated", "ambiguous")}
    measures["eta"] = np.array([st["means"][c] for c in conds])
    ranks = experiment2_ranking(conds, **measures)
    return {
        "condition effect": bool(st["anova"]["condition"]["p"] < ALPHA),
        **{k: bool(v) for k, v in ranks.items()},
    }


def conclusions(runs: pd.DataFrame, experiment: int, stats: dict | None = None) -> dict:
    """The paper's conclusions, each True/False on this cohort.

    Experiment 1: ``NF<VF`` and ``NF<VR`` (medians lower and Bonferroni p < 0.05),
    ``VF~VR`` (p >= 0.05). Experiment 2: ``condition effect`` (mixed ANOVA p < 0.05),
    ``BF best`` (BF's mean eta above NF, RF and SF), ``BF fewest ambiguous``, ``BF most
    undemonstrated``, ``RF fewest errors`` (ties count as fewest/most).
    """
    analysis = ANALYSES[experiment]
    return analysis.conclusions(runs, analysis.tests(runs) if stats is None else stats)


def experiment2_ranking(conditions, errors, undemonstrated, ambiguous, eta) -> dict:
    """Experiment 2's ranking conclusions from per-condition measures (ties count).

    Parameters
    ----------
    conditions : sequence of str
        The order of the first axis of the measures (must hold NF, RF, BF and SF).
    errors, undemonstrated, ambiguous : ndarray (n_conditions, ...)
        Failure totals per condition (any trailing shape, e.g. bootstrap draws).
    eta : ndarray (n_conditions, ...)
        Mean teaching efficiency per condition.

    Returns
    -------
    dict of bool ndarray (...)
        ``BF best``, ``BF fewest ambiguous``, ``BF most undemonstrated``, ``RF fewest
        errors``.
    """
    conditions = list(conditions)
    bf, rf = conditions.index("BF"), conditions.index("RF")
    others = [i for i in range(len(conditions)) if i != bf]
    return {
        "BF best": (eta[bf] > eta[others]).all(axis=0),
        "BF fewest ambiguous": ambiguous[bf] <= ambiguous.min(axis=0),
        "BF most undemonstrated": undemonstrated[bf] >= undemonstrated.max(axis=0),
        "RF fewest errors": errors[rf] <= errors.min(axis=0),
    }


def _table1(st: dict) -> tuple[list, dict]:
    conds = list(st["medians"])
    return conds, {
        "median eta (sim)": [st["medians"][c] for c in conds],
        "median eta (paper)": [paper.EXPERIMENT_1["median_eta"][c] for c in conds],
        "mean demos (sim)": [st["demos"][c] for c in conds],
        "mean efficacy (sim)": [st["efficacy_mean"][c] for c in conds],
        "sd efficacy (sim)": [st["efficacy_sd"][c] for c in conds],
        "reached 90 % (sim)": [st["reached_target"][c] for c in conds],
    }


def _table2(st: dict) -> tuple[list, dict]:
    conds = list(st["means"])
    third = st["by_run"][st["by_run"].columns.max()]
    return conds, {
        "mean eta (sim)": [st["means"][c] for c in conds],
        "mean eta (paper)": [paper.EXPERIMENT_2["mean_eta"][c] for c in conds],
        "run 3 eta (sim)": [third[c] for c in conds],
        "run 3 eta (paper)": [paper.EXPERIMENT_2["third_run_eta"][c] for c in conds],
        "mean demos (sim)": [st["demos"][c] for c in conds],
        "mean efficacy (sim)": [st["efficacy_mean"][c] for c in conds],
        "mean minutes (sim)": [st["seconds"].get(c, np.nan) / 60 for c in conds],
    }


def summary_table(runs: pd.DataFrame, experiment: int, stats: dict | None = None) -> pd.DataFrame:
    """Per condition: the simulation's eta (median or mean) beside the paper's, demos, eps.

    ``stats`` (:func:`experiment1_stats` or ``2``) gives the numbers; without it they are
    :func:`describe`'s (the same numbers, no test needed, so a cohort of any size has
    its table).
    """
    st = describe(runs, experiment) if stats is None else stats
    conds, columns = ANALYSES[experiment].table(st)
    return pd.DataFrame(columns, index=conds)


def compare_two(runs: pd.DataFrame, a: str, b: str, experiment: int) -> dict:
    """Condition ``a`` against ``b`` alone, as the paper's pairwise tests compare two.

    Experiment 1 (within subjects): a paired t-test of η on the teachers who taught
    both; Experiment 2 (between subjects): a Welch t-test of the teachers' mean η. A
    condition beyond the paper is judged this way against the paper's condition it is
    compared with, never inside the paper's ANOVA.

    Returns
    -------
    dict
        ``test`` ("paired t" or "Welch t"), ``n_a`` and ``n_b`` (teachers in the test),
        ``T`` and ``p`` (NaN when there are too few teachers, fewer than 2 a side, or
        no spread to test).
    """
    data = _clean(runs)
    data = data[data.condition.isin([a, b])]
    paired = ANALYSES[experiment].paired
    out = {"test": "paired t" if paired else "Welch t", "T": np.nan, "p": np.nan}
    if paired:
        wide = data.pivot_table(index="teacher", columns="condition", values="eta")
        wide = wide.reindex(columns=[a, b]).dropna()
        x, y = wide[a].to_numpy(float), wide[b].to_numpy(float)
    else:
        means = data.groupby(["teacher", "condition"])["eta"].mean().reset_index()
        x = means.loc[means.condition == a, "eta"].to_numpy(float)
        y = means.loc[means.condition == b, "eta"].to_numpy(float)
    out.update(n_a=len(x), n_b=len(y))
    if min(len(x), len(y)) < 2 or np.ptp(x - y if paired else np.r_[x, y]) == 0:
        return out
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = _pg().ttest(x, y, paired=paired, correction=not paired)
    out.update(T=float(res["T"].iloc[0]), p=float(res[_col(res, "p_val", "p-val")].iloc[0]))
    return out


@dataclass(frozen=True)
class Analysis:
    """How the paper analysed one experiment: the parts :func:`describe`,
    :func:`conclusions`, :func:`relative_improvement`, :func:`summary_table` and
    :func:`compare_two` use.

    Attributes
    ----------
    summary : str
        How the paper sums up eta per condition: "median" (Experiment 1) or "mean".
    paired : bool
        Within subjects: conditions are compared teacher by teacher (paired t).
    paper : dict
        The paper's numbers (:data:`tutor.paper.EXPERIMENT_1` or ``2``).
    tests, describe, relative, conclusions, table : callable
        The statistics with their tests (``runs -> dict``), the numbers without
        (``data, grouped -> dict``), the relative improvements, the conclusions
        (``runs, stats -> dict``) and the summary table's columns.
    class_column : callable
        A class's own column beside the shared ones (``grouped -> (name, Series)``):
        runs that reached 90 % (Experiment 1), mean minutes on the clock (Experiment 2).
    failures : bool
        The paper reports a table of teaching failures (:func:`failure_table`).
    """

    summary: str
    paired: bool
    paper: dict
    tests: Callable
    describe: Callable
    relative: Callable
    conclusions: Callable
    table: Callable
    class_column: Callable
    failures: bool = False

    @property
    def paper_eta(self) -> dict:
        """The paper's eta per condition, summed up as :attr:`summary` says."""
        return self.paper[f"{self.summary}_eta"]

    @property
    def key(self) -> str:
        """The key of the per-condition summary in :func:`describe`'s dict."""
        return self.summary + "s"


#: experiment number -> how the paper analysed it
ANALYSES = {
    1: Analysis(
        "median", True, paper.EXPERIMENT_1, experiment1_stats, _describe1, _relative1,
        _conclusions1, _table1, lambda g: ("reached 90 %", g["reached_target"].sum()),
    ),
    2: Analysis(
        "mean", False, paper.EXPERIMENT_2, experiment2_stats, _describe2, _relative2,
        _conclusions2, _table2, lambda g: ("mean minutes", g["seconds"].mean() / 60),
        failures=True,
    ),
}
