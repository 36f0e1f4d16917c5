"""The typed run record (tutor.framework.record) and the run that keeps it (TeachingRun).

- Random sequences of what a trainee can do (add, undo, reset, load, test, spend, finish,
  restore) on a real maze run and a real pick-and-place run: every refused step leaves
  the record as it was, and ``save`` then ``load`` gives the identical record back (events
  included), the same demos and the same feedback; every record written is valid against
  the published JSON Schema (``run_record.schema.json``).
- The loader and the schema agree on what a run record is: the same corruptions are
  refused by both, and where the loader is stricter than the schema can say, the loader
  alone is tested.
- History is kept: undone demos and earlier attempts survive a resume; a Load of another
  run or into a finished run is refused and changes nothing.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import json
import tempfile
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from tests.helpers import shared_maze_task, shared_pickplace_task
from tutor.demofiles import bundled_demos
from tutor.errors import InvalidFileError, InvalidParameterError, WrongRunError
from tutor.framework import RunOverError, RunRecord, Trainee
from tutor.framework import record as record_module
from tutor.framework.record import EVENT_KINDS
from tutor.tasks.maze_run import MazeRun
from tutor.tasks.pickplace_protocol import PickPlaceRun

SCHEMA_PATH = Path(record_module.__file__).with_name("run_record.schema.json")
SCHEMA = json.loads(SCHEMA_PATH.read_text())
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)


# Built once and reached through functions rather than fixtures, so that hypothesis
# reports a failing case as its steps alone (the tasks are the session's shared ones:
# shared_maze_task() is the maze_task fixture's object, shared_pickplace_task() the
# pickplace_task fixture's).


@functools.cache
def _demos() -> tuple:
    """Five recorded maze demonstrations (bundled with the tutor)."""
    return tuple(bundled_demos("maze_good"))


@functools.cache
def _donor(condition: str) -> RunRecord:
    """Another trainee's record of the same maze run (2 demos, finished)."""
    run = MazeRun.new(condition, shared_maze_task(), trainee=Trainee.from_name("Grace"))
    run.add_demo(_demos()[3])
    run.add_demo(_demos()[1])
    run.finish()
    return run.record


@pytest.fixture(scope="module")
def demos():
    return _demos()


@pytest.fixture(scope="module")
def donors():
    return {c: _donor(c) for c in ("NF", "VF", "VR")}


def test_the_schema_is_a_valid_draft_2020_12_schema():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    kinds = SCHEMA["$defs"]["event"]["properties"]["kind"]["enum"]
    assert tuple(kinds) == EVENT_KINDS  # one list of event kinds, in both


# ------------------------------------------------------------------ property tests


def _try(run, refused, action, kinds: list[str]) -> list[str]:
    """Do ``action``; when ``refused`` (an error class) is expected, check that it is raised
    and that nothing changed. Returns the event kinds the step appends."""
    before, n_before = run.record, run.n_demos
    if refused is not None:
        with pytest.raises(refused):
            action()
        assert run.record == before and run.n_demos == n_before
        return []
    action()
    return kinds


def _check_consistent(run) -> None:
    """What must hold after every step: the record and the session agree."""
    rec = run.record
    assert run.attempt is rec.current and run.attempt.n_demos == run.session.n_demos
    assert all(a.ended for a in rec.attempts[:-1])  # why each earlier attempt ended
    assert rec.current.ended == ""
    assert [e.attempt for e in rec.events] == sorted(e.attempt for e in rec.events)
    assert rec.events[-1].attempt == len(rec.attempts) - 1
    assert all(t.after_demo <= a.n_demos for a in rec.attempts for t in a.tests)


def _save_and_load(run, cls, task):
    """Save ``run``, load a fresh run from the file; returns it and the file's JSON."""
    with tempfile.TemporaryDirectory() as folder:
        path = run.save(Path(folder) / "run.json")
        data = json.loads(path.read_text())
        loaded = cls.load(path, task)
    VALIDATOR.validate(data)  # (a) every record written is valid against the schema
    assert RunRecord.from_dict(data) == run.record
    return loaded, data


def _efficacies(run) -> list[float]:
    return [r.efficacy for r in run.session.history]


ADD_STEP = st.tuples(st.just("add"), st.integers(0, 4))
MAZE_STEPS = st.one_of(
    ADD_STEP,
    ADD_STEP,
    ADD_STEP,  # three times: most of what a trainee does is add demos
    st.tuples(st.just("undo")),
    st.tuples(st.just("reset")),
    st.tuples(st.just("load"), st.lists(st.integers(0, 4), min_size=1, max_size=2)),
    st.tuples(st.just("replace")),
    st.tuples(st.just("test"), st.lists(st.integers(0, 139), min_size=1, max_size=3)),
    st.tuples(st.just("undo")),
    st.tuples(st.just("finish")),
    st.tuples(st.just("restore"), st.integers(0, 2)),
    st.tuples(st.just("restore"), st.integers(0, 2)),
)


def _maze_step(run, step, demos, donor) -> list[str]:
    kind, *args = step
    over = RunOverError if run.finished else None
    if kind == "add":
        i = args[0]
        return _try(run, over, lambda: run.add_demo(demos[i], chosen_by=f"demo {i}"), ["add"])
    if kind == "undo":
        refused = over or (InvalidParameterError if run.n_demos == 0 else None)
        return _try(run, refused, run.undo, ["undo"])
    if kind == "reset":
        return _try(run, None, run.reset, ["reset"])
    if kind == "load":
        items = [(demos[i], {"chosen_by": "file"}) for i in args[0]]
        kinds = ["add"] * len(items) + ["load"]
        return _try(run, over, lambda: run.add_demos(items, "demos.json"), kinds)
    if kind == "replace":
        refused = WrongRunError if run.finished else None
        return _try(run, refused, lambda: run.replace_with(donor, "grace.json"), ["load"])
    if kind == "test":
        refused = InvalidParameterError if run.n_demos == 0 else None
        return _try(run, refused, lambda: run.test(args[0]), ["test"])
    if kind == "finish":
        return _try(run, None, run.finish, [] if run.finished else ["finish"])
    index = args[0]
    refused = None if index < len(run.record.attempts) - 1 else InvalidParameterError
    return _try(run, refused, lambda: run.restore(index), ["restore"])


@settings(
    max_examples=50,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(
    condition=st.sampled_from(["NF", "VF", "VR"]),
    steps=st.lists(MAZE_STEPS, min_size=3, max_size=8),
)
def test_any_maze_run_comes_back_identical_from_its_file(condition, steps):
    maze = shared_maze_task()
    run = MazeRun.new(condition, maze, trainee=Trainee.from_name("Zoë"))
    expected = ["start"]
    for step in steps:
        kinds = _maze_step(run, step, _demos(), _donor(condition))
        event(f"{step[0]} {'done' if kinds or step[0] == 'finish' else 'refused'}")
        expected += kinds
        _check_consistent(run)
    assert [e.kind for e in run.record.events] == expected
    loaded, _ = _save_and_load(run, MazeRun, maze)
    assert loaded.record == run.record  # every attempt, demo, test and event
    assert loaded.n_demos == run.n_demos and loaded.finished == run.finished
    assert _efficacies(loaded) == _efficacies(run)  # the same feedback, the latest included
    assert loaded.compliance == run.compliance


DEMO_STEP = st.tuples(st.just("demo"), st.integers(0, 99), st.integers(0, 2**16))
PICKPLACE_STEPS = st.one_of(
    DEMO_STEP,
    DEMO_STEP,
    DEMO_STEP,  # three times: most of what a trainee does is demonstrate
    st.tuples(st.just("spend"), st.floats(0.0, 900.0)),
    st.tuples(st.just("spend"), st.floats(0.0, 900.0)),
    st.tuples(st.just("test"), st.lists(st.integers(0, 99), min_size=1, max_size=3)),
    st.tuples(st.just("test"), st.lists(st.integers(0, 99), min_size=1, max_size=3)),
    st.tuples(st.just("undo")),
    st.tuples(st.just("undo")),
    st.tuples(st.just("finish")),
    st.tuples(st.just("reset")),
)


def _pickplace_step(run, step) -> list[str]:
    kind, *args = step
    if kind == "demo":
        plant, seed = args
        seconds = run.task.duration(run.task.demonstrate(plant, seed))
        # a demo that cannot end by the 15-minute cap is not started
        refused = RunOverError if run.finished or not run.fits(seconds) else None
        return _try(run, refused, lambda: run.demonstrate(plant, rng=seed), ["add"])
    if kind == "spend":
        return _try(run, None, lambda: run.spend(args[0]), ["spend"])
    if kind == "test":
        plants = args[0]
        during = not run.finished
        refused = None
        if during and run.condition != "SF":
            refused = RunOverError
        elif run.n_demos == 0:
            refused = InvalidParameterError
        elif during and run.realisation_seconds * len(plants) > run.remaining:
            refused = RunOverError
        return _try(run, refused, lambda: run.test(plants), ["test"])
    if kind == "undo":
        refused = InvalidParameterError if run.n_demos == 0 else None
        # a clock that ran out does not stop an Undo (no time comes back); Finish does
        refused = refused or (RunOverError if run.attempt.finished else None)
        return _try(run, refused, run.undo, ["undo"])
    if kind == "finish":
        return _try(run, None, run.finish, [] if run.attempt.finished else ["finish"])
    return _try(run, None, run.reset, ["reset"])


@settings(
    max_examples=20,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(
    condition=st.sampled_from(["NF", "RF", "BF", "SF"]),
    steps=st.lists(PICKPLACE_STEPS, min_size=3, max_size=7),
)
def test_any_pickplace_run_comes_back_identical_with_its_clock(condition, steps):
    pickplace = shared_pickplace_task()
    run = PickPlaceRun(condition, pickplace, trainee=Trainee.from_name("Zoë"), run=2)
    expected = ["start"]
    for step in steps:
        kinds = _pickplace_step(run, step)
        event(f"{step[0]} {'done' if kinds or step[0] == 'finish' else 'refused'}")
        expected += kinds
        _check_consistent(run)
        assert run.elapsed >= sum(d.seconds for d in run.attempt.demos)
        if run.remaining <= 0:
            event("the 15 minutes ran out")
    assert [e.kind for e in run.record.events] == expected
    loaded, data = _save_and_load(run, PickPlaceRun, pickplace)
    assert data["run"] == 2 and data["experiment"] == 2
    assert loaded.record == run.record
    assert loaded.n_demos == run.n_demos and loaded.finished == run.finished
    assert loaded.elapsed == pytest.approx(run.elapsed, abs=1e-9)
    assert loaded.remaining == pytest.approx(run.remaining, abs=1e-9)
    assert _efficacies(loaded) == _efficacies(run)
    assert loaded.shown_plants().tolist() == run.shown_plants().tolist()


# ------------------------------------------------------------------ loader and schema agree


@pytest.fixture(scope="module")
def valid(maze_task, demos):
    """A rich valid record dict: two attempts (the first reset, with an undone demo and a
    robot test), VR compliance, a finished current attempt."""
    run = MazeRun.new("VR", maze_task, trainee=Trainee.from_name("Zoë"))
    run.add_demo(demos[0], chosen_by="plan")
    run.test([3, 70])
    run.add_demo(demos[2], mistake="slip")
    run.undo()
    run.reset()
    run.add_demo(demos[4], point=[0.05, 0.03])
    run.finish()
    data = run.to_dict()
    VALIDATOR.validate(data)
    assert RunRecord.from_dict(data) == run.record
    return data


def _put(path: str, value):
    """A corruption: the entry at ``path`` ("a.0.b") set to ``value``."""

    def change(data):
        *keys, last = [int(k) if k.isdigit() else k for k in path.split(".")]
        for k in keys:
            data = data[k]
        data[last] = value

    change.__name__ = f"{path}={value!r}"[:60]
    return change


def _drop(path: str):
    def change(data):
        *keys, last = [int(k) if k.isdigit() else k for k in path.split(".")]
        for k in keys:
            data = data[k]
        del data[last]

    change.__name__ = f"no {path}"
    return change


#: (corruption, words the loader's message must hold): refused by both the schema and
#: RunRecord.from_dict
BOTH_REFUSE = [
    (_drop("format"), "not an lfd-tutor run record"),
    (_put("format", "lfd-tutor-session"), "older lfd-tutor"),
    (_put("format", "lfd-tutor-runs"), "not an lfd-tutor run record"),
    (_put("version", 99), "version 99 is not supported"),
    (_put("version", True), "version True is not supported"),
    (_put("version", "1"), "version '1' is not supported"),
    (_drop("attempts"), "has no 'attempts'"),
    (_drop("trainee"), "has no 'trainee'"),
    (_put("notes", "hand-edited"), "unknown entries 'notes'"),
    (_put("attempts", []), "attempts: must hold at least one attempt"),
    (_put("attempts", {}), "attempts: must be a list"),
    (_put("events", "none"), "events: must be a list"),
    (_put("experiment", 0), "experiment: must be a whole number >= 1"),
    (_put("experiment", "1"), "experiment: must be a whole number"),
    (_put("run", -1), "run: must be a whole number >= 1"),
    (_put("run", True), "run: must be a whole number"),
    (_put("practice", "no"), "practice: must be true or false"),
    (_put("task", 3), "task: must be text"),
    (_put("tool_version", None), "tool_version: must be text"),
    (_drop("trainee.key"), "trainee: has no 'key'"),
    (_put("trainee.email", "z@example.org"), "trainee: has unknown entries 'email'"),
    (_put("created", "yesterday"), "created: must be a date and time"),
    (_put("created", "01/12/2026 09:14"), "created: must be a date and time"),
    (_put("attempts.0.started", 20261201), r"attempts\[0\]\.started: must be text"),
    (_drop("attempts.1.demos"), r"attempts\[1\]: has no 'demos'"),
    (_put("attempts.1.notes", ""), r"attempts\[1\]: has unknown entries 'notes'"),
    (_put("attempts.0.other_seconds", -1.5), r"attempts\[0\]\.other_seconds: must be a finite"),
    (_put("attempts.0.other_seconds", -(10**400)), r"attempts\[0\]\.other_seconds"),
    (_put("attempts.0.finished", "no"), r"attempts\[0\]\.finished: must be true or false"),
    (_put("attempts.0.ended", "deleted"), r"attempts\[0\]\.ended: must be one of"),
    (_put("attempts.0.demos.0.samples", "x"), r"attempts\[0\]\.demos\[0\]\.samples: must be a"),
    (_put("attempts.0.demos.0.samples", []), r"demos\[0\]\.samples: must be a table"),
    (_put("attempts.0.demos.0.samples", [[]]), r"demos\[0\]\.samples: must be a table"),
    (_put("attempts.0.demos.0.samples.3.1", "0.1"), r"demos\[0\]\.samples\[3\]\[1\]: must be a"),
    (_put("attempts.0.demos.0.samples.3.1", True), r"demos\[0\]\.samples\[3\]\[1\]: must be a"),
    (_put("attempts.0.demos.0.seconds", -3.0), r"demos\[0\]\.seconds: must be a finite number"),
    (_put("attempts.0.demos.0.shown", "all"), r"demos\[0\]\.shown: must be a list"),
    (_put("attempts.0.demos.0.shown", [1, -2]), r"demos\[0\]\.shown\[1\]: must be a whole"),
    (_put("attempts.0.demos.0.followed_rule", "yes"), r"followed_rule: must be true or false"),
    (_put("attempts.0.demos.0.condition", ["a"]), r"demos\[0\]\.condition\[0\]: must be a"),
    (_put("attempts.0.demos.0.chosen_by", 3), r"demos\[0\]\.chosen_by: must be text"),
    (_put("attempts.0.demos.0.colour", "red"), r"demos\[0\]: has unknown entries 'colour'"),
    (_put("attempts.0.undone", None), r"attempts\[0\]\.undone: must be a list"),
    (_put("attempts.0.tests.0.after_demo", -1), r"tests\[0\]\.after_demo: must be a whole"),
    (_put("attempts.0.tests.0.plants", [True]), r"tests\[0\]\.plants\[0\]: must be a whole"),
    (_put("attempts.0.tests.0.plants", 3), r"tests\[0\]\.plants: must be a list"),
    (_put("events.2.kind", "teleport"), r"events\[2\]\.kind: must be one of"),
    (_put("events.2.n_demos", -1), r"events\[2\]\.n_demos: must be a whole number >= 0"),
    (_put("events.2.attempt", 1.5), r"events\[2\]\.attempt: must be a whole number"),
    (_put("events.2.at", "noon"), r"events\[2\]\.at: must be a date and time"),
    (_drop("events.2.at"), r"events\[2\]: has no 'at'"),
    (_put("events.2.detail", ["a"]), r"events\[2\]\.detail: must be text"),
]

#: where the loader is stricter than the schema can say (the schema accepts these; the
#: loader refuses them): rows of one demo of different lengths, a robot test after a demo
#: the attempt does not hold, an event in an attempt the record does not hold, numbers
#: beyond a float's range (JSON numbers have no bound in a schema), and stamps of the right
#: shape that are no date ("2026-13-45")
LOADER_ONLY = [
    (_put("attempts.0.demos.0.samples", [[0.0, 0.1, 0.2], [1.0, 0.1]]), "same columns"),
    (_put("attempts.0.tests.0.after_demo", 5), r"attempts\[0\]\.tests\[0\]: is after demo 5"),
    (_put("events.3.attempt", 7), r"events\[3\]: names attempt 8 of 2"),
    (_put("attempts.0.other_seconds", 10**400), "too large"),
    (_put("attempts.0.demos.0.seconds", float("inf")), "must be a finite number"),
    (_put("attempts.0.demos.0.samples.2.1", 10**400), "too large"),
    (_put("experiment", 1.0), "experiment: must be a whole number"),  # 1.0 is a JSON integer
    (_put("created", "2026-13-45T09:14:03Z"), "created: must be a date and time"),
    (_put("events.1.at", "2026-02-30T25:61:00Z"), r"events\[1\]\.at: must be a date and time"),
]


def _corrupted(valid, change) -> dict:
    data = copy.deepcopy(valid)
    change(data)
    return data


@pytest.mark.parametrize(("change", "words"), BOTH_REFUSE, ids=[c.__name__ for c, _ in BOTH_REFUSE])
def test_schema_and_loader_refuse_the_same_corruptions(valid, change, words):
    data = _corrupted(valid, change)
    assert list(VALIDATOR.iter_errors(data)), "the schema accepts it"
    with pytest.raises(InvalidFileError, match=words) as caught:
        RunRecord.from_dict(data)
    assert "Traceback" not in str(caught.value)


@pytest.mark.parametrize(("change", "words"), LOADER_ONLY, ids=[c.__name__ for c, _ in LOADER_ONLY])
def test_loader_refuses_what_the_schema_cannot_express(valid, change, words):
    data = _corrupted(valid, change)
    assert not list(VALIDATOR.iter_errors(data)), "the schema refuses it too: move the case"
    with pytest.raises(InvalidFileError, match=words):
        RunRecord.from_dict(data)


def test_there_are_enough_corruptions():
    assert len(BOTH_REFUSE) >= 15 and len(LOADER_ONLY) >= 3


def test_a_corrupt_run_file_is_refused_by_the_run_loader(maze_task, valid, tmp_path):
    path = tmp_path / "run.json"
    path.write_text(json.dumps(_corrupted(valid, _put("events.3.attempt", 7))))
    with pytest.raises(InvalidFileError, match="names attempt 8 of 2"):
        MazeRun.load(path, maze_task)
    path.write_text(json.dumps(valid).replace('"other_seconds": 0.0', '"other_seconds": 1e999'))
    with pytest.raises(InvalidFileError, match="too large"):
        MazeRun.load(path, maze_task)
    path.write_text(json.dumps(valid))
    assert MazeRun.load(path, maze_task).record == RunRecord.from_dict(valid)


# ------------------------------------------------------------------ history is kept


def test_undo_events_survive_resume(maze_task, demos, tmp_path):
    run = MazeRun.new("VF", maze_task)
    for i in (0, 1, 2):
        run.add_demo(demos[i])
    taken = run.attempt.demos[2]
    run.undo()
    run.add_demo(demos[3])
    loaded = MazeRun.load(run.save(tmp_path / "run.json"), maze_task)
    events = [(e.kind, e.n_demos) for e in loaded.record.events]
    assert events == [("start", 0), ("add", 1), ("add", 2), ("add", 3), ("undo", 2), ("add", 3)]
    assert loaded.attempt.undone == (taken,)
    assert loaded.attempt.demos == run.attempt.demos and loaded.n_demos == 3
    expected = MazeRun.new("VF", maze_task)
    for i in (0, 1, 3):
        expected.add_demo(demos[i])
    assert loaded.session.latest.efficacy == expected.session.latest.efficacy


def test_reset_keeps_the_attempt_and_restore_brings_it_back(maze_task, demos, tmp_path):
    run = MazeRun.new("VR", maze_task)
    run.add_demo(demos[0])
    run.add_demo(demos[4])
    first, efficacy = run.attempt, run.session.latest.efficacy
    run.reset()
    assert run.n_demos == 0 and run.session.latest is None
    assert run.record.attempts == (dataclasses.replace(first, ended="reset"), run.attempt)
    before = run.record
    with pytest.raises(InvalidParameterError, match="no earlier attempt 2"):
        run.restore(1)  # the current attempt is not an earlier one
    assert run.record == before
    run.restore(0)
    assert run.attempt.demos == first.demos and run.n_demos == 2
    assert run.session.latest.efficacy == efficacy and run.compliance == [
        d.followed_rule for d in first.demos
    ]
    assert [a.ended for a in run.record.attempts] == ["reset", "restore", ""]
    last = run.record.events[-1]
    assert (last.kind, last.detail, last.attempt, last.n_demos) == ("restore", "1", 2, 2)
    loaded = MazeRun.load(run.save(tmp_path / "run.json"), maze_task)
    assert loaded.record == run.record and loaded.session.latest.efficacy == efficacy


@pytest.fixture(scope="module")
def other_runs(maze_task, pickplace_task, demos):
    """Records a VF maze run must not load: another condition, experiment, practice run."""
    vr = MazeRun.new("VR", maze_task, trainee=Trainee.from_name("Grace"))
    vr.add_demo(demos[0])
    practice = MazeRun.new("VF", maze_task, trainee=Trainee.from_name("Grace"), practice=True)
    bf = PickPlaceRun("BF", pickplace_task, trainee=Trainee.from_name("Grace"), run=3)
    return {
        "another condition": (vr.record, "experiment 1, VR run"),
        "a practice run": (practice.record, "experiment 1, VF run (practice)"),
        "another experiment": (bf.record, "experiment 2, BF run 3"),
    }


@pytest.mark.parametrize("which", ["another condition", "a practice run", "another experiment"])
def test_replace_with_another_run_is_refused_and_changes_nothing(
    maze_task, demos, other_runs, which
):
    run = MazeRun.new("VF", maze_task, trainee=Trainee.from_name("Zoë"))
    run.add_demo(demos[1])
    before, efficacy = run.record, run.session.latest.efficacy
    other, label = other_runs[which]
    with pytest.raises(WrongRunError) as caught:
        run.replace_with(other, "grace.json")
    message = str(caught.value)
    assert f"Grace's {label}" in message and "this tutor is experiment 1, VF run" in message
    assert run.record == before and run.session.latest.efficacy == efficacy


def test_replace_with_into_a_finished_run_is_refused(maze_task, demos, donors):
    run = MazeRun.new("VF", maze_task, trainee=Trainee.from_name("Zoë"))
    run.add_demo(demos[1])
    run.finish()
    before = run.record
    with pytest.raises(WrongRunError) as caught:
        run.replace_with(donors["VF"], "grace.json")
    message = str(caught.value)
    assert "experiment 1, VF run is finished" in message and "Grace's" in message
    assert run.record == before and run.n_demos == 1
    run.reset()  # after Reset the same file loads, as a new attempt
    run.replace_with(donors["VF"], "grace.json")
    assert run.attempt.demos == donors["VF"].current.demos and not run.finished
    assert [a.ended for a in run.record.attempts] == ["reset", "load", ""]


def test_a_same_run_load_keeps_this_trainee_and_the_old_attempt(maze_task, demos, donors):
    run = MazeRun.new("NF", maze_task, trainee=Trainee.from_name("Zoë"))
    run.add_demo(demos[0])
    mine = run.attempt
    run.replace_with(donors["NF"], "grace.json")
    assert run.record.trainee.name == "Zoë"
    assert run.record.attempts[0].demos == mine.demos and run.n_demos == 2
    assert np.array_equal(run.session.demos[0], np.asarray(donors["NF"].current.demos[0].samples))
