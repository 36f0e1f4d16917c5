"""The start forms (tutor.views.start) and each condition's instruction (worked_example)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tutor.demofiles import bundled_demos
from tutor.errors import InvalidParameterError
from tutor.framework.protocol import run_file_name
from tutor.framework.record import RunRecord
from tutor.runtime import default_trainee, trainee_dir
from tutor.views.start import HEADLESS_TRAINEE, maze_experiment
from tutor.views.start_pickplace import condition_from_env, pick_and_place_experiment
from tutor.views.worked_example import example_png, instruction_text, instruction_widget


def read_record(path) -> RunRecord:
    return RunRecord.from_dict(json.loads(path.read_text(encoding="utf-8")))


def teach_and_finish(tutor, demos) -> None:
    for demo in demos:
        tutor.pad.draw(demo)
    tutor.buttons["Finish"].click()  # what the trainee's click does, handlers and all


# ------------------------------------------------------------------ the environment


def test_tutor_trainee_comes_before_the_hub_user(person):
    person.setenv("JUPYTERHUB_USER", "student07")
    assert default_trainee() == "student07"
    person.setenv("TUTOR_TRAINEE", "  Mai Anh ")
    assert default_trainee() == "Mai Anh"


def test_condition_from_env(person):
    assert condition_from_env() is None
    person.setenv("TUTOR_CONDITION", "rf")
    assert condition_from_env() == "RF"
    person.setenv("TUTOR_CONDITION", "VR")
    with pytest.raises(InvalidParameterError, match="NF, RF, BF, SF"):
        condition_from_env()


def test_run_file_names_are_the_notebooks():
    assert run_file_name(1, "VF") == "VF.json"
    assert run_file_name(2, "SF", 3) == "pickplace_SF_run3.json"
    assert run_file_name(1, "NF", practice=True) == "practice_NF.json"


# ------------------------------------------------------------------ Experiment 1


def test_the_form_waits_for_start_and_shows_nf_first(person, tmp_path):
    form = maze_experiment()
    assert form.tutors == [] and form.stage.children == ()
    assert "press Start" in form.results()
    form.name.value = "Zoë"
    form.go.click()
    assert [t.condition for t in form.tutors] == ["NF"]
    assert form.name.disabled and form.go.disabled
    assert "Welcome, Zoë" in form.note.value
    # each run begins with its instruction and worked example, then the tutor
    kinds = [type(c).__name__ for c in form.stage.children]
    assert kinds == ["HTML", "VBox", "HBox"]
    assert "lfd-instruction" in form.stage.children[1]._dom_classes
    nf = form.tutors[0]
    assert nf.run_file == trainee_dir("Zoë") / "NF.json"
    assert "1 of 3 runs are finished" not in form.results()


def test_each_run_appears_when_the_previous_is_finished(person):
    form = maze_experiment()
    form.go.click()  # no name typed and none set: refused, said, nothing starts
    assert form.trainee is None and form.tutors == [] and "Type your name" in form.problem
    form.name.value = "Ana"
    form.go.click()
    assert form.trainee == "Ana"
    nf = form.tutors[0]
    nf.buttons["Finish"].click()  # no demo yet: refused, VF does not appear
    assert len(form.tutors) == 1 and not nf.finished
    teach_and_finish(nf, bundled_demos("maze_good")[:2])
    assert [t.condition for t in form.tutors] == ["NF", "VF"]
    assert form.tutors[1].session.n_demos == 0
    assert "1 of 3 runs are finished" in form.results()
    teach_and_finish(form.tutors[1], bundled_demos("maze_good"))
    teach_and_finish(form.tutors[2], bundled_demos("maze_good"))
    assert form.finished
    assert "VR: η =" in form.results()
    for condition in ("NF", "VF", "VR"):
        record = read_record(trainee_dir("Ana") / f"{condition}.json")
        assert record.condition == condition
        assert record.trainee.name == "Ana" and not record.practice


def test_a_wrong_name_is_said_in_the_form_and_nothing_starts(person):
    form = maze_experiment()
    form.name.value = "Mai\u202eAnh"
    form.go.click()
    assert form.tutors == [] and form.trainee is None
    assert "direction controls" in form.note.value
    assert not form.go.disabled
    form.name.value = "Mai Anh"
    form.go.click()
    assert form.trainee == "Mai Anh"


def test_the_educator_fixes_the_name(person):
    person.setenv("TUTOR_TRAINEE", "Group 4")
    form = maze_experiment()
    assert form.name.disabled and form.name.value == "Group 4"
    assert "TUTOR_TRAINEE" in form.note.value
    form.go.click()
    assert form.tutors[0].run_file.parent == trainee_dir("Group 4")


def test_practice_runs_are_recorded_as_practice_in_their_own_files(person):
    form = maze_experiment()
    form.name.value = "Ana"
    form.practice.value = True
    form.go.click()
    nf = form.tutors[0]
    assert nf.run_file.name == "practice_NF.json"
    teach_and_finish(nf, bundled_demos("maze_good")[:1])
    assert read_record(nf.run_file).practice
    assert "practice run" in form.stage.children[1].children[0].value


def test_a_form_run_again_resumes_where_the_trainee_was(person):
    first = maze_experiment()
    first.name.value = "Ana"
    first.go.click()
    teach_and_finish(first.tutors[0], bundled_demos("maze_good")[:3])
    again = maze_experiment()
    again.name.value = "Ana"
    again.go.click()
    assert [t.condition for t in again.tutors] == ["NF", "VF"]
    assert again.tutors[0].finished and again.tutors[0].session.n_demos == 3


def test_headless_runs_feed_the_bundled_demos(person):
    person.setenv("TUTOR_HEADLESS", "1")
    form = maze_experiment()
    assert form.finished and form.trainee == HEADLESS_TRAINEE == form.name.value
    demos = {t.condition: t.session.n_demos for t in form.tutors}
    assert demos == {"NF": 3, "VF": 5, "VR": 5}
    assert "paper's median" in form.results()


# ------------------------------------------------------------------ Experiment 2


def test_the_educator_fixes_the_condition(person):
    person.setenv("TUTOR_CONDITION", "sf")
    form = pick_and_place_experiment(scene3d=False)
    assert form.condition == "SF" and form.condition_buttons.disabled
    assert "set by your educator (TUTOR_CONDITION)" in form.note.value


def test_a_wrong_educator_condition_is_said_and_blocks_start(person):
    person.setenv("TUTOR_CONDITION", "XF")
    form = pick_and_place_experiment(scene3d=False)
    assert "'XF'" in form.note.value and "Ask your educator" in form.note.value
    form.go.click()
    assert form.tutors == [] and "TUTOR_CONDITION" in form.note.value


@pytest.mark.parametrize("condition", ["RF", "AF", "HF"])
def test_pick_and_place_runs_one_after_another_in_the_chosen_condition(person, condition):
    """Notebook 03's form, in one of the paper's conditions and in the two beyond it."""
    form = pick_and_place_experiment(scene3d=False)
    form.condition_buttons.value = condition
    form.name.value = "Ana"
    form.go.click()
    assert form.condition_buttons.disabled
    run1 = form.tutors[0]
    assert (run1.condition, run1.record.run) == (condition, 1)
    assert run1.run_file.name == f"pickplace_{condition}_run1.json"
    run1.buttons["Demonstrate"].click()
    demo = run1.run.attempt.demos[0]
    if condition == "AF":  # the robot tried the plants its selector picked
        assert len(run1.run.session.latest.shown) > 0
    if condition == "HF":  # the hint for the next demo is said, and the first was recorded
        assert "learn most from" in run1.panel.value and demo.followed_rule is not None
    run1.buttons["Finish run"].click()
    assert [t.record.run for t in form.tutors] == [1, 2]
    assert form.tutors[1].task is run1.task  # one task for all runs
    record = read_record(run1.run_file)
    assert (record.trainee.name, record.condition, record.run) == ("Ana", condition, 1)
    assert form.save_scene(1) is None  # no 3-D view was asked for


def test_scene3d_takes_only_its_modes(person):
    with pytest.raises(InvalidParameterError, match="scene3d"):
        pick_and_place_experiment(scene3d="3d")


# ------------------------------------------------------------------ the instructions


def test_every_condition_has_short_plain_words():
    for experiment, conditions in ((1, ("NF", "VF", "VR")), (2, ("NF", "RF", "BF", "SF"))):
        for condition in conditions:
            words = instruction_text(experiment, condition)
            assert len(words.split()) <= 45
            assert "test point" not in words and "eta" not in words.split()
    with pytest.raises(InvalidParameterError, match="NF, VF, VR"):
        instruction_text(1, "BF")


def test_the_worked_example_is_three_frames_of_a_picture():
    png = example_png(1, "VR")
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    import io

    from PIL import Image

    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    assert image.shape[1] > 2 * image.shape[0]  # a strip of frames side by side
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 50  # drawn, not blank
    box = instruction_widget(1, "VR")
    assert "Condition VR" in box.children[0].value
