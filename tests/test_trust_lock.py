"""Work is never lost (issue 19): a lock that cannot be taken fails closed, Save never
writes over another run's file, and a run file whose events contradict its demos is
refused on resume and left untouched."""

from __future__ import annotations

import datetime as dt
import json
import os
import subprocess
import sys
import textwrap

import pytest

from tests.helpers import REPO
from tutor.demofiles import bundled_demos, save_demos
from tutor.errors import InvalidFileError, LockError, SessionInUseError, WrongRunError
from tutor.framework import RunRecord, Trainee
from tutor.tasks.maze_run import MazeRun
from tutor.views.app import TutorApp
from tutor.views.maze_app import MazeTutor

TRAINEE = "Mai Anh"
#: the tutor's Save without the guard that turns errors into panel messages
raw_save = TutorApp.save.__wrapped__


@pytest.fixture(scope="module")
def good():
    return bundled_demos("maze_good")


def _lock_of(path):
    return path.with_name(f".{path.name}.lock")


def _saved_run(good, n=1):
    """Mai Anh's VF run of ``n`` demos, as an earlier session left it (no lock file)."""
    run = MazeRun.new("VF", MazeTutor("VF").task, trainee=Trainee.from_name(TRAINEE))
    for demo in good[:n]:
        run.add_demo(demo)
    return run


# ---------------------------------------------------------------- 1. locks fail closed


def test_a_lock_path_that_is_a_folder_opens_read_only_and_changes_nothing(tmp_path, good):
    path = tmp_path / "VF.json"
    _saved_run(good, 2).save(path)
    before = path.read_bytes()
    _lock_of(path).mkdir()
    app = MazeTutor("VF", run_file=path, trainee=TRAINEE)
    assert app.read_only and app.session.n_demos == 2  # the run is shown as it is
    assert "cannot be locked" in app.message and "folder" in app.message
    assert "read-only" in app.message and "nothing you do here is saved" in app.message
    assert "cannot be locked" in app.status.value
    app.add(good[2])
    app.undo()
    app.finish()
    app.reset()
    assert app.session.n_demos == 2 and "read-only" in app.message
    assert app.save() is None and "Nothing was saved" in app.message
    with pytest.raises(LockError, match="cannot be locked"):
        raw_save(app)
    copy = tmp_path / "copy.json"
    with pytest.raises(LockError):
        raw_save(app, copy)
    assert not copy.exists() and path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [".VF.json.lock", "VF.json"]
    # fixed: Try again takes the file and the tutor saves again
    app.try_again()
    assert app.read_only and "still cannot be locked" in app.message
    _lock_of(path).rmdir()
    app.try_again()
    assert not app.read_only
    app.add(good[2])
    assert RunRecord.from_dict(json.loads(path.read_text())).current.n_demos == 3


def test_a_new_run_whose_lock_is_a_folder_writes_no_file(tmp_path, good):
    path = tmp_path / "runs" / "VF.json"
    path.parent.mkdir()
    _lock_of(path).mkdir()
    app = MazeTutor("VF", run_file=path, trainee=TRAINEE)
    assert app.read_only and app.session.n_demos == 0
    app.add(good[0])
    assert app.session.n_demos == 0 and not path.exists()


@pytest.fixture
def immutable():
    """``immutable(path)``: make a file that even root may not write (chattr +i)."""
    made = []

    def do(path):
        path.touch()
        done = subprocess.run(["chattr", "+i", str(path)], capture_output=True, text=True)
        if done.returncode != 0:
            pytest.skip(f"chattr +i is not possible here: {done.stderr.strip()}")
        made.append(path)

    yield do
    for path in made:
        subprocess.run(["chattr", "-i", str(path)], capture_output=True)


def test_a_stale_lock_that_may_not_be_written_opens_read_only(tmp_path, good, immutable):
    path = tmp_path / "VF.json"
    _saved_run(good, 1).save(path)
    before = path.read_bytes()
    immutable(_lock_of(path))
    app = MazeTutor("VF", run_file=path, trainee=TRAINEE)
    assert app.read_only and "may not be written by you" in app.message
    app.add(good[1])
    assert app.session.n_demos == 1 and path.read_bytes() == before


CHILD = textwrap.dedent(
    """
    import sys
    from tutor.demofiles import bundled_demos
    from tutor.views.maze_app import MazeTutor
    demos = bundled_demos("maze_good")
    app = MazeTutor("VF", run_file=sys.argv[1], trainee=sys.argv[2])
    print("open", app.read_only, flush=True)
    for line in sys.stdin:
        for i in range(int(line)):
            app.add(demos[i % len(demos)])
            saved = not app.read_only and not app.unsaved and "Not saved" not in app.message
            print("add", app.session.n_demos, saved, flush=True)
        print("done", flush=True)
    """
)


def _child(path):
    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg", "TUTOR_HEADLESS": "1"}
    return subprocess.Popen(
        [sys.executable, "-c", CHILD, str(path), TRAINEE],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _ask(proc, n) -> list[str]:
    proc.stdin.write(f"{n}\n")
    proc.stdin.flush()
    lines = []
    for line in proc.stdout:
        if line.startswith("done"):
            return lines
        lines.append(line.split())
    raise AssertionError(f"the child ended early: {lines} {proc.stderr.read()}")


@pytest.mark.parametrize("blocked", ["folder", "immutable"])
def test_two_tutors_where_one_cannot_lock_only_one_writes(tmp_path, good, blocked, immutable):
    """One kernel opens while the lock cannot be taken, another once it can: every demo
    announced as saved is in the file, and the one without the lock writes nothing."""
    path = tmp_path / "VF.json"
    if blocked == "folder":
        _lock_of(path).mkdir()
    else:
        immutable(_lock_of(path))
    child = _child(path)
    try:
        assert child.stdout.readline().split() == ["open", "True"]
        announced = [int(n) for _, n, ok in _ask(child, 3) if ok == "True"]
        assert announced == [] and not path.exists()
        if blocked == "folder":
            _lock_of(path).rmdir()
        else:
            subprocess.run(["chattr", "-i", str(_lock_of(path))], check=True)
        app = MazeTutor("VF", run_file=path, trainee=TRAINEE)
        assert not app.read_only, app.message
        for demo in good[:4]:
            app.add(demo)
            assert not app.unsaved
        lines = _ask(child, 5)
        assert all(ok == "False" for _, _, ok in lines)
        app.add(good[4])
        on_disk = RunRecord.from_dict(json.loads(path.read_text()))
        assert on_disk == app.record and on_disk.current.n_demos == 5
        assert [e.kind for e in on_disk.events].count("add") == 5
    finally:
        child.kill()
        child.wait(30)


def test_a_closed_tutor_writes_nothing_more(tmp_path, good):
    path = tmp_path / "VF.json"
    app = MazeTutor("VF", run_file=path, trainee=TRAINEE)
    app.add(good[0])
    app.close()
    other = MazeTutor("VF", run_file=path, trainee=TRAINEE)  # another tutor takes it over
    other.add(good[1])
    before = path.read_bytes()
    app.add(good[2])
    assert app.read_only and app.session.n_demos == 1 and path.read_bytes() == before
    with pytest.raises(SessionInUseError):
        raw_save(app)
    assert path.read_bytes() == before


def test_the_saved_copy_of_a_read_only_view_is_refused_too(tmp_path, good):
    path = tmp_path / "VF.json"
    one = MazeTutor("VF", run_file=path, trainee=TRAINEE)
    one.add(good[0])
    MazeTutor("VF", run_file=path, trainee=TRAINEE)  # its cell run again
    assert one.read_only
    assert one.save(tmp_path / "copy.json") is None and "Nothing was saved" in one.message
    assert not (tmp_path / "copy.json").exists()


# ------------------------------------------------ 2. Save never writes over another run


def test_save_onto_another_runs_file_is_refused_and_leaves_it_byte_identical(tmp_path, good):
    vr = MazeTutor("VR", run_file=tmp_path / "VR.json", trainee=TRAINEE)
    vr.add(good[0])
    theirs = MazeTutor("VF", run_file=tmp_path / "zoe" / "VF.json", trainee="Zoë")
    theirs.add(good[1])
    earlier = _saved_run(good, 3)  # Mai Anh's VF run of another day: another run id
    earlier.save(tmp_path / "VF-old.json")
    save_demos(tmp_path / "demos.csv", list(good[:2]))
    app = MazeTutor("VF", run_file=tmp_path / "mine" / "VF.json", trainee=TRAINEE)
    app.add(good[2])
    others = {
        "VR.json": ("VR run", WrongRunError),
        "zoe/VF.json": ("Zoë", WrongRunError),
        "VF-old.json": ("another", WrongRunError),
        "demos.csv": ("not a run file", InvalidFileError),
    }
    for name, (why, error) in others.items():
        target = tmp_path / name
        before = target.read_bytes()
        with pytest.raises(error, match=why) as refused:
            raw_save(app, target)
        assert target.name in str(refused.value) and "another file name" in str(refused.value)
        assert app.save(target) is None and "Nothing was saved" in app.message
        assert target.read_bytes() == before, name
    assert vr.session.n_demos == 1 and MazeRun.load(tmp_path / "VR.json", vr.task).n_demos == 1


def test_save_onto_its_own_file_a_copy_or_a_new_name_still_works(tmp_path, good):
    path = tmp_path / "VF.json"
    app = MazeTutor("VF", run_file=path, trainee=TRAINEE)
    app.add(good[0])
    assert app.save(path) == path and "Saved to" in app.message
    copy = tmp_path / "copies" / "VF-copy.json"
    assert app.save(copy) == copy
    app.add(good[1])
    assert app.save(copy) == copy  # the copy holds this very run: written again
    assert RunRecord.from_dict(json.loads(copy.read_text())) == app.record
    old = app.record.to_dict() | {"run_id": None}  # an old record without a run id
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert app.save(tmp_path / "old.json") == tmp_path / "old.json"


# ------------------------------------------------ 3. events checked against the demos


@pytest.fixture(scope="module")
def history(good):
    """A record dict of two attempts: add, test, add, undo | reset, add, add, finish."""
    run = MazeRun.new("VR", MazeTutor("VR").task, trainee=Trainee.from_name(TRAINEE))
    run.add_demo(good[0])
    run.test([3])
    run.add_demo(good[1])
    run.undo()
    run.reset()
    run.add_demo(good[2])
    run.add_demo(good[3])
    run.finish()
    data = run.to_dict()
    assert [e["kind"] for e in data["events"]] == [
        "start", "add", "test", "add", "undo", "reset", "add", "add", "finish",
    ]  # fmt: skip
    return data


def _edited(data, change):
    data = json.loads(json.dumps(data))
    change(data)
    return data


def _stamp(data, i, at):
    data["events"][i]["at"] = at


def _add_after_finish(data):
    data["attempts"][-1]["demos"].append(data["attempts"][-1]["demos"][0])
    data["events"].append({**data["events"][-2], "n_demos": 3})


#: (name, change, words of the refusal)
CONTRADICTIONS = [
    ("time-goes-backwards", lambda d: _stamp(d, 4, "1999-12-31T23:00:00.000Z"),
     r"events\[4\].*time goes backwards"),
    ("an-add-claims-demo-99", lambda d: d["events"][6].update(n_demos=99),
     r"events\[6\].*claims 99 demo\(s\) in attempt 2, which held 0"),
    ("the-last-add-claims-99", lambda d: [e.update(n_demos=99) for e in d["events"][7:]],
     r"events\[7\].*claims 99"),
    ("a-finish-in-an-unfinished-attempt", lambda d: d["attempts"][-1].update(finished=False),
     r"events\[8\].*not finished"),
    ("an-add-after-the-finish", _add_after_finish, r"events\[9\].*after attempt 2 was finished"),
    ("an-undo-from-no-demo", lambda d: d["events"][6].update(kind="undo", n_demos=0),
     r"events\[6\].*'undo'"),
    ("a-demo-dropped-from-the-file", lambda d: d["attempts"][1]["demos"].pop(),
     r"count 2 demo\(s\) in attempt 2, but it holds 1"),
    ("an-event-back-in-the-first-attempt", lambda d: d["events"][7].update(attempt=0),
     r"events\[7\].*attempt 1 after attempt 2 began"),
    ("an-add-that-begins-an-attempt", lambda d: d["events"][5].update(kind="add", n_demos=2),
     r"events\[5\].*cannot begin attempt 2"),
    ("a-reset-inside-an-attempt", lambda d: d["events"][3].update(kind="reset"),
     r"events\[3\].*must begin a new attempt"),
    ("events-that-stop-before-the-last-attempt",
     lambda d: d.update(events=d["events"][:5]), r"end in attempt 1 of the record's 2"),
]  # fmt: skip


@pytest.mark.parametrize("change, words", [pytest.param(*r[1:], id=r[0]) for r in CONTRADICTIONS])
def test_a_record_whose_events_contradict_its_demos_is_refused(history, change, words):
    with pytest.raises(InvalidFileError, match=words):
        RunRecord.from_dict(_edited(history, change))


def test_a_consistent_history_and_a_clock_corrected_by_ntp_are_accepted(history):
    assert RunRecord.from_dict(history).current.n_demos == 2
    at = history["events"][3]["at"]
    back = (_moment_of(at) - dt.timedelta(seconds=0.4)).isoformat().replace("+00:00", "Z")
    assert RunRecord.from_dict(_edited(history, lambda d: _stamp(d, 4, back)))
    no_events = _edited(history, lambda d: d.update(events=[]))  # nothing to check against
    assert RunRecord.from_dict(no_events).events == ()


def _moment_of(at: str) -> dt.datetime:
    return dt.datetime.fromisoformat(at.replace("Z", "+00:00"))


def test_resuming_a_contradictory_run_file_is_refused_and_the_file_kept(tmp_path, history, good):
    path = tmp_path / "VR.json"
    path.write_text(json.dumps(_edited(history, lambda d: d["events"][6].update(n_demos=99))))
    before = path.read_bytes()
    app = MazeTutor("VR", run_file=path, trainee=TRAINEE)
    assert "Could not resume from VR.json" in app.message and "claims 99" in app.message
    assert "kept untouched" in app.message and app.run_file.name == "VR-2.json"
    app.add(good[0])
    assert app.session.n_demos == 1 and path.read_bytes() == before
    with pytest.raises(InvalidFileError, match="VR.json: .*claims 99"):
        MazeRun.load(path, app.task)
    app.load(path)  # the Load button refuses it too
    assert "Nothing was loaded" in app.message and "claims 99" in app.message
    assert app.session.n_demos == 1 and path.read_bytes() == before
