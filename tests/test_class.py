"""``lfd-tutor class``: a class's saved runs read back, checked, scored and analysed.

The classes are written by simulated teachers (:mod:`tutor.study.simulated_class`) with
the tutor's own run files, so these tests read exactly what a workshop leaves behind.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tutor.errors import InvalidFileError, InvalidParameterError
from tutor.study.class_report import MIN_PER_CONDITION, analyse_class, format_class_report
from tutor.study.classroom import PROBLEMS, read_class
from tutor.study.cohort import run_experiment
from tutor.study.simulated_class import write_simulated_class

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def workshop(tmp_path_factory):
    """30 trainees of Experiment 1: 2 left a run unfinished, 3 files were spoiled."""
    folder = tmp_path_factory.mktemp("class") / "lfd-class"
    files = write_simulated_class(folder, 1, 30, seed=1, unfinished=2, damaged=3)
    return folder, files


def _cli(*args, cwd=None):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    return subprocess.run(
        [sys.executable, "-m", "tutor", "class", *map(str, args)],
        env=env,
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_cli_gives_the_statistics_and_lists_the_five_problem_files(workshop, tmp_path):
    folder, files = workshop
    proc = _cli(folder, "--experiment", "1", "--out", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    report = proc.stdout
    assert "This class: repeated-measures ANOVA F(2,48)" in report  # 25 whole trainees
    assert "Mauchly's sphericity" in report and "NF-VF: paired t" in report
    assert "Simulated, same size: repeated-measures ANOVA F(2,48)" in report
    assert "Files not counted (5):" in report
    summary = json.loads((tmp_path / "out" / "class.json").read_text())
    skipped = {s["file"]: s for s in summary["skipped"]}
    expected = {p.relative_to(folder).as_posix() for p in files["unfinished"] + files["damaged"]}
    assert set(skipped) == expected
    kinds = sorted(s["kind"] for s in skipped.values())
    assert kinds == sorted(
        ["unfinished", "unfinished", "unreadable", "not a run record", "cannot be replayed"]
    )
    for s in skipped.values():
        assert s["reason"] and s["file"] in report  # each is listed with its reason
        assert s["reason"] in report
    assert len(summary["trainees"]) == 30
    assert sum(t["complete"] for t in summary["trainees"]) == 25
    assert summary["n_runs_counted"] == 90 - 5
    assert summary["class"]["tested"] and summary["simulated"]["tested"]
    for name in ("class_runs.csv", "class_demos.csv", "class_files.csv", "class_report.txt",
                 "class_experiment1.png"):
        assert (tmp_path / "out" / name).stat().st_size > 0, name
    runs = pd.read_csv(tmp_path / "out" / "class_runs.csv")
    assert len(runs) == 85 and {"trainee", "trainee_key", "file", "eta"} <= set(runs.columns)


def test_a_class_replays_to_the_simulated_cohorts_numbers(tmp_path):
    """The class path (files -> replay -> rows) gives the cohort's rows for its teachers."""
    write_simulated_class(tmp_path, 1, 6, seed=0, workers=1)
    result = read_class(tmp_path, 1, workers=1)
    cohort = run_experiment(1, seed=0, n=6, workers=1, progress=False).runs
    cols = ["teacher", "condition", "n_demos", "efficacy", "eta", "errors", "undemonstrated",
            "ambiguous", "reached_target", "followed_rules"]
    mine = result.runs[cols].sort_values(["teacher", "condition"]).reset_index(drop=True)
    theirs = cohort[cols].sort_values(["teacher", "condition"]).reset_index(drop=True)
    pd.testing.assert_frame_equal(mine, theirs, check_dtype=False, check_categorical=False)


def test_a_zip_of_the_class_reads_the_same(workshop, tmp_path):
    folder, _ = workshop
    archive = tmp_path / "class.zip"
    with zipfile.ZipFile(archive, "w") as z:
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                z.write(path, Path("lfd-class") / path.relative_to(folder))
    from_zip = read_class(archive, 1)
    from_folder = read_class(folder, 1)
    assert [f.kind for f in from_zip.files] == [f.kind for f in from_folder.files]
    np.testing.assert_allclose(from_zip.runs.eta, from_folder.runs.eta)
    assert len(from_zip.not_counted) == 5


def test_duplicates_practice_other_experiment_and_hidden_files(tmp_path):
    write_simulated_class(tmp_path, 1, 3, seed=2, workers=1)
    home = sorted(p for p in tmp_path.iterdir())[0]
    shutil.copy(home / "NF.json", home / "NF-2.json")  # the tutor's "saved beside it" copy
    practice = json.loads((home / "VF.json").read_text())
    practice["practice"] = True
    (home / "practice_VF.json").write_text(json.dumps(practice))
    other = json.loads((home / "VR.json").read_text())
    other.update(experiment=2, task="pickplace", condition="BF")
    (home / "pickplace_BF_run1.json").write_text(json.dumps(other))
    (home / ".NF.lock").write_text("")
    (home / ".NF.json.tmp-123").write_text("{")
    (home / "notes.txt").write_text("not a run")
    os.mkfifo(home / "pipe.json")
    (home / "empty.json").write_bytes(b"")
    (home / "folder.json").mkdir()
    result = read_class(tmp_path, 1, workers=1)
    kinds = {f.file.split("/")[-1]: f.kind for f in result.files if f.file.startswith(home.name)}
    assert kinds == {
        "NF.json": "counted",
        "NF-2.json": "duplicate",
        "VF.json": "counted",
        "VR.json": "counted",
        "practice_VF.json": "practice",
        "pickplace_BF_run1.json": "other experiment",
        "pipe.json": "unreadable",
        "empty.json": "unreadable",
    }
    assert len(result.runs) == 9  # 3 trainees x NF, VF, VR, each once
    report = format_class_report(result, analyse_class(result))
    assert "1 files of Experiment 2 were set aside" in report
    assert "NF-2.json: duplicate" in report and "practice_VF.json: practice" in report


def test_a_class_too_small_for_the_tests_gets_descriptive_numbers(tmp_path):
    write_simulated_class(tmp_path, 1, 4, seed=3, workers=1, damaged=2)
    result = read_class(tmp_path, 1, workers=1)
    analysis = analyse_class(result)
    assert not analysis["class"]["tested"]
    assert f"at least {MIN_PER_CONDITION} trainees per condition" in analysis["class"]["why_not"]
    report = format_class_report(result, analysis)
    assert "This class: no test" in report and "they test nothing" in report
    assert analysis["descriptive"].loc["NF", "trainees"] == 4
    assert np.isfinite(analysis["descriptive"].loc["VR", "median eta"])


def test_experiment_2_class(tmp_path):
    write_simulated_class(tmp_path, 2, 8, seed=0, unfinished=1)
    result = read_class(tmp_path, 2)
    assert len(result.runs) == 8 * 3 - 1
    assert set(result.runs.run) == {1, 2, 3} and (result.runs.seconds > 0).all()
    analysis = analyse_class(result)
    assert not analysis["class"]["tested"]  # 2 trainees per condition
    assert [f.kind for f in result.not_counted] == ["unfinished"]
    report = format_class_report(result, analysis)
    assert "mean η (paper)" in report and "still to do: run 3" in report
    assert "Failures over all counted runs" in report


def test_an_empty_class_and_bad_sources(tmp_path):
    result = read_class(tmp_path, 1)
    assert result.runs.empty and result.files == []
    assert "nothing to analyse yet" in format_class_report(result, analyse_class(result))
    with pytest.raises(InvalidFileError, match="no folder or zip file"):
        read_class(tmp_path / "missing", 1)
    (tmp_path / "class.txt").write_text("x")
    with pytest.raises(InvalidFileError, match="neither a folder nor a zip"):
        read_class(tmp_path / "class.txt", 1)
    with pytest.raises(InvalidParameterError, match="experiment must be 1"):
        read_class(tmp_path, 3)
    with pytest.raises(InvalidParameterError, match="workers"):
        read_class(tmp_path, 1, workers=0)


def test_cli_refuses_a_missing_folder_in_one_line(tmp_path):
    proc = _cli(tmp_path / "nowhere", "--experiment", "1")
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "InvalidFileError" in proc.stderr and "no folder or zip file" in proc.stderr


def test_problem_kinds_are_named_in_plain_words():
    assert set(PROBLEMS) == {
        "unreadable", "not a run record", "cannot be replayed", "duplicate", "practice",
        "unfinished", "no demonstrations",
    }


def test_the_class_plan_lists_who_is_missing_and_who_taught_another_condition(tmp_path):
    write_simulated_class(tmp_path, 2, 8, seed=4)
    names = [f"Trainee {i:02d}" for i in range(1, 9)]
    # trainees 1-2 taught NF (teacher i is in condition i // 2); the plan says RF for one
    taught = ["NF", "NF", "RF", "RF", "BF", "BF", "SF", "SF"]
    lines = ["trainee,condition", "Trainee 01,RF",
             *[f"{n},{c}" for n, c in zip(names[1:], taught[1:], strict=True)],
             "Late Comer,", "Absent Student,BF"]
    (tmp_path / "plan.csv").write_text("\n".join(lines) + "\n")
    result = read_class(tmp_path, 2)
    table = result.trainees.set_index("trainee")
    assert table.loc["Late Comer", "missing"] == "no run file yet"
    assert table.loc["Absent Student", "missing"] == "no run file yet"
    assert "the class plan assigns RF" in table.loc["Trainee 01", "missing"]
    assert table.loc["Trainee 02", "complete"]
    assert len(result.complete_runs) == 7 * 3 and len(result.runs) == 8 * 3
    assert "plan.csv" not in {f.file for f in result.files}
    report = format_class_report(result, analyse_class(result))
    assert "Absent Student" in report and "no run file yet" in report


def test_a_refresh_reads_only_the_files_that_changed(tmp_path, monkeypatch):
    write_simulated_class(tmp_path, 1, 4, seed=5, workers=1)
    cache: dict = {}
    first = read_class(tmp_path, 1, workers=1, cache=cache)
    from tutor.study import classroom

    seen = []
    real_read, real_replay = classroom._read, classroom._replay
    monkeypatch.setattr(classroom, "_read", lambda item: seen.append(item[2]) or real_read(item))
    monkeypatch.setattr(
        classroom, "_replay", lambda item: seen.append(item[0]) or real_replay(item)
    )
    again = read_class(tmp_path, 1, workers=1, cache=cache)
    assert seen == [] and again.runs.equals(first.runs)
    changed = sorted(tmp_path.glob("*/VF.json"))[0]
    data = json.loads(changed.read_text())
    data["attempts"][-1]["finished"] = False
    data["events"] = [e for e in data["events"] if e["kind"] != "finish"]  # never finished
    changed.write_text(json.dumps(data))
    label = changed.relative_to(tmp_path).as_posix()
    third = read_class(tmp_path, 1, workers=1, cache=cache)
    assert seen == [label, label]  # read and replayed once, alone
    assert [f.kind for f in third.files if f.file == label] == ["unfinished"]
    assert len(third.runs) == len(first.runs) - 1


def test_a_condition_beyond_the_paper_is_compared_with_its_own_not_tested_with_the_paper(
    tmp_path,
):
    """VA (Experiment 1, beyond the paper) runs are counted and described; the paper's
    repeated-measures ANOVA stays on NF, VF and VR, and VA is compared with VF alone."""
    write_simulated_class(tmp_path, 1, 4, seed=0, workers=1, conditions=("NF", "VF", "VR", "VA"))
    result = read_class(tmp_path, 1, workers=1)
    assert (result.runs.condition == "VA").sum() == 4 and result.trainees.complete.all()
    analysis = analyse_class(result)
    assert list(analysis["descriptive"].index) == ["NF", "VF", "VR", "VA"]
    assert analysis["class"]["tested"]
    assert analysis["class"]["stats"]["anova"]["ddof1"] == 2  # three conditions, not four
    assert set(analysis["class"]["stats"]["medians"]) == {"NF", "VF", "VR"}
    row = analysis["beyond"].loc["VA"]
    assert (row["compared with"], row["test"], row["trainees"]) == ("VF", "paired t", 4)
    va = result.runs[result.runs.condition == "VA"]
    assert row["median eta"] == pytest.approx(va.eta.median())
