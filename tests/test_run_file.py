"""A run's file: one writer, nothing lost, nothing overwritten (both tutors, one base)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap

import pytest

from tests.helpers import REPO
from tutor.demofiles import bundled_demos, save_demos
from tutor.errors import InvalidParameterError
from tutor.framework import RunRecord, Trainee
from tutor.framework import controller as controller_module
from tutor.runtime import trainee_dir, trainee_key
from tutor.tasks.maze_run import MazeRun
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.views.maze_app import MazeTutor
from tutor.views.pickplace_app import PickPlaceTutor


@pytest.fixture(scope="module")
def good():
    return bundled_demos("maze_good")


def _record(path) -> dict:
    return json.loads(path.read_text())


# ---------------------------------------------------------------- two writers


CHILD = textwrap.dedent(
    """
    import sys, time
    from tutor.demofiles import bundled_demos
    from tutor.views.maze_app import MazeTutor
    path, n = sys.argv[1], int(sys.argv[2])
    app = MazeTutor("VF", run_file=path, trainee="Mai Anh")
    print("read_only", app.read_only, flush=True)
    print("message", app.message, flush=True)
    demos = bundled_demos("maze_good")
    for i in range(n):
        app.add(demos[i % len(demos)])
        print("n_demos", app.session.n_demos, "|", app.message, flush=True)
    print("ready", flush=True)
    sys.stdin.readline()  # hold the file until told to go
    """
)


def _child(path, n):
    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg"}
    return subprocess.Popen(
        [sys.executable, "-c", CHILD, str(path), str(n)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _read_until_ready(proc) -> list[str]:
    lines = []
    for line in proc.stdout:
        lines.append(line.rstrip("\n"))
        if line.startswith("ready"):
            return lines
    raise AssertionError(f"child ended early: {lines} {proc.stderr.read()}")


def test_two_processes_on_one_file_lose_no_demo_and_the_second_is_told(tmp_path):
    path = tmp_path / "VF.json"
    first = _child(path, 3)
    try:
        lines = _read_until_ready(first)
        assert "read_only False" in lines
        second = _child(path, 2)  # a second kernel opens the same run while the first holds it
        try:
            other = _read_until_ready(second)
        finally:
            second.stdin.close()
            second.wait(30)
        assert "read_only True" in other
        assert any("open in another tutor" in line for line in other)
        # the second process's strokes were refused, in words, not silently dropped
        strokes = [ln for ln in other if ln.startswith("n_demos")]
        assert len(strokes) == 2
        assert all("n_demos 3 " in ln and "read-only" in ln for ln in strokes)
        assert len(_record(path)["attempts"][-1]["demos"]) == 3  # the first one's work is whole
        first.stdin.write("\n")
        first.stdin.flush()
        first.wait(30)
    finally:
        if first.poll() is None:
            first.kill()
    # the first has gone: a third process takes the file over and finds every demo
    third = _child(path, 1)
    lines = _read_until_ready(third)
    third.stdin.close()
    third.wait(30)
    assert "read_only False" in lines and any("n_demos 4" in ln for ln in lines)


def test_a_killed_kernels_lock_is_taken_over(tmp_path):
    path = tmp_path / "VF.json"
    first = _child(path, 2)
    _read_until_ready(first)
    first.send_signal(signal.SIGKILL)
    first.wait(30)
    assert (tmp_path / ".VF.json.lock").exists()  # the lock file stays; the OS lock does not
    app = MazeTutor("VF", run_file=path, trainee="Mai Anh")
    assert not app.read_only and app.session.n_demos == 2


def test_a_cell_run_again_takes_over_the_run_and_the_old_view_is_told(tmp_path, good):
    """Re-running a tutor's cell makes a second tutor on the same file in the same kernel:
    the newer one carries on with every demo; the older one says so and is read-only."""
    path = tmp_path / "VF.json"
    one = MazeTutor("VF", run_file=path)
    one.add(good[0])
    two = MazeTutor("VF", run_file=path)
    assert not two.read_only and two.session.n_demos == 1
    assert one.read_only and "replaced by a newer one" in one.message
    assert "replaced by a newer one" in one.panel.value  # the old view was redrawn
    one.add(good[1])
    one.undo()
    one.request_reset()
    one.request_reset()
    one.finish()
    assert one.session.n_demos == 1 and one.pad.enabled is False
    assert len(_record(path)["attempts"][-1]["demos"]) == 1  # the old view changed nothing
    two.add(good[1])
    assert len(_record(path)["attempts"][-1]["demos"]) == 2
    # a tutor for another run on the same file name takes nothing from the first
    other = MazeTutor("VR", run_file=path)
    assert not two.read_only and other.run_file.name == "VF-2.json"


def test_a_read_only_view_can_try_again_once_the_other_kernel_has_gone(tmp_path, good):
    path = tmp_path / "VF.json"
    first = _child(path, 2)
    try:
        _read_until_ready(first)
        view = MazeTutor("VF", run_file=path, trainee="Mai Anh")
        assert view.read_only and view.retry.layout.display != "none"
        view.retry.click()
        assert view.read_only and "still open in another tutor" in view.message
    finally:
        first.stdin.close()
        first.wait(30)
    view.retry.click()
    assert not view.read_only and "saves the run" in view.message
    assert view.session.n_demos == 2 and view.retry.layout.display == "none"
    view.add(good[2])
    assert len(_record(path)["attempts"][-1]["demos"]) == 3


# ---------------------------------------------------------------- nothing deleted


def test_reset_asks_for_a_second_click_and_keeps_the_attempt(tmp_path, good, monkeypatch):
    path = tmp_path / "VF.json"
    app = MazeTutor("VF", run_file=path)
    for d in good[:3]:
        app.add(d)
    app.finish()
    now = [1000.0]
    monkeypatch.setattr(controller_module.time, "monotonic", lambda: now[0])
    app.buttons["Reset"].click()
    assert app.session.n_demos == 3 and "again within 5 seconds" in app.message
    now[0] += 6.0  # too late: the first click has expired
    app.buttons["Reset"].click()
    assert app.session.n_demos == 3
    now[0] += 2.0
    app.buttons["Reset"].click()  # confirmed
    assert app.session.n_demos == 0 and not app.finished
    saved = _record(path)
    assert [len(a["demos"]) for a in saved["attempts"]] == [3, 0]
    assert saved["attempts"][0]["finished"] and saved["attempts"][0]["ended"] == "reset"
    assert app.attempts.layout.display != "none" and app.attempts.options
    app.attempts.value = 1
    app.bring_back.click()
    assert app.session.n_demos == 3 and app.finished  # the finished run is back, as it was
    assert [e["kind"] for e in _record(path)["events"]][-2:] == ["reset", "restore"]


def test_undo_events_and_undone_demos_survive_resume(tmp_path, good):
    path = tmp_path / "VF.json"
    app = MazeTutor("VF", run_file=path)
    for d in good[:3]:
        app.add(d)
    app.undo()
    app.add(good[2])
    app.close()
    again = MazeTutor("VF", run_file=path)
    kinds = [e.kind for e in again.record.events]
    assert kinds == ["start", "add", "add", "add", "undo", "add"]
    assert len(again.run.attempt.undone) == 1 and again.session.n_demos == 3
    again.add(good[3])
    assert [e.kind for e in MazeRun.load(path, again.task).record.events][-2:] == ["add", "add"]


def test_loading_another_runs_file_is_refused_and_nothing_changes(tmp_path, good):
    vr = MazeTutor("VR", run_file=tmp_path / "VR.json")
    vr.add(good[0])
    vf_path = tmp_path / "VF.json"
    vf = MazeTutor("VF", run_file=vf_path)
    vf.add(good[1])
    before = vf_path.read_bytes()
    vf.load(tmp_path / "VR.json")
    assert "Nothing was loaded" in vf.message
    assert "VR run" in vf.message and "VF run" in vf.message  # names both runs
    assert vf.session.n_demos == 1 and vf_path.read_bytes() == before
    # a pick-and-place run into the maze tutor: refused the same way
    pp = PickPlaceRun("BF")
    pp.demonstrate(44, rng=0)
    pp.save(tmp_path / "pp.json")
    vf.load(tmp_path / "pp.json")
    assert "Nothing was loaded" in vf.message and vf_path.read_bytes() == before


def test_loading_into_a_finished_run_is_refused(tmp_path, good):
    path = tmp_path / "VF.json"
    app = MazeTutor("VF", run_file=path)
    app.add(good[0])
    app.finish()
    before = path.read_bytes()
    demo_file = save_demos(tmp_path / "more.csv", list(good)[1:3])
    app.load(demo_file)
    assert "Nothing was loaded" in app.message and "finished" in app.message
    copy = MazeRun.new("VF", app.task)
    copy.add_demo(good[1])
    copy.save(tmp_path / "copy.json")
    app.load(tmp_path / "copy.json")
    assert "finished" in app.message and path.read_bytes() == before


def test_same_run_file_loads_as_a_new_attempt(tmp_path, good):
    other = MazeRun.new("VF", MazeTutor("VF").task)
    for d in good[:2]:
        other.add_demo(d)
    other.save(tmp_path / "mine_from_home.json")
    path = tmp_path / "VF.json"
    app = MazeTutor("VF", run_file=path)
    app.add(good[3])
    app.load(tmp_path / "mine_from_home.json")
    assert app.session.n_demos == 2 and "attempt 2" in app.message
    assert [len(a["demos"]) for a in _record(path)["attempts"]] == [1, 2]


def test_a_file_of_another_run_is_never_overwritten(tmp_path, good):
    path = tmp_path / "NF.json"
    vr = MazeTutor("VR", run_file=path)  # a VR run saved under the NF name
    vr.add(good[0])
    vr.close()
    before = path.read_bytes()
    nf = MazeTutor("NF", run_file=path)
    assert nf.run_file.name == "NF-2.json" and "kept untouched" in nf.message
    nf.add(good[1])
    assert path.read_bytes() == before
    nf.close()
    again = MazeTutor("NF", run_file=path)  # the next time the NF run is found again
    assert again.run_file.name == "NF-2.json" and again.session.n_demos == 1


def test_another_trainees_file_is_not_resumed(tmp_path, good):
    path = tmp_path / "VF.json"
    mai = MazeTutor("VF", run_file=path, trainee="Mai Anh")
    mai.add(good[0])
    mai.close()
    other = MazeTutor("VF", run_file=path, trainee="Mai_Anh")
    assert other.session.n_demos == 0 and other.run_file.name == "VF-2.json"


# ---------------------------------------------------------------- failed saves


def test_a_failed_save_keeps_the_demo_and_tries_again(tmp_path, good):
    folder = tmp_path / "runs"
    app = MazeTutor("VF", run_file=folder / "VF.json")  # takes the file's lock
    folder.rename(tmp_path / "moved")
    folder.write_text("a file where the folder should be")
    app.add(good[0])
    assert app.session.n_demos == 1 and app.unsaved
    assert "Not saved" in app.message and "kept" in app.message
    assert "not saved yet" in app.status.value
    folder.unlink()
    (tmp_path / "moved").rename(folder)
    app.add(good[1])  # the next change saves both
    assert not app.unsaved and len(_record(folder / "VF.json")["attempts"][-1]["demos"]) == 2


def test_a_run_whose_folder_cannot_be_made_opens_read_only(tmp_path, good):
    """No lock can be taken (part of the path is a file): the tutor fails closed."""
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("a file where the folder should be")
    app = MazeTutor("VF", run_file=blocker / "VF.json")
    assert app.read_only and "cannot be locked" in app.message
    app.add(good[0])
    assert app.session.n_demos == 0 and "read-only" in app.message
    blocker.unlink()
    blocker.mkdir()
    app.try_again()
    app.add(good[0])
    assert not app.unsaved and len(_record(blocker / "VF.json")["attempts"][-1]["demos"]) == 1


def test_no_exception_leaves_a_button(tmp_path, good, monkeypatch):
    app = PickPlaceTutor("BF", run_file=tmp_path / "bf.json", seed=0)

    def broken(*args, **kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(app.run, "demonstrate", broken)
    app.buttons["Demonstrate"].click()
    assert "Something went wrong" in app.message and "kept" in app.message
    monkeypatch.undo()
    app._demo_ended = -1e9  # a later click, not the second half of a double click
    app.buttons["Demonstrate"].click()
    assert app.run.n_demos == 1


# ---------------------------------------------------------------- trainee folders


@pytest.mark.parametrize(
    "a, b",
    [
        ("Mai Anh", "Mai_Anh"),
        ("नमस्ते", "नमस्ती"),  # two different Devanagari names
        ("😀", "😁"),
        ("Anna", "anna"),
        ("Jo", "Jo."),
    ],
)
def test_different_trainees_get_different_folders(a, b):
    assert trainee_key(a) != trainee_key(b)


def test_the_same_trainee_gets_the_same_folder():
    assert trainee_key("Zo\u00eb") == trainee_key("Zoe\u0308")  # NFC and NFD
    assert trainee_key("  Mai   Anh ") == trainee_key("Mai Anh")
    assert len(trainee_key("x" * 200).encode()) <= 52


@pytest.mark.parametrize("name", ["", "   ", None, 3, "a\x00b", "x" * 201])
def test_bad_trainee_names_are_refused(name, monkeypatch):
    monkeypatch.delenv("JUPYTERHUB_USER", raising=False)
    if name is None:  # None means "the default name", which exists
        assert Trainee.from_name(None).name == "trainee"
        return
    with pytest.raises(InvalidParameterError):
        trainee_key(name)


def test_session_dir_uses_the_key_and_refuses_a_file(tmp_path, monkeypatch):
    monkeypatch.setenv("TUTOR_RUNS_DIR", str(tmp_path / "class"))
    folder = trainee_dir("Zoë")
    assert folder.parent == tmp_path / "class" and folder.name == trainee_key("Zoë")
    assert trainee_dir("Zoe\u0308") == folder
    (tmp_path / "file").write_text("x")
    monkeypatch.setenv("TUTOR_RUNS_DIR", str(tmp_path / "file"))
    with pytest.raises(InvalidParameterError, match="is a file, not a folder"):
        trainee_dir("Zoë")


def test_the_hub_user_is_the_default_trainee(tmp_path, monkeypatch):
    monkeypatch.setenv("JUPYTERHUB_USER", "student07")
    app = MazeTutor("VF", run_file=tmp_path / "VF.json")
    assert app.trainee.name == "student07"
    assert app.record.trainee == Trainee("student07", trainee_key("student07"))


def test_practice_runs_are_marked_and_kept_apart(tmp_path, good):
    path = tmp_path / "VF.json"
    practice = MazeTutor("VF", run_file=path, practice=True)
    practice.add(good[0])
    practice.close()
    assert RunRecord.from_dict(_record(path)).practice
    real = MazeTutor("VF", run_file=path)
    assert real.session.n_demos == 0 and real.run_file.name == "VF-2.json"


def test_pickplace_load_is_all_or_nothing_with_a_malformed_condition(tmp_path):
    task = PickPlaceTutor("BF").task
    good = task.demonstrate(0, None)
    path = save_demos(
        tmp_path / "two.json",
        [good, task.demonstrate(99, 1)],
        columns="txyzg",
        points=[task.test_points[0], [5.0, 5.0, 5.0]],  # demo 2 meant for nowhere
    )
    app = PickPlaceTutor("BF", run_file=tmp_path / "bf.json")
    before = (app.run.n_demos, app.run.elapsed, app.record)
    app.load(path)
    assert "Nothing was loaded" in app.message and "demo 2" in app.message
    assert (app.run.n_demos, app.run.elapsed, app.record) == before  # the clock did not move


def test_bring_back_offers_the_latest_earlier_attempt(tmp_path, good):
    app = MazeTutor("VF", run_file=tmp_path / "VF.json")
    app.add(good[0])
    app.reset()
    app.add(good[1])
    app.reset()
    assert app.attempts.value == 2  # the latest earlier attempt is chosen already
    app.attempts.value = None
    app.bring_back.click()
    assert "Choose an earlier attempt" in app.message and len(app.record.attempts) == 3
    app.attempts.value = 1
    app.bring_back.click()
    assert app.session.n_demos == 1 and len(app.record.attempts) == 4
