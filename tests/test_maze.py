"""Tests of the maze task (Experiment 1): geometry, criteria with reasons, preprocessing."""

from __future__ import annotations

import numpy as np
import pytest

from tutor.errors import InvalidDemoError
from tutor.framework import TeachingSession


def line(*points, n=200):
    """A polyline through ``points`` sampled at n points, as (n, 2)."""
    pts = np.asarray(points, dtype=float)
    seg = np.linspace(0, len(pts) - 1, n)
    i = np.minimum(seg.astype(int), len(pts) - 2)
    f = (seg - i)[:, None]
    return pts[i] * (1 - f) + pts[i + 1] * f


def good_path(task, start=(0.05, 0.03)):
    return task.layout.reference_path(start)[:, 1:]


def test_geometry_matches_the_paper(maze_task):
    lay = maze_task.layout
    ws, zone = lay.workspace, lay.start_zone
    assert (ws.x1 - ws.x0, ws.y1 - ws.y0) == pytest.approx((0.20, 0.30))
    assert (zone.x1 - zone.x0, zone.y1 - zone.y0) == pytest.approx((0.20, 0.06))
    assert lay.target_diameter == pytest.approx(0.005)
    assert len(lay.obstacles) == 2
    assert maze_task.test_points.shape == (140, 2)
    assert np.all(zone.contains(maze_task.test_points))
    assert (
        len(np.unique(maze_task.test_points[:, 0])) == 20
        and len(np.unique(maze_task.test_points[:, 1])) == 7
    )
    assert lay.n_components == 11
    frames = maze_task.frames(maze_task.test_points[0])
    assert len(frames) == 4
    np.testing.assert_allclose(frames[0].b, maze_task.test_points[0])
    np.testing.assert_allclose(frames[1].b, lay.target_center)


def test_frame_batch_equals_frames(maze_task):
    batch = maze_task.frame_batch(maze_task.test_points)
    for i in (0, 77, 139):
        for j, f in enumerate(maze_task.frames(maze_task.test_points[i])):
            np.testing.assert_allclose(batch.b[i, j], f.b)
            np.testing.assert_allclose(batch.A[i, j], f.A)


def test_scripted_path_passes(maze_task):
    v = maze_task.judge(good_path(maze_task)[None])
    assert v.passed.tolist() == [True] and v.reasons == ("",)


def test_reason_hit_obstacle(maze_task):
    path = line((0.05, 0.03), (0.05, 0.115), (0.10, 0.275))  # straight up into obstacle 1
    v = maze_task.judge(path[None])
    assert not v.passed[0]
    assert v.reasons[0].startswith("hit obstacle 1 (left-hand) at sample ")
    path2 = line((0.18, 0.03), (0.18, 0.195), (0.10, 0.275))  # up the right side into obstacle 2
    assert "hit obstacle 2 (right-hand)" in maze_task.judge(path2[None]).reasons[0]


def test_reason_left_workspace(maze_task):
    path = good_path(maze_task).copy()
    path[100:110, 0] = 0.25  # a detour outside the right wall
    v = maze_task.judge(path[None])
    assert v.reasons[0] == "left the workspace at sample 101 of 200"


def test_reason_did_not_start_in_start_zone(maze_task):
    path = good_path(maze_task).copy()
    path[0] = (0.05, 0.07)
    assert maze_task.judge(path[None]).reasons[0] == "did not start in the start zone"


def test_reason_ended_away_from_target(maze_task):
    path = good_path(maze_task).copy()
    path[-1] = maze_task.layout.target_center + (0.032, 0.0)
    assert maze_task.judge(path[None]).reasons[0] == "ended 3.2 cm from the target"
    path[-1] = maze_task.layout.target_center + (0.002, 0.0)  # inside the 0.5 cm circle
    assert maze_task.judge(path[None]).passed[0]


def test_several_reasons_are_joined(maze_task):
    path = good_path(maze_task).copy()
    path[0] = (0.05, 0.07)
    path[-1] = maze_task.layout.target_center + (0.05, 0.0)
    assert maze_task.judge(path[None]).reasons[0] == (
        "did not start in the start zone and ended 5.0 cm from the target"
    )


def test_preprocess_resamples_in_time(maze_task):
    t = np.linspace(0.0, 2.7, 217)  # an 80 Hz recording of 2.7 s
    xy = line((0.05, 0.03), (0.05, 0.09), n=217)
    demo = maze_task.preprocess(np.column_stack([t, xy]))
    assert demo.shape == (200, 3)
    np.testing.assert_allclose(demo[:, 0], np.linspace(0, 1, 200))
    np.testing.assert_allclose(demo[0, 1:], xy[0])
    np.testing.assert_allclose(demo[-1, 1:], xy[-1])
    np.testing.assert_allclose(maze_task.preprocess(demo), demo)  # idempotent


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda d: d * [1, 100, 100], "centimetres"),
        (lambda d: d * [1, 1000, 1000], "millimetres"),
        (lambda d: d * [1, 1e6, 1e6], "metres"),
        (lambda d: np.column_stack([d[:, 0], np.full((len(d), 2), 0.05)]), "only 0.0 cm long"),
        (lambda d: d[:1], "at least 2"),
        (lambda d: d[:, :2], "columns"),
        (lambda d: np.where(np.arange(d.size).reshape(d.shape) == 40, np.nan, d), "NaN"),
        (lambda d: d[::-1], "increasing"),
    ],
)
def test_preprocess_rejects_junk_with_a_reason(maze_task, make, words):
    demo = maze_task.layout.reference_path((0.05, 0.03))
    with pytest.raises(InvalidDemoError, match=words):
        maze_task.preprocess(make(demo))


def test_demonstrated_covers_the_nearest_grid_points(maze_task):
    c = maze_task.test_points
    on_point = maze_task.demonstrated(c[[5]])
    assert on_point.sum() == 1 and on_point[5]
    assert maze_task.demonstrated(np.empty((0, 2))).sum() == 0
    outside = maze_task.demonstrated([[0.5, 0.5]])
    assert outside.sum() == 0


def test_describe_where(maze_task):
    c = maze_task.test_points
    left_bottom = (c[:, 0] < 0.06) & (c[:, 1] < 0.02)
    assert maze_task.describe_where(left_bottom) == "mostly bottom left of the start zone"
    assert maze_task.describe_where(c[:, 0] > 0.14) == "mostly right of the start zone"
    assert maze_task.describe_where(np.ones(140, bool)) == "everywhere in the start zone"
    spread = np.zeros(140, bool)
    spread[::7] = True
    assert maze_task.describe_where(spread) == "spread across the start zone"


def test_two_demos_from_one_side_leave_most_of_the_grid_red(maze_task):
    s = TeachingSession(maze_task)
    rng = np.random.default_rng(9)
    for start in [(0.02, 0.03), (0.05, 0.03)]:
        r = s.add_demo(maze_task.layout.reference_path(start, rng, jitter=0.004))
    assert r.efficacy < 0.5


def test_a_guided_teacher_needs_few_demos_and_never_loses_ground(maze_task):
    """Demo where the robot fails, farthest from earlier demos: 3-4 demos reach 90 %.

    On the calibrated maze (blocks chosen by ``lfd-tutor calibrate``, which keeps to
    mazes this check holds on: :mod:`tutor.study.steadiness`) a median of at most 4.

    Measured with the learner of issue 14 (seeds 0-4: efficacy 0.02-0.03, 0.21-0.33,
    then 0.93-1.0). The learner before it needed 5-9 (median 7), but only because its
    warm refits fell to 0 % for two to four demos in a row after the second demo; a
    greedy machine teacher reaches 100 % with 3 demos on this maze too.
    """
    needed = []
    for seed in range(5):
        rng = np.random.default_rng(seed)
        s = TeachingSession(maze_task)
        start = maze_task.layout.sample_starts(1, rng)[0]
        best = 0.0
        for _ in range(12):
            r = s.add_demo(maze_task.layout.reference_path(start, rng, jitter=0.004))
            assert r.efficacy >= 0.5 * best  # no collapse after a demo where it failed
            best = max(best, r.efficacy)
            if r.efficacy >= 0.9:
                break
            fail = maze_task.test_points[~r.passed]
            starts = np.array([maze_task.test_point_of(d) for d in s.demos])
            far = np.linalg.norm(fail[:, None] - starts[None], axis=2).min(axis=1)
            start = np.clip(fail[np.argmax(far)] + rng.normal(0, 0.003, 2), 0.003, [0.197, 0.057])
        needed.append(s.n_demos if r.efficacy >= 0.9 else 99)
    assert np.median(needed) <= 4
    assert max(needed) <= 6
