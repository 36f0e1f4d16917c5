"""Tests of the simulated arm (tutor.robot): FK, IK, collisions, path following, the map."""

from __future__ import annotations

import subprocess
import sys
import zipfile

import numpy as np
import pytest

from tutor.errors import InvalidFileError, InvalidParameterError, TutorError
from tutor.robot import (
    DEFAULT_MAP_PATH,
    DOWN,
    REACH_TOL,
    START_CONFIGURATION,
    Arm,
    FeasibilityMap,
    get_arm,
    load_robot,
    open_box,
    scene_obstacles,
)
from tutor.tasks.pickplace import load_scene

# --- fixtures and helpers


@pytest.fixture(scope="module")
def scene():
    return load_scene()


@pytest.fixture(scope="module")
def arm(scene):
    return get_arm(scene_obstacles(scene))


@pytest.fixture(scope="module")
def bare_arm():
    return get_arm(())


@pytest.fixture(scope="module")
def fmap():
    if not DEFAULT_MAP_PATH.exists():
        pytest.fail(f"{DEFAULT_MAP_PATH} is missing: run scripts/make_feasibility_map.py")
    return FeasibilityMap.load()


def min_jerk(s):
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def via(points, n):
    """Minimum-jerk segments through ``points`` (k, 3), about ``n`` samples in all."""
    points = np.asarray(points, float)
    per = max(n // (len(points) - 1), 2)
    s = min_jerk(np.linspace(0, 1, per, endpoint=False))[:, None]
    segs = [(1 - s) * a + s * b for a, b in zip(points[:-1], points[1:], strict=True)]
    return np.vstack([*segs, points[-1:]])


def angle_between(R1, R2):
    c = (np.trace(R1.T @ R2) - 1) / 2
    return float(np.arccos(np.clip(c, -1, 1)))


# --- forward kinematics


def test_start_configuration_matches_scene(scene, arm):
    assert np.array_equal(START_CONFIGURATION, scene.start_configuration)
    assert arm.tool_frame == scene.tool_frame
    assert arm.nq == 9


def test_fk_of_start_configuration(arm):
    p, R = arm.fk(START_CONFIGURATION)
    # Panda at its "ready" pose: TCP 30.7 cm ahead, 48.7 cm up, pointing down.
    np.testing.assert_allclose(p, [0.30702, 0.0, 0.48687], atol=1e-5)
    np.testing.assert_allclose(R, DOWN, atol=1e-12)
    np.testing.assert_allclose(R[:, 2], [0, 0, -1], atol=1e-12)  # tool z axis down
    np.testing.assert_allclose(DOWN @ DOWN.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(DOWN) == pytest.approx(1.0)


def test_fk_changes_with_joint_1(arm):
    q = START_CONFIGURATION.copy()
    q[0] = np.pi / 2  # turn the base a quarter: the tool swings from +x to +y
    p, _ = arm.fk(q)
    np.testing.assert_allclose(p, [0.0, 0.30702, 0.48687], atol=1e-4)


def _pose(p, R):
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = R, p
    return M


def test_visual_placements_move_rigidly_with_their_links(arm):
    names = [g.name for g in load_robot().visual_model.geometryObjects]
    rng = np.random.default_rng(5)
    qs = rng.uniform(arm.lower, arm.upper, size=(6, arm.nq))
    placements = arm.visual_placements(qs)
    assert placements.shape == (6, len(names), 4, 4)
    np.testing.assert_array_equal(placements[:, :, 3], np.tile([0.0, 0, 0, 1], (6, 11, 1)))
    # the base stands still; the hand keeps its offset from the tool frame
    base, hand = names.index("panda_link0_0"), names.index("panda_hand_0")
    np.testing.assert_allclose(placements[:, base], placements[:1, base].repeat(6, 0), atol=1e-12)
    tool = [_pose(*arm.fk(q)) for q in qs]
    offsets = [np.linalg.inv(T) @ M for T, M in zip(tool, placements[:, hand], strict=True)]
    np.testing.assert_allclose(offsets, [offsets[0]] * 6, atol=1e-9)
    assert not np.allclose(placements[0], placements[1])  # the links did move
    # one configuration gives the same as a batch of one
    np.testing.assert_allclose(arm.visual_placements(qs[2]), placements[2], atol=1e-15)


def test_visual_placements_of_fingers_follow_the_opening(arm):
    names = [g.name for g in load_robot().visual_model.geometryObjects]
    left, right = names.index("panda_leftfinger_0"), names.index("panda_rightfinger_0")
    shut = START_CONFIGURATION.copy()
    shut[7:] = 0.0
    wide, narrow = arm.visual_placements(np.array([START_CONFIGURATION, shut]))
    gap = np.linalg.norm(wide[left, :3, 3] - wide[right, :3, 3])
    assert gap - np.linalg.norm(narrow[left, :3, 3] - narrow[right, :3, 3]) == pytest.approx(0.08)


@pytest.mark.parametrize(
    "qs", [np.zeros(8), np.zeros((3, 8)), np.zeros((0, 9)), [[np.nan] * 9], "start"]
)
def test_visual_placements_bad_configurations_are_named(arm, qs):
    with pytest.raises(InvalidParameterError, match="configurations"):
        arm.visual_placements(qs)


def test_visual_placements_need_a_geometry_model(arm):
    with pytest.raises(InvalidParameterError, match="GeometryModel"):
        arm.visual_placements(START_CONFIGURATION, visual_model="meshes")


# --- inverse kinematics


def test_ik_reaches_every_plant_and_the_release_point(scene, arm):
    targets = np.vstack([scene.plant_positions, scene.release_point])
    errors, tilts = [], []
    for p in targets:
        r = arm.ik(p)
        assert r.converged, p
        assert np.all(arm.lower[:7] - 1e-12 <= r.q[:7]) and np.all(r.q[:7] <= arm.upper[:7] + 1e-12)
        np.testing.assert_array_equal(r.q[7:], START_CONFIGURATION[7:])  # fingers kept
        pf, Rf = arm.fk(r.q)
        errors.append(np.linalg.norm(pf - p))
        tilts.append(angle_between(Rf, DOWN))
        assert not arm.in_collision(r.q), f"grasp pose at {p} collides"
    assert max(errors) <= 5e-3
    assert max(errors) <= 2e-4  # in fact the solver's tolerance, 0.1 mm
    assert max(tilts) <= 2e-3  # and the tool points down


def test_ik_accuracy_over_the_workspace(arm, fmap):
    rng = np.random.default_rng(3)
    targets = rng.uniform([0.25, -0.35, 0.05], [0.65, 0.45, 0.45], size=(200, 3))
    # the workspace X (with a 5 mm margin): a few points near the base are outside it
    targets = targets[fmap.value(targets) > 0.005]
    assert len(targets) > 180
    results = [arm.ik(p) for p in targets]
    errors = np.array([r.position_error for r in results])
    tilt = np.array([r.rotation_error for r in results])
    assert np.all(errors <= 5e-3), errors.max()
    assert np.median(errors) <= 1e-4
    assert np.all(tilt <= 0.01)
    # the reported error is the true one
    for r, p in zip(results[:20], targets[:20], strict=True):
        assert np.linalg.norm(arm.fk(r.q)[0] - p) == pytest.approx(r.position_error, abs=1e-9)


def test_ik_with_another_rotation(bare_arm):
    c, s = np.cos(0.5), np.sin(0.5)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ DOWN  # turned 0.5 rad about z
    r = bare_arm.ik([0.45, 0.1, 0.3], rotation=R)
    assert r.converged
    assert angle_between(bare_arm.fk(r.q)[1], R) < 2e-3


def test_every_ik_solution_respects_joint_limits(bare_arm):
    rng = np.random.default_rng(5)
    # inside and far outside the reach, from random starts
    targets = rng.uniform([-1.0, -1.0, -0.5], [1.0, 1.0, 1.3], size=(60, 3))
    for p in targets:
        q0 = rng.uniform(bare_arm.lower, bare_arm.upper)
        r = bare_arm.ik(p, q0, max_iter=60)
        assert np.all(r.q >= bare_arm.lower) and np.all(r.q <= bare_arm.upper)
        assert r.converged == (r.position_error <= 1e-4 and r.rotation_error <= 1e-3)
    far = bare_arm.ik([1.5, 0.0, 0.3])
    assert not far.converged and far.position_error > 0.4


# --- collisions


def test_start_configuration_is_free(arm, bare_arm):
    assert not arm.in_collision(START_CONFIGURATION)
    assert arm.colliding_pair(START_CONFIGURATION) is None
    assert not bare_arm.in_collision(START_CONFIGURATION)
    assert arm.clearance(START_CONFIGURATION) > 0.05


def test_arm_pushed_into_the_table_collides(arm, bare_arm):
    # the tool 2 cm below the table top, beside the tray (IK of the arm without obstacles)
    q = bare_arm.ik([0.4, 0.3, -0.02]).q
    assert arm.in_collision(q)
    assert "table" in arm.colliding_pair(q)
    assert arm.clearance(q) < 0
    assert not bare_arm.in_collision(q)  # no obstacles, no collision


def test_self_collision_when_folded(bare_arm):
    q = START_CONFIGURATION.copy()
    q[3], q[5] = -3.0, 0.5  # elbow folded, wrist bent back: the hand meets link 1
    assert bare_arm.in_collision(q)
    a, b = bare_arm.colliding_pair(q)
    assert a.startswith("panda_") and b.startswith("panda_")


def test_neighbouring_links_are_not_pairs(bare_arm):
    names = set(bare_arm._pair_names)
    for a, b in [
        ("panda_link6", "panda_link7"),
        ("panda_link7", "panda_hand"),
        ("panda_hand", "panda_leftfinger"),
        ("panda_link0", "panda_link1"),
    ]:
        assert (a, b) not in names and (b, a) not in names
    # the SRDF leaves 44 self pairs of the Panda's 17 geometries
    assert bare_arm.n_self_pairs == len(bare_arm.geom_model.collisionPairs) == 44


def test_obstacles_pair_with_every_moving_geometry(arm, scene):
    n_moving = sum(o.parentJoint != 0 for o in arm.geom_model.geometryObjects)
    boxes = scene_obstacles(scene)
    assert len(boxes) == 7  # table, tray, bin floor and four walls
    assert len(arm.geom_model.collisionPairs) == 44 + n_moving * len(boxes)


def test_arm_does_not_touch_the_shared_model():
    shared = load_robot("panda")
    before = (shared.collision_model.ngeoms, len(shared.collision_model.collisionPairs))
    Arm(obstacles=[("box", [0.5, 0, 0.2], [0.1, 0.1, 0.1])])
    after = (shared.collision_model.ngeoms, len(shared.collision_model.collisionPairs))
    assert before == after


def test_get_arm_is_cached(scene):
    a = get_arm(scene_obstacles(scene))
    b = get_arm([(n, list(c), tuple(s)) for n, c, s in scene_obstacles(scene)])
    assert a is b
    assert get_arm(()) is not a


def test_open_box_parts(scene):
    parts = dict(
        (n, (c, s)) for n, c, s in open_box("bin", scene.bin_center, scene.bin_size, scene.bin_wall)
    )
    assert len(parts) == 5
    lo, hi = scene.bin_center - scene.bin_size / 2, scene.bin_center + scene.bin_size / 2
    for c, s in parts.values():  # every part inside the bin's outer box
        assert np.all(c - s / 2 >= lo - 1e-12) and np.all(c + s / 2 <= hi + 1e-12)
    c, s = parts["bin wall +y"]
    assert c[1] + s[1] / 2 == pytest.approx(hi[1]) and s[1] == pytest.approx(scene.bin_wall)


# --- following paths


def test_follow_plant_to_bin_tracks_within_5_mm(scene, arm):
    start = arm.fk(START_CONFIGURATION)[0]
    up = np.array([0, 0, 0.12])
    worst = 0.0
    for plant in scene.plant_positions[scene.generalisation_indices]:
        rel = scene.release_point
        path = via([start, plant + up, plant, plant + up, rel + [0, 0, 0.05], rel], 200)
        grip = np.zeros(len(path))
        grip[len(path) // 2 : -5] = 1.0
        tr = arm.follow(path, grip)
        assert tr.ok, tr.reason
        assert tr.reason == "" and tr.first_problem is None
        assert tr.qs.shape == (len(path), 9)
        assert tr.errors.shape == tr.converged.shape == tr.collision.shape == (len(path),)
        assert np.all(tr.errors <= REACH_TOL)
        worst = max(worst, tr.errors.max())
        # fingers follow the hand command
        np.testing.assert_allclose(tr.qs[:, 7], 0.04 * (1 - grip))
        np.testing.assert_allclose(tr.qs[:, 8], 0.04 * (1 - grip))
        # the configuration moves smoothly (no jumps between IK branches)
        assert np.abs(np.diff(tr.qs[:, :7], axis=0)).max() < 0.1
    assert worst <= 2e-4


def test_follow_flags_a_dip_through_the_table(arm):
    above = np.array([0.6, -0.35, 0.2])  # beside the tray, over the bare table
    path = via([above, above * [1, 1, 0] + [0, 0, -0.03], above], 120)
    tr = arm.follow(path)
    assert not tr.ok
    assert "table" in tr.reason and "collides" in tr.reason
    k = tr.first_problem
    assert f"sample {k}" in tr.reason
    assert tr.collision[k] and not tr.collision[:k].any()
    assert path[k, 2] < 0.02  # fingertips reach about 1 cm below the tool point
    assert tr.collision[np.argmin(path[:, 2])]


def test_follow_flags_out_of_reach_and_joint_limits(arm):
    start = arm.fk(START_CONFIGURATION)[0]
    s = np.linspace(0, 1, 80)[:, None]
    tr = arm.follow((1 - s) * start + s * np.array([0.95, 0.0, 0.3]))
    assert not tr.ok and "cannot reach within 5 mm" in tr.reason
    assert tr.errors[tr.first_problem] > REACH_TOL
    assert not tr.collision.any()
    # straight down next to the base: the elbow runs into its joint limit
    tr = arm.follow((1 - s) * start + s * np.array([0.1, 0.0, 0.05]))
    assert not tr.ok and "joint limit" in tr.reason and tr.at_limit.any()


def test_follow_reports_self_collision(bare_arm):
    # tool path pulled in against the base: the arm folds onto itself
    start = bare_arm.fk(START_CONFIGURATION)[0]
    s = np.linspace(0, 1, 60)[:, None]
    tr = bare_arm.follow((1 - s) * start + s * np.array([0.0, 0.0, 0.2]))
    assert not tr.ok
    assert tr.collision.any()
    a, b = bare_arm.colliding_pair(tr.qs[np.argmax(tr.collision)])
    assert a.startswith("panda_") and b.startswith("panda_")


def test_follow_defaults_and_single_sample(arm):
    tr = arm.follow([[0.4, 0.0, 0.3]])
    assert tr.ok and tr.qs.shape == (1, 9)
    np.testing.assert_allclose(tr.qs[0, 7:], 0.04)  # open by default


# --- bad input


@pytest.mark.parametrize(
    "call",
    [
        lambda a: a.ik([np.nan, 0, 0.3]),
        lambda a: a.ik([0.4, 0.0]),
        lambda a: a.ik("here"),
        lambda a: a.ik([0.4, 0, 0.3], q0=np.zeros(7)),
        lambda a: a.ik([0.4, 0, 0.3], rotation=np.eye(3) * 2),
        lambda a: a.ik([0.4, 0, 0.3], rotation=np.eye(2)),
        lambda a: a.ik([0.4, 0, 0.3], max_iter=0),
        lambda a: a.fk(np.zeros(3)),
        lambda a: a.fk([np.inf] * 9),
        lambda a: a.in_collision(np.zeros(8)),
        lambda a: a.follow(np.zeros((10, 2))),
        lambda a: a.follow(np.zeros(3)),
        lambda a: a.follow(np.zeros((0, 3))),
        lambda a: a.follow(np.full((5, 3), np.nan)),
        lambda a: a.follow(np.zeros((5, 3)), gripper=np.zeros(4)),
        lambda a: a.follow(np.zeros((5, 3)), gripper=[0, 0, np.nan, 0, 0]),
        lambda a: a.follow(np.zeros((5, 3)), reach_tol=-1),
    ],
)
def test_bad_input_gives_named_errors(bare_arm, call):
    with pytest.raises(InvalidParameterError):
        call(bare_arm)


@pytest.mark.parametrize(
    "obstacles",
    [
        [("box", [0, 0], [1, 1, 1])],
        [("box", [0, 0, 0], [1, -1, 1])],
        [("box", [0, 0, np.nan], [1, 1, 1])],
        [("", [0, 0, 0], [1, 1, 1])],
        [("a", [0, 0, 0], [1, 1, 1]), ("a", [1, 0, 0], [1, 1, 1])],
        [("box", [0, 0, 0])],
        5,
    ],
)
def test_bad_obstacles(obstacles):
    with pytest.raises(InvalidParameterError):
        Arm(obstacles=obstacles)


def test_unknown_frame_and_robot():
    with pytest.raises(InvalidParameterError):
        Arm(tool_frame="no_such_frame")
    with pytest.raises(TutorError):
        get_arm((), robot="sawyer")


# --- the feasibility map


def _realisation_like_paths(scene, start, rng, n, T=100):
    """Paths a TP-GMM realisation might take: start -> plant (hand open), plant -> bin
    (closed), bent up, down or sideways; about a fifth sag into the table."""
    s = min_jerk(np.linspace(0, 1, T))[:, None]
    bump = np.sin(np.pi * s)
    paths, grips = [], []
    for _ in range(n):
        plant = scene.plant_positions[rng.integers(100)] + rng.normal(0, 0.003, 3)
        release = scene.release_point + rng.normal(0, 0.02, 3)
        if rng.random() < 0.35:
            a, b, g = start + rng.normal(0, 0.01, 3), plant, 0.0
        else:
            a, b, g = (plant, release, 1.0) if rng.random() < 0.7 else (release, plant, 0.0)
        line = (1 - s) * a + s * b
        kind = rng.random()
        if kind < 0.2:  # sag down to between 4 cm below and 2 cm above the table top
            h = rng.uniform(-0.04, 0.01) - line[T // 2, 2]
        elif kind < 0.5:
            h = rng.uniform(0.0, 0.3)
        elif kind < 0.7:
            h = -rng.uniform(0.0, 0.1)
        else:
            h = 0.0
        lateral = rng.normal(0, 0.08)
        offset = np.column_stack([np.zeros(T), lateral * bump[:, 0], h * bump[:, 0]])
        paths.append(line + offset)
        grips.append(np.full(T, g))
    return np.array(paths), np.array(grips)


def test_map_matches_the_scene(fmap, scene):
    assert fmap.matches(scene_obstacles(scene), scene.robot, scene.tool_frame)
    assert not fmap.matches(scene_obstacles(scene)[:-1])
    assert fmap.spacing <= 0.02
    assert np.all(fmap.origin <= [0.1, -0.45, -0.05] + np.array(1e-9))
    assert np.all(fmap.upper >= [0.8, 0.65, 0.65] - np.array(1e-9))
    np.testing.assert_allclose(fmap.meta["rotation"], DOWN)


def test_map_agrees_with_ik_and_collisions_on_points(fmap, arm, scene):
    rng = np.random.default_rng(11)
    points = rng.uniform([0.1, -0.45, -0.05], [0.8, 0.65, 0.65], size=(500, 3))
    truth = np.array([arm.feasible(p) for p in points])
    agree = float(np.mean(truth == fmap.contains(points)))
    print(
        f"\nmap vs IK + collisions, 500 random points: {agree:.1%} agree "
        f"({truth.mean():.0%} feasible)"
    )
    assert 0.3 < truth.mean() < 0.9  # the sample tests both sides
    assert agree >= 0.98
    # plants, release point and start are inside
    assert fmap.contains(scene.plant_positions).all()
    assert fmap.contains(scene.release_point) and fmap.contains(arm.fk(START_CONFIGURATION)[0])


def test_map_agrees_with_follow_on_realisation_like_paths(fmap, arm, scene):
    rng = np.random.default_rng(7)
    start = arm.fk(START_CONFIGURATION)[0]
    paths, grips = _realisation_like_paths(scene, start, rng, 500)
    truth = np.array([arm.follow(p, g).ok for p, g in zip(paths, grips, strict=True)])
    with_hand = float(np.mean(truth == fmap.path_ok(paths, grips)))
    open_only = float(np.mean(truth == fmap.path_ok(paths)))
    dipping = paths[..., 2].min(axis=1) < 0
    print(
        f"\nmap vs follow, 500 paths ({truth.mean():.0%} ok, {dipping.mean():.0%} dip below "
        f"the table top): {with_hand:.1%} agree with the hand state, {open_only:.1%} "
        "taking the hand open"
    )
    assert 0.3 < truth.mean() < 0.95
    assert dipping.mean() > 0.1 and not truth[dipping].any()
    assert with_hand >= 0.98
    assert open_only >= 0.97


def test_map_lookup_shapes_and_outside(fmap):
    pts = np.zeros((4, 5, 3)) + [0.4, 0.0, 0.3]
    assert fmap.contains(pts).shape == (4, 5)
    assert fmap.contains(pts, np.ones((4, 5))).all()
    assert fmap.contains([0.4, 0.0, 0.3]).shape == ()
    outside = np.array([[5.0, 0, 0], [0.4, 0.0, 2.0], [np.nan, 0.0, 0.3]])
    assert not fmap.contains(outside).any()
    assert np.isneginf(fmap.value(outside)).all()
    with pytest.raises(InvalidParameterError):
        fmap.contains(np.zeros((4, 2)))
    with pytest.raises(InvalidParameterError):
        fmap.contains(pts, np.zeros(3))


def test_map_contains_is_exactly_the_interpolation_s_sign(fmap):
    """contains() skips the interpolation in cells whose eight corners agree: the same
    answer as value() > 0 for every point, on the grid's borders, on X's border (the
    mixed cells), off the grid and for either hand."""
    rng = np.random.default_rng(7)
    low, high = fmap.origin - 0.05, fmap.upper + 0.05
    pts = rng.uniform(low, high, (40_000, 3))
    # points on voxel centres and faces, where a weight is exactly 0 or 1
    grid = fmap.grid_points().reshape(-1, 3)
    pts = np.concatenate([pts, grid[rng.choice(len(grid), 5000)],
                          grid[rng.choice(len(grid), 5000)] + [fmap.spacing / 2, 0, 0]])
    grip = rng.uniform(0, 1, len(pts))
    for g in (None, grip):
        value = fmap.value(pts, g)
        assert np.array_equal(fmap.contains(pts, g), value > 0)
        mixed = np.abs(value) < fmap.spacing  # near X's border: cells whose corners differ
        assert mixed.sum() > 1000
    # a map whose margins change sign in every cell, and one of one sign
    checker = np.indices((2, 5, 6, 7)).sum(axis=0) % 2 - 0.5
    for margin in (checker, np.full((2, 5, 6, 7), 0.3), np.full((2, 5, 6, 7), -0.3)):
        small = FeasibilityMap(margin, (0, 0, 0), 0.1)
        pts = rng.uniform(-0.05, 0.7, (5000, 3))
        assert np.array_equal(small.contains(pts, grip[:5000]), small.value(pts, grip[:5000]) > 0)


def test_map_value_is_scipy_s_trilinear_interpolation(fmap):
    """The compiled lookup against an independent one: scipy's RegularGridInterpolator
    (linear) on each hand's layer, -inf off the grid."""
    from scipy.interpolate import RegularGridInterpolator

    rng = np.random.default_rng(3)
    axes = [fmap.origin[i] + fmap.spacing * np.arange(fmap.shape[i]) for i in range(3)]
    pts = rng.uniform(fmap.origin - 0.03, fmap.upper + 0.03, (20_000, 3))
    for closed in (0, 1):
        layer = RegularGridInterpolator(
            axes, fmap.margin[closed].astype(float), bounds_error=False, fill_value=-np.inf
        )
        got = fmap.value(pts, np.full(len(pts), float(closed)))
        want = layer(pts)
        assert np.array_equal(np.isinf(got), np.isinf(want))
        finite = np.isfinite(want)
        assert finite.sum() > 5000
        np.testing.assert_allclose(got[finite], want[finite], rtol=0, atol=1e-9)


def _first_outside_by_definition(check, paths, grip, known):
    """The first sample each path (B, T) fails, sample by sample: off the grid beyond
    the arm's reach or where the map says no; an off-grid sample within reach before
    that sends the path to the full check (followed up to its first known-bad sample)."""
    B, T = known.shape
    out = np.empty(B, dtype=int)
    inside = check.map.contains(paths, grip)
    off = np.isinf(check.map.value(paths, grip))
    for b in range(B):
        known_at = int(np.argmax(known[b])) if known[b].any() else T
        out[b] = known_at
        for t in range(known_at):
            if off[b, t]:
                if np.linalg.norm(paths[b, t] - check.shoulder) <= check.reach:
                    out[b] = check.full.first_problem(paths[b], grip[b], known_at)
                else:
                    out[b] = t
                break
            if not inside[b, t]:
                out[b] = t
                break
    return out


def test_first_outside_stops_where_the_definition_does(fmap, arm):
    """The compiled scan stops at each path's first failure: the same index as checking
    every sample, for paths that stay in X, leave it, leave the grid within and beyond
    the arm's reach, and meet a known-bad sample first; the map alone and with the arm."""
    from tutor.robot import MapCheck

    check = MapCheck(fmap, arm)
    rng = np.random.default_rng(11)
    T = 60
    start = np.array([0.45, 0.0, 0.25])
    ends = rng.uniform(fmap.origin - 0.4, fmap.upper + 0.4, (40, 3))
    s = np.linspace(0, 1, T)[None, :, None]
    paths = start + s * (ends[:, None] - start)
    paths += rng.normal(0, 0.003, paths.shape)
    grip = (rng.uniform(0, 1, (40, T)) > 0.5).astype(float)
    known = np.zeros((40, T), dtype=bool)
    known[::4, T // 3] = True
    got = check.first_outside(paths, grip, known_bad=known)
    np.testing.assert_array_equal(got, _first_outside_by_definition(check, paths, grip, known))
    kinds = {"whole": got == T, "known": got == T // 3, "failed": (got < T) & (got != T // 3)}
    assert all(k.any() for k in kinds.values()), {k: int(v.sum()) for k, v in kinds.items()}
    # the map alone: off the grid is outside X
    alone = fmap.first_outside(paths, grip, known_bad=known)
    bad = ~fmap.contains(paths, grip) | known
    want = np.where(bad.any(axis=1), np.argmax(bad, axis=1), T)
    np.testing.assert_array_equal(alone, want)
    # batch shapes: one path, and paths in a (2, 20) grid
    one = fmap.first_outside(paths[0], grip[0])
    assert one.shape == () and int(one) == int(fmap.first_outside(paths[:1], grip[:1])[0])
    np.testing.assert_array_equal(
        check.first_outside(paths.reshape(2, 20, T, 3), grip.reshape(2, 20, T)),
        check.first_outside(paths, grip).reshape(2, 20),
    )


def test_map_file_loads_without_pickle(fmap):
    with np.load(DEFAULT_MAP_PATH, allow_pickle=False) as z:
        for key in z.files:
            assert z[key].dtype != object, key
        assert z["margin"].shape == (2, *fmap.shape)
    with zipfile.ZipFile(DEFAULT_MAP_PATH) as zf:
        assert all(name.endswith(".npy") for name in zf.namelist())
    assert DEFAULT_MAP_PATH.stat().st_size < 2_000_000


def _map_file(path, **fields):
    """A map file with the right header and ``fields`` replacing its arrays."""
    arrays = {
        "format": np.array("lfd-tutor-feasibility-map"),
        "version": np.array(1),
        "origin": np.zeros(3),
        "spacing": np.array(0.01),
        **fields,
    }
    np.savez(path, **arrays)
    return path


def test_map_round_trip_and_bad_files(fmap, tmp_path):
    path = tmp_path / "map.npz"
    fmap.save(path)
    again = FeasibilityMap.load(path)
    np.testing.assert_array_equal(again.margin, fmap.margin)
    assert again.obstacles == fmap.obstacles
    with pytest.raises(InvalidFileError):
        FeasibilityMap.load(tmp_path / "missing.npz")
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip file at all")
    with pytest.raises(InvalidFileError):
        FeasibilityMap.load(junk)
    hostile = _map_file(tmp_path / "hostile.npz", margin=np.array([{"a": 1}], dtype=object))
    with pytest.raises(InvalidFileError):
        FeasibilityMap.load(hostile)
    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(InvalidFileError):
        FeasibilityMap.load(other)
    old = _map_file(tmp_path / "old.npz", version=np.array(99), margin=np.zeros((2, 2, 2)))
    with pytest.raises(InvalidFileError, match="version"):
        FeasibilityMap.load(old)


def test_robot_module_does_not_import_tasks():
    code = "import sys, tutor.robot; sys.exit('tutor.tasks' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0
