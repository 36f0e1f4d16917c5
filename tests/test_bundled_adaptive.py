"""The adaptive-feedback study bundled for notebook 06 is the full study, as the command
wrote it (``lfd-tutor adaptive --seeds 10 --out tutor/assets/adaptive``)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from tutor.resources import asset
from tutor.study.adaptive import DEFAULT_POLICIES, teach_policy

STUDY = asset("adaptive")


def test_the_bundled_study_is_the_full_one_with_every_policy():
    summary = json.loads((STUDY / "adaptive_summary.json").read_text())
    plan = summary["plan"]
    assert plan["seeds"] == 10 and plan["n"] == 36 and plan["runs"] == 3
    assert not plan["quick"] and summary["missing"] == []
    # every arm on every teacher and seed (HF too), the variants on 3 seeds
    assert plan["hf_teachers"] is None and plan["secondary_seeds"] is None
    assert plan["variant_seeds"] == 3 and len(plan["variants"]) == 4
    assert set(summary["headline"]) == set(DEFAULT_POLICIES)
    for name, row in summary["headline"].items():
        assert 0 <= row["efficacy"] <= 1, name
        if name != "BF":
            low, high = row["delta_efficacy"]["low"], row["delta_efficacy"]["high"]
            assert low <= row["delta_efficacy"]["mean"] <= high, name
    report = (STUDY / "adaptive_report.txt").read_text()
    assert "BF" in report and "95 %" in report
    assert (STUDY / "adaptive_figure.png").read_bytes()[:4] == b"\x89PNG"


REWRITE = "lfd-tutor adaptive --seeds 10 --out DIR, then copy (see tutor/assets/README.md)"


def bundled_runs() -> pd.DataFrame:
    return pd.read_csv(STUDY / "adaptive_runs.csv.gz")


def test_the_bundled_runs_hold_every_run_and_give_the_summary():
    runs, summary = bundled_runs(), json.loads((STUDY / "adaptive_summary.json").read_text())
    main = runs[runs.variant == "default"]
    # every arm: 36 teachers x 3 runs x 10 seeds; the variants: 2 arms x 3 seeds each
    assert main.groupby("policy").size().to_dict() == {p: 36 * 3 * 10 for p in DEFAULT_POLICIES}
    assert len(runs) - len(main) == 4 * 2 * 3 * 36 * 3
    for name, row in summary["headline"].items():
        mine = main[main.policy == name]
        assert np.isclose(mine.efficacy.mean(), row["efficacy"]), name
        assert np.isclose(mine.undemonstrated.mean(), row["undemonstrated_per_run"]), name


@pytest.mark.parametrize(
    ("policy", "seed", "teacher"), [("BF", 3, 7), ("DIS2", 9, 30), ("HF1", 5, 35)]
)
def test_bundled_runs_are_what_the_simulation_gives(policy, seed, teacher):
    runs = bundled_runs()
    mine = runs[(runs.variant == "default") & (runs.policy == policy) & (runs.seed == seed)
                & (runs.teacher == teacher)].sort_values("run")
    rows, _ = teach_policy(policy, seed, teacher, 3)
    fresh = pd.DataFrame(rows)
    for column in ("n_demos", "efficacy", "undemonstrated", "robot_seconds", "seconds"):
        assert np.allclose(fresh[column].astype(float), mine[column].astype(float)), (
            column, REWRITE)
