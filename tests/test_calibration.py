"""The calibration of the simulated teachers and the maze (tutor.study.calibration)."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pandas as pd
import pytest

from tutor.__main__ import main
from tutor.errors import InvalidParameterError
from tutor.study import calibration
from tutor.study.cohort import StudySettings, cohort_task
from tutor.tasks.maze import MazeTask, load_layout
from tutor.teachers.traits import DEFAULT_POPULATION


def test_the_bundled_blocks_give_the_bundled_maze_back():
    layout = load_layout()  # the calibrated maze: blocks 15.5 cm in, 2.9 cm high
    assert layout.blocks == pytest.approx({"reach": 0.155, "low": 0.091, "height": 0.029,
                                           "gap": 0.061})
    def corners(lay):
        return [v for b in lay.obstacles for v in (b.x0, b.x1, b.y0, b.y1)]

    same = layout.with_blocks(**layout.blocks)
    assert corners(same) == pytest.approx(corners(layout), abs=1e-12)
    np.testing.assert_allclose(same.guide_points, layout.guide_points, atol=1e-12)
    assert corners(layout.with_blocks()) == pytest.approx(corners(layout), abs=1e-12)  # as now


def test_new_blocks_move_both_blocks_and_a_careful_hand_still_passes():
    task = MazeTask(load_layout().with_blocks(reach=0.16, low=0.08, height=0.06, gap=0.03))
    one, two = task.layout.obstacles
    assert (one.x0, one.x1, one.y0, one.y1) == pytest.approx((0.0, 0.16, 0.08, 0.14))
    assert (two.x0, two.x1, two.y0, two.y1) == pytest.approx((0.04, 0.20, 0.17, 0.23))
    assert task.layout.blocks["gap"] == pytest.approx(0.03)
    rng = np.random.default_rng(0)
    for i in (0, 69, 139):  # the scripted hand goes through both gaps
        demo = task.preprocess(task.scripted_demo(i, rng))
        assert task.judge_demo(demo, task.test_points[i]).passed[0]


@pytest.mark.parametrize(
    "blocks, match",
    [({"reach": 0.195}, "side gap"), ({"reach": -0.1}, "reach"),
     ({"height": 0.005}, "high"), ({"gap": 0.01}, "between"), ({"low": 0.065}, "start zone"),
     ({"low": 0.12, "height": 0.06, "gap": 0.07}, "target"),
     ({"reach": float("nan")}, "reach"), ({"low": "0.1"}, "low"), ({"gap": True}, "gap")],
)
def test_a_maze_no_hand_can_pass_is_named(blocks, match):
    with pytest.raises(InvalidParameterError, match=match):
        load_layout().with_blocks(**blocks)


def test_the_study_settings_build_the_maze_with_the_blocks():
    task = cohort_task("maze", StudySettings(maze_blocks=(0.145, None, None, None)))
    assert task.layout.blocks["reach"] == pytest.approx(0.145)
    assert task.layout.blocks["low"] == pytest.approx(load_layout().blocks["low"])
    assert cohort_task("maze", StudySettings()).layout.blocks == pytest.approx(
        load_layout().blocks
    )


@pytest.mark.parametrize("corner", range(8))
def test_every_corner_of_the_geometry_prior_is_a_maze_a_hand_passes(corner):
    names = ("maze_low", "maze_height", "maze_gap_share")
    theta = {n: (calibration.PARAMETERS[n].low, calibration.PARAMETERS[n].high)[(corner >> i) & 1]
             for i, n in enumerate(names)}
    _, settings = calibration.apply(theta)
    layout = load_layout().with_blocks(*settings.maze_blocks)  # refused if no hand passes
    assert layout.blocks["gap"] >= calibration.NARROWEST_GAP - 1e-12
    assert calibration.distance({}) == pytest.approx(4 * math.sqrt(10))


def test_every_parameter_lands_where_it_says():
    theta = {name: p.from_unit(0.25) for name, p in calibration.PARAMETERS.items()}
    population, settings = calibration.apply(theta)
    assert settings.maze_blocks[:3] == pytest.approx(tuple(
        theta[f"maze_{k}"] for k in ("reach", "low", "height")
    ))
    assert settings.maze_blocks[3] >= calibration.NARROWEST_GAP
    assert population.enough_median_maze == pytest.approx(theta["enough_median_maze"])
    assert population.satisfaction_low == pytest.approx(theta["satisfaction_low"])
    mean_repeat = population.repeat_a / (population.repeat_a + population.repeat_b)
    assert mean_repeat == pytest.approx(theta["repeat_mean"])
    mean_slip = population.slip_a / (population.slip_a + population.slip_b)
    assert mean_slip == pytest.approx(theta["slip_mean"])
    middle = (population.setup_low + population.setup_high) / 2
    assert middle == pytest.approx(theta["setup_middle"])
    assert (population.heed_low, population.heed_high) == pytest.approx(
        (max(0.0, theta["heed_middle"] - 0.25), theta["heed_middle"] + 0.25)
    )
    assert population.aim_low == DEFAULT_POPULATION.aim_low  # what is not free stays
    for p in calibration.PARAMETERS.values():  # the unit scale round-trips
        for u in (0.0, 0.3, 1.0):
            assert p.to_unit(p.from_unit(u)) == pytest.approx(u)


@pytest.mark.parametrize(
    "theta, match",
    [({"nonsense": 1.0}, "unknown"), ({"maze_reach": 0.5}, "prior"),
     ({"enough_median_maze": 1.0}, "prior")],
)
def test_a_bad_parameter_set_is_named(theta, match):
    with pytest.raises(InvalidParameterError, match=match):
        calibration.apply(theta)


def test_the_statistics_are_the_papers_and_split_fitted_from_held_out():
    stats = calibration.STATISTICS
    assert stats["median eta VF"].value == 0.134 and stats["median eta VF"].fitted
    assert stats["NF did well"].value == 7 and stats["F"].value == 7.952
    assert stats["undemonstrated BF"].value == 827 and not stats["undemonstrated BF"].fitted
    held = [s for s in stats.values() if not s.fitted]
    assert len(held) == 15 and all(s.experiment == 2 for s in held)
    perfect = {n: s.value for n, s in stats.items()}
    assert calibration.distance(perfect) == 0.0
    off = dict(perfect, **{"median eta NF": perfect["median eta NF"] * 1.25})
    assert calibration.distance(off) == pytest.approx(1.0)
    assert calibration.distance(dict(perfect, F=math.nan)) == pytest.approx(4.0)


def test_summary_statistics_scale_counts_to_the_papers_groups():
    exp2 = pd.DataFrame({
        "condition": ["NF"] * 6, "run": [1, 2, 3] * 2, "eta": [0.1, 0.2, 0.3] * 2,
        "errors": [1, 0, 0, 0, 0, 1], "undemonstrated": [10] * 6, "ambiguous": [2] * 6,
    })
    stats = calibration.summary_statistics(None, exp2)
    assert stats["mean eta NF"] == pytest.approx(0.2)
    assert stats["third-run eta NF"] == pytest.approx(0.3)
    assert stats["errors NF"] == pytest.approx(2 * 27 / 6)  # 2 in 6 runs, of 27
    assert stats["undemonstrated NF"] == pytest.approx(270)


def test_a_bad_budget_is_named():
    with pytest.raises(InvalidParameterError, match="population_size"):
        calibration.calibrate(calibration.Budget(population_size=1))
    with pytest.raises(InvalidParameterError, match="max_simulations"):
        calibration.calibrate(calibration.Budget(max_simulations=0))


def test_the_calibrate_command_runs_end_to_end_on_the_quick_budget(tmp_path, capsys):
    out = tmp_path / "cal"
    assert main(["calibrate", "--quick", "--workers", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "held-out statistics inside their 90 % interval" in text and "quick" in text
    summary = json.loads((out / "calibration_summary.json").read_text(encoding="utf-8"))
    assert set(summary["point"]) == set(calibration.PARAMETERS)
    for name, p in calibration.PARAMETERS.items():
        assert p.low <= summary["point"][name] <= p.high
    posterior = pd.read_csv(out / "calibration_posterior.csv")
    assert len(posterior) == calibration.QUICK_BUDGET.population_size
    assert posterior.weight.sum() == pytest.approx(1.0)
    generations = pd.read_csv(out / "calibration_generations.csv")
    assert len(generations) == calibration.QUICK_BUDGET.generations
    assert (np.diff(generations.epsilon) <= 0).all()  # the tolerance shrinks
    predictive = pd.read_csv(out / "calibration_predictive.csv")
    assert len(predictive) == calibration.QUICK_BUDGET.draws
    assert {"mean eta BF", "undemonstrated SF", "median eta VR"} <= set(predictive.columns)
    assert len(summary["statistics"]) == len(calibration.STATISTICS)

    # refine chose the bundled point among the last generation's closest particles
    refined = pd.read_csv(out / "calibration_refined.csv")
    assert len(refined) == 2 and set(calibration.PARAMETERS) <= set(refined.columns)
    assert refined.chosen.sum() == 1
    best = refined[refined.chosen].iloc[0]
    steady = refined[refined.steady_as_bundled] if refined.steady_as_bundled.any() else refined
    assert best.mean_distance == steady.mean_distance.min()  # the closest steady maze
    assert summary["chosen"] == pytest.approx({n: best[n] for n in calibration.PARAMETERS})
    assert set(refined.abc_distance) <= set(posterior.distance)
    at_point = pd.read_csv(out / "calibration_point_predictive.csv")
    assert len(at_point) == calibration.QUICK_BUDGET.draws
    for name in calibration.PARAMETERS:  # every row of the point check is the chosen point
        assert (at_point[name] == summary["chosen"][name]).all()
    assert "the bundled point (fresh seeds)" in text and "<- bundled" in text

    # what save wrote, load reads back (numbers only), and the check's figure draws it
    found, predicted, table = calibration.load(out)
    assert found.point() == pytest.approx(summary["point"])
    assert found.bundled() == pytest.approx(summary["chosen"])
    assert table.point_median.notna().all() == table["median"].notna().all()
    assert found.budget == calibration.QUICK_BUDGET
    assert len(predicted) == calibration.QUICK_BUDGET.draws
    assert list(table.statistic) == list(calibration.STATISTICS)
    saved = (out / "calibration_report.txt").read_text(encoding="utf-8")
    assert calibration.format_report(found, table).strip() == saved.strip()
    from tutor.study.figures import calibration_figure

    fig = calibration_figure(table)
    assert len(fig.axes[0].get_yticklabels()) == len(calibration.STATISTICS)
    assert "held-out statistics" in fig.axes[0].get_title()
    import matplotlib.pyplot as plt

    plt.close(fig)

    # a stopped run is finished from its history: the same last generation
    again = calibration.from_history(out, calibration.QUICK_BUDGET)
    pd.testing.assert_frame_equal(again.particles, found.particles[again.particles.columns],
                                  check_exact=False, rtol=1e-9)
    assert again.generations.simulations.sum() == found.generations.simulations.sum()
    # generation 0 counts pyabc's first sample of the prior too
    assert generations.simulations.iloc[0] >= 2 * calibration.QUICK_BUDGET.population_size

    # --recheck runs the two checks again and keeps the posterior and the chosen point
    assert main(["calibrate", "--recheck", "--quick", "--out", str(out)]) == 2
    assert "InvalidParameterError" in capsys.readouterr().err  # named, no traceback
    assert main(["calibrate", "--recheck", "--workers", "1", "--out", str(out)]) == 0
    assert "predictive checks rerun" in capsys.readouterr().out
    rechecked, predicted_again, table_again = calibration.load(out)
    pd.testing.assert_frame_equal(rechecked.particles, found.particles)
    assert rechecked.bundled() == found.bundled()
    pd.testing.assert_frame_equal(predicted_again, predicted)  # same seeds, same code
    assert list(table_again.statistic) == list(calibration.STATISTICS)
    # ... with more (or fewer) posterior draws when asked, the rest of the budget kept
    assert main(["calibrate", "--recheck", "--generations", "2", "--out", str(out)]) == 2
    assert "InvalidParameterError" in capsys.readouterr().err
    draws = calibration.QUICK_BUDGET.draws + 1
    assert main(["calibrate", "--recheck", "--draws", str(draws), "--workers", "1",
                 "--out", str(out)]) == 0
    more, predicted_more, _ = calibration.load(out)
    assert len(predicted_more) == draws and more.budget.draws == draws
    assert dataclasses.replace(more.budget, draws=found.budget.draws) == found.budget
    pd.testing.assert_frame_equal(more.particles, found.particles)
    assert f"{draws} predictive draws" in (out / "calibration_report.txt").read_text("utf-8")
    with pytest.raises(InvalidParameterError, match="draws"):
        calibration.recheck(out, draws=1)


def test_a_folder_without_a_calibration_is_refused_by_name(tmp_path):
    from tutor.errors import InvalidFileError

    with pytest.raises(InvalidFileError, match="lfd-tutor calibrate --out"):
        calibration.load(tmp_path)
    with pytest.raises(InvalidFileError, match="no calibration history"):
        calibration.from_history(tmp_path)
    (tmp_path / "calibration_summary.json").write_text("{not json", encoding="utf-8")
    with pytest.raises(InvalidFileError, match="calibrate"):
        calibration.load(tmp_path)



def test_report_checks_the_posterior_and_the_bundled_point_apart():
    paper = {n: s.value for n, s in calibration.STATISTICS.items()}
    around = pd.DataFrame([{n: v * f for n, v in paper.items()} for f in (0.5, 1.0, 1.5)])
    far = pd.DataFrame([{n: v * 3 + 10 for n, v in paper.items()} for _ in range(3)])
    table = calibration.report(None, far, point_predicted=around)
    assert not table.inside.any() and table.point_inside.all()
    assert table.point_median.tolist() == pytest.approx(list(paper.values()))
    alone = calibration.report(None, around)  # no point check: its columns are empty
    assert alone.inside.all() and alone.point_median.isna().all()


def test_refine_needs_the_particles_distances():
    particles = pd.DataFrame([{n: p.from_unit(0.5) for n, p in calibration.PARAMETERS.items()}])
    particles["weight"] = 1.0
    old = calibration.Calibration(particles, pd.DataFrame(), calibration.QUICK_BUDGET, 0.0, 0)
    assert old.bundled() == old.point()  # nothing chosen yet: the marginal medians
    with pytest.raises(InvalidParameterError, match="rerun lfd-tutor calibrate"):
        calibration.refine(old)



def test_the_posterior_quantiles_follow_the_particles_weights():
    names = list(calibration.PARAMETERS)
    rows = [{n: calibration.PARAMETERS[n].from_unit(u) for n in names} for u in (0.1, 0.5, 0.9)]
    particles = pd.DataFrame(rows)
    particles["weight"] = [0.1, 0.1, 0.8]  # the last particle holds most of the mass
    found = calibration.Calibration(particles, pd.DataFrame(), calibration.QUICK_BUDGET, 0.0, 0)
    name = names[0]
    assert found.quantile(name, 0.05) == pytest.approx(rows[0][name])
    assert found.point()[name] == found.quantile(name, 0.5) == pytest.approx(rows[2][name])
    assert found.quantile(name, 0.99) == pytest.approx(rows[2][name])


def test_the_bundled_population_and_maze_are_the_bundled_calibration():
    """scripts/apply_calibration.py wrote the bundled calibration's point into the
    defaults: Population's fields (to 4 decimals) and the maze's blocks (to the mm)."""
    import dataclasses

    found, _, table = calibration.load()  # tutor/assets/calibration
    assert not found.budget.quick and found.chosen is not None
    point = {k: round(v, 4) for k, v in found.bundled().items()}
    population, _ = calibration.apply(point)
    for f in dataclasses.fields(population):
        want, have = getattr(population, f.name), getattr(DEFAULT_POPULATION, f.name)
        assert have == pytest.approx(want, abs=1e-4), f.name
    bundled = load_layout()
    expected = bundled.with_blocks(*calibration.bundled_blocks(point))
    for a, b in zip(bundled.obstacles, expected.obstacles, strict=True):
        assert (a.x0, a.x1, a.y0, a.y1) == pytest.approx((b.x0, b.x1, b.y0, b.y1), abs=1e-6)
    np.testing.assert_allclose(bundled.guide_points, expected.guide_points, atol=1e-6)
    assert list(table.statistic) == list(calibration.STATISTICS)
