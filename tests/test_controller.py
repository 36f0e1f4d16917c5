"""The run controller below the views: every control works without a widget, and the
message is set in one place (:mod:`tutor.framework.controller`)."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

from tests.helpers import REPO
from tutor.demofiles import bundled_demos, save_demos
from tutor.errors import InvalidFileError
from tutor.framework.controller import RunController
from tutor.tasks.maze import MazeTask
from tutor.tasks.maze_run import MazeRun


@pytest.fixture(scope="module")
def good():
    return bundled_demos("maze_good")


def _controller(path=None, **kw):
    return RunController(MazeRun, "VF", MazeTask(), path, "Ana", demo_columns=("t", "x", "y"), **kw)


def test_every_control_works_without_widgets(tmp_path, good, monkeypatch):
    path = tmp_path / "VF.json"
    demos = save_demos(tmp_path / "three.csv", list(good)[:3])
    c = _controller(path)
    c.load(demos)
    assert c.run.n_demos == 3 and c.message == "Added 3 demonstration(s) from three.csv."
    c.undo()
    assert c.run.n_demos == 2 and "Took back" in c.message
    now = [100.0]
    monkeypatch.setattr("tutor.framework.controller.time.monotonic", lambda: now[0])
    c.request_reset()
    assert c.run.n_demos == 2 and "again within 5 seconds" in c.message
    c.request_reset()
    assert c.run.n_demos == 0 and "Started attempt 2" in c.message
    c.bring_back(None)
    assert "Choose an earlier attempt" in c.message
    c.bring_back(1)
    assert c.run.n_demos == 2 and c.message.startswith("Brought back attempt 1 as attempt 3")
    c.finish()
    assert c.finished and c.message == ""
    saved = json.loads(path.read_text())
    # the demo taken back is kept in the attempt's "undone"
    assert [len(a["demos"]) for a in saved["attempts"]] == [2, 0, 2]
    c.close()
    assert c.read_only
    again = _controller(path)
    assert again.finished and "Resumed 2 demonstration(s) from VF.json" in again.message
    again.close()


def test_a_load_names_the_file_as_the_trainee_knows_it(tmp_path, good):
    stored = save_demos(tmp_path / "up_1.csv", list(good)[:1])
    c = _controller()
    c.load(stored, "up?1.csv")
    assert c.message == "Added 1 demonstration(s) from up?1.csv."
    bad = tmp_path / "bad_name.csv"
    bad.write_text("demo;t;x;y\n1;0;0,5;1\n")
    with pytest.raises(InvalidFileError) as caught:
        c.load(bad, "bad?name.csv")
    text = str(caught.value)
    assert text.startswith("Nothing was loaded from bad?name.csv: bad?name.csv (values")
    assert "bad_name.csv" not in text and c.run.n_demos == 1


def test_a_newer_controller_takes_the_file_over_and_the_older_view_is_told(tmp_path, good):
    path = tmp_path / "VF.json"
    told = []
    older = _controller(path, on_change=lambda: told.append(True))
    older.run.add_demo(good[0])
    newer = _controller(path)
    assert told == [True] and older.read_only and "replaced by a newer one" in older.message
    assert newer.run.n_demos == 1 and not newer.read_only
    older.undo()
    assert older.run.n_demos == 1 and "read-only" in older.message
    newer.close()


def test_an_error_becomes_the_message():
    c = _controller()
    c.failed(InvalidFileError("that file is empty"), "load")
    assert c.message == "that file is empty"
    c.failed(KeyError("x"), "load")
    assert "Something went wrong inside the tutor (KeyError" in c.message
    assert "Your demonstrations are kept" in c.message


#: the modules of the tutors' runs and controls (Scene3D's caption is its own message)
_RUN_MODULES = [
    "tutor/framework/controller.py",
    "tutor/framework/run_file.py",
    "tutor/framework/run_loading.py",
    "tutor/views/app.py",
    "tutor/views/maze_app.py",
    "tutor/views/pickplace_app.py",
    "tutor/views/pickplace_files.py",
    "tutor/views/tray.py",
    "tutor/views/uploads.py",
]


def _message_assignments(path: Path) -> list[str]:
    """``where`` of every assignment to an attribute ``message`` or ``_message``."""
    found = []
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        targets = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            targets = [node.target]
        for target in targets:
            if isinstance(target, ast.Attribute) and target.attr in ("message", "_message"):
                found.append(f"{path.name}:{node.lineno}")
    return found


def test_the_message_is_set_in_one_place():
    places = [p for name in _RUN_MODULES for p in _message_assignments(REPO / name)]
    assert len(places) == 1, places
    source = (REPO / "tutor/framework/controller.py").read_text().splitlines()
    line = int(places[0].split(":")[1])
    assert places[0].startswith("controller.py") and "self._message = text" in source[line - 1]
    uploads = (REPO / "tutor/views/uploads.py").read_text()
    assert "__self__" not in uploads and ".replace(" not in uploads
