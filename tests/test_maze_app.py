"""The interactive maze tutor, driven from Python as headless runs drive it."""

from __future__ import annotations

import datetime
import json
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from tutor.demofiles import bundled_demos, save_demos
from tutor.views.maze_app import MazeTutor, compare_runs


@pytest.fixture(scope="module")
def good():
    return bundled_demos("maze_good")


def test_a_stroke_updates_the_picture_and_panel(tmp_path, good):
    app = MazeTutor("VF", run_file=tmp_path / "vf.json")
    assert "demonstrations: 0" in app.panel.value and app.pad.realisations == []
    render = app.pad.render_id
    app.pad.draw(good[0])
    assert app.session.n_demos == 1
    assert app.run.visibility().totals  # VF: the panel may give the totals
    assert app.pad.render_id > render
    assert len(app.pad.realisations) == 140 and len(app.pad.shown) == 140
    assert len(app.pad.demos) == 1
    assert (tmp_path / "vf.json").exists()


def test_no_feedback_hides_the_picture_until_finish(tmp_path, good):
    app = MazeTutor("NF", run_file=tmp_path / "nf.json")
    for demo in good[:2]:
        app.pad.draw(demo)
    seen = app.run.visibility()
    assert app.pad.shown == [] and len(seen.shown) == 0 and not seen.totals
    app.finish()
    assert app.run.finished and app.run.visibility().everything
    assert len(app.pad.shown) == 140
    assert "7.6%" in app.panel.value  # the paper's NF median beside the score
    app.pad.draw(good[2])  # no more demos after finishing
    assert app.session.n_demos == 2 and "finished" in app.message


def test_rules_circle_and_compliance(tmp_path, good):
    app = MazeTutor("VR", run_file=tmp_path / "vr.json")
    assert app.pad.rule_circle is None and "Rule 1" in app.panel.value
    app.pad.draw(good[0])
    assert app.pad.rule_circle["radius"] == pytest.approx(0.04)
    np.testing.assert_allclose(app.pad.rule_circle["center"], good[0][0, 1:], atol=1e-9)
    app.pad.draw(good[1])  # starts 14 cm away: breaks rule 2
    assert app.compliance == [True, False]
    assert "did not follow rule 2" in app.message
    app.undo()
    assert app.compliance == [True]


def test_a_stroke_through_an_obstacle_is_drawn_and_counted(maze_task):
    """The demo hits obstacle 1: the picture marks where, the panel says which."""
    app = MazeTutor("VF", task=maze_task)
    start, goal = np.array([0.10, 0.03]), np.asarray(maze_task.layout.target_center, float)
    app.pad.draw(np.c_[np.linspace(0.0, 2.0, 40), np.linspace(start, goal, 40)])
    assert app.session.n_demos == 1 and not app.session.latest.demo_passed
    assert app.session.latest.demo_causes[0].obstacle == 0  # the first obstacle, as data
    assert "refreshing the tutor failed" not in app.message
    assert "obstacle 1" in app.pad.summary  # the picture's own count names it


def test_rejected_stroke_changes_nothing(tmp_path, good):
    app = MazeTutor("VF", run_file=tmp_path / "vf.json")
    app.pad.draw(good[0])
    saved = (tmp_path / "vf.json").read_text()
    app.pad.draw([[0.0, 0.05, 0.03]])  # a click, not a stroke
    assert app.session.n_demos == 1 and "not used" in app.message
    assert (tmp_path / "vf.json").read_text() == saved


def test_killed_kernel_loses_no_demo(tmp_path):
    """A process teaching 3 demos is killed with SIGKILL; reopening resumes at the same eps."""
    path = tmp_path / "run.json"
    script = textwrap.dedent(
        f"""
        import os, signal, json
        from tutor.demofiles import bundled_demos
        from tutor.views.maze_app import MazeTutor
        app = MazeTutor("VF", run_file={str(path)!r})
        for demo in bundled_demos("maze_good")[:3]:
            app.pad.draw(demo)
        print(json.dumps(app.session.latest.efficacy), flush=True)
        os.kill(os.getpid(), signal.SIGKILL)
        """
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == -signal.SIGKILL
    eps = json.loads(proc.stdout.strip().splitlines()[-1])
    app = MazeTutor("VF", run_file=path)
    assert app.session.n_demos == 3
    assert app.session.latest.efficacy == eps
    assert "Resumed 3" in app.panel.value


@pytest.mark.parametrize(
    "content",
    [
        "",
        '{"format": "lfd-tutor-session", "version": 1, "task": {"name": "maze"}, "demos": [[[0,',
        '{"format": "lfd-tutor-session", "version": 1, "task": {"name": "maze"}, '
        '"demos": [[[0, 1e308, 1e308], [1, -1e308, 1e308]]]}',
        "\x80\x04\x95 not json at all",
    ],
)
def test_corrupt_session_file_is_left_untouched(tmp_path, good, content):
    path = tmp_path / "run.json"
    path.write_bytes(
        content.encode("utf-8", "surrogateescape") if isinstance(content, str) else content
    )
    before = path.read_bytes()
    app = MazeTutor("VF", run_file=path)
    assert "Could not resume" in app.panel.value
    app.pad.draw(good[0])
    assert app.session.n_demos == 1
    assert path.read_bytes() == before  # never overwritten


def test_load_demo_file_and_hostile_files(tmp_path, good):
    app = MazeTutor("VF", run_file=tmp_path / "vf.json")
    path = save_demos(tmp_path / "mine.csv", list(good)[:2])
    app.load(path)
    assert app.session.n_demos == 2 and "Added 2" in app.message
    hostile = tmp_path / "evil.json"
    hostile.write_text(json.dumps({"format": "lfd-tutor-demos", "demos": [[[0, 0.05, 0.03]]]}))
    app.load(hostile)
    assert app.session.n_demos == 2 and "Nothing was loaded" in app.message
    pickled = tmp_path / "evil2.json"
    pickled.write_bytes(b"\x80\x04\x95\x10\x00\x00\x00\x00\x00\x00\x00}\x94.")
    app.load(pickled)
    assert app.session.n_demos == 2 and "Nothing was loaded" in app.message


def test_upload_widget_loads_through_the_same_checks(tmp_path, good):
    app = MazeTutor("VF", run_file=tmp_path / "vf.json")
    data = save_demos(tmp_path / "up.json", list(good)[:1], task="maze").read_bytes()
    upload = {
        "name": "up.json",
        "type": "application/json",
        "size": len(data),
        "content": memoryview(data),
        "last_modified": datetime.datetime.now(datetime.UTC),
    }
    app.upload.value = (upload,)
    assert app.session.n_demos == 1


def test_save_export_and_compare(tmp_path, good):
    runs = []
    for cond, demos in [("NF", good[:2]), ("VF", good), ("VR", good)]:
        app = MazeTutor(cond, run_file=tmp_path / f"{cond}.json")
        for d in demos:
            app.pad.draw(d)
        app.finish()
        runs.append(app)
    text = compare_runs(runs)
    assert "NF: η" in text and "7.6%" in text and "13.4%" in text and "14.0%" in text
    assert "one person" in text
    exported = json.loads((tmp_path / "VF.json").read_text())
    assert exported["format"] == "lfd-tutor-run" and exported["condition"] == "VF"
    assert exported["attempts"][-1]["finished"]
    assert len(exported["attempts"][-1]["demos"]) == len(good)
    assert os.path.getsize(tmp_path / "VF.json") > 0
