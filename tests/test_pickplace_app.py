"""The pick-and-place tutor driven from Python."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tutor.views.pickplace_app import PickPlaceTutor, compare_runs, tray_status


def test_tray_shows_only_what_the_condition_shows(pickplace_task, tmp_path):
    nf = PickPlaceTutor("NF", run_file=tmp_path / "nf.json", task=pickplace_task, seed=0)
    nf.select(0)
    nf.demonstrate()
    status = tray_status(nf.run)
    assert set(status[status != "demo"]) == {"unknown"}  # NF: nothing shown while teaching
    assert not nf.run.visibility().totals
    nf.finish()
    assert "unknown" not in set(tray_status(nf.run, reveal=True))
    assert nf.run.finished and nf.run.visibility().everything

    bf = PickPlaceTutor("BF", task=pickplace_task, seed=0)
    bf.demonstrate(44)
    shown = np.flatnonzero(tray_status(bf.run) != "unknown")
    assert set(shown) >= {0, 9, 90, 99}
    # BF shows the five samples, never the totals over all 100 plants (the paper's BF)
    seen = bf.run.visibility()
    assert len(seen.shown) == 5 and not seen.totals
    assert "ε" not in bf.panel.value  # the panel keeps to it

    rf = PickPlaceTutor("RF", task=pickplace_task, seed=0)
    rf.demonstrate(12)
    assert np.flatnonzero(tray_status(rf.run) != "unknown").tolist() == [12]
    assert tray_status(rf.run)[12] in ("pass", "fail")  # the replay's outcome, not just ●
    assert rf.run.visibility().shown.tolist() == [12] and not rf.run.visibility().totals

    practice = PickPlaceTutor("RF", task=pickplace_task, seed=0, practice=True)
    practice.demonstrate(12)  # practice shows everything, and says it is practice
    assert "unknown" not in set(tray_status(practice.run))
    assert practice.run.visibility().everything and practice.record.practice


def test_selected_tests_and_messages(pickplace_task):
    sf = PickPlaceTutor("SF", task=pickplace_task, seed=1)
    sf.test()
    assert "demonstration before" in sf.message
    sf.demonstrate(0)
    sf.select(55)
    sf.test()
    assert "plant (6, 6)" in sf.message and "0:50" not in sf.clock.value
    assert tray_status(sf.run)[55] in ("pass", "fail")
    rf = PickPlaceTutor("RF", task=pickplace_task, seed=1)
    rf.demonstrate(0)
    rf.test()
    assert "only after the run" in rf.message


def test_wrong_plant_mistake_is_flagged(pickplace_task):
    t = PickPlaceTutor("RF", task=pickplace_task, seed=2)
    for p in (0, 99, 9):
        t.demonstrate(p)
    t.demonstrate(44, mistake="wrong_plant")
    assert "instead of the chosen plant (5, 5)" in t.panel.value


def test_resume_and_corrupt_file(pickplace_task, tmp_path):
    path = tmp_path / "bf.json"
    t = PickPlaceTutor("BF", run_file=path, task=pickplace_task, seed=3)
    t.demonstrate(0)
    t.demonstrate(99)
    again = PickPlaceTutor("BF", run_file=path, task=pickplace_task)
    assert again.run.session.n_demos == 2
    assert again.run.elapsed == pytest.approx(t.run.elapsed)
    other = PickPlaceTutor("SF", run_file=path, task=pickplace_task)
    assert other.run.session.n_demos == 0 and "Could not resume" in other.message
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "lfd-tutor-session", "version": 1, "task": {"name": "pickpl')
    before = bad.read_text()
    fresh = PickPlaceTutor("BF", run_file=bad, task=pickplace_task)
    fresh.demonstrate(5)
    assert bad.read_text() == before


def test_compare_runs_reports_the_paper(pickplace_task):
    runs = []
    for seed in range(3):
        t = PickPlaceTutor("BF", task=pickplace_task, seed=seed)
        for p in (0, 99, 9, 90):
            t.demonstrate(p)
        t.finish()
        runs.append(t)
    text = compare_runs(runs)
    assert "Run 3 (BF)" in text and "23.5%" in text and "27.0%" in text


def test_load_recorded_demos_keeps_the_chosen_plant(pickplace_task, tmp_path):
    from tutor.demofiles import BUNDLED_DIR

    rf = PickPlaceTutor("RF", run_file=tmp_path / "rf.json", task=pickplace_task)
    rf.load(BUNDLED_DIR / "pickplace_wrong_plant.json")
    s = rf.run.session
    assert s.n_demos == 3 and "Added 3" in rf.message
    # demo 2 went to the plant next to the chosen corner: the file says which was meant
    assert [r.demo_passed for r in s.history] == [True, False, True]
    assert "instead of the chosen plant (10, 10)" in s.history[1].demo_reason
    assert rf.run.elapsed > 3 * 9  # each recording costs its own duration (~10 s) and 25 s
    assert (tmp_path / "rf.json").exists()  # autosaved


def test_load_bad_files_changes_nothing(pickplace_task, tmp_path):
    from tutor.demofiles import BUNDLED_DIR, save_demos

    bf = PickPlaceTutor("BF", task=pickplace_task, seed=0)
    bf.demonstrate(44)
    before = (bf.run.session.n_demos, bf.run.elapsed)
    maze = BUNDLED_DIR / "maze_good.json"
    bf.load(maze)
    assert "Nothing was loaded" in bf.message and "t, x, y, z, g" in bf.message
    good = pickplace_task.demonstrate(0, np.random.default_rng(0))
    bad = good.copy()
    bad[:, 4] *= 2  # the hand column must be 0 .. 1
    save_demos(tmp_path / "half.csv", [good, bad], columns="txyzg")
    bf.load(tmp_path / "half.csv")  # demo 1 is fine, demo 2 is not: all or nothing
    assert "demo 2 of half.csv" in bf.message and "between 0 (open) and 1" in bf.message
    (tmp_path / "junk.json").write_text("{not json")
    bf.load(tmp_path / "junk.json")
    assert "Nothing was loaded" in bf.message
    assert (bf.run.session.n_demos, bf.run.elapsed) == before


def test_undo_keeps_the_time_spent(pickplace_task):
    bf = PickPlaceTutor("BF", task=pickplace_task, seed=0)
    bf.demonstrate(44)
    spent = bf.run.elapsed
    bf.undo()
    assert bf.run.session.n_demos == 0 and bf.run.elapsed == pytest.approx(spent)


def test_upload_widget_adds_recorded_demos(pickplace_task):
    import datetime

    from tutor.demofiles import BUNDLED_DIR

    data = (BUNDLED_DIR / "pickplace_corners.json").read_bytes()
    app = PickPlaceTutor("NF", task=pickplace_task)
    app.upload.value = (
        {
            "name": "my corners.json",
            "type": "application/json",
            "size": len(data),
            "content": memoryview(data),
            "last_modified": datetime.datetime.now(datetime.UTC),
        },
    )
    assert app.run.session.n_demos == 5 and "my corners.json" in app.message


def test_controls_one_selected_plant_busy_button_and_mistake_reset(pickplace_task, monkeypatch):
    from tutor.views import pickplace_app

    app = PickPlaceTutor("BF", task=pickplace_task, seed=0)
    for plant in (3, 57, 12):
        app.plant_buttons[plant].click()
    selected = [i for i, b in enumerate(app.plant_buttons) if b.layout.border.startswith("3px")]
    assert selected == [12] and "(selected)" in app.plant_buttons[12].tooltip
    app.mistake.value = "sloppy grab"
    seen = []
    real = app.demonstrate

    def watch(*args, **kwargs):
        button = app.buttons["Demonstrate"]
        seen.append((button.disabled, button.description))
        return real(*args, **kwargs)

    monkeypatch.setattr(app, "demonstrate", watch)
    app.buttons["Demonstrate"].click()
    app.buttons["Demonstrate"].click()  # a double click: the second arrives at once
    assert app.run.n_demos == 1 and seen == [(True, "Working…")]
    assert app.run.attempt.demos[0].mistake == "sloppy_grab"
    assert app.mistake.value == "no mistake"  # the chooser goes back after each demo
    assert app.buttons["Demonstrate"].description == "Demonstrate"
    monkeypatch.setattr(pickplace_app, "DOUBLE_CLICK_SECONDS", 0.0)
    app.buttons["Demonstrate"].click()  # a deliberate second demo still works
    assert app.run.n_demos == 2


def test_tray_map_is_laid_out_as_the_3d_camera_sees_it(pickplace_task):
    app = PickPlaceTutor("BF", task=pickplace_task, seed=0)
    cells = app.tray.children
    cols = pickplace_task.scene.cols
    assert "1" in cells[1].value and "10" in cells[cols].value  # column numbers on top
    first_row = cells[cols + 2 : 2 * cols + 2]
    assert first_row == tuple(app.plant_buttons[:cols])  # row 1, nearest the robot, on top
    assert "row 1, at the top" in app.widget.children[0].children[0].value
    # the 3-D camera looks from the front-right: the robot (x = 0) is at the back, the
    # tray's +y (higher columns) goes to the right of the screen
    from tutor.views.scene3d import CAMERA_POSITION

    assert CAMERA_POSITION[0] > 0 and CAMERA_POSITION[1] < 0


def test_the_run_ends_with_the_last_complete_demo_at_the_cap(pickplace_task, tmp_path):
    app = PickPlaceTutor("BF", task=pickplace_task, seed=0, run_file=tmp_path / "bf.json")
    app.demonstrate(44)
    app.run.spend(app.run.remaining - 20)  # 20 s left: no demo and its 5 attempts fit
    app.demonstrate(0)
    assert app.run.n_demos == 1  # the demo that could not end by 15:00 was not started
    assert app.run.attempt.finished and app.run.attempt.stopped == "time"
    assert "past the 15 minutes" in app.panel.value and "Run over" in app.panel.value
    assert "of 15:00 used" in app.clock.value
    saved = json.loads((tmp_path / "bf.json").read_text())
    assert saved["attempts"][-1]["stopped"] == "time"
