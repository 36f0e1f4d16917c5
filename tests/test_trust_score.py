"""One score, one message, one unit: every η of a run is the run's own score, written one way.

One simulated run of each experiment is saved as a trainee's file; the after-Finish
summary (the tutor opened on that file), the results cell (``compare_runs``), the class
analysis (``lfd-tutor class``'s report), the dashboard's table and the cohort table
(``summary_table`` of the run's cohort row, as notebook 04 prints it) must all show the
same η, in %, to the same decimal.
"""

from __future__ import annotations

import html
import re
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from tutor.errors import InvalidParameterError
from tutor.fileio import write_json
from tutor.framework.metrics import rule_of
from tutor.framework.record import Trainee
from tutor.framework.run import TeachingRun
from tutor.framework.wording import percent
from tutor.study import stats
from tutor.study.class_report import analyse_class, format_class_report
from tutor.study.classroom import read_class
from tutor.study.cohort import StudySettings, rows_of
from tutor.study.dashboard import ClassDashboard
from tutor.study.tables import readable_table
from tutor.tasks.maze import MazeTask
from tutor.tasks.pickplace import PickPlaceTask
from tutor.teachers.maze import MazeTeacher
from tutor.teachers.pickplace import PickPlaceTeacher
from tutor.teachers.traits import DEFAULT_POPULATION
from tutor.views import maze_app, pickplace_app
from tutor.views.start import run_file_name

#: one run of each experiment, chosen so that the two rules give different η: the maze
#: VF run reaches 90 % at demo 4 of 5, the pick-and-place NF run at demo 3 of 7
RUNS = {1: ("VF", 3, 4), 2: ("NF", 0, 10)}
TRAINEE = Trainee.from_name("Ada Lovelace")
ETA = re.compile(r"η = (\d+\.\d%)")


def _teach(experiment: int):
    condition, person_seed, run_seed = RUNS[experiment]
    person = DEFAULT_POPULATION.sample(np.random.default_rng(person_seed))
    if experiment == 1:
        teacher = MazeTeacher(person, MazeTask())
    else:
        teacher = PickPlaceTeacher(person, PickPlaceTask())
    return teacher.teach(condition, np.random.default_rng(run_seed))


@pytest.fixture(scope="module", params=[1, 2], ids=["experiment1", "experiment2"])
def saved(request, tmp_path_factory):
    """(experiment, run, class folder, run file): the run saved as Ada's file."""
    experiment = request.param
    run = _teach(experiment)
    folder = tmp_path_factory.mktemp(f"class{experiment}")
    home = folder / TRAINEE.key
    home.mkdir()
    record = replace(run.record, trainee=TRAINEE)
    path = write_json(home / run_file_name(experiment, run.condition), record.to_dict())
    return experiment, run, folder, path


def _text(value: str) -> str:
    return html.unescape(re.sub(r"<[^>]+>", " ", value))


def _shown_etas(experiment, run, folder, path) -> dict[str, str]:
    """The η each place shows for the run."""
    shown = {}
    app_module = maze_app if experiment == 1 else pickplace_app
    tutor_class = maze_app.MazeTutor if experiment == 1 else pickplace_app.PickPlaceTutor
    tutor = tutor_class(run.condition, session_file=path, task=run.task, trainee=TRAINEE)
    assert tutor.run.finished and tutor.run.n_demos == run.n_demos
    summary = _text(tutor.panel.value)
    assert summary.count("η = ") == 1, summary  # one score after Finish
    shown["after-Finish summary"] = ETA.search(summary).group(1)
    shown["results cell"] = ETA.search(app_module.compare_runs([tutor])).group(1)

    result = read_class(folder, experiment, workers=1)
    assert len(result.runs) == 1
    report = format_class_report(result, analyse_class(result))
    row = next(line for line in report.splitlines() if line.startswith(f"{run.condition} "))
    shown["class analysis"] = row.split()[2]  # condition, trainees, η (class)

    board = ClassDashboard(folder, experiment)
    cell = re.search(
        rf"<th>{run.condition}</th>\s*<td>1</td>\s*<td>([^<]*)</td>", board.beside.value
    )
    shown["dashboard table"] = cell.group(1)

    row, _ = rows_of(run, {"teacher": 0, "condition": run.condition, "run": 1}, StudySettings())
    cohort = readable_table(stats.summary_table(pd.DataFrame([row]), experiment))
    shown["cohort table"] = cohort.loc[run.condition].iloc[0]  # the simulation's η
    return shown


def test_every_place_shows_the_runs_one_score(saved):
    experiment, run, folder, path = saved
    expected = percent(run.score().efficiency)
    other_rule = "final" if experiment == 1 else "target"
    wrong = percent(run.session.score(rule=other_rule).efficiency)
    assert wrong != expected  # the run tells the two rules apart
    shown = _shown_etas(experiment, run, folder, path)
    assert shown == dict.fromkeys(shown, expected), shown
    assert re.fullmatch(r"\d+\.\d%", expected)


def test_the_rule_comes_from_the_experiment_never_a_default():
    assert (rule_of(1), rule_of(2)) == ("target", "final")
    with pytest.raises(InvalidParameterError, match="experiment must be 1"):
        rule_of(3)
    with pytest.raises(InvalidParameterError):
        rule_of(True)

    class Unnamed(TeachingRun):  # a run class that forgot its experiment
        conditions = {"NF": "none"}

    with pytest.raises(InvalidParameterError, match="scoring rule"):
        Unnamed.new("NF", MazeTask()).score()
    session = _teach(1).session
    with pytest.raises(TypeError):
        session.score()  # a session does not know its experiment: the rule must be named
    with pytest.raises(InvalidParameterError, match="scoring rule must be one of"):
        session.score(rule="best")


def test_percent_is_one_decimal_and_a_dash_for_none():
    assert percent(0.30459) == "30.5%" and percent(1) == "100.0%"
    assert percent(None) == percent(float("nan")) == "–"
