"""Tests of the task-agnostic framework: metrics, failure rules, the session and its files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tutor.errors import InvalidDemoError, InvalidFileError, InvalidParameterError
from tutor.framework import (
    AMBIGUOUS,
    INCORRECT,
    UNDEMONSTRATED,
    TeachingSession,
    Thresholds,
    efficacy,
    efficiency,
    session_score,
    similarity,
)
from tutor.framework.failures import demo_warnings, is_ambiguous, undemonstrated_warning
from tutor.tasks.maze import MazeTask

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


@pytest.fixture(scope="module")
def task():
    return MazeTask()


def demo_from(task, start, seed=0):
    return task.layout.reference_path(start, np.random.default_rng(seed), jitter=0.003)


def test_session_record_fields_and_undemonstrated_set(task):
    s = TeachingSession(task)
    r = s.add_demo(demo_from(task, (0.03, 0.03)))
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


def test_rejected_demo_leaves_session_unchanged(task):
    s = TeachingSession(task)
    s.add_demo(demo_from(task, (0.03, 0.03)))
    before = s.to_dict()
    bad = demo_from(task, (0.1, 0.03))
    bad[10, 1] = np.nan
    for raw in (bad, bad[:1], bad[:, :2], bad * [1, 100, 100]):
        with pytest.raises(InvalidDemoError):
            s.add_demo(raw)
    assert s.to_dict() == before and s.n_demos == 1


def test_demo_outside_the_maze_is_accepted_and_flagged_incorrect(task):
    s = TeachingSession(task)
    t = np.linspace(0, 1, 50)
    start, end = np.array([0.05, 0.03]), task.layout.target_center
    straight = np.column_stack([t, start + np.outer(t, end - start)])  # through both obstacles
    r = s.add_demo(straight)
    assert not r.demo_passed and "hit obstacle" in r.demo_reason
    assert INCORRECT in r.kinds


def test_undo_and_remove(task):
    s = TeachingSession(task)
    first = s.add_demo(demo_from(task, (0.03, 0.03)))
    s.add_demo(demo_from(task, (0.17, 0.03)))
    back = s.undo()
    assert s.n_demos == 1 and back.efficacy == first.efficacy
    s.add_demo(demo_from(task, (0.17, 0.03)))
    third = s.add_demo(demo_from(task, (0.10, 0.03)))
    again = s.remove_demo(1)
    assert s.n_demos == 2
    fresh = TeachingSession(task)
    fresh.add_demo(demo_from(task, (0.17, 0.03)))
    assert again.efficacy == fresh.add_demo(demo_from(task, (0.10, 0.03))).efficacy
    assert third.n_demos == 3
    with pytest.raises(InvalidParameterError):
        s.remove_demo(7)
    s.reset()
    with pytest.raises(InvalidParameterError):
        s.undo()


def test_feedback_modes_choose_r(task):
    demo = demo_from(task, (0.03, 0.03))
    assert TeachingSession(task, feedback="none").add_demo(demo).shown.size == 0
    batch = TeachingSession(task, feedback="batch", batch=[0, 19, 139]).add_demo(demo)
    assert batch.shown.tolist() == [0, 19, 139]
    replay = TeachingSession(task, feedback="replay").add_demo(demo)
    assert replay.shown.size == 1
    assert np.linalg.norm(task.conditions[replay.shown[0]] - [0.03, 0.03]) < 0.01
    sel = TeachingSession(task, feedback="selected").add_demo(demo, shown=[5, 6])
    assert sel.shown.tolist() == [5, 6]
    with pytest.raises(InvalidParameterError):
        TeachingSession(task, feedback="sometimes")
    with pytest.raises(InvalidParameterError):
        TeachingSession(task, feedback="batch")


def test_json_round_trip_gives_identical_results(task, tmp_path):
    s = TeachingSession(task, thresholds=Thresholds(delta_upper=0.03))
    for start in [(0.03, 0.03), (0.17, 0.03), (0.10, 0.03)]:
        s.add_demo(demo_from(task, start))
    path = s.save(tmp_path / "session.json")
    loaded = TeachingSession.load(path, task)
    assert loaded.to_dict()["records"] == s.to_dict()["records"]
    assert [r.efficacy for r in loaded.history] == [r.efficacy for r in s.history]
    np.testing.assert_array_equal(loaded.realisations, s.realisations)
    assert loaded.thresholds == s.thresholds
    assert not list(tmp_path.glob(".*.tmp"))  # the atomic write left no temporary file


HEAD = '{"format": "lfd-tutor-session", "version": 1, "task": {"name": "maze"}, '


@pytest.mark.parametrize(
    "content, words",
    [
        ("", "empty"),
        (
            HEAD + '"demos": [[',
            "not valid JSON",
        ),
        ('{"format": "something-else"}', "not an lfd-tutor session"),
        ('{"format": "lfd-tutor-session", "version": 99}', "version"),
        (
            HEAD.replace("maze", "pickplace") + '"demos": []}',
            "task",
        ),
        (
            HEAD + '"demos": [[[0, NaN, 1]]]}',
            "not valid JSON",
        ),
        (
            HEAD + '"demos": [[[0, 1]]]}',
            "invalid data",
        ),
        (
            HEAD + '"demos": "x"}',
            "demos",
        ),
        (
            '{"format": "lfd-tutor-session", "version": 1, "task": {"name": "maze"}, '
            '"demos": [], "feedback": "hypnosis"}',
            "invalid data",
        ),
        ("[" * 100000 + "]" * 100000, "not"),
    ],
)
def test_corrupt_session_files_give_clear_errors(task, tmp_path, content, words):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(InvalidFileError, match=words):
        TeachingSession.load(path, task)


def test_pickle_file_is_refused(task, tmp_path):
    import pickle

    path = tmp_path / "evil.json"
    path.write_bytes(pickle.dumps({"format": "lfd-tutor-session"}))
    with pytest.raises(InvalidFileError):
        TeachingSession.load(path, task)


def test_saving_over_a_session_replaces_it_whole(task, tmp_path):
    s = TeachingSession(task)
    s.add_demo(demo_from(task, (0.03, 0.03)))
    path = s.save(tmp_path / "s.json")
    s.add_demo(demo_from(task, (0.17, 0.03)))
    s.save(path)
    assert len(json.loads(path.read_text())["demos"]) == 2


def test_explicit_condition_is_kept_and_round_trips(task, tmp_path):
    s = TeachingSession(task)
    demo = demo_from(task, (0.03, 0.03))
    s.add_demo(demo, condition=[0.031, 0.029])
    np.testing.assert_allclose(s.conditions[0], [0.031, 0.029])
    with pytest.raises(InvalidParameterError, match="condition"):
        s.add_demo(demo, condition=[0.1, 0.2, 0.3])
    with pytest.raises(InvalidParameterError, match="condition"):
        s.add_demo(demo, condition=[np.nan, 0.2])
    assert s.n_demos == 1
    loaded = TeachingSession.load(s.save(tmp_path / "s.json"), task)
    np.testing.assert_allclose(loaded.conditions[0], [0.031, 0.029])
    assert loaded.latest.efficacy == s.latest.efficacy


def test_a_copied_session_shares_its_task():
    import copy

    from tutor.tasks.maze import MazeTask

    task = MazeTask()
    session = TeachingSession(task)
    twin = copy.deepcopy(session)
    assert twin.task is task and twin is not session
