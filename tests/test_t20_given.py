"""Issue 20, part A: each demo records how it was given, and an own-hand demo its recording.

Round trips through the run file, old records without the fields, hostile values, and
who sets what: an own hand, the guided hand, a Load, the maze's strokes, simulated
teachers.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from tutor.errors import InvalidFileError, InvalidParameterError
from tutor.framework import record as record_module
from tutor.framework.record import HOW_GIVEN, Demo, RunRecord, round_recording
from tutor.limits import MAX_RECORDING_SAMPLES
from tutor.tasks.maze import MazeTask
from tutor.tasks.maze_run import MazeRun
from tutor.tasks.pickplace import PickPlaceTask
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.tasks.recording import steady_hand
from tutor.teachers.maze import MazeTeacher
from tutor.teachers.pickplace import PickPlaceTeacher
from tutor.teachers.traits import DEFAULT_POPULATION

SCHEMA = json.loads(Path(record_module.__file__).with_name("run_record.schema.json").read_text())
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)


@pytest.fixture(scope="module")
def mixed_run(pickplace_task):
    """An NF run with an own-hand demo, a guided one with a mistake and a loaded one."""
    run = PickPlaceRun("NF", pickplace_task)
    own = steady_hand(pickplace_task, 18, rng=7)
    run.demonstrate(18, raw=own, given="own", setup_seconds=3.0)
    run.demonstrate(81, mistake="sloppy_grab", rng=1)
    run.add_demos(
        [(pickplace_task.demonstrate(88, rng=2), {"point": pickplace_task.test_points[88]})],
        "f.json",
    )
    return run, own


def test_given_and_the_recording_round_trip_through_the_run_file(
    pickplace_task, mixed_run, tmp_path
):
    run, own = mixed_run
    demos = run.attempt.demos
    assert [d.given for d in demos] == ["own", "guided", "loaded"]
    assert [d.mistake for d in demos] == ["", "sloppy_grab", ""]
    assert demos[0].recording is not None and demos[1].recording is None
    assert demos[2].recording is None
    # stored rounded: 1 ms, 0.1 mm, 0.001
    np.testing.assert_allclose(np.array(demos[0].recording), own, atol=5.01e-4)
    assert np.array(demos[0].recording)[:, 1:4].round(4).tolist() == [
        list(r[1:4]) for r in demos[0].recording
    ]
    path = run.save(tmp_path / "run.json")
    data = json.loads(path.read_text())
    VALIDATOR.validate(data)
    stored = data["attempts"][0]["demos"]
    assert [d["given"] for d in stored] == ["own", "guided", "loaded"]
    assert len(stored[0]["recording"]) == len(own) and stored[1]["recording"] is None
    back = PickPlaceRun.load(path, pickplace_task)
    assert back.record == run.record
    assert back.attempt.demos[0].recording == demos[0].recording
    # an undone demo keeps both
    back.undo()
    back.undo()
    back.undo()
    assert [d.given for d in back.attempt.undone] == ["loaded", "guided", "own"]
    again = PickPlaceRun.load(back.save(tmp_path / "undone.json"), pickplace_task)
    assert again.attempt.undone[-1].recording == demos[0].recording


def test_an_old_record_without_the_fields_still_reads(pickplace_task, mixed_run):
    run, _ = mixed_run
    data = run.to_dict()
    for attempt in data["attempts"]:
        for demo in attempt["demos"]:
            del demo["given"], demo["recording"]
    VALIDATOR.validate(data)
    old = PickPlaceRun.from_dict(data, pickplace_task)
    assert [d.given for d in old.attempt.demos] == ["", "", ""]
    assert all(d.recording is None for d in old.attempt.demos)
    assert old.n_demos == 3


@pytest.mark.parametrize(
    ("field", "value", "words", "schema_says"),
    [
        ("given", "hand", "given: must be one of", True),
        ("given", 3, "given: must be text", True),
        ("recording", "rows", "recording: must be a list", True),
        ("recording", [], "recording: must be a table of numbers", True),
        # a schema cannot say that rows have the same length, and JSON has no NaN
        ("recording", [[0, 1, 2], [1, 2]], "recording: must be a table of numbers", False),
        ("recording", [[0, "x", 2]], "recording[0][1]: must be a number", True),
        ("recording", [[0, float("nan"), 2]], "recording[0][1]: must be a finite", False),
        ("recording", [[0.0]] * (MAX_RECORDING_SAMPLES + 1), "more than the", True),
    ],
)
def test_a_hostile_given_or_recording_is_refused(
    pickplace_task, mixed_run, field, value, words, schema_says
):
    run, _ = mixed_run
    data = run.to_dict()
    data["attempts"][0]["demos"][0][field] = value
    with pytest.raises(InvalidFileError, match="demos\\[0\\]") as info:
        PickPlaceRun.from_dict(data, pickplace_task)
    assert words in str(info.value)
    assert VALIDATOR.is_valid(data) is not schema_says


def test_add_demo_checks_given_and_recording(pickplace_task):
    run = PickPlaceRun("NF", pickplace_task)
    raw = pickplace_task.demonstrate(3, rng=0)
    for options in (
        {"given": "hand"},
        {"given": None},
        {"recording": "junk"},
        {"recording": np.zeros((0, 5))},
        {"recording": np.full((3, 5), np.nan)},
    ):
        with pytest.raises(InvalidParameterError):
            run.add_demo(raw, **options)
    assert run.n_demos == 0 and len(run.record.events) == 1
    run.add_demo(raw, given="guided", recording=raw)
    assert run.attempt.demos[0].recording == round_recording(raw)


def test_every_way_of_giving_a_demo_says_so(pickplace_task, layout):
    maze = MazeTask()
    drawn = MazeRun.new("NF", maze)
    drawn.add_demo(layout.reference_path(layout.sample_starts(1, np.random.default_rng(0))[0]))
    assert drawn.attempt.demos[-1].given == "drawn"
    person = dataclasses.replace(DEFAULT_POPULATION.sample(np.random.default_rng(3)))
    person = dataclasses.replace(person, patience=2, setup_seconds=0.0)
    simulated = MazeTeacher(person, maze).teach("NF", np.random.default_rng(1))
    assert {d.given for d in simulated.attempt.demos} == {"simulated"}
    arm = PickPlaceTeacher(person, PickPlaceTask(feasibility=None)).teach(
        "NF", np.random.default_rng(2)
    )
    assert {d.given for d in (*arm.attempt.demos, *arm.attempt.undone)} == {"simulated"}
    assert set(HOW_GIVEN) == {"own", "guided", "loaded", "drawn", "simulated"}


def test_a_demo_record_equals_itself_after_json(pickplace_task):
    raw = steady_hand(pickplace_task, 11, rng=0)
    demo = Demo(samples=((0.0, 1.0),), given="own", recording=round_recording(raw))
    text = json.dumps(demo.to_dict())
    assert Demo.from_dict(json.loads(text), "demo") == demo
    rec = RunRecord.from_dict(PickPlaceRun("SF", pickplace_task).to_dict())
    assert rec.current.demos == ()
