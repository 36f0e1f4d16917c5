"""Issue 19 (trust), the educator's side: run ids, name clashes, crashes, caps, CSVs."""

from __future__ import annotations

import json
import uuid

import pytest

from tutor.errors import InvalidFileError
from tutor.framework.record import RunRecord, Trainee
from tutor.runtime import trainee_key
from tutor.study.class_report import analyse_class, format_class_report
from tutor.study.classroom import read_class
from tutor.study.simulated_class import write_simulated_class


def _rename_all(folder, name="Ann"):
    """Every run file under ``folder`` as if its trainee had typed ``name``."""
    for path in sorted(folder.rglob("*.json")):
        data = json.loads(path.read_text())
        data["trainee"] = {"name": name, "key": trainee_key(name)}
        path.write_text(json.dumps(data))


# ---------------------------------------------------------------- run ids


def test_a_new_record_has_a_run_id_kept_through_changes_and_files():
    rec = RunRecord.new(1, "maze", "VF", Trainee.from_name("Zoë"))
    assert len(rec.run_id) == 32 and int(rec.run_id, 16) >= 0
    again = RunRecord.from_dict(rec.to_dict())
    assert again == rec and again.run_id == rec.run_id
    assert rec.to_dict()["run_id"] == rec.run_id
    assert RunRecord.new(1, "maze", "VF", rec.trainee).run_id != rec.run_id
    attempt = rec.current
    assert rec.with_current(attempt).run_id == rec.run_id
    event = rec.events[0]
    assert rec.with_new_attempt(attempt, "reset", event).run_id == rec.run_id


def test_run_id_is_read_checked_and_optional():
    rec = RunRecord.new(1, "maze", "VF", Trainee.from_name("Zoë"))
    data = rec.to_dict()
    canonical = str(uuid.UUID(rec.run_id))
    assert RunRecord.from_dict({**data, "run_id": canonical}).run_id == rec.run_id
    old = {k: v for k, v in data.items() if k != "run_id"}
    assert RunRecord.from_dict(old).run_id is None
    for bad in ("xyz", 12, "0" * 31, True):
        with pytest.raises(InvalidFileError, match="run_id"):
            RunRecord.from_dict({**data, "run_id": bad})


def test_a_simulated_class_file_on_disk_holds_its_run_id(tmp_path):
    write_simulated_class(tmp_path, 1, 3, seed=0, workers=1)
    ids = {json.loads(p.read_text())["run_id"] for p in tmp_path.rglob("*.json")}
    assert len(ids) == 9 and None not in ids


# ---------------------------------------------------------------- same name, other people


def test_six_trainees_of_one_name_in_six_folders_count_as_six(tmp_path):
    write_simulated_class(tmp_path, 1, 6, seed=3, workers=1)
    _rename_all(tmp_path)
    result = read_class(tmp_path, 1, workers=1)
    assert [f.kind for f in result.files] == ["counted"] * 18
    assert len(result.trainees) == 6
    assert result.runs.trainee_key.nunique() == 6 and result.runs.teacher.nunique() == 6
    assert len(result.complete_runs) == 18
    assert len(result.name_clashes) == 18
    stats = analyse_class(result)
    report = format_class_report(result, stats)
    assert "duplicate" not in report
    assert "Name clash: 1 name(s) (Ann)" in report


def test_a_copied_file_is_a_duplicate_by_its_run_id(tmp_path):
    write_simulated_class(tmp_path, 1, 3, seed=3, workers=1)
    a, b, _ = sorted(p for p in tmp_path.iterdir() if p.is_dir())
    (b / "copy-of-a-NF.json").write_text((a / "NF.json").read_text())
    result = read_class(tmp_path, 1, workers=1)
    kinds = {f.file: f.kind for f in result.files}
    assert kinds[f"{b.name}/copy-of-a-NF.json"] == "duplicate"
    assert len(result.trainees) == 3 and not result.name_clashes


def test_old_records_without_a_run_id_are_judged_as_before_and_said(tmp_path):
    write_simulated_class(tmp_path, 1, 3, seed=3, workers=1)
    for path in tmp_path.rglob("*.json"):
        data = json.loads(path.read_text())
        data.pop("run_id")
        path.write_text(json.dumps(data))
    result = read_class(tmp_path, 1, workers=1)
    assert result.old_runs == 9
    assert "9 old runs without a run id" in format_class_report(result, analyse_class(result))


# ---------------------------------------------------------------- spreadsheets and the board


def test_csv_cells_that_could_start_a_formula_are_escaped_numbers_stay(tmp_path):
    import pandas as pd

    from tutor.study.class_report import save_class

    write_simulated_class(tmp_path / "class", 1, 3, seed=3, workers=1)
    _rename_all(tmp_path / "class", "=HYPERLINK(1)")
    result = read_class(tmp_path / "class", 1, workers=1)
    paths = save_class(result, analyse_class(result), tmp_path / "out", figures=False)
    for kind in ("runs", "demos", "files"):
        text = paths[kind].read_text()
        assert "'=HYPERLINK(1)" in text and ",=HYPERLINK" not in text, kind
    runs = pd.read_csv(paths["runs"])
    assert pd.api.types.is_numeric_dtype(runs.eta)


def test_spreadsheet_safe_escapes_text_only():
    from tutor.study.class_report import spreadsheet_safe

    for text in ("=1", "+1", "-1", "@x", "\tx", "\rx"):
        assert spreadsheet_safe(text) == "'" + text
    assert spreadsheet_safe(-1.5) == -1.5 and spreadsheet_safe("Ann") == "Ann"


@pytest.mark.parametrize(
    "options",
    [
        {"experiment": 3},
        {"experiment": True},
        {"refresh_seconds": float("nan")},
        {"refresh_seconds": 5},
        {"refresh_seconds": 30.5},
        {"refresh_seconds": "30"},
    ],
)
def test_the_dashboard_refuses_bad_options_naming_the_allowed(tmp_path, options):
    from tutor.errors import InvalidParameterError
    from tutor.study.dashboard import class_dashboard

    with pytest.raises(InvalidParameterError, match="must be"):
        class_dashboard(tmp_path, **options)


# ---------------------------------------------------------------- crashes


def test_a_finished_pickplace_run_without_demonstrations_is_not_counted_with_a_reason(tmp_path):
    write_simulated_class(tmp_path, 2, 8, seed=0, workers=1)
    path = sorted(tmp_path.rglob("*.json"))[0]
    data = json.loads(path.read_text())
    data["attempts"][-1].update(demos=[], undone=[], tests=[])
    data["events"] = [e for e in data["events"] if e["kind"] in ("start", "finish")]
    for event in data["events"]:
        event["n_demos"] = 0
    path.write_text(json.dumps(data))
    result = read_class(tmp_path, 2, workers=1)
    empty = [f for f in result.files if f.file == path.relative_to(tmp_path).as_posix()][0]
    assert empty.kind == "no demonstrations" and "η" in empty.reason
    format_class_report(result, analyse_class(result))


def test_runs_that_all_hold_the_same_demonstrations_are_reported_not_crashed(tmp_path):
    from tutor.study.dashboard import ClassDashboard

    write_simulated_class(tmp_path, 1, 3, seed=0, workers=1)
    files = sorted(tmp_path.rglob("*.json"))
    source = json.loads(files[0].read_text())
    for path in files:
        data = json.loads(path.read_text())
        data.update(attempts=source["attempts"], events=source["events"])
        path.write_text(json.dumps(data))
    result = read_class(tmp_path, 1, workers=1)
    analysis = analyse_class(result)
    assert not analysis["class"]["tested"]
    assert "the same η" in format_class_report(result, analysis)
    board = ClassDashboard(tmp_path, 1)
    assert "the same η" in board.tests.value


# ---------------------------------------------------------------- workers


def test_too_many_workers_are_clamped_with_a_message(monkeypatch, capsys):
    import resource

    from tutor import workers

    monkeypatch.setattr(resource, "getrlimit", lambda _: (3, 3))
    assert workers.max_workers() == min(2, workers._cores())
    pool = workers.process_pool(10_000)
    try:
        assert pool._max_workers == workers.max_workers()
    finally:
        pool.shutdown()
    assert "not 10000" in capsys.readouterr().err


# ---------------------------------------------------------------- the dashboard's words


def test_the_dashboard_says_1_trainee_and_the_simulated_class_count_it_writes(
    tmp_path, monkeypatch
):
    import shutil

    from tutor.study import simulated_class
    from tutor.study.dashboard import ClassDashboard

    write_simulated_class(tmp_path, 1, 3, seed=0, workers=1)
    for folder in sorted(p for p in tmp_path.iterdir() if p.is_dir())[1:]:
        shutil.rmtree(folder)
    board = ClassDashboard(tmp_path, 1)
    assert "<b>1 trainee</b>" in board.status.value and "1 trainees" not in board.status.value
    said = []

    def fake(folder, experiment, n, **_):
        said.append((board.status.value, n))
        raise SystemExit  # stop before the slow writing

    monkeypatch.setattr(simulated_class, "write_simulated_class", fake)
    board.experiment.value = 2
    with pytest.raises(SystemExit):
        board.rehearse()
    status, n = said[0]
    assert n == 36 and "(36 trainees)" in status


def test_a_link_to_a_run_outside_the_class_folder_is_not_counted(tmp_path):
    write_simulated_class(tmp_path / "class", 1, 3, seed=0, workers=1)
    write_simulated_class(tmp_path / "elsewhere", 1, 3, seed=5, workers=1)
    outside = sorted((tmp_path / "elsewhere").rglob("NF.json"))[0]
    home = sorted(p for p in (tmp_path / "class").iterdir() if p.is_dir())[0]
    (home / "linked.json").symlink_to(outside)
    result = read_class(tmp_path / "class", 1, workers=1)
    linked = [f for f in result.files if f.file.endswith("linked.json")][0]
    assert not linked.counted and "outside the class folder" in linked.reason
    assert len(result.runs) == 9
