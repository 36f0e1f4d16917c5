"""The tracking controller (tutor.tpgmm.tracking): a robot follows the TP-GMR from where
it is. Properties of the maths, and the maze's attempts starting at their start points."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tutor.errors import InvalidParameterError
from tutor.tpgmm.tracking import _plant, track, tracking_gains, tracking_precision


def _reference(rng, n=3, T=40, d=2, tight=1e4):
    t = np.linspace(0.0, 1.0, T)
    ends = rng.uniform(-1, 1, size=(n, 2, d))
    mean = ends[:, :1] + (ends[:, 1:] - ends[:, :1]) * t[None, :, None]
    precision = np.broadcast_to(tight * np.eye(d), (n, T, d, d)).copy()
    return mean, precision, 1.0 / (T - 1)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), d=st.integers(1, 3))
def test_the_path_starts_exactly_where_the_robot_is(seed, d):
    rng = np.random.default_rng(seed)
    mean, precision, dt = _reference(rng, d=d)
    start = rng.uniform(-2, 2, size=(mean.shape[0], d))
    path = track(mean, precision, start, dt)
    np.testing.assert_array_equal(path[:, 0], start)
    assert np.isfinite(path).all()


def _rollout(mean, precision, start, dt, r):
    """The feedback controller run forward: x_{t+1} = A x_t + B (k_t - K_t x_t)."""
    n, T, d = mean.shape
    K, k = tracking_gains(mean, precision, dt, r)
    A, B = _plant(d, dt)
    x = np.zeros((n, 2 * d))
    x[:, : start.shape[1]] = start
    out = [x[:, :d].copy()]
    for t in range(T - 1):
        u = k[:, t] - np.einsum("bij,bj->bi", K[:, t], x)
        x = x @ A.T + u @ B.T
        out.append(x[:, :d].copy())
    return np.stack(out, axis=1)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    d=st.integers(1, 3),
    T=st.integers(2, 40),
    log_r=st.floats(-6, 0),
    shared=st.booleans(),
    moving=st.booleans(),
)
def test_the_batch_solution_is_the_feedback_controllers_path(seed, d, T, log_r, shared, moving):
    """The banded least squares (track) and the Riccati feedback (tracking_gains) are the
    same optimum: their paths agree, for shared or per-point precisions, at rest or not."""
    rng = np.random.default_rng(seed)
    n = 3
    mean = rng.normal(size=(n, T, d))
    root = rng.normal(size=(1 if shared else n, T, d, d))
    precision = root @ np.swapaxes(root, -1, -2) + 0.5 * np.eye(d)
    start = rng.normal(size=(n, 2 * d if moving else d))
    dt = 1.0 / max(T - 1, 1)
    batch = track(mean, precision, start, dt, 10.0**log_r)
    feedback = _rollout(mean, precision, start, dt, 10.0**log_r)
    np.testing.assert_allclose(batch, feedback, atol=1e-8 * max(1.0, np.abs(feedback).max()))


def test_shared_covariances_are_inverted_once():
    rng = np.random.default_rng(4)
    root = rng.normal(size=(1, 5, 2, 2))
    cov = root @ np.swapaxes(root, -1, -2) + np.eye(2)
    assert tracking_precision(np.repeat(cov, 4, axis=0)).shape == (1, 5, 2, 2)
    different = np.concatenate([cov, 2 * cov])
    np.testing.assert_allclose(tracking_precision(different), np.linalg.inv(different))
    with pytest.raises(InvalidParameterError, match="cov must have shape"):
        tracking_precision(cov[0])


def test_batched_is_one_at_a_time():
    rng = np.random.default_rng(0)
    mean, precision, dt = _reference(rng, n=4)
    start = rng.uniform(-1, 1, size=(4, 2))
    together = track(mean, precision, start, dt)
    alone = [
        track(mean[i : i + 1], precision[i : i + 1], start[i : i + 1], dt)[0] for i in range(4)
    ]
    np.testing.assert_allclose(together, np.stack(alone), atol=1e-12)


def test_a_reference_from_the_start_is_followed_closely():
    rng = np.random.default_rng(1)
    mean, precision, dt = _reference(rng, tight=1e6)
    path, velocity = track(mean, precision, mean[:, 0], dt, return_velocity=True)
    np.testing.assert_array_equal(velocity[:, 0], 0.0)  # it starts at rest,
    np.testing.assert_array_equal(path[:, 1], path[:, 0])  # so its first step cannot move
    assert np.abs(path[:, 2:] - mean[:, 2:]).max() < 0.02 * np.abs(mean).max()


def test_minimal_intervention_loose_where_the_demos_disagree():
    """Offset in both axes at the start; tight in x, loose in y: x is corrected first."""
    T = 60
    mean = np.zeros((1, T, 2))
    precision = np.broadcast_to(np.diag([1e4, 1e1]), (1, T, 2, 2)).copy()
    precision[0, -1] = np.diag([1e4, 1e4])  # both must arrive
    path = track(mean, precision, np.array([[0.1, 0.1]]), 1 / (T - 1), control_cost=1e-4)
    mid = T // 3
    assert abs(path[0, mid, 0]) < 0.2 * abs(path[0, mid, 1])  # x already on, y not yet
    assert np.abs(path[0, -1]).max() < 0.01  # both on at the end


def test_gains_have_the_shapes_of_the_plant():
    rng = np.random.default_rng(2)
    mean, precision, dt = _reference(rng, n=2, T=10, d=3)
    K, k = tracking_gains(mean, precision, dt)
    assert K.shape == (2, 9, 3, 6) and k.shape == (2, 9, 3)


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda m, p, s: (m[0], p, s, 0.1), "mean must have shape"),
        (lambda m, p, s: (m, p[:, :-1], s, 0.1), "precision must have shape"),
        (lambda m, p, s: (m, p, s[:, :1], 0.1), "start must have shape"),
        (lambda m, p, s: (m, p, np.full_like(s, np.nan), 0.1), "finite"),
        (lambda m, p, s: (m, p, s, 0.0), "dt must be"),
        (lambda m, p, s: (m[:, :1], p[:, :1], s, 0.1), "at least 2 time steps"),
    ],
)
def test_bad_inputs_are_named_errors(change, match):
    rng = np.random.default_rng(3)
    mean, precision, _ = _reference(rng)
    with pytest.raises(InvalidParameterError, match=match):
        track(*change(mean, precision, mean[:, 0]))


def test_maze_attempts_after_one_and_two_demos_start_at_their_start_points(maze_task):
    """The regression's first mean is cm from the start point after one or two demos; the
    robot's attempts (the session's realisations) start on it, and no attempt fails
    for starting outside the start zone (issue 22's first line)."""
    from tutor.demofiles import load_demos
    from tutor.framework.session import TeachingSession
    from tutor.resources import asset

    good = load_demos(asset("demos/maze_good.json")).demos
    session = TeachingSession(maze_task)
    points = maze_task.test_points
    for demo in good[:2]:
        session.add_demo(demo)
        mean, _ = session.learner.reproduce_batch(maze_task.frame_batch(points), maze_task.times)
        assert np.linalg.norm(mean[:, 0] - points, axis=1).max() > 0.01  # the regression's
        attempts = session.realisations
        assert np.linalg.norm(attempts[:, 0] - points, axis=1).max() <= 0.001
        causes = maze_task.judge(attempts, points).causes
        assert not any(reason.kind == "start" for c in causes for reason in c)


def test_pickplace_attempts_after_one_and_two_demos_start_at_the_start_pose(pickplace_task):
    from tutor.demofiles import load_demos
    from tutor.framework.session import TeachingSession
    from tutor.resources import asset

    task = pickplace_task
    demos = load_demos(asset("demos/pickplace_corners.json"), columns=("t", "x", "y", "z", "g"))
    session = TeachingSession(task)
    for demo in demos.demos[:2]:
        session.add_demo(demo)
        mean, _ = session.learner.reproduce_batch(task.frame_batch(task.test_points), task.times)
        assert np.linalg.norm(mean[:, 0, :3] - task.start, axis=1).max() > 0.01
        attempts = session.realisations
        assert np.linalg.norm(attempts[:, 0, :3] - task.start, axis=1).max() <= 0.001
        assert np.all((attempts[..., 3] >= 0) & (attempts[..., 3] <= 1))  # the hand's range


@pytest.mark.parametrize("bad", ["abc", -1, 0, None])
@pytest.mark.parametrize("which", ["maze", "pickplace"])
def test_a_bad_control_cost_in_a_task_file_is_a_named_file_error(tmp_path, which, bad):
    import json

    from tutor.errors import InvalidFileError
    from tutor.resources import asset
    from tutor.tasks.maze import load_layout
    from tutor.tasks.pickplace import load_scene

    data = json.loads(asset(f"{which}.json").read_text())
    data["control_cost"] = bad
    path = tmp_path / "task.json"
    path.write_text(json.dumps(data))
    loader = load_layout if which == "maze" else load_scene
    with pytest.raises(InvalidFileError, match="control_cost in .*task.json must be a finite"):
        loader(path)


@pytest.mark.parametrize(
    "points, match",
    [
        ([[np.nan, np.nan]], "holds NaN or inf"),
        ([[1.0]], r"shape \(B, 2\)"),
        ("abc", "holds text"),
        ([1.0, 2.0, 3.0], r"got shape \(3,\)"),
    ],
)
def test_realise_names_bad_points_and_learners(maze_task, points, match):
    learner = maze_task.make_learner().fit(
        [maze_task.preprocess(maze_task.scripted_demo(0, np.random.default_rng(0)))],
        [maze_task.frames(maze_task.test_points[0])],
    )
    with pytest.raises(InvalidParameterError, match=match):
        maze_task.realise(learner, points)
    with pytest.raises(InvalidParameterError, match="learner must be a fitted TPGMM"):
        maze_task.realise(object())
    assert maze_task.realise(learner, maze_task.test_points[:3]).shape == (3, 200, 2)
