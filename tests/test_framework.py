"""Tests of the task-agnostic framework: metrics, failure rules, the session, the run record
and its files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tutor.errors import InvalidDemoError, InvalidFileError, InvalidParameterError, WrongRunError
from tutor.framework import (
    AMBIGUOUS,
    INCORRECT,
    UNDEMONSTRATED,
    RunRecord,
    TeachingSession,
    Thresholds,
    Trainee,
    efficacy,
    efficiency,
    session_score,
    similarity,
)
from tutor.framework.failures import demo_warnings, is_ambiguous, undemonstrated_warning
from tutor.tasks.maze_run import MazeRun

# --- metrics


def test_efficacy_is_the_share_passed():
    assert efficacy([True, False, True, True]) == 0.75
    assert efficacy(np.ones(140, bool)) == 1.0
    assert efficacy(np.zeros(140, bool)) == 0.0
    with pytest.raises(InvalidParameterError):
        efficacy([])


def test_efficiency_divides_by_the_number_of_demos():
    assert efficiency(0.9, 6) == pytest.approx(0.15)
    assert efficiency(0.0, 0) == 0.0
    with pytest.raises(InvalidParameterError):
        efficiency(0.5, -1)


def test_session_score_counts_demos_to_ninety_percent():
    s = session_score([0.1, 0.5, 0.85, 0.92, 1.0])
    assert (s.n_demos, s.efficacy, s.reached) == (4, 0.92, True)
    assert s.efficiency == pytest.approx(0.23)
    never = session_score([0.1, 0.5, 0.6])
    assert (never.n_demos, never.efficacy, never.reached) == (3, 0.6, False)
    assert never.efficiency == pytest.approx(0.2)
    assert session_score([0.9]).n_demos == 1  # exactly 90 % counts
    with pytest.raises(InvalidParameterError):
        session_score([])
    with pytest.raises(InvalidParameterError):
        session_score([0.5], target=1.5)


# --- failure rules, hand-computed


def test_similarity_is_mean_aligned_distance_to_nearest_demo():
    t = np.linspace(0, 1, 5)
    a = np.column_stack([t, np.zeros(5), np.zeros(5)])
    b = np.column_stack([t, np.full(5, 3.0), np.full(5, 4.0)])  # 5 away everywhere
    c = np.column_stack([t, np.array([0, 0, 0, 0, 1.0]), np.zeros(5)])  # 1/5 away on average
    assert similarity(a, []) == (float("inf"), -1)
    assert similarity(a, [b]) == (5.0, 0)
    assert similarity(a, [b, c]) == (pytest.approx(0.2), 1)


def _warn(**overrides):
    args = dict(
        demo_passed=True,
        demo_reason="",
        delta=0.1,
        previous=0.3,
        similarity=0.05,
        nearest=1,
        ambiguity_distance=0.01,
        thresholds=Thresholds(),
    )
    args.update(overrides)
    return demo_warnings(4, **args)


def test_a_useful_distinct_demo_raises_nothing():
    assert _warn() == []


def test_a_demo_failing_the_criteria_is_incorrect_with_its_reason():
    (w,) = _warn(demo_passed=False, demo_reason="hit obstacle 2 at sample 57 of 200")
    assert w.kind == INCORRECT and w.demo == 4
    assert "hit obstacle 2 at sample 57" in w.message


@pytest.mark.parametrize("delta, previous", [(-0.1, 0.5), (0.0, 0.5)])
def test_no_gain_from_a_distinct_demo_is_incorrect(delta, previous):
    (w,) = _warn(delta=delta, previous=previous)
    assert w.kind == INCORRECT
    assert ("fell from 50% to 40%" if delta < 0 else "stayed at 50%") in w.message


def test_a_first_demo_that_teaches_nothing_says_so_without_other_demos():
    w = demo_warnings(
        1,
        demo_passed=True,
        demo_reason="",
        delta=0.0,
        previous=0.0,
        similarity=float("inf"),
        nearest=None,
        ambiguity_distance=0.01,
        thresholds=Thresholds(),
    )
    assert [x.kind for x in w] == [INCORRECT]
    assert "stayed at 0%" in w[0].message and "other demos" not in w[0].message
    assert "give another from a different place" in w[0].message


def test_no_gain_at_full_efficacy_is_not_a_failure():
    assert _warn(delta=0.0, previous=1.0) == []
    (w,) = _warn(delta=-0.2, previous=1.0)
    assert w.kind == INCORRECT


def test_incorrect_effect_names_the_earlier_wrong_demo():
    (w,) = _warn(delta=-0.1, previous=0.5, wrong_earlier=[3])
    assert "demo 3 is not a correct example" in w.message


@pytest.mark.parametrize(
    "sim, delta, expected",
    [
        (0.005, 0.0, True),  # similar, no change
        (0.005, 0.02, True),  # upper bound included
        (0.005, -0.05, True),  # lower bound included
        (0.005, 0.03, False),  # similar but helped
        (0.005, -0.06, False),  # similar but harmed: incorrect, not ambiguous
        (0.011, 0.0, False),  # not similar
    ],
)
def test_ambiguity_thresholds(sim, delta, expected):
    assert is_ambiguous(sim, delta, 0.01, Thresholds()) is expected
    kinds = [w.kind for w in _warn(similarity=sim, delta=delta, previous=0.5)]
    if expected:
        assert kinds == [AMBIGUOUS]
    else:
        assert AMBIGUOUS not in kinds


def test_ambiguous_message_names_the_nearest_demo():
    (w,) = _warn(
        similarity=0.004, delta=0.0, nearest=2, format_distance=lambda d: f"{d * 100:.1f} cm"
    )
    assert "almost the same as demo 2" in w.message and "0.4 cm" in w.message


def test_undemonstrated_warning_counts_and_locates():
    mask = np.array([True, False, True])
    w = undemonstrated_warning(mask, "start point", "start points", lambda m: "mostly on the left")
    assert w.kind == UNDEMONSTRATED and w.count == 2
    assert w.message.startswith("2 start points still fail") and "mostly on the left" in w.message
    assert undemonstrated_warning(np.zeros(3, bool), "a", "b", str) is None


def test_thresholds_validation():
    with pytest.raises(InvalidParameterError):
        Thresholds(delta_lower=0.1, delta_upper=0.0)
    with pytest.raises(InvalidParameterError):
        Thresholds(ambiguity_distance=-1.0)


# --- the session on the maze


def demo_from(task, start, seed=0):
    return task.layout.reference_path(start, np.random.default_rng(seed), jitter=0.003)


def test_session_record_fields_and_undemonstrated_set(maze_task):
    s = TeachingSession(maze_task)
    r = s.add_demo(demo_from(maze_task, (0.03, 0.03)))
    assert r.n_demos == 1 and r.delta == r.efficacy
    assert r.passed.shape == (140,) and r.passed.dtype == bool
    assert r.efficiency == pytest.approx(r.efficacy)
    assert r.demo_passed and r.demo_reason == ""
    # B^ minus (R^ or b): failing and not covered by the demo
    np.testing.assert_array_equal(r.undemonstrated, ~r.passed & ~r.demonstrated)
    assert r.demonstrated.sum() >= 1
    assert len(r.reasons) == 140 and all(
        bool(x) != p for x, p in zip(r.reasons, r.passed, strict=True)
    )
    assert np.array_equal(r.shown, np.arange(140))
    assert s.realisations.shape == (140, 200, 2)


def test_rejected_demo_leaves_session_and_run_unchanged(maze_task):
    s = TeachingSession(maze_task)
    s.add_demo(demo_from(maze_task, (0.03, 0.03)))
    run = MazeRun.new("VF", maze_task, trainee=Trainee.from_name("Ada"))
    run.add_demo(demo_from(maze_task, (0.03, 0.03)))
    history, demos, record = [r.to_dict() for r in s.history], s.demos, run.record
    bad = demo_from(maze_task, (0.1, 0.03))
    bad[10, 1] = np.nan
    for raw in (bad, bad[:1], bad[:, :2], bad * [1, 100, 100]):
        with pytest.raises(InvalidDemoError):
            s.add_demo(raw)
        with pytest.raises(InvalidDemoError):
            run.add_demo(raw)
    assert [r.to_dict() for r in s.history] == history and s.n_demos == 1
    assert all(np.array_equal(a, b) for a, b in zip(s.demos, demos, strict=True))
    assert run.record == record and run.n_demos == 1


def test_demo_outside_the_maze_is_accepted_and_flagged_incorrect(maze_task):
    s = TeachingSession(maze_task)
    t = np.linspace(0, 1, 50)
    start, end = np.array([0.05, 0.03]), maze_task.layout.target_center
    straight = np.column_stack([t, start + np.outer(t, end - start)])  # through both obstacles
    r = s.add_demo(straight)
    assert not r.demo_passed and "hit obstacle" in r.demo_reason
    assert INCORRECT in r.kinds


def test_undo_and_remove(maze_task):
    s = TeachingSession(maze_task)
    first = s.add_demo(demo_from(maze_task, (0.03, 0.03)))
    s.add_demo(demo_from(maze_task, (0.17, 0.03)))
    back = s.undo()
    assert s.n_demos == 1 and back.efficacy == first.efficacy
    s.add_demo(demo_from(maze_task, (0.17, 0.03)))
    third = s.add_demo(demo_from(maze_task, (0.10, 0.03)))
    again = s.remove_demo(1)
    assert s.n_demos == 2
    fresh = TeachingSession(maze_task)
    fresh.add_demo(demo_from(maze_task, (0.17, 0.03)))
    assert again.efficacy == fresh.add_demo(demo_from(maze_task, (0.10, 0.03))).efficacy
    assert third.n_demos == 3
    with pytest.raises(InvalidParameterError):
        s.remove_demo(7)
    s.reset()
    with pytest.raises(InvalidParameterError):
        s.undo()


def test_feedback_modes_choose_r(maze_task):
    demo = demo_from(maze_task, (0.03, 0.03))
    assert TeachingSession(maze_task, feedback="none").add_demo(demo).shown.size == 0
    batch = TeachingSession(maze_task, feedback="batch", batch=[0, 19, 139]).add_demo(demo)
    assert batch.shown.tolist() == [0, 19, 139]
    replay = TeachingSession(maze_task, feedback="replay").add_demo(demo)
    assert replay.shown.size == 1
    assert np.linalg.norm(maze_task.test_points[replay.shown[0]] - [0.03, 0.03]) < 0.01
    sel = TeachingSession(maze_task, feedback="selected").add_demo(demo, shown=[5, 6])
    assert sel.shown.tolist() == [5, 6]
    with pytest.raises(InvalidParameterError):
        TeachingSession(maze_task, feedback="sometimes")
    with pytest.raises(InvalidParameterError):
        TeachingSession(maze_task, feedback="batch")


# --- the run record on the maze: files


def test_run_record_round_trip_gives_identical_results(maze_task, tmp_path):
    run = MazeRun.new("VF", maze_task, trainee=Trainee.from_name("Zoë"))
    for start in [(0.03, 0.03), (0.17, 0.03), (0.10, 0.03)]:
        run.add_demo(demo_from(maze_task, start))
    path = run.save(tmp_path / "run.json")
    loaded = MazeRun.load(path, maze_task)
    assert loaded.record == run.record  # every field, attempt and event
    assert [r.to_dict() for r in loaded.session.history] == [
        r.to_dict() for r in run.session.history
    ]
    np.testing.assert_array_equal(loaded.session.realisations, run.session.realisations)
    assert loaded.record.trainee.name == "Zoë" and loaded.condition == "VF"
    assert not list(tmp_path.glob(".*.tmp"))  # the atomic write left no temporary file


@pytest.fixture(scope="module")
def valid_record(maze_task):
    """The dict of a VF run with one demo (corrupted by the cases below)."""
    run = MazeRun.new("VF", maze_task, trainee=Trainee.from_name("Ada"))
    run.add_demo(demo_from(maze_task, (0.03, 0.03)))
    return run.to_dict()


def _edit(change):
    """A case: ``change`` applied to a copy of the valid record, written as JSON."""

    def text(record):
        data = json.loads(json.dumps(record))
        change(data)
        return json.dumps(data)

    return text


def _set(path, value):
    def change(data):
        *keys, last = path
        for k in keys:
            data = data[k]
        data[last] = value

    return _edit(change)


@pytest.mark.parametrize(
    "content, words",
    [
        (lambda r: "", "empty"),
        (lambda r: json.dumps(r)[:-40], "not valid JSON"),
        (lambda r: '{"format": "something-else"}', "not an lfd-tutor run record"),
        (_set(("format",), "lfd-tutor-session"), "older lfd-tutor"),
        (_set(("version",), 99), "version 99 is not supported"),
        (_set(("task",), "pickplace"), "'pickplace' run of experiment 1"),
        (_set(("experiment",), 2), "run of experiment 2"),
        (_set(("condition",), "hypnosis"), "condition 'hypnosis'"),
        (lambda r: json.dumps(r).replace("0.0,", "NaN,", 1), "NaN is not allowed"),
        (lambda r: json.dumps(r).replace("0.0,", "1e400,", 1), "too large"),
        (_set(("attempts", 0, "demos", 0, "samples"), [[0, 1]]), "cannot be replayed"),
        (_set(("attempts",), "x"), "attempts: must be a list"),
        (_set(("attempts",), []), "at least one attempt"),
        (_edit(lambda d: d.pop("trainee")), "has no 'trainee'"),
        (_set(("events", 0, "kind"), "hypnosis"), r"events\[0\]\.kind"),
        (lambda r: "[" * 100000 + "]" * 100000, "nested too deeply"),
    ],
)
def test_corrupt_run_files_give_clear_errors(maze_task, tmp_path, valid_record, content, words):
    path = tmp_path / "bad.json"
    path.write_text(content(valid_record))
    with pytest.raises(InvalidFileError, match=words):
        MazeRun.load(path, maze_task)


def test_a_run_of_another_task_is_a_wrong_run(maze_task, tmp_path, valid_record):
    path = tmp_path / "other.json"
    path.write_text(_set(("task",), "pickplace")(valid_record))
    with pytest.raises(WrongRunError, match="not a 'maze' run"):
        MazeRun.load(path, maze_task)


def test_pickle_file_is_refused(maze_task, tmp_path):
    import pickle

    path = tmp_path / "evil.json"
    path.write_bytes(pickle.dumps({"format": "lfd-tutor-run"}))
    with pytest.raises(InvalidFileError, match="UTF-8|not valid JSON"):
        MazeRun.load(path, maze_task)


def test_saving_over_a_run_replaces_it_whole(maze_task, tmp_path):
    run = MazeRun.new("VF", maze_task)
    run.add_demo(demo_from(maze_task, (0.03, 0.03)))
    path = run.save(tmp_path / "s.json")
    run.add_demo(demo_from(maze_task, (0.17, 0.03)))
    run.save(path)
    saved = json.loads(path.read_text())
    assert len(saved["attempts"][-1]["demos"]) == 2
    assert RunRecord.from_dict(saved) == run.record


def test_explicit_test_point_is_kept_and_round_trips(maze_task, tmp_path):
    s = TeachingSession(maze_task)
    demo = demo_from(maze_task, (0.03, 0.03))
    s.add_demo(demo, point=[0.031, 0.029])
    np.testing.assert_allclose(s.demo_points[0], [0.031, 0.029])
    with pytest.raises(InvalidParameterError, match="point must be"):
        s.add_demo(demo, point=[0.1, 0.2, 0.3])
    with pytest.raises(InvalidParameterError, match="point must be"):
        s.add_demo(demo, point=[np.nan, 0.2])
    assert s.n_demos == 1
    run = MazeRun.new("VF", maze_task)
    run.add_demo(demo, point=[0.031, 0.029])
    with pytest.raises(InvalidParameterError, match="point must be"):
        run.add_demo(demo, point=[np.nan, 0.2])
    assert run.attempt.demos[0].point == (0.031, 0.029) and run.n_demos == 1
    loaded = MazeRun.load(run.save(tmp_path / "s.json"), maze_task)
    np.testing.assert_allclose(loaded.session.demo_points[0], [0.031, 0.029])
    assert loaded.session.latest.efficacy == s.latest.efficacy == run.session.latest.efficacy


def test_a_copied_session_shares_its_task():
    import copy

    from tutor.tasks.maze import MazeTask

    task = MazeTask()
    session = TeachingSession(task)
    twin = copy.deepcopy(session)
    assert twin.task is task and twin is not session


def test_verdict_words_come_on_first_use_and_travel_with_it(maze_task):
    """A Verdict words its causes only when read (studies read ``passed`` alone), the
    same words as before; a copy or a pickle carries the words, not the task."""
    import copy
    import pickle

    s = TeachingSession(maze_task)
    s.add_demo(demo_from(maze_task, (0.03, 0.03)))
    verdict = maze_task.judge(s.realisations, maze_task.test_points)
    assert "reasons" not in verdict.__dict__  # nothing worded yet
    words = tuple(maze_task.reason_words(c) for c in verdict.causes)
    assert verdict.reasons == words and any(words)
    for other in (copy.deepcopy(verdict), pickle.loads(pickle.dumps(verdict))):
        assert other.words is None and other.reasons == words
        np.testing.assert_array_equal(other.passed, verdict.passed)
        assert other.causes == verdict.causes
