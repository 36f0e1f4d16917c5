"""Issue 19, boundaries: what the browser sends, text at the UTF-8 edge, path lengths,
blank names and the command line's counts."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tutor.demofiles import bundled_demos, save_demos
from tutor.errors import InvalidPayloadError
from tutor.payloads import (
    MAX_STROKE_POINTS,
    check_choice,
    check_stroke,
    check_text,
    check_upload,
    check_view_message,
)

# --------------------------------------------------------------------------- 1. payloads

GOOD = bundled_demos("maze_good")[0].tolist()

BAD_STROKES = {
    "ragged rows": [[0.0, 0.05, 0.03], [0.1, 0.06], [0.2, 0.07, 0.04]],
    "text cells": [[0.0, "0.05", 0.03], [0.1, 0.06, 0.04]],
    "objects as points": [{"t": 0, "x": 0.05, "y": 0.03}, {"t": 1, "x": 0.1, "y": 0.1}],
    "an object": {"t": [0, 1], "x": [0.05, 0.1]},
    "None": None,
    "null cells (a NaN sent as JSON)": [[0.0, None, 0.03], [0.1, 0.06, 0.04]],
    "NaN": [[0.0, math.nan, 0.03], [0.1, 0.06, 0.04]],
    "inf": [[0.0, 0.05, math.inf], [0.1, 0.06, 0.04]],
    "bools": [[False, True, True], [True, True, True]],
    "nested deeper": [[[0.0], [0.05], [0.03]], [[0.1], [0.06], [0.04]]],
    "text": "0,0.05,0.03",
    "a number": 3,
    "huge": [[i * 1e-3, 0.05, 0.03] for i in range(MAX_STROKE_POINTS + 1)],
    "one point": [[0.0, 0.05, 0.03]],
    "time going back": [[0.2, 0.05, 0.03], [0.1, 0.06, 0.04]],
}


@pytest.mark.parametrize("stroke", BAD_STROKES.values(), ids=BAD_STROKES.keys())
def test_a_bad_stroke_is_refused_with_a_named_error(stroke):
    with pytest.raises(InvalidPayloadError, match="stroke"):
        check_stroke(stroke)


def test_a_good_stroke_comes_back_as_floats():
    arr = check_stroke(GOOD)
    assert arr.dtype == float and arr.shape == (len(GOOD), 3)
    assert check_stroke(np.asarray(GOOD)).shape == arr.shape
    assert check_stroke([[0, 1, 2], [1, 2, 3]]).tolist() == [[0, 1, 2], [1, 2, 3]]


def test_the_other_payloads_are_checked():
    assert check_text("Mai Anh", "your name") == "Mai Anh"
    for value in (None, 3, ["a"], {"a": 1}, b"bytes"):
        with pytest.raises(InvalidPayloadError, match="not as text"):
            check_text(value, "your name")
    with pytest.raises(InvalidPayloadError, match="characters long"):
        check_text("x" * 5000, "your name")
    assert check_choice(2, "the experiment", (1, 2)) == 2
    for value in (True, 2.0, "2", 3, None):
        with pytest.raises(InvalidPayloadError, match="not one of those offered"):
            check_choice(value, "the experiment", (1, 2))
    assert check_upload(({"name": "a.csv", "content": memoryview(b"x")},)) == ("a.csv", b"x")
    for value in ((), None, 3, ({"name": "a.csv"},), ({"name": 3, "content": "text"},)):
        with pytest.raises(InvalidPayloadError, match="without"):
            check_upload(value)
    assert check_view_message({"type": "hello", "id": "k3x9"}) == "k3x9"
    assert check_view_message({"type": "other"}) is None
    for content in (None, [], {"type": 3}, {"type": "hello"}, {"type": "hello", "id": "x" * 99},
                    {"type": "hello", "id": {"a": 1}}, {"type": "hello", "id": "<b>"}):
        with pytest.raises(InvalidPayloadError, match="reload the page"):
            check_view_message(content)


@pytest.fixture(scope="module")
def maze_tutor(tmp_path_factory):
    from tutor.views.maze_app import MazeTutor

    path = tmp_path_factory.mktemp("maze") / "VF.json"
    app = MazeTutor("VF", run_file=path, trainee="Mai Anh")
    app.pad.draw(GOOD)
    return app


@pytest.mark.parametrize("stroke", BAD_STROKES.values(), ids=BAD_STROKES.keys())
def test_a_bad_stroke_from_the_page_is_said_in_the_panel_and_adds_nothing(maze_tutor, stroke):
    app = maze_tutor
    saved = app.run_file.read_text()
    n = app.session.n_demos
    # what the widget's comm does with an update from the page
    app.pad.set_state({"stroke": stroke, "stroke_count": app.pad.stroke_count + 1})
    assert app.session.n_demos == n
    assert app.message.startswith("That stroke was not used") and "stroke" in app.message
    assert "not used" in app.panel.value
    assert app.run_file.read_text() == saved


def test_a_good_stroke_from_the_page_is_added(maze_tutor):
    app = maze_tutor
    n = app.session.n_demos
    app.pad.set_state({"stroke": bundled_demos("maze_good")[1].tolist(),
                       "stroke_count": app.pad.stroke_count + 1})
    assert app.session.n_demos == n + 1 and "not used" not in app.message


def test_an_upload_without_content_is_said_in_the_panel(maze_tutor):
    app = maze_tutor
    n = app.session.n_demos
    app.upload.set_state({"value": [{"name": "demos.csv", "type": "text/csv", "size": 3,
                                      "last_modified": 0}]})
    assert app.session.n_demos == n and "Nothing was loaded" in app.message
    app.upload.set_state({"value": "not a list of files"})
    assert app.session.n_demos == n and "without its content" in app.message


def test_a_good_upload_from_the_page_loads(maze_tutor, tmp_path):
    app = maze_tutor
    n = app.session.n_demos
    save_demos(tmp_path / "two.json", bundled_demos("maze_good")[2:4])
    data = (tmp_path / "two.json").read_bytes()
    app.upload.set_state({"value": [{"name": "two.json", "type": "application/json",
                                     "size": len(data), "content": memoryview(data),
                                     "last_modified": 1.7e12}]})
    assert app.session.n_demos == n + 2, app.message
    assert app.upload.value[0]["last_modified"].year >= 2023


def test_the_start_form_says_what_is_wrong_with_what_the_page_sent(person):
    from tutor.views.start_pickplace import PickPlaceExperiment

    form = PickPlaceExperiment(start=False, scene3d=False)
    form.name.value = "x" * 5000
    form.go.click()
    assert form.trainee is None and "characters long" in form.problem
    form._safely(lambda: 1 / 0)  # a bug in what a click does: said, not raised
    assert "Something went wrong" in form.problem and "ZeroDivisionError" in form.problem


def test_the_dashboard_says_what_is_wrong_with_its_folder_field(tmp_path):
    from tutor.study.dashboard import ClassDashboard

    board = ClassDashboard(tmp_path)
    board.folder.value = "y" * 5000
    assert "characters long" in board.status.value
    board.save_button.click()  # nothing to save, said, not raised
    assert "nothing to save" in board.status.value


def test_a_bad_message_from_the_3d_view_is_said_in_its_caption_and_sends_nothing():
    from tutor.tasks.pickplace import PickPlaceTask
    from tutor.views.scene3d import Scene3D

    scene = Scene3D(PickPlaceTask(), mode="static", robot=False)
    view = scene.widget.children[1]
    sent = []
    view.send = lambda content, buffers=None: sent.append(content)
    for content in (None, ["hello"], {"type": "hello", "id": {"x": 1}}, {"type": "hello"}):
        scene._on_view_msg(view, content, [])
    assert sent == [] and "reload the page" in scene._caption.value
    scene._on_view_msg(view, {"type": "hello", "id": "v1"}, [])
    assert sent == [{"type": "full", "to": "v1"}]


# --------------------------------------------------------------------------- 2. UTF-8 edge


def test_safe_text_replaces_lone_surrogates_and_reads_escaped_bytes():
    from tutor.runtime import safe_text

    assert safe_text("Mai Anh") == "Mai Anh"
    assert safe_text("a\udcff") == "a\ufffd"
    assert safe_text("\ud800x\udfff") == "\ufffdx\ufffd"
    assert safe_text("\ud83d\ude00") == "\U0001f600"  # a pair is its character
    assert safe_text("Zo\udceb", from_bytes=True) == "Zoë"  # Latin-1 bytes
    assert safe_text("Zo\udcc3\udcab", from_bytes=True) == "Zoë"  # UTF-8 bytes
    assert safe_text("\udc80", from_bytes=True) == "€"  # Windows-1252, not a control
    assert safe_text("a\ud800", from_bytes=True) == "a\ufffd"  # not an escaped byte
    for text in ("a\udcff", "Zo\udceb", "\ud800\udc00\udfff"):
        safe_text(text).encode("utf-8")
        safe_text(text, from_bytes=True).encode("utf-8")


def _strict_print(*texts) -> bytes:
    import io

    out = io.TextIOWrapper(io.BytesIO(), encoding="utf-8", errors="strict")
    print(*texts, file=out)
    out.flush()
    return out.buffer.getvalue()


def test_a_name_with_a_lone_surrogate_typed_in_the_form_starts_saves_and_prints(person):
    from tutor.views.start import MazeExperiment

    form = MazeExperiment(start=False)
    form.name.value = "a\udcff"  # as the page's JSON "a\\udcff" arrives
    form.go.click()
    assert form.trainee == "a\ufffd" and form.problem is None
    tutor = form.current
    tutor.pad.draw(GOOD)
    assert tutor.run_file.is_file() and not tutor.unsaved
    assert json.loads(tutor.run_file.read_text())["trainee"]["name"] == "a\ufffd"
    assert "a\ufffd".encode() in _strict_print(form.note.value, tutor.status.value)


def test_tutor_trainee_in_latin1_bytes_is_read_as_latin1(person):
    import os

    from tutor.framework import Trainee
    from tutor.views.start import MazeExperiment

    os.environb[b"TUTOR_TRAINEE"] = b"Zo\xeb"
    try:
        assert Trainee.from_name().name == "Zoë"
        form = MazeExperiment(start=True)
        assert form.name.value == "Zoë" and form.name.disabled and form.trainee == "Zoë"
    finally:
        del os.environb[b"TUTOR_TRAINEE"]


def _run_file_named(folder, name: str):
    """A finished VF run of 3 demos whose file names the trainee ``name`` (as JSON writes
    a lone surrogate: an escape)."""
    from tutor.framework import Trainee
    from tutor.tasks.maze import MazeTask
    from tutor.tasks.maze_run import MazeRun

    run = MazeRun.new("VF", MazeTask(), trainee=Trainee.from_name("Mai"))
    for demo in bundled_demos("maze_good")[:3]:
        run.add_demo(demo)
    run.finish()
    doc = run.to_dict()
    doc["trainee"]["name"] = name
    path = folder / doc["trainee"]["key"] / "VF.json"
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps(doc), encoding="utf-8")  # ensure_ascii: "\\udcff"
    return path


def test_a_run_file_naming_a_lone_surrogate_loads_saves_and_prints(tmp_path):
    from tutor.tasks.maze import MazeTask
    from tutor.tasks.maze_run import MazeRun

    path = _run_file_named(tmp_path, "a\udcff")
    assert "\\udcff" in path.read_text()
    run = MazeRun.load(path, MazeTask())
    assert run.record.trainee.name == "a\ufffd"
    run.save(tmp_path / "again.json")
    assert json.loads((tmp_path / "again.json").read_text())["trainee"]["name"] == "a\ufffd"
    assert "a\ufffd".encode() in _strict_print(run.record.trainee.name, run.record.label)


def test_the_class_command_prints_a_run_naming_a_lone_surrogate(tmp_path):
    import os
    import subprocess
    import sys

    _run_file_named(tmp_path / "class", "a\udcff")
    env = {**os.environ, "PYTHONIOENCODING": "utf-8:strict"}
    out = subprocess.run(
        [sys.executable, "-m", "tutor", "class", str(tmp_path / "class"), "--experiment", "1",
         "--workers", "1", "--out", str(tmp_path / "out")],
        capture_output=True, env=env, timeout=300,
    )
    assert out.returncode == 0, out.stderr.decode("utf-8", "replace")
    assert "a\ufffd".encode() in out.stdout and b"Traceback" not in out.stderr
    written = b"".join(p.read_bytes() for p in (tmp_path / "out").glob("*.csv"))
    assert "a\ufffd".encode() in written


def test_a_class_plan_naming_a_lone_surrogate_assigns_it(tmp_path):
    from tutor.framework.assignment import load_plan

    plan_file = tmp_path / "plan.json"
    plan_file.write_text(json.dumps({
        "format": "lfd-tutor-class-plan", "version": 1, "experiment": 2,
        "assign": {"a\udcff": "RF"}, "trainees": ["Zo\udceb", "Ana"],
    }))
    plan = load_plan(plan_file, ("NF", "RF", "BF", "SF"))
    got = plan.assign("a\udcff")
    assert got.condition == "RF" and got.trainee == "a\ufffd"
    assert "a\ufffd".encode() in _strict_print(got.reason, got.trainee, plan.counts)


# --------------------------------------------------------------------------- 3. path lengths

LONG_NAME = "n" * 300  # one name over NAME_MAX (255)
DEEP = "/".join(["d" * 200] * 21)  # every name fits, the whole path is over PATH_MAX
DEEP_WIDE = "/".join(["é" * 100] * 21)  # the same in bytes, half as many characters


def test_check_path_length_refuses_a_long_name_or_path_before_the_file_system_does(tmp_path):
    from tutor.errors import InvalidFileError, InvalidParameterError
    from tutor.fileio import check_path_length

    assert check_path_length(tmp_path / "fine", "x") == tmp_path / "fine"
    with pytest.raises(InvalidParameterError, match="bytes long"):
        check_path_length(tmp_path / LONG_NAME, "the folder")
    with pytest.raises(InvalidFileError, match="as a full path"):
        check_path_length(tmp_path / DEEP, "the folder", InvalidFileError)
    with pytest.raises(InvalidParameterError, match="room for the 100 bytes"):
        check_path_length(tmp_path / "/".join(["d" * 200] * 19) / ("e" * 120), "out", room=100)
    with pytest.raises(OSError) as raw:  # what the check saves everyone from
        (tmp_path / DEEP).exists()
    assert raw.value.errno == 36  # ENAMETOOLONG


@pytest.mark.parametrize("where", [LONG_NAME, DEEP], ids=["long name", "deep path"])
def test_tutor_session_dir_too_long_is_a_named_error_and_said_by_the_form(person, tmp_path,
                                                                         where):
    from tutor.errors import InvalidParameterError
    from tutor.runtime import trainee_dir
    from tutor.views.start import MazeExperiment

    person.setenv("TUTOR_RUNS_DIR", str(tmp_path / where))
    with pytest.raises(InvalidParameterError, match="TUTOR_RUNS_DIR"):
        trainee_dir("Mai Anh")
    form = MazeExperiment(start=False)
    form.name.value = "Mai Anh"
    form.go.click()
    assert form.trainee is None and "TUTOR_RUNS_DIR" in form.problem


def test_a_run_file_path_too_long_is_a_named_error(tmp_path):
    from tutor.errors import InvalidParameterError
    from tutor.views.maze_app import MazeTutor

    for where in (LONG_NAME, DEEP):
        with pytest.raises(InvalidParameterError, match="run_file"):
            MazeTutor("VF", run_file=tmp_path / where / "VF.json", trainee="Mai")


@pytest.mark.parametrize(
    "argv",
    [
        ["reproduce", "--experiment", "1", "--out", "{out}"],
        ["robustness", "--experiment", "1", "--seeds", "1", "--out", "{out}"],
        ["adaptive", "--quick", "--out", "{out}"],
        ["class", "{tmp}", "--experiment", "1", "--out", "{out}"],
    ],
    ids=["reproduce", "robustness", "adaptive", "class"],
)
@pytest.mark.parametrize("where", [LONG_NAME, DEEP], ids=["long name", "deep path"])
def test_out_too_long_is_refused_in_one_line_before_any_work(tmp_path, capsys, argv, where):
    from tutor.__main__ import main

    out = str(tmp_path / where)
    code = main([a.format(out=out, tmp=tmp_path) for a in argv])
    err = capsys.readouterr().err
    assert code == 2 and "InvalidParameterError" in err and "--out" in err
    assert err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize("option", ["class_folder", "--plan"])
def test_a_class_folder_or_plan_too_long_is_refused(tmp_path, capsys, option):
    from tutor.__main__ import main

    where = str(tmp_path / DEEP)
    argv = ["class", where if option == "class_folder" else str(tmp_path), "--experiment", "1"]
    if option == "--plan":
        argv += ["--plan", where]
    assert main(argv) == 2
    assert "InvalidFileError" in capsys.readouterr().err


def test_the_dashboard_says_a_folder_or_results_folder_is_too_long(tmp_path, person):
    from tutor.errors import InvalidParameterError
    from tutor.study.dashboard import ClassDashboard, default_class_folder

    board = ClassDashboard(tmp_path)
    for where in (LONG_NAME, DEEP_WIDE):
        board.folder.value = str(tmp_path / where)
        assert "the class folder" in board.status.value and "bytes long" in board.status.value
    near = tmp_path / ("c" * 250)  # fits; its "_results" folder beside it would not
    near.mkdir()
    board.folder.value = str(near)
    assert "No run files" in board.status.value
    board.result = board.analysis = object()  # as if there were something to save
    board.save_button.click()
    assert "the results folder" in board.status.value and "bytes long" in board.status.value
    person.setenv("TUTOR_CLASS_DIR", str(tmp_path / DEEP))
    with pytest.raises(InvalidParameterError, match="TUTOR_CLASS_DIR"):
        default_class_folder()


# --------------------------------------------------------------------------- 4. blank names


@pytest.mark.parametrize("typed", ["", "   ", "\u200b", " \t "])
def test_a_blank_name_is_refused_and_nothing_is_made(person, tmp_path, typed):
    from tutor.views.start import MazeExperiment

    form = MazeExperiment(start=True)  # a person: Start at once, nothing typed
    form.name.value = typed
    form.go.click()
    assert form.trainee is None and form.tutors == [] and not form.go.disabled
    assert "Type your name" in form.problem
    assert not (tmp_path / "sessions").exists() or not any((tmp_path / "sessions").iterdir())
    assert "e.g." in form.name.placeholder


def test_a_blank_name_with_a_hub_user_is_the_hub_user(person):
    from tutor.views.start import MazeExperiment

    person.setenv("JUPYTERHUB_USER", "mai")
    form = MazeExperiment(start=False)
    assert form.name.placeholder == "mai"
    form.go.click()
    assert form.trainee == "mai"


def test_no_name_and_none_set_is_refused_by_session_dir(person):
    from tutor.errors import InvalidParameterError
    from tutor.framework import Trainee
    from tutor.framework.record import CODE_TRAINEE
    from tutor.runtime import default_trainee, trainee_dir

    assert default_trainee() is None
    with pytest.raises(InvalidParameterError, match="no name was given"):
        trainee_dir(None)
    for blank in ("", "  ", "\u200b"):
        with pytest.raises(InvalidParameterError, match="empty"):
            Trainee.from_name(blank)
    assert Trainee.from_name(None).name == CODE_TRAINEE  # a run made from code, not typed


def test_a_headless_form_records_under_the_name_autoplay_is_given(person):
    from tutor.views.start import MazeExperiment

    person.setenv("TUTOR_HEADLESS", "1")
    form = MazeExperiment(start=False)
    form.autoplay(name="ci run")
    assert form.finished and form.trainee == "ci run" == form.name.value


# --------------------------------------------------------------------------- 5. counts


@pytest.mark.parametrize(
    "argv, words",
    [
        (["robustness", "--experiment", "1", "--seeds", "1000000000"], "at most 1000 seeds"),
        (["robustness", "--experiment", "2", "--seeds", "1001"], "at most 1000 seeds"),
        (["adaptive", "--seeds", "1000000000"], "at most 1000 seeds"),
        (["adaptive", "--variant-seeds", "5000"], "at most 1000 seeds"),
        (["reproduce", "--experiment", "1", "--seed", str(2**63)], f"at most {2**63 - 1}"),
        (["reproduce", "--experiment", "1", "--n", "1000000000"], "at most 3000 teachers"),
    ],
    ids=["robustness-1e9", "robustness-1001", "adaptive-1e9", "variant-seeds", "seed", "n"],
)
def test_counts_on_the_command_line_are_capped_in_one_line(capsys, argv, words):
    from tutor.__main__ import main

    with pytest.raises(SystemExit) as end:
        main([*argv, "--out", "unused"])
    err = capsys.readouterr().err
    assert end.value.code == 2 and words in err and err.count("\n") == 1


def test_the_caps_are_stated_in_the_help(capsys):
    from tutor.__main__ import main

    with pytest.raises(SystemExit):
        main(["robustness", "--help"])
    assert "at most 1000" in capsys.readouterr().out


def test_the_library_caps_seeds_before_any_work():
    from tutor.errors import InvalidParameterError
    from tutor.study.limits import MAX_SEEDS
    from tutor.study.report import check_seeds, robustness

    assert check_seeds(range(3)) == [0, 1, 2] and len(check_seeds(range(MAX_SEEDS))) == MAX_SEEDS
    for seeds, words in ((range(10**9), "at most 1000 seeds"), ([], "empty"), (5, "list"),
                         ("012", "list")):
        with pytest.raises(InvalidParameterError, match=words):
            robustness(1, seeds)
    with pytest.raises(InvalidParameterError, match="seed must be"):
        robustness(1, [0, -1])
    with pytest.raises(InvalidParameterError, match="seed must be"):
        robustness(1, [2**63])


def test_the_optimal_teachers_counts_are_capped_before_any_work():
    from tutor.errors import InvalidParameterError
    from tutor.study.optimal import MAX_CAP, MAX_DRAWS, compute_reference

    for options, words in (({"draws": MAX_DRAWS + 1}, "at most 20"),
                           ({"pair_draws": 10**9}, "at most 20"),
                           ({"cap": MAX_CAP + 1}, "at most 200"), ({"draws": 0}, ">= 1")):
        with pytest.raises(InvalidParameterError, match=words):
            compute_reference(**options)
