"""Replication rates of the paper's conclusions (tutor.study.replication)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tutor import paper
from tutor.errors import InvalidParameterError
from tutor.study.replication import (
    CONCLUSIONS,
    chance_of_at_least,
    replication_rates,
    teacher_totals,
)

CONDS = ("NF", "RF", "BF", "SF")


def _cohort(values: dict, per: int = 3, seed: int = 0, noise: float = 0.0) -> pd.DataFrame:
    """``values[cond] = (errors, undemonstrated, ambiguous, eta)`` per run."""
    rng = np.random.default_rng(seed)
    rows = []
    for i, cond in enumerate(CONDS):
        for j in range(per):
            teacher = i * per + j
            for run in (1, 2, 3):
                e, u, a, eta = values[cond]
                rows.append(
                    {
                        "teacher": teacher,
                        "condition": cond,
                        "run": run,
                        "errors": e,
                        "undemonstrated": max(0, int(u + noise * rng.normal() * 50)),
                        "ambiguous": a,
                        "eta": eta,
                    }
                )
    runs = pd.DataFrame(rows)
    runs["condition"] = pd.Categorical(runs["condition"], categories=CONDS, ordered=True)
    return runs


PAPERLIKE = {
    "NF": (1, 10, 2, 0.12),
    "RF": (0, 20, 2, 0.13),
    "BF": (1, 30, 0, 0.24),
    "SF": (1, 10, 1, 0.15),
}


def test_teacher_totals_sum_counts_and_average_eta():
    runs = _cohort(PAPERLIKE, per=2)
    runs.loc[runs.teacher == 0, "eta"] = [0.1, 0.2, 0.3]
    table = teacher_totals(runs)
    assert len(table) == 8
    first = table.iloc[0]
    assert first.condition == "NF" and first.undemonstrated == 30 and first.errors == 3
    assert first.eta == pytest.approx(0.2)


def test_clear_cut_cohort_replicates_every_time():
    rates = replication_rates(_cohort(PAPERLIKE), 2, n_boot=200)
    assert list(rates.index) == list(CONCLUSIONS[2])
    assert (rates == 1.0).all()


def test_reversed_cohort_never_replicates():
    reversed_ = {
        c: (v[0] + 2 * (c == "RF"), 40 - v[1], 3 - v[2], 0.4 - v[3]) for c, v in PAPERLIKE.items()
    }
    rates = replication_rates(_cohort(reversed_), 2, n_boot=200)
    assert (rates == 0.0).all()


def test_noisy_cohort_gives_a_rate_between_and_is_seeded():
    close = {**PAPERLIKE, "RF": (0, 28, 2, 0.13)}
    runs = _cohort(close, per=9, noise=1.0, seed=3)
    a = replication_rates(runs, 2, n_boot=500, seed=1)
    b = replication_rates(runs, 2, n_boot=500, seed=1)
    pd.testing.assert_series_equal(a, b)
    assert 0.05 < a["BF most undemonstrated"] < 0.95


def test_match_paper_rescales_each_condition_to_the_papers_totals():
    # identical teachers within a condition: the rescaled sums are the paper's exactly,
    # so every paper conclusion holds in every draw, whatever the simulation's own ranks
    flat = {c: (1, 10, 1, 0.1) for c in CONDS}
    rates = replication_rates(_cohort(flat), 2, n_boot=200, match_paper=True)
    ref = paper.EXPERIMENT_2["failures"]
    assert ref["undemonstrated"]["BF"] == max(ref["undemonstrated"].values())
    assert (rates == 1.0).all()


def test_match_paper_gives_nan_when_no_rescaling_exists():
    zero_bf_ambiguous = {**PAPERLIKE, "BF": (1, 30, 0, 0.24)}  # paper's BF has 6
    rates = replication_rates(_cohort(zero_bf_ambiguous), 2, n_boot=200, match_paper=True)
    assert np.isnan(rates["BF fewest ambiguous"])
    assert np.isnan(rates["all four"])  # one of the four unknown: so are all four together
    assert rates["BF most undemonstrated"] == 1.0


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda r: r.drop(columns="ambiguous"), "lacks the columns"),
        (lambda r: r[r.condition != "SF"], "Experiment 2's conditions"),
    ],
)
def test_bad_frames_are_named_errors(change, match):
    with pytest.raises(InvalidParameterError, match=match):
        replication_rates(change(_cohort(PAPERLIKE)), 2, n_boot=200)


def test_bad_settings_are_named_errors():
    with pytest.raises(InvalidParameterError, match="n_boot"):
        replication_rates(_cohort(PAPERLIKE), 2, n_boot=10)
    for seed in (-1, 1.5, "x"):
        with pytest.raises(InvalidParameterError, match="seed must be"):
            replication_rates(_cohort(PAPERLIKE), 2, n_boot=100, seed=seed)
    with pytest.raises(InvalidParameterError, match="0 <= k <= n"):
        chance_of_at_least(11, 10, 0.5)
    with pytest.raises(InvalidParameterError, match="rate must be"):
        chance_of_at_least(8, 10, 1.5)


def test_chance_of_at_least_is_the_binomial_tail():
    assert chance_of_at_least(8, 10, 1.0) == pytest.approx(1.0)
    assert chance_of_at_least(8, 10, 0.5) == pytest.approx(56 / 1024)
    assert chance_of_at_least(0, 10, 0.3) == pytest.approx(1.0)
    assert np.isnan(chance_of_at_least(8, 10, float("nan")))


def test_experiment2_report_prints_the_replication_rates(tmp_path):
    from tutor.study import analyse, format_report, run_experiment, save_result

    result = run_experiment(2, seed=2, n=8, workers=2, progress=False)
    analysis = analyse(result)
    table = analysis["replication"]
    assert list(table.columns) == ["this cohort", "paper's levels", "8 of 10 seeds"]
    assert list(table.index) == list(CONCLUSIONS[2])
    text = format_report(result, analysis)
    assert "How often each conclusion comes out again" in text
    paths = save_result(result, analysis, tmp_path, figures=False)
    import json

    summary = json.loads(paths["summary"].read_text())
    assert set(summary["replication"]) == set(CONCLUSIONS[2])


def test_robustness_command_prints_paper_matched_rates(tmp_path, capsys):
    from tutor.__main__ import main

    args = ["robustness", "--experiment", "2", "--n", "8", "--seeds", "1"]
    code = main([*args, "--out", str(tmp_path), "--workers", "2", "--no-progress"])
    assert code == 0
    out = capsys.readouterr().out
    assert "If each condition's level were the paper's" in out
    assert "BF most undemonstrated:" in out
    table = pd.read_csv(tmp_path / "experiment2_robustness.csv")
    assert "paper-matched rate: BF most undemonstrated" in table.columns
    assert {"undemonstrated BF", "errors RF", "ambiguous NF"} <= set(table.columns)


# ---------------------------------------------------------------- Experiment 1

MAZE = ("NF", "VF", "VR")


def _maze_cohort(levels: dict, n: int = 30, spread: float = 0.2, seed: int = 0) -> pd.DataFrame:
    """Experiment 1 runs: each teacher's eta = level x (1 + spread x normal), per condition."""
    rng = np.random.default_rng(seed)
    rows = [
        {"teacher": t, "condition": c,
         "eta": max(0.0, levels[c] * (1 + spread * rng.normal()))}
        for t in range(n) for c in MAZE
    ]
    runs = pd.DataFrame(rows)
    # the rest of a maze run's record, as the paper's analysis reads it (5 demos each)
    runs = runs.assign(n_demos=5, efficacy=5 * runs.eta, reached_target=5 * runs.eta >= 0.9)
    runs["condition"] = pd.Categorical(runs["condition"], categories=MAZE, ordered=True)
    return runs


def test_experiment1_rates_follow_the_papers_pattern():
    paperlike = _maze_cohort({"NF": 0.076, "VF": 0.134, "VR": 0.134})
    # VR: VF's values in reverse teacher order, so VF - VR has mean 0 in this cohort
    vf = paperlike.condition == "VF"
    paperlike.loc[paperlike.condition == "VR", "eta"] = paperlike.loc[vf, "eta"].to_numpy()[::-1]
    rates = replication_rates(paperlike, 1, n_boot=400)
    assert list(rates.index) == list(CONCLUSIONS[1])
    assert rates["NF<VF"] > 0.99 and rates["NF<VR"] > 0.99
    assert rates["VF~VR"] > 0.9
    assert rates["all three"] <= rates[["NF<VF", "NF<VR", "VF~VR"]].min()
    # NF as good as the others (the same values, other teachers): rarely found below them
    flat = _maze_cohort({c: 0.15 for c in MAZE})
    values = flat.loc[flat.condition == "VF", "eta"].to_numpy()
    flat.loc[flat.condition == "NF", "eta"] = np.roll(values, 1)
    flat.loc[flat.condition == "VR", "eta"] = values[::-1]
    flat = replication_rates(flat, 1, n_boot=400)
    assert flat["NF<VF"] < 0.1 and flat["NF<VR"] < 0.1 and flat["all three"] < 0.1


def test_experiment1_match_paper_rescales_to_the_papers_medians():
    # the simulation's own ranking reversed (NF best): rescaled to the paper's medians,
    # keeping each condition's relative spread, the paper's NF < VF, VR come out
    reversed_ = _maze_cohort({"NF": 0.3, "VF": 0.1, "VR": 0.1}, seed=1)
    own = replication_rates(reversed_, 1, n_boot=400)
    matched = replication_rates(reversed_, 1, n_boot=400, match_paper=True)
    assert own["NF<VF"] == 0.0 and own["NF<VR"] == 0.0
    assert matched["NF<VF"] > 0.99 and matched["NF<VR"] > 0.99
    # a condition whose median is 0 cannot be rescaled to the paper's 7.6 %
    zero = reversed_.copy()
    zero.loc[zero.condition == "NF", "eta"] = 0.0
    assert replication_rates(zero, 1, n_boot=100, match_paper=True).isna().all()


def test_experiment1_bootstrap_is_the_papers_analysis_on_each_draw():
    """Every draw is judged exactly as tutor.study.stats judges a cohort (pingouin)."""
    from tutor.study.stats import conclusions

    runs = _maze_cohort({"NF": 0.08, "VF": 0.13, "VR": 0.14}, n=12, spread=0.6, seed=5)
    n_boot, seed = 100, 7
    rates = replication_rates(runs, 1, n_boot=n_boot, seed=seed)
    # the same draws, each as a cohort of its own (teachers in the pivot's order)
    teachers = np.sort(runs.teacher.unique())
    idx = np.random.default_rng(seed).integers(0, len(teachers), size=(n_boot, len(teachers)))
    held = []
    for draw in idx:
        parts = [runs[runs.teacher == teachers[i]].assign(teacher=k) for k, i in enumerate(draw)]
        held.append(conclusions(pd.concat(parts, ignore_index=True), 1))
    expected = pd.DataFrame(held)
    for name in ("NF<VF", "NF<VR", "VF~VR"):
        assert rates[name] == pytest.approx(expected[name].mean())
    assert rates["all three"] == pytest.approx(expected.all(axis=1).mean())
    # a cohort on which every conclusion sometimes holds and sometimes not
    assert ((rates > 0.0) & (rates < 1.0)).all()


def test_experiment1_bad_input_is_named():
    with pytest.raises(InvalidParameterError, match="Experiment 1's conditions"):
        replication_rates(_cohort(PAPERLIKE), 1, n_boot=100)
    with pytest.raises(InvalidParameterError, match="at least 3 teachers"):
        replication_rates(_maze_cohort({c: 0.1 for c in MAZE}, n=2), 1, n_boot=100)
    for experiment in (0, 3, True, "1"):
        with pytest.raises(InvalidParameterError, match="experiment must be 1 or 2"):
            replication_rates(_maze_cohort({c: 0.1 for c in MAZE}), experiment, n_boot=100)


def test_experiment1_report_and_robustness_print_the_rates(tmp_path, capsys):
    from tutor.__main__ import main

    args = ["robustness", "--experiment", "1", "--n", "6", "--seeds", "1"]
    assert main([*args, "--out", str(tmp_path), "--workers", "2", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "If each condition's level were the paper's" in out
    assert "all three:" in out
    table = pd.read_csv(tmp_path / "experiment1_robustness.csv")
    assert "paper-matched rate: all three" in table.columns
    code = main(["reproduce", "--experiment", "1", "--n", "6", "--out", str(tmp_path),
                 "--workers", "2", "--no-figures", "--no-progress"])
    assert code == 0
    report = (tmp_path / "experiment1_report.txt").read_text()
    assert "30 teachers, each keeping their three conditions" in report
    assert "paper's levels" in report
