"""The adaptive-feedback study bundled for notebook 06 is the full study, as the command
wrote it (``lfd-tutor adaptive --seeds 10 --out tutor/assets/adaptive``)."""

from __future__ import annotations

import json

from tutor.resources import asset
from tutor.study.adaptive import DEFAULT_POLICIES

STUDY = asset("adaptive")


def test_the_bundled_study_is_the_full_one_with_every_policy():
    summary = json.loads((STUDY / "adaptive_summary.json").read_text())
    plan = summary["plan"]
    assert plan["seeds"] == 10 and plan["n"] == 36 and plan["runs"] == 3
    assert not plan["quick"] and summary["missing"] == []
    assert set(summary["headline"]) == set(DEFAULT_POLICIES)
    for name, row in summary["headline"].items():
        assert 0 <= row["efficacy"] <= 1, name
        if name != "BF":
            low, high = row["delta_efficacy"]["low"], row["delta_efficacy"]["high"]
            assert low <= row["delta_efficacy"]["mean"] <= high, name
    report = (STUDY / "adaptive_report.txt").read_text()
    assert "BF" in report and "95 %" in report
    assert (STUDY / "adaptive_figure.png").read_bytes()[:4] == b"\x89PNG"
