"""The educator's dashboard (notebook 05), headless on generated class folders."""

from __future__ import annotations

import asyncio
import json
import shutil

import pytest

from tutor.study.dashboard import ClassDashboard, class_dashboard
from tutor.study.simulated_class import write_simulated_class


@pytest.fixture(scope="module")
def small_class(tmp_path_factory):
    folder = tmp_path_factory.mktemp("dash") / "class"
    write_simulated_class(folder, 1, 6, seed=7, unfinished=1, damaged=1)
    return folder


def test_it_shows_the_class_the_tests_the_trainees_and_the_problems(small_class):
    board = ClassDashboard(small_class)
    assert "<b>16 runs</b> counted from <b>6 trainees</b>" in board.status.value
    assert "2 files not counted" in board.status.value
    assert "median η (paper)" in board.beside.value
    assert board.figure.value.startswith('<img src="data:image/png;base64,iVBOR')
    assert 'alt="Box plots of the class' in board.figure.value
    assert "This class: repeated-measures ANOVA F(2,6)" in board.tests.value  # 4 whole
    assert board.trainees.value.count("<li>") == 2
    assert "still to do: VR" in board.trainees.value
    assert board.problems.value.count("<li>") == 2 and "unfinished" in board.problems.value


def test_refresh_picks_up_a_new_trainee_and_the_other_experiment_is_set_aside(
    small_class, tmp_path
):
    folder = tmp_path / "class"
    shutil.copytree(small_class, folder)
    board = ClassDashboard(folder)
    write_simulated_class(tmp_path / "more", 1, 7, seed=7, workers=1)
    newcomer = sorted((tmp_path / "more").iterdir())[-1]  # trainee 07
    shutil.copytree(newcomer, folder / newcomer.name)
    board.refresh_button.click()
    assert "counted from <b>7 trainees</b>" in board.status.value
    board.experiment.value = 2
    assert "<b>0 runs</b>" in board.status.value
    assert "files of Experiment 1 are set aside" in board.status.value
    assert "No finished run of this experiment yet" in board.beside.value


def test_problems_are_said_in_words_and_never_raised(tmp_path):
    board = ClassDashboard(tmp_path / "nowhere")
    assert "there is no folder or zip file" in board.status.value
    assert board.figure.layout.display == "none"
    (tmp_path / "empty").mkdir()
    board.folder.value = str(tmp_path / "empty")
    board.refresh()
    assert "No run files in" in board.status.value
    board.save_button.click()  # an empty class saves its (empty) tables
    assert "Saved" in board.status.value or "nothing to save" in board.status.value


def test_save_writes_what_the_command_line_writes(small_class, tmp_path):
    folder = tmp_path / "class"
    shutil.copytree(small_class, folder)
    board = ClassDashboard(folder)
    board.save_button.click()
    out = tmp_path / "class_results"
    assert "Saved 6 files" in board.status.value
    summary = json.loads((out / "class.json").read_text())
    assert summary["n_runs_counted"] == 16 and len(summary["skipped"]) == 2
    assert (out / "class_experiment1.png").stat().st_size > 10_000


def test_refresh_every_n_seconds_schedules_itself_on_the_kernels_loop(small_class):
    async def scenario():
        board = ClassDashboard(small_class)
        board.seconds.value = 45
        board.auto.value = True
        loop = asyncio.get_running_loop()
        assert board._timer is not None
        assert board._timer.when() - loop.time() == pytest.approx(45, abs=1)
        before = board.status.value
        await asyncio.sleep(1.1)  # the stamp is to the second
        board._tick()  # what the loop calls after 45 s
        assert board.status.value != before and board._timer is not None
        board.auto.value = False
        assert board._timer is None
        return board

    asyncio.run(scenario())


def test_without_a_running_loop_it_says_to_press_refresh(small_class):
    board = ClassDashboard(small_class)
    board.auto.value = True
    assert board.auto.value is False and "press Refresh" in board.status.value


def test_headless_notebook_shows_a_simulated_class(monkeypatch):
    monkeypatch.setenv("TUTOR_HEADLESS", "1")
    monkeypatch.delenv("TUTOR_CLASS_DIR", raising=False)
    board = class_dashboard()
    assert "lfd-simulated-class-" in board.folder.value
    assert "counted from <b>30 trainees</b>" in board.status.value
    assert "5 files not counted" in board.status.value
