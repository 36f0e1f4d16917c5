r"""Statistics of the adaptive-feedback study (:mod:`tutor.study.adaptive`).

Everything is paired: a policy's run is compared with BF's run of the same teacher
(same traits), seed and run number (the study's common random numbers), and a
teacher's three runs are averaged first, so the unit of every resampling is a teacher.

- **Per seed**: the mean paired difference over the seed's teachers, with a percentile
  bootstrap CI over teachers (``n_boot`` draws).
- **Over seeds** (the claim): the mean of the per-seed means with a t interval across
  the seeds (each seed a new cohort), the number of seeds whose own CI is above 0, and a
  pooled bootstrap CI (teachers resampled within every seed, then averaged over seeds).
- **Replication rates** (in the manner of :mod:`tutor.study.replication`): per
  teacher-model variant, the share of seeds whose CI is above 0 and the share of
  bootstrap cohorts (n teachers drawn with replacement from all the variant's teachers)
  whose normal-approximation 95 % CI of the mean difference is above 0.

Every function takes the ``runs`` (or ``curves``) frame of
:class:`~tutor.study.adaptive.StudyResult`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats as sps

from ..errors import InvalidParameterError

__all__ = [
    "MEASURES",
    "DELTA_MEASURES",
    "teacher_deltas",
    "bootstrap_ci",
    "seed_interval",
    "policy_table",
    "delta_table",
    "replication_table",
    "mean_curves",
    "why_stopped",
]

#: per-run measures summarised per policy (column -> what it is)
MEASURES = {
    "efficacy": "eps at the end of the run",
    "reached_target": "share of runs reaching eps >= 0.9 at some demo",
    "final_reached": "share of runs ending with eps >= 0.9",
    "undemonstrated": "undemonstrated plants at the end",
    "n_demos": "demos kept",
    "retries": "demos taken back and redone",
    "eta": "eta = eps / demos",
    "eta_target": "eta at 0.9 (Experiment 1's rule)",
    "robot_seconds": "robot seconds (realisations x 25 s)",
    "seconds": "clock used (s)",
}
#: the measures given as paired differences against BF
DELTA_MEASURES = ("efficacy", "reached_target", "undemonstrated", "n_demos", "robot_seconds")
KEYS = ["variant", "seed", "teacher", "run"]
LEVEL = 0.95


def _need(frame: pd.DataFrame, columns) -> None:
    missing = set(columns) - set(frame.columns)
    if missing:
        raise InvalidParameterError(
            f"the frame lacks the columns {sorted(missing)}; pass the runs frame of an "
            "adaptive study (run_study(...).runs)"
        )


def teacher_deltas(runs: pd.DataFrame, column: str = "efficacy", baseline: str = "BF"):
    """Paired differences against ``baseline``, averaged over each teacher's runs.

    Returns
    -------
    DataFrame
        Columns ``variant``, ``seed``, ``teacher``, ``policy``, ``delta`` (one row per
        teacher and policy other than the baseline).
    """
    _need(runs, [*KEYS, "policy", column])
    data = runs.assign(value=runs[column].astype(float))
    base = data[data.policy == baseline][[*KEYS, "value"]].rename(columns={"value": "base"})
    if base.empty:
        raise InvalidParameterError(f"the runs hold no {baseline} arm to compare with")
    others = data[data.policy != baseline][[*KEYS, "policy", "value"]]
    paired = others.merge(base, on=KEYS, how="inner", validate="many_to_one")
    paired["delta"] = paired["value"] - paired["base"]
    out = paired.groupby(["variant", "seed", "teacher", "policy"], sort=False)["delta"].mean()
    return out.reset_index()


def bootstrap_ci(values, n_boot: int = 2000, rng=None) -> tuple[float, float]:
    """Percentile bootstrap CI (95 %) of the mean of ``values`` (NaN for < 2 values)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if len(v) < 2:
        return float("nan"), float("nan")
    rng = np.random.default_rng(rng)
    means = v[rng.integers(0, len(v), size=(n_boot, len(v)))].mean(axis=1)
    lo, hi = np.percentile(means, [100 * (1 - LEVEL) / 2, 100 * (1 + LEVEL) / 2])
    return float(lo), float(hi)


def seed_interval(values) -> tuple[float, float, float]:
    """Mean and t interval (95 %) across seeds: (mean, low, high); NaN for < 2 seeds."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if len(v) == 0:
        return float("nan"), float("nan"), float("nan")
    mean = float(v.mean())
    if len(v) < 2:
        return mean, float("nan"), float("nan")
    half = float(sps.t.ppf((1 + LEVEL) / 2, len(v) - 1) * v.std(ddof=1) / np.sqrt(len(v)))
    return mean, mean - half, mean + half


def _order(frame: pd.DataFrame, policies=None) -> list[str]:
    present = list(dict.fromkeys(frame.policy))
    if policies is None:
        return present
    return [p for p in policies if p in present]


def policy_table(runs: pd.DataFrame, policies=None) -> pd.DataFrame:
    """Per policy and measure: the mean over all runs and its t interval across seeds.

    Returns
    -------
    DataFrame
        Index the policies; columns ``<measure>``, ``<measure>_low``, ``<measure>_high``
        for every measure of :data:`MEASURES` (shares for the booleans), and ``runs``.
    """
    _need(runs, ["seed", "policy", *MEASURES])
    table = {}
    for policy in _order(runs, policies):
        rows = runs[runs.policy == policy]
        entry = {"runs": len(rows)}
        for column in MEASURES:
            per_seed = rows.groupby("seed")[column].apply(lambda s: s.astype(float).mean())
            mean, lo, hi = seed_interval(per_seed)
            entry.update({column: float(rows[column].astype(float).mean()),
                          f"{column}_low": lo, f"{column}_high": hi})
            del mean
        table[policy] = entry
    return pd.DataFrame(table).T


def delta_table(
    runs: pd.DataFrame, column: str = "efficacy", n_boot: int = 2000, seed: int = 0,
    policies=None, baseline: str = "BF",
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Paired differences against BF, per seed and over seeds (the module docstring).

    Returns
    -------
    per_seed : DataFrame
        Rows policy x seed: ``mean``, ``low``, ``high`` (bootstrap over teachers), ``n``.
    overall : DataFrame
        Index the policies: ``mean`` (of the per-seed means), ``low``, ``high`` (t
        across seeds), ``pooled_low``, ``pooled_high`` (teachers resampled within seeds),
        ``seeds``, ``seeds_above`` (seeds whose CI is above 0), ``seeds_below``,
        ``seeds_positive`` (seeds whose mean is above 0).
    """
    deltas = teacher_deltas(runs, column, baseline)
    rng = np.random.default_rng(seed)
    per_seed, overall = [], {}
    for policy in _order(deltas, policies):
        mine = deltas[deltas.policy == policy]
        draws, rows = [], []
        for s, group in mine.groupby("seed", sort=True):
            d = group["delta"].to_numpy(float)
            lo, hi = bootstrap_ci(d, n_boot, rng)
            rows.append({"policy": policy, "seed": int(s), "mean": float(d.mean()),
                         "low": lo, "high": hi, "n": len(d)})
            draws.append(d[rng.integers(0, len(d), size=(n_boot, len(d)))].mean(axis=1))
        mean, lo, hi = seed_interval([r["mean"] for r in rows])
        pooled = np.mean(draws, axis=0)
        p_lo, p_hi = np.percentile(pooled, [100 * (1 - LEVEL) / 2, 100 * (1 + LEVEL) / 2])
        overall[policy] = {
            "mean": mean, "low": lo, "high": hi,
            "pooled_low": float(p_lo), "pooled_high": float(p_hi),
            "seeds": len(rows),
            "seeds_above": sum(r["low"] > 0 for r in rows),
            "seeds_below": sum(r["high"] < 0 for r in rows),
            "seeds_positive": sum(r["mean"] > 0 for r in rows),
        }
        per_seed += rows
    return pd.DataFrame(per_seed), pd.DataFrame(overall).T


def replication_table(
    runs: pd.DataFrame, n: int, n_boot: int = 2000, seed: int = 0, column: str = "efficacy"
) -> pd.DataFrame:
    """Replication rates of "the policy beats BF" per teacher-model variant.

    Parameters
    ----------
    runs : DataFrame
        Every variant's runs (the main study is variant "default").
    n : int
        Teachers per resampled cohort (the study's cohort size).

    Returns
    -------
    DataFrame
        Rows variant x policy: ``seeds``, ``mean`` (of the paired difference),
        ``seed_rate`` (share of seeds whose bootstrap CI over teachers is above 0) and
        ``boot_rate`` (share of resampled cohorts of ``n`` teachers whose 95 % CI is
        above 0).
    """
    deltas = teacher_deltas(runs, column)
    rng = np.random.default_rng(seed)
    z = sps.norm.ppf((1 + LEVEL) / 2)
    rows = []
    for variant in dict.fromkeys(deltas.variant):
        mine = deltas[deltas.variant == variant]
        for policy in _order(mine):
            d = mine[mine.policy == policy]
            seed_ci = [bootstrap_ci(g["delta"], n_boot, rng)[0] for _, g in d.groupby("seed")]
            pool = d["delta"].to_numpy(float)
            draw = pool[rng.integers(0, len(pool), size=(n_boot, n))]
            low = draw.mean(axis=1) - z * draw.std(axis=1, ddof=1) / np.sqrt(n)
            rows.append({
                "variant": variant, "policy": policy, "seeds": len(seed_ci),
                "mean": float(pool.mean()),
                "seed_rate": float(np.mean(np.array(seed_ci) > 0)),
                "boot_rate": float(np.mean(low > 0)),
            })
    return pd.DataFrame(rows)


def mean_curves(curves: pd.DataFrame, cap: float = 900.0, step: float = 5.0) -> pd.DataFrame:
    """Mean eps against the clock per policy: each run's eps after its latest event
    (0 before its first demo, its final eps once it ended), averaged over runs.

    Returns
    -------
    DataFrame
        Index the seconds 0, step, ..., cap; one column per policy.
    """
    _need(curves, ["policy", "seed", "teacher", "run", "seconds", "efficacy"])
    grid = np.arange(0.0, cap + step / 2, step)
    out = {}
    for policy in _order(curves):
        total = np.zeros(len(grid))
        count = 0
        for _, run in curves[curves.policy == policy].groupby(
            ["variant", "seed", "teacher", "run"], sort=False
        ):
            t = run["seconds"].to_numpy(float)
            e = run["efficacy"].to_numpy(float)
            at = np.searchsorted(t, grid, side="right") - 1
            total += np.where(at >= 0, e[np.clip(at, 0, None)], 0.0)
            count += 1
        out[policy] = total / max(count, 1)
    return pd.DataFrame(out, index=pd.Index(grid, name="seconds"))


def why_stopped(runs: pd.DataFrame, policies=None) -> pd.DataFrame:
    """Share of runs per policy that ended by each reason ("time", "satisfied", ...)."""
    _need(runs, ["policy", "why_stopped"])
    table = pd.crosstab(runs.policy, runs.why_stopped, normalize="index")
    return table.loc[_order(runs, policies)]
