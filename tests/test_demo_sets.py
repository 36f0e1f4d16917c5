"""The bundled demonstration sets raise the failures they illustrate; demo files load safely."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tutor.demofiles import load_demos, save_demos
from tutor.errors import InvalidFileError
from tutor.framework import AMBIGUOUS, INCORRECT, TeachingSession

ASSETS = Path(__file__).resolve().parents[1] / "tutor" / "assets" / "demos"


def replay(task, name):
    s = TeachingSession(task)
    for demo in load_demos(ASSETS / f"maze_{name}.json"):
        s.add_demo(demo)
    per_demo = {w.kind for r in s.history for w in r.warnings if w.demo is not None}
    return s, per_demo


def test_good_teacher_reaches_ninety_percent_within_eight_demos(maze_task):
    s, per_demo = replay(maze_task, "good")
    score = s.score(rule="target")  # the maze is Experiment 1
    assert score.reached and score.n_demos <= 8
    assert per_demo == set()
    assert s.latest.n_undemonstrated == 0


def test_ambiguous_teacher_raises_ambiguous(maze_task):
    s, per_demo = replay(maze_task, "ambiguous")
    assert per_demo == {AMBIGUOUS}
    flagged = [r.n_demos for r in s.history if AMBIGUOUS in r.kinds]
    assert len(flagged) >= 2


def test_undemonstrated_teacher_leaves_undemonstrated_states(maze_task):
    s, per_demo = replay(maze_task, "undemonstrated")
    assert per_demo == set()
    assert s.latest.n_undemonstrated >= 20
    assert s.latest.efficacy < 0.9
    assert "right" in next(w.message for w in s.latest.warnings)


def test_incorrect_teacher_raises_incorrect(maze_task):
    s, per_demo = replay(maze_task, "incorrect")
    assert per_demo == {INCORRECT}
    third = s.history[2]
    assert not third.demo_passed and "hit obstacle 1" in third.demo_reason
    assert s.latest.n_undemonstrated == 0  # the later good demos repair the damage


def test_a_typical_novice_scores_near_the_papers_nf_median_not_the_optimum(maze_task):
    """The bundled novice set (a typical simulated NF teacher of the calibrated
    population) scores nearer the paper's NF median eta than the optimal teacher's."""
    from tutor.paper import PAPER_MEDIAN_ETA
    from tutor.tasks.optimal_reference import optimal_reference

    s, _ = replay(maze_task, "novice")
    eta = s.score(rule="target").efficiency
    paper = PAPER_MEDIAN_ETA["NF"]
    best = optimal_reference("maze").eta["0.9"]
    assert abs(eta - paper) < abs(eta - best)


def test_every_bundled_file_is_documented_and_loads():
    files = sorted(ASSETS.glob("*.json"))
    assert len(files) >= 4
    readme = (ASSETS.parent / "README.md").read_text()
    for f in files:
        ds = load_demos(f)
        # a typical novice may stop after two demos; the scripted sets have three or more
        assert ds.task == f.stem.split("_")[0] and ds.description
        assert len(ds) >= (2 if f.stem == "maze_novice" else 3)
        assert f.name in readme


def test_conditions_round_trip_and_bad_conditions(tmp_path):
    demos = [np.zeros((3, 5)), np.ones((4, 5))]
    path = save_demos(
        tmp_path / "d.json",
        demos,
        task="pickplace",
        columns="txyzg",
        points=[[0.1, 0.2, 0.3], None],
    )
    ds = load_demos(path)
    np.testing.assert_allclose(ds.demo_points[0], [0.1, 0.2, 0.3])
    assert ds.demo_points[1] is None
    data = json.loads(path.read_text())
    data["conditions"][0] = "plant 7"
    path.write_text(json.dumps(data))
    with pytest.raises(InvalidFileError, match="condition 1"):
        load_demos(path)
    data["conditions"] = [None]
    path.write_text(json.dumps(data))
    with pytest.raises(InvalidFileError, match="one entry per demo"):
        load_demos(path)


@pytest.mark.parametrize("suffix", [".json", ".csv"])
def test_save_and_load_round_trip(tmp_path, suffix):
    rng = np.random.default_rng(0)
    demos = [rng.normal(size=(n, 3)) for n in (5, 9)]
    path = save_demos(tmp_path / f"d{suffix}", demos, task="maze")
    loaded = load_demos(path)
    assert len(loaded) == 2
    for a, b in zip(demos, loaded, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    "name, content, words",
    [
        ("a.json", '{"format": "lfd-tutor-demos", "demos": [[[0, 1]]]}', "3 numbers"),
        ("a.json", '{"format": "lfd-tutor-demos", "demos": [[[0, 1, "x"]]]}', "finite number"),
        ("a.json", '{"format": "lfd-tutor-demos", "demos": [[[0, 1, true]]]}', "finite number"),
        ("a.json", '{"format": "lfd-tutor-demos", "demos": [[[0, 1, 1e999]]]}', "too large"),
        ("a.json", '{"demos": []}', "not an lfd-tutor demonstration file"),
        ("a.json", '{"format": "lfd-tutor-demos", "demos": [[[0, 1, 2]', "not valid JSON"),
        ("a.csv", "t,x,y\n0,1,2\n", "header"),
        ("a.csv", "demo,t,x,y\n1,0,1\n", "3 values"),
        ("a.csv", "demo,t,x,y\n1,0,1,abc\n", "line 2"),
        ("a.csv", "demo,t,x,y\n1,0,1,nan\n", "NaN"),
        ("a.csv", "demo,t,x,y\n", "no samples"),
        ("a.pkl", "anything", ".json or .csv"),
    ],
)
def test_malformed_demo_files(tmp_path, name, content, words):
    path = tmp_path / name
    path.write_text(content)
    with pytest.raises(InvalidFileError, match=words):
        load_demos(path)


def test_csv_demo_labels_keep_their_order(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text("demo,t,x,y\nb,0,1,1\nb,1,2,2\na,0,5,5\na,1,6,6\n")
    ds = load_demos(path)
    assert ds[0][0, 1] == 1 and ds[1][0, 1] == 5
