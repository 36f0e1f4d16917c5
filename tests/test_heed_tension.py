"""scripts/heed_tension.py: the README's argument that one heed cannot serve both
experiments rests on it, so it must run and keep its control (NF) fixed."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))

import heed_tension  # noqa: E402


def test_heed_moves_only_the_conditions_that_show_something(capsys):
    table, held = heed_tension.levels(seeds=1)
    assert set(table.heed) == {label for label, _, _ in heed_tension.HEEDS}
    assert set(table.condition) == {"NF", "VF", "VR", "RF", "BF", "SF"}
    wide = table.pivot_table(index=["experiment", "condition"], columns="heed", values="eta")
    bundled, heeding = (label for label, _, _ in heed_tension.HEEDS)
    # NF is shown nothing: heed changes no NF run in either experiment
    for experiment in (1, 2):
        assert wide.loc[(experiment, "NF"), bundled] == wide.loc[(experiment, "NF"), heeding]
    # the guided maze teachers are the ones it moves
    assert (wide.loc[1, heeding] != wide.loc[1, bundled]).any()
    # Experiment 2's conclusions are counted for each heed, one row per seed
    assert len(held) == len(heed_tension.HEEDS)
    assert {"BF best", "BF most undemonstrated", "all hold"} <= set(held.columns)
    heed_tension.report(table, held)
    out = capsys.readouterr().out
    assert out.count("Experiment") == 8 and "paper 23.5 %" in out
    assert "BF most undemonstrated: " in out and out.count(" of 1") >= 2 * 6
