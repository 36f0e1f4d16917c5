"""The VR condition's rule guidance."""

from __future__ import annotations

import numpy as np

from tutor.framework import TeachingSession
from tutor.tasks.maze_rules import RULE_RADIUS, advise, advise_from, followed


def test_rule_one_before_any_demo(maze_task):
    advice = advise(maze_task, TeachingSession(maze_task))
    assert advice.rule == 1 and advice.center is None
    assert followed(advice, (0.19, 0.01))


def test_rule_two_centres_on_the_first_start(maze_task):
    s = TeachingSession(maze_task)
    s.add_demo(maze_task.layout.reference_path((0.03, 0.03)))
    advice = advise(maze_task, s)
    assert advice.rule == 2
    np.testing.assert_allclose(advice.center, (0.03, 0.03))
    assert followed(advice, (0.05, 0.04)) and not followed(advice, (0.10, 0.03))


def test_rule_three_marks_a_green_start_next_to_the_most_red(maze_task):
    starts = maze_task.test_points
    first = np.array([0.03, 0.03])
    passed = starts[:, 0] < 0.12  # left green, right red
    advice = advise_from(maze_task, passed, first)
    assert advice.rule == 3 and "right" in advice.message
    i = np.argmin(np.linalg.norm(starts - advice.center, axis=1))
    assert passed[i]  # the marked start point is green
    red = starts[~passed]
    counts = [(np.linalg.norm(red - g, axis=1) <= RULE_RADIUS).sum() for g in starts[passed]]
    assert (np.linalg.norm(red - advice.center, axis=1) <= RULE_RADIUS).sum() == max(counts)
    assert followed(advice, advice.center + (0.03, 0.0))
    assert not followed(advice, (0.01, 0.01))


def test_rule_two_until_the_first_start_is_surrounded(maze_task):
    starts = maze_task.test_points
    passed = np.ones(len(starts), bool)
    passed[np.argmin(np.linalg.norm(starts - (0.05, 0.03), axis=1))] = False  # one red nearby
    assert advise_from(maze_task, passed, (0.03, 0.03)).rule == 2
    assert advise_from(maze_task, np.ones(len(starts), bool), (0.03, 0.03)).rule == 0


def test_rule_zero_when_all_green(maze_task):
    s = TeachingSession(maze_task)
    start = np.array([0.03, 0.03])
    for _ in range(10):  # each next demo from the red start farthest from the demos
        r = s.add_demo(maze_task.layout.reference_path(start))
        if r.efficacy == 1.0:
            break
        assert advise(maze_task, s).rule != 0  # something is still red
        red = maze_task.test_points[~r.passed]
        mine = np.array([maze_task.test_point_of(d) for d in s.demos])
        start = red[np.argmax(np.linalg.norm(red[:, None] - mine[None], axis=2).min(axis=1))]
    assert s.latest.efficacy == 1.0  # these starts cover the whole start zone
    assert advise(maze_task, s).rule == 0
