"""The paper-sized cohorts bundled for notebook 04 are what the simulation gives today.

Notebook 04 reads the cohorts ``lfd-tutor reproduce --seed 0`` and ``lfd-tutor
robustness --seeds 10`` wrote (``tutor/assets/cohorts``) instead of simulating them for a
minute. Each teacher's randomness depends only on (seed, experiment, teacher), so a few
teachers simulated afresh must give exactly their bundled rows: when the model changes,
this fails and says which command rewrites the files.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tutor.errors import InvalidFileError, InvalidParameterError
from tutor.framework.protocol import EXPERIMENTS
from tutor.study.cohort import simulate_teacher
from tutor.study.report import analyse, load_result, load_robustness, seeds_report

REWRITE = "lfd-tutor reproduce --experiment {e} --seed 0 --out tutor/assets/cohorts"


@pytest.mark.parametrize(("experiment", "teachers"), [(1, (0, 17)), (2, (0, 20))])
def test_bundled_rows_are_what_the_simulation_gives(experiment, teachers):
    bundled = load_result(experiment)
    n = EXPERIMENTS[experiment].n_teachers
    assert bundled.seed == 0 and bundled.runs.teacher.nunique() == n
    for teacher in teachers:
        rows, _ = simulate_teacher(experiment, teacher, 0, n, settings=bundled.settings)
        fresh = pd.DataFrame(rows)
        mine = bundled.runs[bundled.runs.teacher == teacher].reset_index(drop=True)
        for column in ("condition", "n_demos", "efficacy", "eta", "undemonstrated", "errors"):
            got = fresh[column].astype(str if column == "condition" else float).to_numpy()
            want = mine[column].astype(str if column == "condition" else float).to_numpy()
            if column == "condition":
                assert list(got) == list(want), REWRITE.format(e=experiment)
            else:
                assert np.allclose(got, want), (column, REWRITE.format(e=experiment))


def test_bundled_cohorts_analyse_and_report():
    a2 = analyse(load_result(2))
    assert set(a2["conclusions"]) >= {"BF best"}
    for experiment in (1, 2):
        text = seeds_report(load_robustness(experiment), experiment)
        assert "Over seeds 0-19 (20 cohorts" in text and "seeds where each conclusion holds" in text


def test_a_missing_or_wrong_folder_says_which_command_writes_it(tmp_path):
    with pytest.raises(InvalidFileError, match="lfd-tutor reproduce --experiment 1"):
        load_result(1, tmp_path)
    with pytest.raises(InvalidFileError, match="lfd-tutor robustness --experiment 2"):
        load_robustness(2, tmp_path)
    with pytest.raises(InvalidParameterError, match="experiment must be 1"):
        load_result(3)
