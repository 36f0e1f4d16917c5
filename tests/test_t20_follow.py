"""Issue 20, part A: the arm that follows the trainee's hand (tutor.robot.follow).

Real Pinocchio IK and coal collision checks on the Panda in the pick-and-place scene.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from tutor.errors import InvalidParameterError
from tutor.robot import REACH_TOL, get_arm, load_robot, scene_obstacles
from tutor.robot.follow import (
    FLOOR_CLEARANCE,
    REACH_CENTER,
    REACH_RADIUS,
    FollowState,
    HandFollower,
    guide_limits,
    reach_sphere,
)
from tutor.tasks.pickplace import load_scene, start_position


@pytest.fixture(scope="module")
def scene():
    return load_scene()


@pytest.fixture
def follower(scene):
    return HandFollower.for_scene(scene)


def _walk(follower, target, grip=0.0, steps=40):
    """Drag the handle from where the tool is to ``target`` in ``steps`` moves."""
    here = follower.state.position.copy()
    state = follower.state
    for s in np.linspace(0.0, 1.0, steps)[1:]:
        state = follower.step(here + s * (np.asarray(target, float) - here), grip)
    return state


def test_the_start_state_is_the_start_pose(scene, follower):
    state = follower.reset()
    assert isinstance(state, FollowState)
    np.testing.assert_allclose(state.position, start_position(scene), atol=1e-9)
    assert state.reached and state.collision is None and state.clamped is None
    assert state.words == "" and state.grip == 0.0
    n_visual = load_robot(scene.robot).visual_model.ngeoms
    assert state.placements.shape == (n_visual, 4, 4)
    np.testing.assert_allclose(state.placements[:, 3], np.tile([0, 0, 0, 1], (n_visual, 1)))
    with pytest.raises(ValueError):
        state.q[0] = 1.0  # a state is read-only


@pytest.mark.parametrize("plant", [0, 9, 45, 90, 99])
def test_the_follower_reaches_every_corner_plant_and_the_bin(scene, follower, plant):
    grasp = scene.plant_positions[plant]
    state = _walk(follower, grasp + [0, 0, 0.1])
    state = _walk(follower, grasp, steps=15)
    assert state.reached and state.clamped is None and state.collision is None
    assert np.linalg.norm(state.position - grasp) <= REACH_TOL
    state = _walk(follower, grasp + [0, 0, 0.2], grip=1.0, steps=15)
    state = _walk(follower, scene.release_point, grip=1.0)
    assert state.reached and state.collision is None and state.words == ""
    assert np.linalg.norm(state.position - scene.release_point) <= REACH_TOL
    # the fingers follow the hand command: closed
    arm = follower.arm
    np.testing.assert_allclose(state.q[arm.n_arm :], arm.fingers(1.0))


def test_a_target_below_the_table_stops_at_the_table(scene, follower):
    floor = guide_limits(scene)["z"][0]
    beside_tray = np.array([0.25, 0.2, 0.05])
    _walk(follower, beside_tray)
    state = _walk(follower, [0.25, 0.2, -0.3], steps=30)
    assert state.clamped == "table"
    assert state.target[2] == pytest.approx(floor)
    assert state.position[2] >= floor - REACH_TOL
    assert state.collision is None  # the fingertips stay above the table top
    assert "table: it cannot go lower" in state.words
    # every moving link stays above the table top (link 0, the base, stands on it)
    assert state.placements[1:, 2, 3].min() > 0.0
    # over the tray the hand stops at the same height and touches the tray (shown red)
    state = _walk(follower, [0.5, -0.05, -0.2], steps=30)
    assert state.clamped == "table" and state.position[2] >= floor - REACH_TOL
    assert state.collision is not None and "tray" in state.words


def test_out_of_reach_is_clamped_to_the_reach_sphere(follower):
    state = _walk(follower, [1.5, 0.0, 0.3])
    assert state.clamped == "reach"
    assert np.linalg.norm(state.target - REACH_CENTER) == pytest.approx(REACH_RADIUS)
    assert state.reached  # the arm stretches as far as the sphere
    assert "Out of the arm's reach" in state.words
    back = _walk(follower, [0.4, 0.0, 0.3], steps=20)
    assert back.clamped is None and back.reached and back.words == ""


def test_a_pose_driven_into_the_bin_reports_the_link(scene, follower):
    _walk(follower, [0.22, 0.42, 0.3])
    state = _walk(follower, [0.22, 0.325, 0.10], steps=20)  # onto the bin's front wall
    assert state.collision is not None and state.collision.startswith("panda_")
    assert state.words.endswith("the bin.")
    arm = get_arm(scene_obstacles(scene))
    assert arm.colliding_pair(state.q)[0] == state.collision
    # the configuration is kept (the recording goes on), the words say what touches what
    assert np.linalg.norm(state.position - state.target) <= REACH_TOL


def test_the_message_is_json_and_bad_input_changes_nothing(follower):
    state = _walk(follower, [0.4, 0.1, 0.2], grip=0.5)
    message = json.loads(json.dumps(state.to_message()))
    assert set(message) == {
        "position",
        "target",
        "grip",
        "reached",
        "collision",
        "clamped",
        "words",
    }
    assert message["grip"] == 0.5 and len(message["position"]) == 3
    for bad_target, bad_grip in (
        ([np.nan, 0, 0.2], 0),
        ([0.4, 0.1], 0),
        ("here", 0),
        ([0.4, 0.1, 0.2], "closed"),
        ([0.4, 0.1, 0.2], np.inf),
    ):
        with pytest.raises(InvalidParameterError):
            follower.step(bad_target, bad_grip)
        assert follower.state is state


def test_guide_limits_hold_the_scene_and_start_at_the_table(scene):
    limits = guide_limits(scene)
    assert set(limits) == {"x", "y", "z"}
    table_top = scene.table_center[2] + scene.table_size[2] / 2
    assert limits["z"][0] == pytest.approx(table_top + FLOOR_CLEARANCE)
    lo = np.array([limits[k][0] for k in "xyz"])
    hi = np.array([limits[k][1] for k in "xyz"])
    points = np.vstack([scene.plant_positions, scene.release_point, start_position(scene)])
    assert np.all(points >= lo) and np.all(points <= hi)
    assert np.all(np.linalg.norm(points - REACH_CENTER, axis=1) < REACH_RADIUS)
    json.dumps(limits)
    assert reach_sphere()["radius"] == REACH_RADIUS


@settings(max_examples=60, deadline=None)
# a jump from one corner of the box to the far one once swung the hand under the table
@example(path=[(0.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0)] * 2 + [(0.0, 1.0, 0.0, 0.0)])
@given(
    st.lists(
        st.tuples(
            st.floats(-1.5, 1.5), st.floats(-1.5, 1.5), st.floats(-1.0, 1.5), st.floats(0, 1)
        ),
        min_size=1,
        max_size=6,
    )
)
def test_any_handle_path_keeps_the_hand_in_the_box_and_above_the_table(path):
    scene = load_scene()
    follower = HandFollower.for_scene(scene)
    limits = guide_limits(scene)
    lo = np.array([limits[k][0] for k in "xyz"])
    hi = np.array([limits[k][1] for k in "xyz"])
    for x, y, z, g in path:
        state = follower.step([x, y, z], g)
        assert np.all(state.target >= lo - 1e-9) and np.all(state.target <= hi + 1e-9)
        assert np.linalg.norm(state.target - REACH_CENTER) <= REACH_RADIUS + 1e-9
        assert state.position[2] >= lo[2] - 0.02  # never through the table
        assert state.clamped in (None, "table", "reach")
        assert (state.words == "") == (
            state.reached and state.clamped is None and state.collision is None
        )
