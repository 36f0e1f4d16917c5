"""The optimal teacher (tutor.study.optimal) and its bundled reference (optimal.json)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tutor.demofiles import bundled_demos
from tutor.errors import InvalidFileError, InvalidParameterError
from tutor.framework import TeachingSession
from tutor.resources import asset
from tutor.study import optimal
from tutor.tasks.maze import MazeTask
from tutor.tasks.optimal_reference import load_references, optimal_reference
from tutor.views.maze_app import MazeTutor
from tutor.views.text import finish_summary, optimal_sentence

BUNDLED = json.loads(asset("optimal.json").read_text())


def _path_bank(task, name):
    """The bank demos of the bundled greedy path of ``name`` (same seeds as the full bank)."""
    path = BUNDLED["tasks"][name]["greedy"]
    draws = max(path["draws"]) + 1
    bank = optimal.make_bank(task, draws, BUNDLED["settings"]["seed"], sorted(set(path["indices"])))
    where = {
        (int(i), int(k)): p for p, (i, k) in enumerate(zip(bank.index, bank.draw, strict=True))
    }
    return bank.subset([where[i, k] for i, k in zip(path["indices"], path["draws"], strict=True)])


class Corner(MazeTask):
    """The maze with B^ cut down to ``keep`` (its criteria are per start point, so a
    realisation passes here exactly when it passes in the full maze)."""

    def __init__(self, keep):
        super().__init__()
        self._test_points = self._test_points[np.asarray(keep)]
        self._batch = self.layout.frame_batch(self._test_points)


# ---------------------------------------------------------------- the fast parts are exact


@pytest.mark.parametrize("name", ["maze_task", "pickplace_task"])
def test_realisation_and_fast_judging_equal_the_sessions(name, request):
    task = request.getfixturevalue(name)
    bank = optimal.make_bank(task, 1, indices=[0, len(task.test_points) - 1, 7])
    state = optimal.State.empty(task)
    session = TeachingSession(task, feedback="none")
    for demo, cond in zip(bank.demos, bank.demo_points, strict=True):
        state, eps, passed = state.added(task, demo, cond)
        record = session.add_demo(demo, point=cond)
        plain = task.realise(state.learner)
        np.testing.assert_array_equal(session.realisations, plain)
        context = task.criteria_context(state.demos, np.array(state.demo_points))
        np.testing.assert_array_equal(
            optimal.judged(task, plain, context),
            task.judge(plain, task.test_points, context).passed,
        )
        assert eps == record.efficacy
        np.testing.assert_array_equal(passed, record.passed)


def test_the_bank_is_careful_demos_seeded_per_condition(maze_task):
    full = optimal.make_bank(maze_task, 2, indices=[3, 50])
    part = optimal.make_bank(maze_task, 1, indices=[50])
    assert (
        len(full) == 4
        and full.index.tolist() == [3, 50, 3, 50]
        and full.draw.tolist()
        == [
            0,
            0,
            1,
            1,
        ]
    )
    np.testing.assert_array_equal(full.demos[1], part.demos[0])
    assert not np.array_equal(full.demos[1], full.demos[3])  # another draw of the hand
    for demo, cond in zip(full.demos, full.demo_points, strict=True):
        assert maze_task.judge_demo(demo, cond).passed[0]
    assert len(full.first_draws(1)) == 2


@pytest.mark.parametrize(
    "kwargs", [{"draws": 0}, {"draws": 1.5}, {"seed": -1}, {"indices": [140]}, {"indices": []}]
)
def test_a_bad_bank_request_is_named(maze_task, kwargs):
    with pytest.raises(InvalidParameterError):
        optimal.make_bank(maze_task, **kwargs)


# ---------------------------------------------------------------- greedy and pairs


@pytest.fixture(scope="module")
def tiny(maze_task):
    """The bundled greedy path's three demos and two distractors (start points 0, 139)."""
    path = _path_bank(maze_task, "maze")
    others = optimal.make_bank(maze_task, 1, indices=[0, 139])
    demos = np.concatenate([others.demos[:1], path.demos, others.demos[1:]])
    return optimal.Bank(
        demos,
        np.concatenate([others.demo_points[:1], path.demo_points, others.demo_points[1:]]),
        np.concatenate([others.index[:1], path.index, others.index[1:]]),
        np.concatenate([others.draw[:1], path.draw, others.draw[1:]]),
    )


def test_greedy_on_a_tiny_bank_reaches_the_known_optimum(maze_task, tiny):
    found = optimal.greedy(maze_task, tiny, workers=1)
    # brute force: every single demo, and every pair after the greedy first demo
    empty = optimal.State.empty(maze_task)
    singles = [
        optimal.efficacy_after(maze_task, empty, d, c)[0]
        for d, c in zip(tiny.demos, tiny.demo_points, strict=True)
    ]
    assert found.best_single == max(singles) == found.efficacies[0]
    assert found.positions[0] == int(np.argmax(singles))  # ties: the first
    pairs = optimal.pair_bound(maze_task, tiny, workers=1)
    assert pairs.ordered and pairs.n_pairs == len(tiny) * (len(tiny) - 1)
    assert found.efficacies[1] <= pairs.best
    # the optimum: no pair of the bank reaches 0.9, and three demos reach everything
    assert pairs.best < 0.9 and pairs.reaching == {0.9: 0, 1.0: 0}
    assert len(found.efficacies) == 3 and found.efficacies[-1] == 1.0
    td = optimal.teaching_dimension(0.9, found, pairs)
    assert td["n_demos"] == 3 and td["lower_bound"] == 3 and td["exact"]
    assert td["eta"]["target"] == pytest.approx(1 / 3, abs=1e-6)


def test_the_pair_bound_finds_a_pair_that_suffices(maze_task, tiny):
    """On a B^ of the start points the first two greedy demos win, that pair reaches 1."""
    state = optimal.State.empty(maze_task)
    for p in (1, 2):
        state, _, passed = state.added(maze_task, tiny.demos[p], tiny.demo_points[p])
    keep = np.flatnonzero(passed)
    task = Corner(keep)
    pairs = optimal.pair_bound(task, tiny, workers=1)
    assert pairs.best == 1.0 and pairs.reaching[1.0] >= 1
    found = optimal.greedy(task, tiny, workers=1)
    td = optimal.teaching_dimension(1.0, found, pairs)
    assert td["n_demos"] <= 2 and td["exact"]


def test_best_next_is_the_greedy_step_of_a_session_with_ties_to_the_first(maze_task, tiny):
    session = TeachingSession(maze_task, feedback="all")
    session.add_demo(tiny.demos[1], point=tiny.demo_points[1])
    doubled = tiny.subset([0, 2, 2, 3])  # the same demo twice: a tie
    choice = optimal.best_next(maze_task, session, doubled, workers=1)
    assert choice.position == 1 and choice.index == int(tiny.index[2])
    state = optimal.State.from_session(session)
    scores = [
        optimal.efficacy_after(maze_task, state, d, c)[0]
        for d, c in zip(doubled.demos, doubled.demo_points, strict=True)
    ]
    assert choice.efficacy == max(scores)
    assert (
        session.add_demo(doubled.demos[1], point=doubled.demo_points[1]).efficacy
        == choice.efficacy
    )
    only = optimal.best_next(maze_task, state, doubled, candidates=[0, 3], workers=1)
    assert only.position in (0, 3) and only.candidates.tolist() == [0, 3]
    with pytest.raises(InvalidParameterError):
        optimal.best_next(maze_task, state, doubled, candidates=[4])


def test_two_workers_give_the_same_choice(maze_task, tiny):
    state = optimal.State.empty(maze_task)
    one = optimal.best_next(maze_task, state, tiny, workers=1)
    two = optimal.best_next(maze_task, state, tiny, workers=2)
    assert (one.position, one.efficacy) == (two.position, two.efficacy)
    np.testing.assert_array_equal(one.scores, two.scores)


def test_scoring_here_stops_at_the_first_demo_reaching_one(maze_task, tiny):
    """On one process the candidates are scored one at a time and scoring stops at the
    first reaching eps = 1: the same choice as scoring every one, fewer refits."""
    state = optimal.State.empty(maze_task)
    for p in (1, 2):  # the greedy path's first two demos: its third reaches eps = 1
        state, _, _ = state.added(maze_task, tiny.demos[p], tiny.demo_points[p])
    bank = tiny.subset([0, 1, 3, 0, 1, 3, 2, 0])  # the third reaches eps = 1 (and the sixth)
    choice = optimal.best_next(maze_task, state, bank, workers=1)
    assert choice.position == 2 and choice.efficacy == 1.0
    assert np.isfinite(choice.scores[:3]).all() and np.isnan(choice.scores[3:]).all()
    every = [optimal.efficacy_after(maze_task, state, d, c)[0] for d, c in
             zip(bank.demos, bank.demo_points, strict=True)]
    assert int(np.argmax(every)) == choice.position and max(every) == choice.efficacy
    np.testing.assert_array_equal(choice.scores[:3], every[:3])


# ---------------------------------------------------------------- the bundled reference


def test_the_bundled_reference_is_what_the_code_computes_for_a_reduced_bank():
    """Same schema as a reduced run of the command, and its regeneration is documented."""
    path = BUNDLED["tasks"]["maze"]["greedy"]["indices"]  # the bundled greedy path, and one more
    small = optimal.compute_reference(
        tasks=("maze",), draws=1, indices={"maze": [0, *path]}, workers=1
    )

    def keys(d):
        return {k: keys(v) for k, v in d.items()} if isinstance(d, dict) else None

    bundled = keys(BUNDLED)
    mine = keys(small)
    mine["tasks"]["maze"]["bank"].pop("indices")
    assert mine["tasks"]["maze"] == bundled["tasks"]["maze"]
    assert set(bundled["tasks"]) == {"maze", "pickplace"}
    assert small["format"] == BUNDLED["format"] and small["command"] == BUNDLED["command"]
    assert BUNDLED["command"] in asset("README.md").read_text()
    assert (
        small["tasks"]["maze"]["greedy"]["efficacy"]
        == small["tasks"]["maze"]["greedy"]["session_efficacy"]
    )


@pytest.mark.parametrize("name", ["maze", "pickplace"])
def test_the_bundled_numbers_replay_in_a_session(name, maze_task, pickplace_task):
    """The greedy path and the best pair give, in a TeachingSession, the bundled eps."""
    task = maze_task if name == "maze" else pickplace_task
    entry = BUNDLED["tasks"][name]
    bank = _path_bank(task, name)
    session = TeachingSession(task, feedback="none")
    got = [
        session.add_demo(d, point=c).efficacy
        for d, c in zip(bank.demos, bank.demo_points, strict=True)
    ]
    assert got == pytest.approx(entry["greedy"]["efficacy"], abs=1e-6)
    assert entry["greedy"]["session_efficacy"] == entry["greedy"]["efficacy"]
    first, second = entry["pairs"]["best_pair"]
    pair = optimal.make_bank(task, 1, BUNDLED["settings"]["seed"], [first, second])
    order = [0, 1] if first != second else [0, 0]
    session = TeachingSession(task, feedback="none")
    eps = [session.add_demo(pair.demos[k], point=pair.demo_points[k]).efficacy for k in order]
    assert eps == pytest.approx(entry["pairs"]["best_path"], abs=1e-6)


@pytest.mark.parametrize("name", ["maze", "pickplace"])
def test_td_values_agree_with_the_bundled_json(name):
    entry = BUNDLED["tasks"][name]
    ref = optimal_reference(name)
    effs = entry["greedy"]["efficacy"]
    for key, target in (("0.9", 0.9), ("1", 1.0)):
        td = entry["td"][key]
        assert ref.fewest[key] == td["n_demos"]
        first = next((m for m, e in enumerate(effs, 1) if e >= target - 1e-12), None)
        pair_ok = entry["pairs"]["best_efficacy"] >= target
        single_ok = entry["greedy"]["best_single"] >= target
        expected = 1 if single_ok else 2 if pair_ok and (first is None or first > 2) else first
        assert td["n_demos"] == expected
        assert td["exact"] == (td["n_demos"] == td["lower_bound"])
        if not (single_ok or pair_ok) and (first is None or first > 2):
            assert td["lower_bound"] == 3
    assert ref.best_eta == entry["td"]["0.9" if ref.experiment == 1 else "1"]["eta"][entry["rule"]]
    assert ref.experiment == (1 if name == "maze" else 2)
    # no run of any length beats it by stopping early: one demo, the best pair, the path
    by_length = [entry["greedy"]["best_single"], entry["pairs"]["best_efficacy"] / 2]
    by_length += [e / m for m, e in enumerate(effs, 1)]
    assert ref.eta_any_stop == pytest.approx(max(by_length))


def test_a_broken_reference_file_is_named(tmp_path):
    bad = tmp_path / "optimal.json"
    bad.write_text(json.dumps({"format": "something else"}))
    with pytest.raises(InvalidFileError, match="not the optimal teacher's"):
        load_references(bad)
    half = dict(BUNDLED, tasks={"maze": {"experiment": 1}})
    bad.write_text(json.dumps(half))
    with pytest.raises(InvalidFileError, match="regenerate"):
        load_references(bad)


# ---------------------------------------------------------------- what the trainee reads


def test_a_finished_run_says_how_few_demos_this_robot_needs(maze_task):
    app = MazeTutor("VF", task=maze_task)
    for demo in bundled_demos("maze_good"):
        app.add(demo)
    app.finish()
    ref = optimal_reference("maze")
    summary = finish_summary(app.run, 0.134, "median")
    n = app.run.score().n_demos
    assert f"You used {n} demonstration" in summary
    assert f"to reach 90% is {ref.n_demos}" in summary
    assert f"best possible η by this experiment's score is {ref.best_eta:.1%}" in summary
    assert summary.count("η =") == 1  # one score: the trainee's
    assert optimal_sentence(maze_task) in summary.replace(f"You used {n} demonstrations; t", "T")


def _optimal_lines(figure) -> list[float]:
    """Heights of the optimal teacher's lines on a figure's first (eta) axis."""
    return [
        ln.get_ydata()[0]
        for ln in figure.axes[0].get_lines()
        if ln.get_label().startswith("optimal teacher")
    ]


def test_the_results_and_the_cohort_figures_draw_the_optimal_line(maze_task):
    import matplotlib.pyplot as plt

    from tutor.study.figures import experiment1_figure, experiment2_figure
    from tutor.study.report import load_result
    from tutor.views.maze_app import compare_runs, plot_runs

    app = MazeTutor("VF", task=maze_task)
    for demo in bundled_demos("maze_good"):
        app.add(demo)
    assert optimal_sentence(maze_task) in compare_runs([app])
    ax = plot_runs([app])
    ref = optimal_reference("maze")
    lines = [ln for ln in ax.get_lines() if ln.get_label().startswith("optimal teacher")]
    assert len(lines) == 1 and lines[0].get_ydata()[0] == pytest.approx(100 * ref.best_eta)
    plt.close(ax.figure)
    for experiment, name, draw in (
        (1, "maze", experiment1_figure),
        (2, "pickplace", experiment2_figure),
    ):
        ref = optimal_reference(name)
        fig = draw(load_result(experiment).runs, optimal=ref)
        assert _optimal_lines(fig) == [pytest.approx(ref.best_eta)]
        plt.close(fig)
        plain = draw(load_result(experiment).runs)
        assert not _optimal_lines(plain)
        plt.close(plain)


def test_the_lookahead_below_the_views_hints_from_a_run(pickplace_task):
    """The next-demo hint's call: a run, a bank of the task's own scripted demos."""
    from tutor.tasks import lookahead
    from tutor.tasks.pickplace_protocol import PickPlaceRun

    run = PickPlaceRun.new("BF", pickplace_task)
    run.demonstrate(0, rng=np.random.default_rng(1))
    bank = lookahead.make_bank(pickplace_task, 1, indices=[0, 4, 76, 99])
    for demo, cond in zip(bank.demos, bank.demo_points, strict=True):
        assert pickplace_task.judge_demo(demo, cond).passed[0]
    hint = lookahead.best_next(pickplace_task, run, bank, workers=1)
    state = lookahead.State.from_session(run)
    assert len(state.demos) == 1
    scores = [
        lookahead.efficacy_after(pickplace_task, state, d, c)[0]
        for d, c in zip(bank.demos, bank.demo_points, strict=True)
    ]
    assert hint.efficacy == max(scores) and hint.index == int(bank.index[np.argmax(scores)])
