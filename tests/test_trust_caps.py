"""Issue 19 (trust): size and count caps with a clear message and progress, and zips in a
class folder read as the trainees' hand-ins."""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
import time
import uuid
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tutor import fileio, limits
from tutor.demofiles import load_demos, save_demos
from tutor.errors import InvalidFileError, InvalidParameterError, LimitError
from tutor.framework.record import Event, RunRecord, Trainee
from tutor.runtime import trainee_key
from tutor.study.classroom import read_class
from tutor.study.simulated_class import write_simulated_class

ROOT = Path(__file__).resolve().parents[1]


# ---------------------------------------------------------------- one place, stated


def test_every_cap_is_defined_in_tutor_limits_only():
    """No module but tutor/limits.py assigns a cap's name (the others import it)."""
    names = set(limits.__all__)
    owners = {}
    for path in sorted((ROOT / "tutor").rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            targets = node.targets if isinstance(node, ast.Assign) else (
                [node.target] if isinstance(node, ast.AnnAssign) else []
            )
            for target in targets:
                if isinstance(target, ast.Name) and target.id in names:
                    owners.setdefault(target.id, []).append(path.relative_to(ROOT).as_posix())
    assert owners == {name: ["tutor/limits.py"] for name in names}
    from tutor import payloads
    from tutor.study import limits as study_limits

    assert fileio.MAX_FILE_BYTES is limits.MAX_FILE_BYTES
    assert payloads.MAX_UPLOAD_BYTES is limits.MAX_UPLOAD_BYTES  # the upload's check
    assert study_limits.MAX_TEACHERS is limits.MAX_TEACHERS


def test_the_readme_states_the_caps():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("### Limits") :]
    section = section[: section.index("\n#")]
    mb = limits.MB
    for shown in (
        f"| {limits.MAX_CLASS_FILES} |",
        f"| {limits.MAX_RUN_FILE_BYTES // mb} MB",
        f"| {limits.MAX_ZIP_MEMBERS} |",
        f"| {limits.MAX_ZIP_BYTES // mb} MB |",
        f"at most {limits.MAX_ZIP_RATIO} times",
        f"above {limits.ZIP_RATIO_FROM_BYTES // mb} MB",
        f"| {limits.MAX_DEMOS_PER_RUN} (",
        f"| {limits.MAX_SAMPLES_PER_DEMO} (",
        f"| {limits.MAX_SAMPLES_PER_FILE:,} |".replace(",", " "),
        f"| {limits.MAX_FILE_BYTES // mb} MB |",
        f"| {limits.MAX_UPLOAD_BYTES // mb} MB |",
    ):
        assert shown in section, shown
    assert "tutor/limits.py" in section and "LimitError" in section


def test_a_limit_error_is_an_invalid_file_error():
    """Every handler of a bad file (the widgets, the class reader, the command line)
    handles a file over a cap too."""
    assert issubclass(LimitError, InvalidFileError)


# ---------------------------------------------------------------- demonstration files


def _csv(path, n_demos: int, rows: int) -> Path:
    line = "{d},{t},0.1,0.2\n"
    body = "".join(line.format(d=d, t=k * 0.01) for d in range(n_demos) for k in range(rows))
    path.write_text("demo,t,x,y\n" + body)
    return path


@pytest.mark.parametrize(
    "n_demos, rows, words",
    [
        (1000, 1000, "more than 100 demonstrations"),  # 10^6 rows, 1000 demos
        (1, 10**6, "more than 5000 samples"),  # 10^6 rows, one demo
        (25, 4001, "more than 100000 samples"),  # each demo within its cap
    ],
)
def test_a_csv_of_a_million_rows_is_refused_in_seconds(tmp_path, n_demos, rows, words):
    path = _csv(tmp_path / "big.csv", n_demos, rows)
    started = time.perf_counter()
    with pytest.raises(LimitError, match=words):
        load_demos(path)
    assert time.perf_counter() - started < 10


def test_a_csv_just_within_the_caps_loads(tmp_path):
    path = _csv(tmp_path / "ok.csv", 100, 2)
    assert len(load_demos(path)) == limits.MAX_DEMOS_PER_RUN
    path = _csv(tmp_path / "long.csv", 1, limits.MAX_SAMPLES_PER_DEMO)
    assert load_demos(path)[0].shape == (limits.MAX_SAMPLES_PER_DEMO, 3)


def test_a_json_demo_file_over_the_caps_is_refused(tmp_path):
    demo = [[0.0, 0.1, 0.2], [1.0, 0.1, 0.2]]
    save_demos(tmp_path / "many.json", [demo] * 101)
    with pytest.raises(LimitError, match="more than 100 demonstrations"):
        load_demos(tmp_path / "many.json")
    long = np.column_stack([np.arange(5001.0), np.zeros(5001), np.zeros(5001)])
    save_demos(tmp_path / "long.json", [demo, long])
    with pytest.raises(LimitError, match="demo 2 has more than 5000 samples"):
        load_demos(tmp_path / "long.json")
    save_demos(tmp_path / "ok.json", [demo] * 100)
    assert len(load_demos(tmp_path / "ok.json")) == 100


# ---------------------------------------------------------------- uploads and runs


def _upload(name: str, data: bytes) -> dict:
    return {"new": ({"name": name, "content": memoryview(data)},)}


def test_an_upload_over_its_cap_is_refused_unwritten(tmp_path):
    from tutor.views.maze_app import MazeTutor
    from tutor.views.uploads import on_upload

    app = MazeTutor("VF", run_file=tmp_path / "vf.json")
    before = sorted(Path(os.environ.get("TMPDIR", "/tmp")).glob("lfd-upload-*"))
    on_upload(app.load, app.tell)(_upload("big.csv", b"x" * (limits.MAX_UPLOAD_BYTES + 1)))
    assert "larger than the 10 MB an upload can be" in app.message
    assert app.session.n_demos == 0
    assert sorted(Path(os.environ.get("TMPDIR", "/tmp")).glob("lfd-upload-*")) == before


def test_a_run_takes_no_demo_beyond_its_cap(monkeypatch, tmp_path):
    """The cap, lowered to 3 here so that the test fits quickly, is the run's own."""
    from tutor.demofiles import bundled_demos
    from tutor.framework import run as run_module
    from tutor.tasks.maze_run import MazeRun
    from tutor.views.maze_app import MazeTutor

    assert run_module.MAX_DEMOS_PER_RUN is limits.MAX_DEMOS_PER_RUN
    monkeypatch.setattr(run_module, "MAX_DEMOS_PER_RUN", 3)
    demos = list(bundled_demos("maze_good"))
    app = MazeTutor("VF", run_file=tmp_path / "vf.json")
    run = app.run
    for demo in demos[:3]:
        run.add_demo(demo)
    with pytest.raises(LimitError, match="holds 3 demonstrations and cannot take one more"):
        run.add_demo(demos[3])
    assert run.n_demos == 3 and run.attempt.n_demos == 3
    record = run.record
    fresh = MazeRun.new("VF", app.task)
    fresh.add_demo(demos[0])
    with pytest.raises(LimitError, match="cannot take 3 more"):
        fresh.add_demos([(d, {}) for d in demos[1:4]])
    assert fresh.n_demos == 1  # all or nothing
    monkeypatch.setattr(run_module, "MAX_DEMOS_PER_RUN", 2)
    with pytest.raises(LimitError, match="holds 3 demonstrations, more than the 2"):
        MazeRun.from_record(app.task, record)


def test_the_tutor_says_so_when_a_file_would_take_the_run_over_its_cap(tmp_path):
    from tutor.views.maze_app import MazeTutor

    demo = [[0.0, 0.1, 0.2], [1.0, 0.1, 0.2]]
    path = save_demos(tmp_path / "many.json", [demo] * 101)
    app = MazeTutor("VF", run_file=tmp_path / "vf.json")
    app.load(path)
    assert "Nothing was loaded" in app.message and "more than 100" in app.message
    assert app.session.n_demos == 0


def test_simulated_teachers_stay_within_the_run_cap():
    from tutor.teachers.traits import Population

    Population(patience_high=limits.MAX_DEMOS_PER_RUN)
    with pytest.raises(InvalidParameterError, match="patience_high must be at most 100"):
        Population(patience_high=limits.MAX_DEMOS_PER_RUN + 1)


# ---------------------------------------------------------------- a class: caps


@pytest.fixture(scope="module")
def small_class(tmp_path_factory):
    """3 Experiment 1 trainees (9 runs), and what their folder reads as."""
    folder = tmp_path_factory.mktemp("small") / "class"
    write_simulated_class(folder, 1, 3, seed=4, workers=1)
    return folder, read_class(folder, 1, workers=1)


def _copy(folder: Path, to: Path) -> Path:
    shutil.copytree(folder, to)
    return to


def test_a_class_of_too_many_run_files_is_refused_before_reading_them(tmp_path):
    for i in range(limits.MAX_CLASS_FILES + 1):
        sub = tmp_path / f"t{i // 100}"
        sub.mkdir(exist_ok=True)
        (sub / f"r{i}.json").write_text("{}")
    started = time.perf_counter()
    with pytest.raises(LimitError, match="more than 2000 run files"):
        read_class(tmp_path, 1, workers=1)
    assert time.perf_counter() - started < 20


def test_a_class_zip_of_10000_entries_is_refused_at_once(tmp_path):
    archive = tmp_path / "class.zip"
    with zipfile.ZipFile(archive, "w") as z:
        for i in range(10_000):
            z.writestr(f"t{i // 100}/r{i}.json", "{}")
    started = time.perf_counter()
    with pytest.raises(LimitError, match="has 10000 entries, more than the 5000"):
        read_class(archive, 1, workers=1)
    assert time.perf_counter() - started < 5


def test_a_run_file_too_large_or_of_too_many_demos_is_not_counted(small_class, tmp_path):
    folder = _copy(small_class[0], tmp_path / "class")
    big = folder / "big" / "NF.json"
    big.parent.mkdir()
    with open(big, "wb") as fh:
        fh.truncate(limits.MAX_RUN_FILE_BYTES + 1)
    one = RunRecord.from_dict(json.loads(sorted(folder.glob("*/VF.json"))[0].read_text()))
    n, at = limits.MAX_DEMOS_PER_RUN + 1, one.created
    many = replace(
        one,
        trainee=Trainee.from_name("Many"),
        attempts=(replace(one.current, demos=(one.current.demos[0],) * n),),
        events=(
            Event("start", at, 0, 0),
            *(Event("add", at, 0, i) for i in range(1, n + 1)),
            Event("finish", at, 0, n),
        ),
        run_id=uuid.uuid4().hex,
    )
    (folder / "many").mkdir()
    (folder / "many" / "VF.json").write_text(json.dumps(many.to_dict()))
    started = time.perf_counter()
    result = read_class(folder, 1, workers=1)
    kinds = {f.file: (f.kind, f.reason) for f in result.not_counted}
    assert kinds["big/NF.json"][0] == "unreadable" and "larger than the 5 MB" in kinds[
        "big/NF.json"
    ][1]
    kind, reason = kinds["many/VF.json"]
    assert kind == "cannot be replayed" and "101 demonstrations, more than the 100" in reason
    assert len(result.runs) == 9
    assert time.perf_counter() - started < 120


def _run_zip(path: Path, folder: Path, top: str = "") -> Path:
    """A trainee's hand-in: their run files, at the top of the zip or under ``top``."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for f in sorted(folder.glob("*.json")):
            z.write(f, f"{top}{f.name}")
    return path


def test_zip_bombs_and_zips_of_too_much_are_not_counted(small_class, tmp_path):
    folder = tmp_path / "zips"
    folder.mkdir()
    trainee = sorted(p for p in small_class[0].iterdir() if p.is_dir())[0]
    _run_zip(folder / "ann.zip", trainee)
    with zipfile.ZipFile(folder / "bomb.zip", "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("NF.json", b" " * (4 * limits.MB))  # packs to a few kB
    with zipfile.ZipFile(folder / "many.zip", "w") as z:
        for i in range(limits.MAX_ZIP_MEMBERS + 1):
            z.writestr(f"r{i}.txt", "")
    with zipfile.ZipFile(folder / "huge.zip", "w", zipfile.ZIP_DEFLATED) as z:
        for i in range(6):
            with z.open(f"part{i}.bin", "w", force_zip64=True) as part:
                for _ in range(90):
                    part.write(bytes(limits.MB))
    result = read_class(folder, 1, workers=1)
    reasons = {f.file: f.reason for f in result.not_counted}
    assert "more than 100 times its packed size" in reasons["bomb.zip/NF.json"]
    assert "more than the 5000 a zip may have" in reasons["many.zip"]
    assert "more than the 500 MB a zip may unpack to" in reasons["huge.zip"]
    assert [f.kind for f in result.files if f.file.startswith("ann.zip/")] == ["counted"] * 3
    assert len(result.runs) == 3


def test_a_class_may_say_how_far_it_has_read(small_class, capsys):
    folder, _ = small_class
    seen = []
    read_class(folder, 1, workers=1, progress=lambda done, total: seen.append((done, total)))
    assert seen == [(i, 9) for i in range(1, 10)]
    read_class(folder, 1, workers=1)  # headless here: no bar unless asked
    assert "Reading the class" not in capsys.readouterr().err
    read_class(folder, 1, workers=1, progress=True)
    err = capsys.readouterr().err
    assert "Reading the class" in err and "9/9" in err
    with pytest.raises(InvalidParameterError, match="progress must be"):
        read_class(folder, 1, progress="yes")


def test_the_dashboard_says_how_far_it_has_read(small_class):
    from tutor.study.dashboard import ClassDashboard

    board = ClassDashboard(small_class[0], 1)
    said = []
    board.status.observe(lambda change: said.append(change["new"]), "value")
    board._cache.clear()
    board.refresh()
    assert any("Reading the class: 9 of 9 files" in s for s in said)
    assert "9 runs" in board.status.value


# ---------------------------------------------------------------- zips as hand-ins


@pytest.fixture(scope="module")
def hand_ins(small_class, tmp_path_factory):
    """The small class handed in as one zip per trainee: flat, or with a top folder."""
    folder, _ = small_class
    zips = tmp_path_factory.mktemp("handins") / "class"
    zips.mkdir()
    for i, trainee in enumerate(sorted(p for p in folder.iterdir() if p.is_dir())):
        _run_zip(zips / f"{trainee.name}.zip", trainee, top=f"{trainee.name}/" if i else "")
    return zips


def test_a_class_folder_of_per_trainee_zips_reads_as_their_folders(small_class, hand_ins):
    _, from_folders = small_class
    result = read_class(hand_ins, 1, workers=1)
    assert [f.kind for f in result.files] == ["counted"] * 9
    assert len(result.trainees) == 3 and len(result.complete_runs) == 9
    np.testing.assert_allclose(
        sorted(result.runs.eta), sorted(from_folders.runs.eta), rtol=0, atol=0
    )
    labels = sorted(f.file for f in result.files)
    first = sorted(p.name for p in hand_ins.iterdir())[0]
    assert labels[0] == f"{first}/NF.json"  # flat: the zip is the folder
    assert all(lab.count("/") == 2 for lab in labels[3:])  # its top folder inside


def test_same_name_trainees_in_different_zips_count_apart(small_class, tmp_path):
    folder = _copy(small_class[0], tmp_path / "same")
    for path in folder.rglob("*.json"):
        data = json.loads(path.read_text())
        data["trainee"] = {"name": "Ann", "key": trainee_key("Ann")}
        path.write_text(json.dumps(data))
    zips = tmp_path / "zips"
    zips.mkdir()
    for i, trainee in enumerate(sorted(p for p in folder.iterdir() if p.is_dir())):
        _run_zip(zips / f"hand-in-{i}.zip", trainee)
    result = read_class(zips, 1, workers=1)
    assert [f.kind for f in result.files] == ["counted"] * 9
    assert result.runs.trainee_key.nunique() == 3 and len(result.name_clashes) == 9


def test_trainees_zips_inside_a_class_zip_read_the_same(small_class, hand_ins, tmp_path):
    archive = tmp_path / "class.zip"
    with zipfile.ZipFile(archive, "w") as z:
        for path in sorted(hand_ins.iterdir()):
            z.write(path, f"hand-ins/{path.name}")
    result = read_class(archive, 1, workers=1)
    assert [f.kind for f in result.files] == ["counted"] * 9
    np.testing.assert_allclose(sorted(result.runs.eta), sorted(small_class[1].runs.eta))
    assert all(f.file.startswith("hand-ins/") and ".zip/" in f.file for f in result.files)


def _hostile_zip(path: Path, run: bytes) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("../../escaped.json", run)
        z.writestr("/etc/absolute.json", run)
        z.writestr("..\\windows.json", run)
        link = zipfile.ZipInfo("link.json")
        link.external_attr = 0o120777 << 16
        z.writestr(link, "/etc/passwd")
        z.writestr("bz.json", run, compress_type=zipfile.ZIP_BZIP2)
        z.writestr("bell\x07.json", run)
        z.writestr("inner.zip", b"PK\x05\x06" + bytes(18))
        z.writestr("secret.json", run)
        z.writestr("NF.json", run)  # the one good entry
    return _mark_encrypted(path, b"secret.json")


def _mark_encrypted(path: Path, name: bytes) -> Path:
    """Set the "encrypted" flag of entry ``name`` in the zip's directory (zipfile writes
    no encrypted entries)."""
    data = bytearray(path.read_bytes())
    at = data.find(b"PK\x01\x02")
    while at >= 0:
        length = int.from_bytes(data[at + 28 : at + 30], "little")
        if data[at + 46 : at + 46 + length] == name:
            data[at + 8] |= 0x1
        at = data.find(b"PK\x01\x02", at + 4)
    path.write_bytes(bytes(data))
    return path


def test_hostile_zip_entries_are_refused_unread_and_listed(small_class, tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    run = sorted(small_class[0].glob("*/NF.json"))[0].read_bytes()
    _hostile_zip(folder / "eve.zip", run)
    (folder / "notazip.zip").write_text("not a zip")
    outside = tmp_path / "outside.zip"
    _run_zip(outside, sorted(p for p in small_class[0].iterdir() if p.is_dir())[1])
    (folder / "away.zip").symlink_to(outside)
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    result = read_class(folder, 1, workers=1)
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before
    assert not list(Path("/etc").glob("absolute.json"))
    reasons = {f.file: f.reason for f in result.not_counted}
    why = {
        "eve.zip/../../escaped.json": "leads out of the zip's folder",
        "eve.zip//etc/absolute.json": "leads out of the zip's folder",
        "eve.zip/..\\windows.json": "leads out of the zip's folder",
        "eve.zip/link.json": "links are not followed",
        "eve.zip/bz.json": "only stored or deflate",
        "eve.zip/bell?.json": "control characters",
        "eve.zip/inner.zip": "a zip inside a trainee's zip is not opened",
        "eve.zip/secret.json": "encrypted",
        "notazip.zip": "not a zip file that can be read",
        "away.zip": "links out are not followed",
    }
    for label, words in why.items():
        assert words in reasons[label], (label, reasons.get(label))
    assert set(reasons) == set(why)
    assert [f.file for f in result.files if f.counted] == ["eve.zip/NF.json"]


def test_a_refresh_reads_a_trainees_zip_again_only_when_it_changed(hand_ins, tmp_path, monkeypatch):
    folder = _copy(hand_ins, tmp_path / "class")
    cache: dict = {}
    first = read_class(folder, 1, workers=1, cache=cache)
    from tutor.study import classroom

    seen = []
    real_read = classroom._read
    monkeypatch.setattr(classroom, "_read", lambda item: seen.append(item[2]) or real_read(item))
    again = read_class(folder, 1, workers=1, cache=cache)
    assert seen == [] and again.runs.equals(first.runs)
    changed = sorted(folder.glob("*.zip"))[0]
    with zipfile.ZipFile(changed) as z:
        kept = {name: z.read(name) for name in z.namelist()}
    with zipfile.ZipFile(changed, "w") as z:
        for name, data in kept.items():
            z.writestr(name, data)
    os.utime(changed, ns=(time.time_ns() + 10**9,) * 2)
    read_class(folder, 1, workers=1, cache=cache)
    assert sorted(seen) == sorted(f"{changed.name}/{name}" for name in kept)


def test_the_dashboard_and_the_command_line_read_a_folder_of_zips(hand_ins, tmp_path):
    from tutor.study.dashboard import ClassDashboard

    board = ClassDashboard(hand_ins, 1)
    assert len(board.result.runs) == 9 and "9 runs" in board.status.value
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    proc = subprocess.run(
        [sys.executable, "-m", "tutor", "class", str(hand_ins), "--experiment", "1",
         "--workers", "1", "--out", str(tmp_path / "out"), "--no-figures"],
        env=env, capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr and "Reading the class" not in proc.stderr
    summary = json.loads((tmp_path / "out" / "class.json").read_text())
    assert summary["n_runs_counted"] == 9


def test_reading_zips_never_writes_to_disk(hand_ins, tmp_path, monkeypatch):
    """The members are read in memory: no temporary folder is made, nothing is written."""
    import tempfile

    made = []
    real = tempfile.mkdtemp
    monkeypatch.setattr(tempfile, "mkdtemp", lambda *a, **k: made.append(a) or real(*a, **k))
    monkeypatch.setattr(zipfile.ZipFile, "extract", None)
    monkeypatch.setattr(zipfile.ZipFile, "extractall", None)
    result = read_class(hand_ins, 1, workers=1)
    assert made == [] and len(result.runs) == 9
