"""Issue 20's polish of notebook 03: the start form never preselects a condition and
warns about runs in another condition (tutor.views.start)."""

from __future__ import annotations

import pytest

from tutor.views.start import counted_runs, pick_and_place_experiment


def form():
    return pick_and_place_experiment(scene3d=False)


def begin(condition: str, name: str = "Ana", finish: bool = False):
    """A form started in ``condition`` under ``name``, its run 1 given one demonstration
    (so that its file is written) and finished if asked."""
    f = form()
    f.condition_buttons.value = condition
    f.name.value = name
    f.go.click()
    assert f.trainee == name, f.note.value
    run1 = f.tutors[0]
    run1.buttons["Demonstrate"].click()
    if finish:
        run1.buttons["Finish run"].click()
    return f


@pytest.fixture
def plan(person, tmp_path):
    path = tmp_path / "plan.csv"
    path.write_text("trainee,condition\nAna,RF\n", encoding="utf-8")
    person.setenv("TUTOR_CLASS_PLAN", str(path))
    return path


# ------------------------------------------------------------------ no preselection


def test_no_condition_is_preselected(person):
    f = form()
    assert f.condition is None and f.condition_buttons.index is None
    assert not f.condition_buttons.disabled
    assert "Choose your condition" in f.condition_prompt.value
    f.condition_buttons.value = "SF"
    assert f.condition == "SF" and f.condition_prompt.value == ""


def test_start_without_a_condition_is_refused_in_the_panel(person):
    f = form()
    f.name.value = "Ana"
    f.go.click()  # a click: nothing raises out of the callback
    assert f.trainee is None and f.tutors == []
    assert "Choose your condition first" in f.problem and "Choose your condition" in f.note.value
    assert not f.go.disabled
    f.condition_buttons.value = "NF"
    f.go.click()
    assert f.trainee == "Ana" and f.tutors[0].condition == "NF"


def test_the_plans_condition_is_shown_and_used(plan):
    f = form()
    assert f.condition is None  # no name yet: the plan gives no condition
    f.name.value = "Ana"
    assert f.condition == "RF" and f.condition_buttons.disabled
    assert f.condition_prompt.value == ""
    f.go.click()
    assert f.trainee == "Ana" and f.tutors[0].condition == "RF"
    f.name.value = "Mai\u202eAnh"  # after Start nothing follows the name any more
    assert f.condition == "RF"


def test_a_name_the_plan_cannot_take_leaves_no_condition(plan):
    f = form()
    f.name.value = "Ana"
    f.name.value = "Mai\u202eAnh"  # refused at Start: the RF of "Ana" must not stay shown
    assert f.condition is None


# ------------------------------------------------------------------ another condition


def test_counted_runs_reads_the_run_records(person):
    begin("BF", finish=True)
    practice = form()
    practice.condition_buttons.value = "SF"
    practice.name.value = "Ana"
    practice.practice.value = True
    practice.go.click()
    practice.tutors[0].buttons["Demonstrate"].click()  # a practice run is not counted
    assert counted_runs("Ana") == {"BF": (1, 1)}
    assert counted_runs("Ana", experiment=1) == {}
    assert counted_runs("Ben") == {}


def test_runs_in_another_condition_need_a_confirmation(person):
    first = begin("BF", finish=True)
    first.tutors[1].buttons["Demonstrate"].click()  # run 2 begun, not finished
    assert counted_runs("Ana") == {"BF": (2, 1)}
    f = form()
    assert f.confirm.layout.display == "none"
    f.condition_buttons.value = "SF"
    f.name.value = "Ana"
    f.go.click()
    assert f.trainee is None and f.tutors == []  # nothing started yet
    assert "Ana already has runs in BF (1 finished, 1 begun)" in f.note.value
    assert "Start SF anyway?" in f.note.value
    assert f.confirm.layout.display is None  # the Start anyway button is shown
    f.confirm.click()
    assert f.trainee == "Ana" and f.tutors[0].condition == "SF"
    assert f.tutors[0].session_file.name == "pickplace_SF_run1.json"
    assert f.confirm.disabled and f.confirm.layout.display == "none"


def test_pressing_start_again_confirms_but_a_change_asks_again(person):
    begin("BF", finish=True)
    f = form()
    f.condition_buttons.value = "SF"
    f.name.value = "Ana"
    f.go.click()
    assert f.trainee is None and "BF (1 finished)" in f.note.value
    f.condition_buttons.value = "RF"  # the warning was about SF: it no longer stands
    assert f.confirm.layout.display == "none"
    f.go.click()
    assert f.trainee is None and "Start RF anyway?" in f.note.value
    f.go.click()  # Start again: confirmed
    assert f.trainee == "Ana" and f.tutors[0].condition == "RF"


def test_the_same_condition_resumes_without_a_warning(person):
    begin("BF", finish=True)
    f = form()
    f.condition_buttons.value = "BF"
    f.name.value = "Ana"
    f.go.click()
    assert f.trainee == "Ana" and f.problem is None
    assert "already has runs" not in f.note.value
    assert f.tutors[0].finished and f.tutors[1].record.run == 2  # resumed at run 2


def test_practice_and_other_trainees_get_no_warning(person):
    begin("BF", finish=True)
    practice = form()
    practice.condition_buttons.value = "SF"
    practice.name.value = "Ana"
    practice.practice.value = True
    practice.go.click()
    assert practice.trainee == "Ana" and practice.problem is None
    other = form()
    other.condition_buttons.value = "SF"
    other.name.value = "Ben"
    other.go.click()
    assert other.trainee == "Ben" and other.problem is None


def test_an_unreadable_file_is_not_counted(person):
    folder = begin("BF").folder
    (folder / "pickplace_NF_run1.json").write_text("{not json", encoding="utf-8")
    assert counted_runs("Ana") == {"BF": (1, 0)}
    f = form()
    f.condition_buttons.value = "BF"
    f.name.value = "Ana"
    f.go.click()  # the broken NF file is no run in NF: no warning
    assert f.trainee == "Ana" and f.problem is None


def test_educator_set_condition_still_warns(person):
    begin("BF", finish=True)
    person.setenv("TUTOR_CONDITION", "NF")
    f = form()
    f.name.value = "Ana"
    f.go.click()
    assert f.trainee is None and "Start NF anyway?" in f.note.value
    assert "else choose" not in f.note.value  # the buttons are locked: no choice offered
    f.confirm.click()
    assert f.trainee == "Ana" and f.tutors[0].condition == "NF"
