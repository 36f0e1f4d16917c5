"""Adaptive test sets (tutor.framework.selectors), the adaptive policy and condition AF."""

from __future__ import annotations

import numpy as np
import pytest

from tutor.errors import InvalidParameterError
from tutor.framework import TeachingSession
from tutor.framework.selectors import (
    SELECTORS,
    FarthestPoint,
    FrameDisagreement,
    PredictedFailures,
    SelectionContext,
    check_k,
    normalised_space,
    select,
)
from tutor.tasks.pickplace import load_scene
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.tpgmm import TPGMM, Frame, frame_disagreement, frame_views

TRAY = load_scene().plant_positions  # (100, 3), index = row * 10 + col; z is constant
CORNERS = {0, 9, 90, 99}


# ---------------------------------------------------------------- a small 2-D task

T = 50
TIMES = np.linspace(0.0, 1.0, T)


def line_frames(c: float, same: bool = False):
    """A start frame at the origin and a target frame at (c, 1) (or at the origin too)."""
    target = np.zeros(2) if same else np.array([c, 1.0])
    return [Frame(np.eye(2), np.zeros(2)), Frame(np.eye(2), target)]


def line_demo(c: float, rng) -> np.ndarray:
    """A straight stroke from the origin to (c, 1)."""
    path = TIMES[:, None] * np.array([c, 1.0]) + 0.002 * rng.standard_normal((T, 2))
    return np.column_stack([TIMES, path])


def two_clusters():
    """A model taught at both ends of [-1, 1], and the 21 conditions between."""
    rng = np.random.default_rng(0)
    taught = [-1.0, -0.9, -0.8, 0.8, 0.9, 1.0]
    model = TPGMM(4, reg_covar=1e-3).fit(
        [line_demo(c, rng) for c in taught], [line_frames(c) for c in taught]
    )
    conditions = np.linspace(-1.0, 1.0, 21)[:, None]
    context = SelectionContext(
        test_points=conditions,
        demo_points=np.array(taught)[:, None],
        learner=model,
        frames=[line_frames(c) for c in conditions[:, 0]],
        times=TIMES,
    )
    return model, context


# ---------------------------------------------------------------- (a) farthest point


def test_farthest_point_from_the_tray_centre_picks_the_corners_first():
    centre = TRAY.mean(axis=0)
    ctx = SelectionContext(test_points=TRAY, demo_points=centre[None])
    picks = SELECTORS["farthest"](6, ctx)
    assert set(picks[:4].tolist()) == CORNERS
    assert len(set(picks.tolist())) == 6
    # then the middles of the edges: 5 or 4 plants from two corners
    r, c = np.divmod(picks[4:], 10)
    assert np.all((r == 0) | (r == 9) | (c == 0) | (c == 9))


def test_farthest_point_after_a_corner_goes_to_the_opposite_one():
    ctx = SelectionContext(test_points=TRAY, demo_points=TRAY[[0]])
    picks = FarthestPoint()(3, ctx)
    assert picks[0] == 99 and set(picks[1:].tolist()) == {9, 90}


def test_the_normalised_space_scales_each_column_and_keeps_constant_ones():
    X, Y = normalised_space(TRAY, TRAY[[0, 99]])
    assert X[:, :2].min() == 0 and X[:, :2].max() == 1
    assert np.all(X[:, 2] == 0)  # z is the same for every plant: only shifted
    assert np.allclose(Y, X[[0, 99]])


# ---------------------------------------------------------------- (b) frame disagreement


def test_frame_disagreement_is_zero_for_a_single_frame():
    rng = np.random.default_rng(1)
    one = lambda c: [Frame(np.eye(2), np.array([c, 1.0]))]  # noqa: E731
    model = TPGMM(3).fit([line_demo(c, rng) for c in (0.0, 0.5)], [one(0.0), one(0.5)])
    D = frame_disagreement(model, [one(c) for c in np.linspace(-2, 2, 9)], TIMES)
    assert D.shape == (9,) and np.all(np.abs(D) < 1e-9)


def test_frame_disagreement_is_zero_where_the_frames_coincide():
    rng = np.random.default_rng(2)
    taught = (0.0, 0.5)
    model = TPGMM(3).fit(
        [line_demo(c, rng) for c in taught], [line_frames(c, same=True) for c in taught]
    )
    D = frame_disagreement(model, [line_frames(c, same=True) for c in (0.0, 3.0)], TIMES)
    assert np.all(np.abs(D) < 1e-9)


def test_frame_views_are_the_local_regressions_moved_into_the_world():
    model, ctx = two_clusters()
    means, covs = frame_views(model, ctx.frames[:2], TIMES)
    local, local_cov = model.regress_local(TIMES)
    assert means.shape == (2, 2, T, 2) and covs.shape == (2, 2, T, 2, 2)
    assert np.allclose(means[1, 1], local[1] + ctx.frames[1][1].b)  # A = I: a shift
    assert np.allclose(covs[0, 0], local_cov[0])
    # D from the views themselves, in the world, agrees with the local computation
    mu, _ = model.reproduce_batch(ctx.frames[:2], TIMES)
    gap = means - mu[:, None]
    world = np.einsum("bpti,bptij,bptj->bt", gap, np.linalg.inv(covs), gap).mean(axis=1)
    assert np.allclose(frame_disagreement(model, ctx.frames[:2], TIMES), world)


def test_the_score_finds_the_gap_between_two_clusters_of_demos_where_d_alone_does_not():
    model, ctx = two_clusters()
    D = frame_disagreement(model, ctx.frames, TIMES)
    score = FrameDisagreement().scores(ctx)
    middle, ends = 10, [0, 20]
    # D alone: near 0 in the gap, largest at the demonstrated ends (module docstring)
    assert D[middle] < 0.1 * D[ends].min()
    # the combined score: largest in the gap, 0 where demonstrated
    assert score[middle] == score.max() and np.all(score[ends] == 0)
    assert FrameDisagreement()(1, ctx).tolist() == [middle]


def test_disagreement_on_the_tray_looks_across_a_line_of_demos(pickplace_task):
    session = TeachingSession(pickplace_task, feedback="adaptive", selector="disagreement", k=2)
    rng = np.random.default_rng(3)
    for plant in (0, 44, 99):  # the diagonal
        record = session.add_demo(
            pickplace_task.demonstrate(plant, rng), point=pickplace_task.test_points[plant]
        )
    assert set(record.shown.tolist()) == {9, 90}  # the two corners off the diagonal


def test_picks_are_kept_the_minimum_distance_apart(pickplace_task):
    session = TeachingSession(pickplace_task, feedback="none")
    session.add_demo(
        pickplace_task.demonstrate(44, np.random.default_rng(4)),
        point=pickplace_task.test_points[44],
    )
    ctx = SelectionContext(
        test_points=pickplace_task.test_points,
        demo_points=np.array(session.demo_points),
        learner=session.learner,
        frames=pickplace_task.frame_batch(pickplace_task.test_points),
        times=pickplace_task.times,
        realisations=session.realisations,
    )
    X, _ = normalised_space(pickplace_task.test_points)
    for spacing in (0.3, 0.5):
        picks = FrameDisagreement(min_distance=spacing)(5, ctx)
        gaps = np.linalg.norm(X[picks][:, None] - X[picks][None], axis=-1)
        assert len(set(picks.tolist())) == 5
        assert gaps[np.triu_indices(5, 1)].min() >= spacing
    close = FrameDisagreement(min_distance=0.0)(5, ctx)
    loose = np.linalg.norm(X[close][:, None] - X[close][None], axis=-1)
    assert loose[np.triu_indices(5, 1)].min() < 0.3  # without it, the picks bunch up
    # a spacing no two plants have: still 5 picks (the best of the rest), same cost
    assert len(set(FrameDisagreement(min_distance=5.0)(5, ctx).tolist())) == 5


# ---------------------------------------------------------------- (c) the oracle, random


def test_the_oracle_picks_failures_nearest_to_the_demos_first():
    passed = np.ones(100, dtype=bool)
    passed[[1, 55, 99, 12]] = False
    ctx = SelectionContext(
        test_points=TRAY, demo_points=TRAY[[0]], passed=passed, rng=np.random.default_rng(0)
    )
    assert select("failures", 3, ctx).tolist() == [1, 12, 55]
    assert select("failures", 10, ctx).tolist() == [1, 12, 55, 99]  # only 4 fail
    shuffled = PredictedFailures(order="random")(4, ctx)
    assert sorted(shuffled.tolist()) == [1, 12, 55, 99]
    with pytest.raises(InvalidParameterError, match="needs passed"):
        select("failures", 3, SelectionContext(test_points=TRAY, demo_points=TRAY[[0]]))


def test_random_picks_come_from_the_generator_without_repeats():
    make = lambda seed: SelectionContext(  # noqa: E731
        test_points=TRAY, demo_points=TRAY[[0]], rng=np.random.default_rng(seed)
    )
    a, b, c = (select("random", 5, make(s)) for s in (7, 7, 8))
    assert a.tolist() == b.tolist() != c.tolist() and len(set(a.tolist())) == 5
    with pytest.raises(InvalidParameterError, match="needs rng"):
        select("random", 5, SelectionContext(test_points=TRAY, demo_points=TRAY[[0]]))


# ---------------------------------------------------------------- k and names


def test_k_larger_than_b_hat_shows_every_condition_once():
    model, ctx = two_clusters()
    full = SelectionContext(**{**ctx.__dict__, "rng": np.random.default_rng(0)})
    for name in ("farthest", "disagreement", "random"):
        picks = select(name, 1000, full)
        assert sorted(picks.tolist()) == list(range(21)), name


@pytest.mark.parametrize("k", [0, -2, 2.5, "3", True, None])
def test_a_bad_k_is_refused_with_what_k_means(k):
    with pytest.raises(InvalidParameterError, match="how many test points the robot shows"):
        check_k(k)
    ctx = SelectionContext(test_points=TRAY, demo_points=TRAY[[0]])
    with pytest.raises(InvalidParameterError, match="k must be a whole number >= 1"):
        select("farthest", k, ctx)


def test_bad_selectors_and_options_are_refused(pickplace_task):
    ctx = SelectionContext(test_points=TRAY, demo_points=TRAY[[0]])
    with pytest.raises(InvalidParameterError, match="farthest, disagreement, failures, random"):
        select("kcenter", 5, ctx)
    with pytest.raises(InvalidParameterError, match="only used with feedback='adaptive'"):
        TeachingSession(pickplace_task, feedback="batch", batch=[0], k=3)
    with pytest.raises(InvalidParameterError, match="selector must be one of"):
        TeachingSession(pickplace_task, feedback="adaptive", selector="nearest")
    with pytest.raises(InvalidParameterError, match="min_distance"):
        FrameDisagreement(min_distance=-1)


# ---------------------------------------------------------------- the session and condition AF


def test_an_adaptive_session_shows_k_picks_and_withholds_the_totals(pickplace_task):
    session = TeachingSession(pickplace_task, feedback="adaptive", selector="farthest", k=4)
    record = session.add_demo(
        pickplace_task.demonstrate(44, np.random.default_rng(5)),
        point=pickplace_task.test_points[44],
    )
    assert record.shown.tolist()[:1] == [99] and len(record.shown) == 4
    from tutor.framework import reveal

    assert not reveal("adaptive", 100, record.shown).totals


def test_af_costs_what_bf_costs(pickplace_task):
    raw = pickplace_task.demonstrate(12, np.random.default_rng(6))
    af, bf = PickPlaceRun("AF", pickplace_task), PickPlaceRun("BF", pickplace_task)
    assert af.feedback_seconds == bf.feedback_seconds == 125.0
    af.demonstrate(12, raw=raw)
    bf.demonstrate(12, raw=raw)
    assert af.elapsed == pytest.approx(bf.elapsed)
    assert (af.selector.name, af.k) == ("disagreement", 5)
    assert PickPlaceRun("AF", pickplace_task, k=2).feedback_seconds == 50.0
    design = PickPlaceRun.protocol()
    assert design.paper_codes == ("NF", "RF", "BF", "SF")  # the paper's four, unchanged
    assert design.codes == ("NF", "RF", "BF", "SF", "AF", "HF")
    assert design.condition("AF").selector == ("disagreement", 5)


@pytest.mark.parametrize("selector", ["random", "disagreement"])
def test_an_af_run_saved_and_loaded_shows_the_same_r(pickplace_task, tmp_path, selector):
    run = PickPlaceRun("AF", pickplace_task, selector=selector, rng=11)
    rng = np.random.default_rng(7)
    for plant in (44, 3, 96):
        run.demonstrate(plant, rng=rng)
    shown = [r.shown.tolist() for r in run.session.history]
    assert [list(d.shown) for d in run.attempt.demos] == shown  # stored in the record
    path = run.save(tmp_path / "af.json")
    back = PickPlaceRun.load(path, pickplace_task)  # a fresh generator: only the stored picks agree
    assert [r.shown.tolist() for r in back.session.history] == shown
    assert back.elapsed == pytest.approx(run.elapsed)
    if selector == "random":  # a replay that picked again would show other plants
        again = PickPlaceRun("AF", pickplace_task, selector="random", rng=12)
        for d in run.attempt.demos:
            again.add_demo(np.asarray(d.samples), point=d.point, seconds=d.seconds)
        assert [r.shown.tolist() for r in again.session.history] != shown


def test_undo_and_remove_keep_what_was_shown(pickplace_task):
    run = PickPlaceRun("AF", pickplace_task, selector="random", rng=2)
    rng = np.random.default_rng(8)
    for plant in (0, 55, 99):
        run.demonstrate(plant, rng=rng)
    first = [r.shown.tolist() for r in run.session.history]
    run.session.remove_demo(1)
    assert [r.shown.tolist() for r in run.session.history] == first[1:]
    spent = run.elapsed
    run.undo()
    assert run.elapsed == pytest.approx(spent)  # its 125 s stay spent


def test_the_simulated_teacher_reads_af_as_bf(pickplace_task):
    from tutor.teachers.pickplace import PickPlaceTeacher
    from tutor.teachers.traits import DEFAULT_POPULATION

    traits = DEFAULT_POPULATION.sample(np.random.default_rng(3))
    run = PickPlaceTeacher(traits, pickplace_task).teach("AF", np.random.default_rng(4))
    assert run.finished and run.session.n_demos >= 1
    assert all(len(r.shown) == 5 for r in run.session.history)
    two = PickPlaceTeacher(traits, pickplace_task).teach("AF", np.random.default_rng(4), k=2)
    assert all(len(r.shown) == 2 for r in two.session.history)
    with pytest.raises(InvalidParameterError, match="only for the adaptive conditions"):
        PickPlaceTeacher(traits, pickplace_task).teach("BF", 0, k=2)


def test_the_cohort_runs_af_only_when_asked():
    from tutor.study.cohort import check_conditions, check_request, run_experiment

    assert check_conditions(2) == ("NF", "RF", "BF", "SF")
    assert check_request(2, None, 0, ("NF", "RF", "BF", "SF", "AF")) == (2, 45, 0)
    with pytest.raises(InvalidParameterError, match="distinct conditions"):
        check_conditions(2, ("BF", "BF"))
    with pytest.raises(InvalidParameterError, match="distinct conditions"):
        check_conditions(1, ("NF", "AF"))
    with pytest.raises(InvalidParameterError, match="multiple of 2"):
        check_request(2, 5, 0, ("BF", "AF"))
    result = run_experiment(2, seed=0, n=4, workers=1, progress=False, conditions=("BF", "AF"))
    runs = result.runs
    assert list(runs["condition"].cat.categories) == ["BF", "AF"]
    assert (runs["condition"] == "AF").sum() == 6  # 2 teachers x 3 runs


def test_the_start_form_offers_af_after_the_papers_four(person):
    from tutor.views.start_pickplace import condition_from_env, pick_and_place_experiment

    form = pick_and_place_experiment(scene3d=False)
    buttons = form.condition_buttons
    assert list(buttons.options) == ["NF", "RF", "BF", "SF", "AF", "HF"] and form.condition is None
    assert "beyond the paper" in buttons.tooltips[-2] and "beyond the paper" in (
        form.beyond_note.value
    )
    person.setenv("TUTOR_CONDITION", "af")
    assert condition_from_env() == "AF"


def test_the_tutor_shows_af_picks_on_the_tray(pickplace_task):
    from tutor.views.pickplace_app import PickPlaceTutor, tray_status

    tutor = PickPlaceTutor("AF", task=pickplace_task, seed=1)
    tutor.demonstrate(44)
    shown = tutor.run.session.latest.shown
    status = tray_status(tutor.run)
    assert set(np.flatnonzero(np.isin(status, ["pass", "fail"])).tolist()) == set(shown.tolist())
    assert "Condition AF" in tutor.panel.value


# ---------------------------------------------------------------- the cost


def test_the_selector_benchmark_runs_and_reports_every_selector(tmp_path):
    """Its cost is measured by ``benchmarks/bench_selectors.py`` (target 20 ms per demo,
    README), not here: this runs the script once, small, as a user would."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "bench_selectors.json"
    done = subprocess.run(
        [
            sys.executable,
            str(root / "benchmarks" / "bench_selectors.py"),
            "--repeats",
            "1",
            "--sets",
            "1",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=root,
    )
    assert done.returncode == 0, done.stderr
    assert f"written to {out}" in done.stdout
    results = json.loads(out.read_text())
    text = json.dumps(results)
    assert all(name in text for name in SELECTORS), results


# ---------------------------------------------------------------- the maze: VA


def test_the_maze_va_run_shows_k_start_points_and_is_read_as_vf():
    from tutor.tasks.maze import MazeTask
    from tutor.tasks.maze_run import MazeRun
    from tutor.teachers.maze import MazeTeacher
    from tutor.teachers.traits import DEFAULT_POPULATION

    task = MazeTask()
    assert MazeRun.protocol().paper_codes == ("NF", "VF", "VR")  # the paper's three
    traits = DEFAULT_POPULATION.sample(np.random.default_rng(0))
    run = MazeTeacher(traits, task).teach("VA", np.random.default_rng(1), k=3)
    assert all(len(r.shown) == 3 for r in run.session.history)
    assert not run.visibility().totals or run.finished
    back = MazeRun.from_dict(run.to_dict(), task)
    assert [r.shown.tolist() for r in back.session.history] == [
        r.shown.tolist() for r in run.session.history
    ]
    with pytest.raises(InvalidParameterError, match="only for the adaptive conditions"):
        MazeTeacher(traits, task).teach("VF", 0, k=3)


def test_af_has_its_instruction_and_worked_example():
    from tutor.views.worked_example import example_png, instruction_text

    words = instruction_text(2, "AF")
    assert "beyond the paper" in words and len(words.split()) <= 45
    assert example_png(2, "AF")[:8] == b"\x89PNG\r\n\x1a\n"
