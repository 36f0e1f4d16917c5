"""Words that agree with the numbers: notebook 01's prose, its advice, notebook 00's list."""

from __future__ import annotations

import ast
import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tutor.demofiles import bundled_demos
from tutor.framework import INCORRECT, TeachingSession
from tutor.framework.wording import change_points, efficacy_change
from tutor.views.text import incorrect_mark, summary

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
NB01 = next(NOTEBOOKS.glob("01_*.ipynb"))

#: a sentence in prose that says which way efficacy moved
DIRECTION = re.compile(
    r"efficacy\W+(?:\w+\W+){0,2}?(drops?|falls?|fell|rises?|rose|increases?|decreases?|"
    r"goes (?:up|down)|improves?|worsens?)\b",
    re.IGNORECASE,
)


def _cells(path: Path, kind: str) -> list[str]:
    return [
        "".join(c["source"])
        for c in json.loads(path.read_text())["cells"]
        if c["cell_type"] == kind
    ]


def _direction(text: str) -> int:
    """+1, -1 or 0 for the direction a generated sentence states."""
    if "rises by" in text:
        return 1
    if "drops by" in text:
        return -1
    assert "stays the same" in text, text
    return 0


@pytest.mark.parametrize(
    ("delta", "points", "words"),
    [
        (1 / 140, 1, "rises by 1 point"),
        (0.25, 25, "rises by 25 points"),
        (-1 / 140, -1, "drops by 1 point"),
        (-0.3, -30, "drops by 30 points"),
        (0.0, 0, "stays the same"),
        (0.004, 0, "stays the same"),  # shown as 0 points: not called a rise
        (-0.004, 0, "stays the same"),
    ],
)
def test_the_change_sentence_follows_the_points_shown(delta, points, words):
    assert change_points(delta) == points
    sentence = efficacy_change(delta)
    assert words in sentence
    assert _direction(sentence) == np.sign(points)


def test_the_incorrect_cell_says_the_direction_of_its_own_number(maze_task):
    # what notebook 01's "MainCause 1" cell computes, on the bundled set it uses
    wrong = TeachingSession(maze_task)
    for demo in bundled_demos("maze_incorrect")[:3]:
        wrong.add_demo(demo)
    record = wrong.latest
    assert INCORRECT in record.kinds and not record.demo_passed
    sign = int(np.sign(change_points(record.delta)))
    first = summary(record).splitlines()[0]
    assert _direction(first) == sign, first
    mark = incorrect_mark(record, maze_task)
    assert _direction(mark) == sign, mark
    assert ("does not show" in mark) == (sign > 0), mark
    assert "obstacle 1" in mark  # the tutor's own check, with the rule it breaks


@pytest.mark.parametrize("name", ["maze_good", "maze_incorrect", "maze_ambiguous"])
def test_every_step_of_the_bundled_sets_says_its_direction(maze_task, name):
    session = TeachingSession(maze_task)
    for demo in bundled_demos(name):
        record = session.add_demo(demo)
        text = summary(record)
        assert _direction(text.splitlines()[0]) == np.sign(change_points(record.delta)), text
        assert "+0 points" not in text and "-0 points" not in text, text
        assert not re.search(r"(?<![0-9])1 points", text), text  # "71 points" is fine


def test_notebook_01_prose_claims_no_direction_and_its_cells_say_it():
    prose = "\n".join(_cells(NB01, "markdown"))
    claims = [m.group(0) for m in DIRECTION.finditer(prose)]
    assert not claims, claims  # the direction is said by the cells, from the number
    code = "\n".join(_cells(NB01, "code"))
    assert "incorrect_mark(wrong.latest, task)" in code and "summary(wrong.latest)" in code


def test_notebook_01_asks_for_nothing_it_cannot_do(maze_task):
    # "undo" is a button of notebooks 02 and 03; notebook 01 has none
    text = "\n".join(_cells(NB01, "markdown") + _cells(NB01, "code"))
    assert "undo" not in text.lower()
    # its "Your turn" cell, as shipped: demo 3 makes things no better and is to be taken back
    code = next(c for c in _cells(NB01, "code") if c.startswith("my_starts = ["))
    assert 'summary(mine.latest, starts="my_starts")' in code
    starts = ast.literal_eval(ast.parse(code).body[0].value)  # the cell's own start points
    rng = np.random.default_rng(0)
    mine = TeachingSession(maze_task)
    for start in starts:
        mine.add_demo(maze_task.layout.reference_path(start, rng, jitter=0.004))
    out = summary(mine.latest, starts="my_starts")
    assert "undo" not in out.lower()
    assert [w.take_back for w in mine.latest.warnings if w.kind == INCORRECT] == [(3,)]
    assert "my_starts[2]" in out and "run the cell again" in out
    # bundled demos cannot be taken back here: the line points at the tutors' Undo
    bundled = summary(mine.latest)
    assert "Undo button" in bundled and "my_starts" not in bundled


def test_notebook_00_lists_every_notebook_and_only_those():
    welcome = next(NOTEBOOKS.glob("00_*.ipynb"))
    table = next(c for c in _cells(welcome, "markdown") if c.startswith("## The notebooks"))
    rows = re.findall(r"^\| \[([^\]]+)\]\(([^)]+)\) \|", table, re.MULTILINE)
    listed = [target for _, target in rows]
    on_disk = sorted(p.name for p in NOTEBOOKS.glob("*.ipynb"))
    assert listed == on_disk, (listed, on_disk)  # every one, in order, none that is not there
    assert all(f"{name}.ipynb" == target for name, target in rows), rows


def test_the_notebooks_voila_serves_ask_for_the_offline_template():
    repo = NOTEBOOKS.parent
    template = repo / "share" / "jupyter" / "voila" / "templates" / "lfd-tutor"
    assert json.loads((template / "conf.json").read_text())["base_template"] == "lab"
    page = (template / "index.html.j2").read_text()
    assert "block notebook_css" in page and "_xsrf" in page
    for name in ("02_maze_experiment", "03_pick_and_place", "05_class_results"):
        meta = json.loads((NOTEBOOKS / f"{name}.ipynb").read_text())["metadata"]
        assert meta.get("voila") == {"template": "lfd-tutor"}, name
    # every file of the template is installed with the package (a wheel's data files)
    with open(repo / "pyproject.toml", "rb") as f:
        data_files = tomllib.load(f)["tool"]["setuptools"]["data-files"]
    listed = data_files["share/jupyter/voila/templates/lfd-tutor"]
    assert sorted(listed) == sorted(str(p.relative_to(repo)) for p in template.iterdir())
