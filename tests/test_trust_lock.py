"""Work is never lost (issue 19): a lock that cannot be taken fails closed, Save never
writes over another run's file, and a run file whose events contradict its demos is
refused on resume and left untouched."""

from __future__ import annotations

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
    app = MazeTutor("VF", session_file=path, trainee=TRAINEE)
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
    app = MazeTutor("VF", session_file=path, trainee=TRAINEE)
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
    app = MazeTutor("VF", session_file=path, trainee=TRAINEE)
    assert app.read_only and "may not be written by you" in app.message
    app.add(good[1])
    assert app.session.n_demos == 1 and path.read_bytes() == before


CHILD = textwrap.dedent(
    """
    import sys
    from tutor.demofiles import bundled_demos
    from tutor.views.maze_app import MazeTutor
    demos = bundled_demos("maze_good")
    app = MazeTutor("VF", session_file=sys.argv[1], trainee=sys.argv[2])
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
        app = MazeTutor("VF", session_file=path, trainee=TRAINEE)
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
    app = MazeTutor("VF", session_file=path, trainee=TRAINEE)
    app.add(good[0])
    app.close()
    other = MazeTutor("VF", session_file=path, trainee=TRAINEE)  # another tutor takes it over
    other.add(good[1])
    before = path.read_bytes()
    app.add(good[2])
    assert app.read_only and app.session.n_demos == 1 and path.read_bytes() == before
    with pytest.raises(SessionInUseError):
        raw_save(app)
    assert path.read_bytes() == before


def test_the_saved_copy_of_a_read_only_view_is_refused_too(tmp_path, good):
    path = tmp_path / "VF.json"
    one = MazeTutor("VF", session_file=path, trainee=TRAINEE)
    one.add(good[0])
    MazeTutor("VF", session_file=path, trainee=TRAINEE)  # its cell run again
    assert one.read_only
    assert one.save(tmp_path / "copy.json") is None and "Nothing was saved" in one.message
    assert not (tmp_path / "copy.json").exists()


# ------------------------------------------------ 2. Save never writes over another run


def test_save_onto_another_runs_file_is_refused_and_leaves_it_byte_identical(tmp_path, good):
    vr = MazeTutor("VR", session_file=tmp_path / "VR.json", trainee=TRAINEE)
    vr.add(good[0])
    theirs = MazeTutor("VF", session_file=tmp_path / "zoe" / "VF.json", trainee="Zoë")
    theirs.add(good[1])
    earlier = _saved_run(good, 3)  # Mai Anh's VF run of another day: another run id
    earlier.save(tmp_path / "VF-old.json")
    save_demos(tmp_path / "demos.csv", list(good[:2]))
    app = MazeTutor("VF", session_file=tmp_path / "mine" / "VF.json", trainee=TRAINEE)
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
    app = MazeTutor("VF", session_file=path, trainee=TRAINEE)
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
