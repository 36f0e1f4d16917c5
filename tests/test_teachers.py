"""Simulated teachers (tutor.teachers), cohorts and their statistics (tutor.study).

Small cases only: each teacher model on one run, reduced cohorts for reproducibility.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from tutor.errors import InvalidParameterError
from tutor.tasks.maze_rules import advise_from
from tutor.tasks.pickplace import PickPlaceTask
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.teachers.maze import MazeTeacher
from tutor.teachers.model import CLUSTER, Belief, TeacherModel
from tutor.teachers.pickplace import MAX_RETRIES, PickPlaceTeacher
from tutor.teachers.traits import DEFAULT_POPULATION, Population, TeacherTraits

BASE = TeacherTraits(
    enough_maze=4,
    enough_pickplace=5,
    plan_focus=(0.5, 0.5),
    plan_spread_maze=0.2,
    plan_spread_pickplace=0.2,
    plan_choices_maze=1,
    plan_choices_pickplace=1,
    aim_sd=0.02,
    motor_noise=0.003,
    slip_rate=0.0,
    satisfaction=0.97,
    patience=12,
    setup_seconds=30.0,
    test_rate=0.5,
    notice_rate=0.9,
    repeat_rate=0.0,
)


def traits(**kw) -> TeacherTraits:
    return dataclasses.replace(BASE, **kw)


@pytest.fixture(scope="module")
def pickplace():
    return PickPlaceTask(feasibility=None)


# --------------------------------------------------------------------------- population


def test_population_draws_are_seeded_and_in_range():
    a = DEFAULT_POPULATION.sample(np.random.default_rng(7))
    b = DEFAULT_POPULATION.sample(np.random.default_rng(7))
    assert a == b
    pop = DEFAULT_POPULATION
    many = [pop.sample(np.random.default_rng(s)) for s in range(200)]
    for t in many:
        assert pop.enough_range[0] <= t.enough_maze <= pop.enough_range[1]
        assert pop.enough_range[0] <= t.enough_pickplace <= pop.enough_range[1]
        assert pop.aim_low <= t.aim_sd <= pop.aim_high
        assert 0 <= t.slip_rate <= 1 and pop.patience_low <= t.patience <= pop.patience_high
        assert all(0 <= f <= 1 for f in t.plan_focus)
    # one personal optimism factor: the two priors move together
    z = np.array([(t.enough_maze, t.enough_pickplace) for t in many], float)
    assert np.corrcoef(z.T)[0, 1] > 0.8
    # one personal scatter factor: the tray's spread is the maze's times the medians' ratio
    ratio = pop.spread_median_pickplace / pop.spread_median_maze
    for t in many:
        assert t.plan_spread("pickplace") == pytest.approx(t.plan_spread("maze") * ratio)
        assert t.plan_spread("maze") == t.plan_spread_maze


def test_population_rejects_impossible_settings():
    with pytest.raises(InvalidParameterError, match="satisfaction"):
        Population(satisfaction_low=0.9, satisfaction_high=1.2)
    with pytest.raises(InvalidParameterError, match="enough_range"):
        Population(enough_range=(5, 2))
    with pytest.raises(InvalidParameterError, match="heed"):
        Population(heed_low=0.8, heed_high=0.5)


def test_heed_is_drawn_last_and_only_when_it_varies():
    # a population whose teachers all heed draws every trait as before heed existed
    heeding = dataclasses.replace(DEFAULT_POPULATION, heed_low=1.0, heed_high=1.0)
    for seed in range(20):
        rng = np.random.default_rng(seed)
        t = heeding.sample(rng)
        after = rng.random()
        mixed = dataclasses.replace(heeding, heed_low=0.2, heed_high=0.6)
        rng2 = np.random.default_rng(seed)
        u = mixed.sample(rng2)
        assert t.heed == 1.0 and 0.2 <= u.heed <= 0.6
        assert dataclasses.replace(u, heed=1.0) == t  # every other trait the same draw
        assert rng2.random() != after  # heed took one draw from the same stream


def test_a_teacher_who_never_heeds_follows_their_plan_even_when_shown_red():
    pts = np.array([[x, y] for y in range(5) for x in range(5)], float)
    seen_failing = ([24, 23, 19, 18], [False] * 4)

    def targets(heed):
        model = TeacherModel(traits(heed=heed, aim_sd=1e-6, plan_focus=(0.0, 0.0),
                                    plan_spread_maze=1e-6),
                             np.random.default_rng(3), pts, pts.min(0), pts.max(0), "maze")
        model.belief.observe(*seen_failing)
        return [model.next_target()[1] for _ in range(40)]

    assert set(targets(1.0)) == {"red"}
    assert set(targets(0.0)) == {"plan"}
    half = targets(0.5)
    assert 5 < half.count("red") < 35  # about half of the time


def test_heed_changes_nothing_without_feedback(maze_task):
    a = MazeTeacher(traits(heed=1.0), maze_task).teach("NF", 4)
    b = MazeTeacher(traits(heed=0.0), maze_task).teach("NF", 4)
    assert a.n_demos == b.n_demos
    for x, y in zip(a.session.demos, b.session.demos, strict=True):
        np.testing.assert_array_equal(x, y)


# --------------------------------------------------------------------------- belief (omega)


def test_belief_prior_then_evidence():
    pts = np.array([[x, y] for y in range(5) for x in range(5)], float)
    b = Belief(pts, width=4.0, enough_demos=3)
    assert not b.estimate(2).any() and b.estimate(3).all()  # the prior alone
    b.demonstrate(0)
    assert b.estimate(1)[0] and b.coverage(1) == pytest.approx(1 / 25)
    # successes seen at three corners: everything between them is believed
    b.observe([0, 4, 20], [True, True, True])
    est = b.estimate(1)
    assert est[12] and est[6]  # inside the triangle
    assert not est[24]  # outside it and far from every success
    # a failure seen marks its neighbourhood as failing, even after the prior says enough
    b.observe([24], [False])
    assert not b.estimate(5)[24] and b.estimate(5)[0]
    assert np.allclose(b.worst_region(), pts[24])
    # demonstrating there counts (for the teacher) as mending it
    b.demonstrate(24)
    assert b.worst_region() is None and b.estimate(5)[24]


def test_worst_region_prefers_red_away_from_demos():
    pts = np.array([[x, 0.0] for x in range(11)], float)
    b = Belief(pts, width=10.0, enough_demos=5)
    b.observe(range(11), [False] * 11)
    b.demonstrated[0] = True
    far = b.worst_region()
    assert far[0] >= CLUSTER * 10  # all red: go where nothing was shown
    inside = np.zeros(11, bool)
    inside[:3] = True
    assert b.worst_region(within=inside)[0] <= 2 + CLUSTER * 10


def test_plan_repeats_on_purpose_and_starts_from_lessons():
    from tutor.teachers.model import TeacherModel

    pts = np.array([[x, y] for y in range(5) for x in range(5)], float)

    def model(**kw):
        person = traits(enough_maze=3, plan_spread_maze=0.2, **kw)
        return TeacherModel(person, np.random.default_rng(0), pts, (0, 0), (4, 4), "maze")

    never = model(repeat_rate=0.0)
    assert all(never.nearest(never.plan_point(avoid=[12])) != 12 for _ in range(20))
    always = model(repeat_rate=1.0)
    assert always.nearest(always.plan_point(avoid=[7])) == 7
    remembering = model()
    remembering.lessons = [3, 20, 4]
    firsts = [remembering.nearest(remembering.plan_point(avoid=[20])) for _ in range(2)]
    assert firsts == [3, 4]  # remembered failures first, skipping what was demonstrated


def test_plan_weighing_places_spreads_demos_out():
    from tutor.teachers.model import TeacherModel

    pts = np.array([[x, y] for y in range(11) for x in range(11)], float)
    given = [60]  # the centre

    def mean_gap(choices):
        person = traits(enough_maze=3, plan_spread_maze=0.3, plan_choices_maze=choices)
        m = TeacherModel(person, np.random.default_rng(1), pts, (0, 0), (10, 10), "maze")
        picks = np.array([m.plan_point(avoid=given) for _ in range(300)])
        return np.linalg.norm(picks - pts[60], axis=1).mean()

    assert mean_gap(3) > 1.3 * mean_gap(1)  # the farthest of three lands farther away
    # nothing given yet: nothing to weigh, so the first place drawn, as with one choice
    firsts = [
        TeacherModel(
            traits(enough_maze=3, plan_spread_maze=0.3, plan_choices_maze=choices),
            np.random.default_rng(1),
            pts,
            (0, 0),
            (10, 10),
            "maze",
        ).plan_point(avoid=[])
        for choices in (4, 1)
    ]
    np.testing.assert_array_equal(firsts[0], firsts[1])
    assert firsts[0].shape == (2,) and np.all((firsts[0] >= 0) & (firsts[0] <= 10))
    assert DEFAULT_POPULATION.sample(np.random.default_rng(0)).plan_choices("maze") == 1
    assert DEFAULT_POPULATION.sample(np.random.default_rng(0)).plan_choices("pickplace") == 2
    with pytest.raises(InvalidParameterError, match="plan_choices"):
        Population(plan_choices_pickplace=0)
    with pytest.raises(InvalidParameterError, match="task must be one of"):
        TeacherModel(traits(), np.random.default_rng(1), pts, (0, 0), (10, 10), "mazes")


# --------------------------------------------------------------------------- maze teachers


def test_nf_maze_teacher_stops_at_its_prior(maze_task):
    for enough in (2, 5):
        run = MazeTeacher(traits(enough_maze=enough), maze_task).teach(
            "NF", np.random.default_rng(1)
        )
        assert run.n_demos == enough and run.attempt.n_demos == enough and run.finished
        assert run.attempt.stopped == "satisfied"
        assert {d.chosen_by for d in run.attempt.demos} == {"plan"}
        assert all(len(r.shown) == 0 for r in run.session.history)  # r is empty


def test_vf_maze_teacher_aims_at_red(maze_task):
    teacher = MazeTeacher(traits(enough_maze=2, aim_sd=0.01), maze_task)
    run = teacher.teach("VF", np.random.default_rng(3))
    s = run.session
    targets = [d.chosen_by for d in run.attempt.demos]
    assert targets[0] == "plan" and "red" in targets
    for k, why in enumerate(targets):
        if why != "red":
            continue
        before = s.history[k - 1]
        start = maze_task.test_point_of(s.demos[k])
        gap = np.linalg.norm(maze_task.test_points[~before.passed] - start, axis=1).min()
        assert gap <= 0.02, f"demo {k + 1} started {gap:.3f} m from the nearest red start"
    # it stops on what it sees, not on its prior of 2 demos
    assert s.latest.efficacy >= 0.9 or run.attempt.stopped == "patience"


def test_vr_maze_teacher_follows_the_rules(maze_task):
    run = MazeTeacher(traits(), maze_task).teach("VR", np.random.default_rng(5))
    assert run.compliance and all(run.compliance)
    assert len(run.compliance) == run.n_demos  # every demo's compliance is in the record
    assert all(d.chosen_by.startswith("rule ") for d in run.attempt.demos)
    s = run.session
    # replay the rules: demo 2 starts within 4 cm of demo 1 (rule 2)
    assert [d.chosen_by for d in run.attempt.demos[:2]] == ["rule 1", "rule 2"]
    first = maze_task.test_point_of(s.demos[0])
    advice = advise_from(maze_task, s.history[0].passed, first)
    assert advice.rule == 2  # one demo cannot surround its start with green
    assert np.linalg.norm(maze_task.test_point_of(s.demos[1]) - first) <= advice.radius + 1e-9


def test_maze_teacher_same_traits_in_every_condition(maze_task):
    person = traits(enough_maze=3, patience=6, motor_noise=0.002)
    teacher = MazeTeacher(person, maze_task)
    runs = {c: teacher.teach(c, np.random.default_rng(11)) for c in ("NF", "VF", "VR")}
    assert all(run.condition == c for c, run in runs.items())
    assert teacher.traits == person  # teaching changes no trait
    # the same person's traits act in every condition: NF stops at their prior,
    # every run within their patience, every first demo from the same plan
    assert runs["NF"].n_demos == person.enough_maze
    assert all(run.n_demos <= person.patience for run in runs.values())
    firsts = {c: run.attempt.demos[0].samples for c, run in runs.items()}
    assert firsts["NF"] == firsts["VF"] == firsts["VR"]
    again = MazeTeacher(person, maze_task).teach("VF", np.random.default_rng(11))
    assert again.attempt.demos[0].samples == firsts["VF"]
    with pytest.raises(InvalidParameterError, match="NF, VF, VR"):
        teacher.teach("BF", np.random.default_rng(0))


def _trait_columns(rows: list[dict]) -> pd.DataFrame:
    table = pd.DataFrame(rows)
    return table[[c for c in table.columns if c.startswith("trait_")]]


@pytest.mark.parametrize("experiment, runs", [(1, 3), (2, 3)])
def test_cohort_teacher_keeps_its_traits_in_every_run(experiment, runs):
    """Within subjects (Experiment 1) and across the three runs (Experiment 2), every run
    of one simulated teacher records the same traits; another teacher's differ."""
    from tutor.study.cohort import simulate_teacher

    n = 2 if experiment == 1 else 8
    tables = [_trait_columns(simulate_teacher(experiment, k, 5, n)[0]) for k in (0, 1)]
    for table in tables:
        assert len(table) == runs and table.shape[1] > 5
        assert (table.nunique() == 1).all(), table.T
    assert not tables[0].iloc[0].equals(tables[1].iloc[0])


def test_experiment2_counts_ambiguous_demos_as_the_paper_did():
    """The paper's failure table for Experiment 2 found ambiguous demos by the efficacy
    change alone (delta_l <= eps_m - eps_{m-1} <= delta_u): every correct demo after the
    first whose change lies in the band counts, however far from the earlier ones; the
    maze keeps the task's similarity test."""
    from tutor.framework.failures import Thresholds
    from tutor.study.cohort import StudySettings, simulate_teacher

    assert StudySettings().ambiguity("pickplace") == np.inf
    assert StudySettings().ambiguity("maze") is None
    assert StudySettings(pickplace_ambiguity=0.03).ambiguity("pickplace") == 0.03
    thr = Thresholds()
    demos = pd.DataFrame([d for k in range(4) for d in simulate_teacher(2, k, 3, 8)[1]])
    band = demos.delta.between(thr.delta_lower, thr.delta_upper)
    expected = demos.correct & (demos.demo > 1) & band
    assert (demos.ambiguous == expected).all()
    assert expected.any() and not demos[demos.demo == 1].ambiguous.any()
    far = demos.ambiguous & (demos.similarity > 0.03)  # the old 3 cm test would miss them
    assert far.any()


def test_maze_slip_makes_an_incorrect_demo(maze_task):
    t = MazeTeacher(traits(), maze_task)
    rng = np.random.default_rng(2)
    bad = maze_task.preprocess(t.stroke(np.array([0.1, 0.03]), rng, slip=True))
    good = maze_task.preprocess(t.stroke(np.array([0.1, 0.03]), rng, slip=False))
    assert not maze_task.judge_demo(bad, bad[0, 1:]).passed[0]
    assert maze_task.judge_demo(good, good[0, 1:]).passed[0]


# --------------------------------------------------------------------------- pick-and-place


def test_rf_teacher_catches_a_wrong_plant_slip_after_the_replay(pickplace):
    clumsy = traits(slip_rate=1.0, notice_rate=1.0, patience=1, setup_seconds=0.0)
    rf = PickPlaceTeacher(clumsy, pickplace).teach("RF", np.random.default_rng(4))
    assert len(rf.attempt.undone) == MAX_RETRIES  # noticed every slip it was shown
    assert all(d.mistake == "wrong_plant" for d in rf.attempt.undone)
    assert [e.kind for e in rf.record.events].count("undo") == MAX_RETRIES
    nf = PickPlaceTeacher(clumsy, pickplace).teach("NF", np.random.default_rng(4))
    assert nf.attempt.undone == ()  # nothing shown, nothing noticed
    assert not nf.session.history[-1].demo_passed  # the wrong-plant demo stays
    assert nf.attempt.demos[-1].mistake == "wrong_plant"


def test_rf_teacher_keeps_correct_demos(pickplace):
    careful = traits(slip_rate=0.0, notice_rate=1.0, patience=3, setup_seconds=0.0)
    run = PickPlaceTeacher(careful, pickplace).teach("RF", np.random.default_rng(8))
    assert all(r.demo_passed for r in run.session.history)
    assert all(len(r.shown) == 1 for r in run.session.history)  # r = the replay


def test_bf_teacher_pays_125_s_per_demo_under_the_cap(pickplace):
    t = traits(enough_pickplace=12, satisfaction=1.0, patience=12, setup_seconds=30.0)
    run = PickPlaceTeacher(t, pickplace).teach("BF", np.random.default_rng(6))
    s = run.session
    assert all(len(r.shown) == 5 for r in s.history)
    robot = 125.0 * s.n_demos
    demo_seconds = [d.seconds for d in run.attempt.demos]
    assert all(x is not None and x > 0 for x in demo_seconds)
    assert run.elapsed >= robot + sum(demo_seconds) + 30.0 * s.n_demos - 1e-6
    # a slow set-up runs out of the 15 minutes: 300 s + ~10 s demo + 125 s each, so no
    # more than 3 demos start before the cap, and (the paper's rule) none ends after it
    slow = PickPlaceTeacher(dataclasses.replace(t, setup_seconds=300.0), pickplace)
    late = slow.teach("BF", np.random.default_rng(6))
    assert late.attempt.stopped == "time"
    assert late.elapsed <= late.cap and late.out_of_time
    assert 1 <= late.session.n_demos <= 3


def test_sf_teacher_picks_tests_near_its_demos(pickplace):
    t = traits(test_rate=1.0, patience=4, enough_pickplace=4)
    run = PickPlaceTeacher(t, pickplace).teach("SF", np.random.default_rng(9))
    assert all(not test.after_run for test in run.attempt.tests)  # SF tests during the run
    tests = [p for test in run.attempt.tests for p in test.plants]
    assert tests, "an SF teacher with test_rate 1 asks for tests"
    demos = {pickplace.nearest_test_point(c) for c in run.session.demo_points}
    cols = pickplace.scene.cols

    def near(p):
        return any(abs(p // cols - d // cols) <= 1 and abs(p % cols - d % cols) <= 1 for d in demos)

    assert np.mean([near(p) for p in tests]) >= 0.5


def test_teacher_remembers_failures_between_runs(pickplace):
    teacher = PickPlaceTeacher(traits(patience=2, enough_pickplace=2), pickplace)
    run1 = teacher.teach("BF", np.random.default_rng(12))
    seen_failing = [int(i) for r in run1.session.history for i in r.shown[~r.passed[r.shown]]]
    assert teacher.lessons and set(seen_failing) <= set(teacher.lessons)
    lessons = list(teacher.lessons)
    run2 = teacher.teach("BF", np.random.default_rng(13))
    first = pickplace.nearest_test_point(run2.session.demo_points[0])
    assert first == lessons[0]
    nf = PickPlaceTeacher(traits(patience=2, enough_pickplace=2), pickplace)
    run = nf.teach("NF", np.random.default_rng(14))
    assert [t.after_run for t in run.attempt.tests] == [True]  # tests after the run


def test_protocol_spend_and_undo_keep_the_time(pickplace):
    run = PickPlaceRun("RF", pickplace)
    run.spend(40.0)
    run.demonstrate(44, rng=np.random.default_rng(0))
    used = run.elapsed
    assert used == pytest.approx(40.0 + run.attempt.demos[0].seconds + 25.0)
    assert run.undo() is None and run.session.n_demos == 0
    assert run.elapsed == pytest.approx(used)  # taking a demo back does not give time back
    assert len(run.attempt.undone) == 1 and run.attempt.other_seconds == pytest.approx(used)
    with pytest.raises(InvalidParameterError):
        run.spend(-1)


# --------------------------------------------------------------------------- cohorts


def test_same_seed_same_numbers_whatever_the_workers():
    from tutor.study.cohort import run_experiment

    a = run_experiment(1, seed=3, n=3, workers=1, progress=False)
    b = run_experiment(1, seed=3, n=3, workers=2, progress=False)
    pd.testing.assert_frame_equal(a.runs, b.runs)
    pd.testing.assert_frame_equal(a.demos, b.demos)
    c = run_experiment(1, seed=4, n=3, workers=2, progress=False)
    assert not a.runs["eta"].equals(c.runs["eta"])


def test_experiment2_reduced_cohort_is_reproducible():
    from tutor.study.cohort import run_experiment

    a = run_experiment(2, seed=1, n=8, workers=2, progress=False)
    b = run_experiment(2, seed=1, n=8, workers=2, progress=False)
    pd.testing.assert_frame_equal(a.runs, b.runs)
    assert len(a.runs) == 8 * 3
    assert a.runs.groupby("condition", observed=True).teacher.nunique().tolist() == [2] * 4
    assert (a.runs.seconds <= 900 + 300).all()  # the last demo may run past the cap


@pytest.mark.parametrize(
    ("experiment", "n", "seed", "match"),
    [
        (3, None, 0, "experiment must be 1"),
        (1, 1, 0, "at least 3 teachers"),
        (1, 2, 0, "at least 3 teachers"),
        (1, 3001, 0, "at most 3000 teachers"),
        (2, 3004, 0, "at most 3000 teachers"),
        (2, 10, 0, "multiple of 4"),
        (1, None, -1, "seed must be"),
        (1, 2.5, 0, "integer"),
    ],
)
def test_bad_requests_are_named_errors(experiment, n, seed, match):
    from tutor.study.cohort import check_request

    with pytest.raises(InvalidParameterError, match=match):
        check_request(experiment, n, seed)


def test_cli_reports_bad_input_and_writes_results(tmp_path, capsys):
    from tutor.__main__ import main

    for bad in (["--experiment", "3"], ["--experiment", "1", "--seed", "-2"]):
        with pytest.raises(SystemExit) as info:  # argparse's refusal, exit code 2
            main(["reproduce", *bad, "--out", str(tmp_path)])
        assert info.value.code == 2
        assert "error: argument --" in capsys.readouterr().err
    assert main(["reproduce", "--experiment", "2", "--n", "6", "--out", str(tmp_path)]) == 2
    assert "InvalidParameterError" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # refused before anything was written
    code = main(
        [
            "reproduce",
            "--experiment",
            "1",
            "--n",
            "3",
            "--seed",
            "2",
            "--out",
            str(tmp_path),
            "--workers",
            "1",
            "--no-progress",
        ]
    )
    assert code == 0
    out = capsys.readouterr().out
    assert "paper" in out and "Repeated-measures ANOVA" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "experiment1.png",
        "experiment1_demos.csv",
        "experiment1_report.txt",
        "experiment1_runs.csv",
        "experiment1_summary.json",
    ]


# --------------------------------------------------------------------------- statistics


def _synthetic_within(effect: float, n: int = 12, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    rows = []
    for t in range(n):
        base = rng.normal(0.1, 0.02)
        for cond, shift in (("NF", 0.0), ("VF", effect), ("VR", effect)):
            eta = base + shift + rng.normal(0, 0.01)
            rows.append(
                {
                    "teacher": t,
                    "condition": cond,
                    "run": 1,
                    "eta": eta,
                    "n_demos": 5,
                    "efficacy": min(1, 5 * eta),
                    "reached_target": True,
                }
            )
    return pd.DataFrame(rows)


def test_experiment1_stats_on_a_synthetic_frame():
    from tutor.study import stats

    st = stats.experiment1_stats(_synthetic_within(0.08))
    a = st["anova"]
    assert (a["ddof1"], a["ddof2"]) == (2, 22) and a["p"] < 1e-6
    assert 0 <= a["sphericity_p"] <= 1
    assert set(zip(st["pairwise"].A, st["pairwise"].B, strict=True)) == {
        ("NF", "VF"),
        ("NF", "VR"),
        ("VF", "VR"),
    }
    c = stats.conclusions(_synthetic_within(0.08), 1)
    assert c == {"NF<VF": True, "NF<VR": True, "VF~VR": True}
    assert not stats.conclusions(_synthetic_within(0.0), 1)["NF<VF"]
    rel = stats.relative_improvement(st, 1)
    assert rel["VF/NF"] > 1.5


def test_experiment2_stats_and_failure_table_on_a_synthetic_frame():
    from tutor.study import stats

    rng = np.random.default_rng(1)
    rows = []
    for t in range(16):
        cond = ("NF", "RF", "BF", "SF")[t // 4]
        for run in (1, 2, 3):
            eta = (0.25 if cond == "BF" else 0.12) + rng.normal(0, 0.02)
            rows.append(
                {
                    "teacher": t,
                    "condition": cond,
                    "run": run,
                    "eta": eta,
                    "n_demos": 4,
                    "efficacy": 4 * eta,
                    "seconds": 600.0,
                    "errors": int(cond != "RF"),
                    "undemonstrated": 30 if cond == "BF" else 10,
                    "ambiguous": 0 if cond == "BF" else 2,
                }
            )
    runs = pd.DataFrame(rows)
    st = stats.experiment2_stats(runs)
    assert st["anova"]["condition"]["ddof1"] == 3 and st["anova"]["condition"]["p"] < 1e-4
    assert st["anova"]["interaction"]["ddof1"] == 6
    table = stats.failure_table(runs)
    assert table.loc["undemonstrated", "BF"] == 12 * 30
    assert list(table.columns) == ["NF", "RF", "BF", "SF"]
    assert all(stats.conclusions(runs, 2, st).values())
    assert stats.relative_improvement(st, 2)["mean"] == pytest.approx(
        st["means"]["BF"] / np.mean([st["means"][c] for c in ("NF", "RF", "SF")])
    )
