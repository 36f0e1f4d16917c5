"""scripts/calibration_candidates.py: the README's answer to "is it the steadiness check
that keeps the model from the paper?" rests on it."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))

import calibration_candidates  # noqa: E402

from tutor.errors import InvalidFileError  # noqa: E402
from tutor.study import calibration  # noqa: E402


def test_every_candidate_runs_both_experiments_and_is_reported(capsys):
    table = calibration_candidates.candidates_table(None, seeds=1, first_seed=100,
                                                    sizes=(3, 8))
    refined = calibration.load()[0].refined
    assert len(table) == len(refined)  # one row per candidate for the one seed
    # the unsteady candidates are run too, and marked; exactly one is the bundled point
    assert set(table.steady) == {True, False}
    assert table.bundled.sum() == 1 and bool(table.loc[table.bundled, "steady"].iloc[0])
    assert {"E1 NF<VR", "E1 all hold", "E2 BF most undemonstrated", "E2 all hold"} <= set(
        table.columns
    )
    assert {"E1 eta VF", "E2 eta BF"} <= set(table.columns)
    assert table[["E1 eta NF", "E2 eta NF"]].notna().all().all()
    calibration_candidates.report(table)
    out = capsys.readouterr().out
    assert "seeds (of 1) in which each conclusion holds" in out and "E2 eta SF" in out


def test_a_folder_without_a_calibration_is_a_named_error(tmp_path, capsys):
    with pytest.raises(InvalidFileError):
        calibration_candidates.candidates_table(tmp_path, seeds=1, first_seed=0)
    with pytest.raises(SystemExit) as stop:
        calibration_candidates.main(["--calibration", str(tmp_path)])
    assert stop.value.code == 2
    assert "does not hold a calibration" in capsys.readouterr().err
