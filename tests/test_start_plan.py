"""The start forms with a class plan (TUTOR_CLASS_PLAN): Experiment 2's condition is
assigned, locked and explained; Experiment 1 keeps the paper's order."""

from __future__ import annotations

import json

import pytest

from tutor.framework.assignment import ClassPlan
from tutor.framework.protocol import EXPERIMENTS
from tutor.framework.record import RunRecord
from tutor.runtime import trainee_dir
from tutor.views.start import maze_experiment
from tutor.views.start_pickplace import pick_and_place_experiment

CONDITIONS = EXPERIMENTS[2].paper_codes

PLAN = "trainee,condition\nAna,RF\nBen,sf\nstudent07,NF\nZoë,balanced\n"


@pytest.fixture
def plan(person, tmp_path):
    """The educator's class plan, named by TUTOR_CLASS_PLAN; returns its path."""
    path = tmp_path / "plan.csv"
    path.write_text(PLAN, encoding="utf-8")
    person.setenv("TUTOR_CLASS_PLAN", str(path))
    return path


def form():
    return pick_and_place_experiment(scene3d=False)


def test_the_plan_assigns_and_locks_the_condition(plan):
    f = form()
    f.name.value = "Ana"
    assert f.condition == "RF" and f.condition_buttons.disabled
    assert "Your educator's class plan assigns you RF (for Ana)." in f.note.value
    f.go.click()
    run1 = f.tutors[0]
    assert run1.run_file == trainee_dir("Ana") / "pickplace_RF_run1.json"
    assert run1.condition == "RF" and f.condition_buttons.disabled


def test_the_condition_follows_the_name_as_it_is_typed(plan):
    f = form()
    f.name.value = "Ben"
    assert f.condition == "SF"
    f.name.value = "  Ana "  # the same trainee as "Ana" (matched by folder key)
    assert f.condition == "RF"
    f.name.value = "Zoë"
    assert f.assignment.how == "balanced"
    assert "shares the conditions evenly among its 1 trainees" in f.note.value
    f.name.value = "Late Arrival"
    outsider = ClassPlan.from_entries([("x", "Ana", "RF")], CONDITIONS).assign("Late Arrival")
    assert f.condition == outsider.condition  # hash mod 4 of the folder key
    assert "not on your educator's class plan" in f.note.value
    assert "tell your educator" in f.note.value
    f.name.value = "Mai\u202eAnh"  # refused at Start; the note asks for a name meanwhile
    assert "Type your name" in f.note.value
    f.go.click()
    assert f.tutors == [] and "direction controls" in f.note.value
    f.name.value = "Ben"
    f.go.click()
    assert f.trainee == "Ben" and f.tutors[0].condition == "SF"
    f.name.value = "Ana"  # after Start nothing changes any more
    assert f.condition == "SF"


def test_the_hub_user_gets_their_condition_without_typing(plan, person):
    person.setenv("JUPYTERHUB_USER", "student07")
    f = form()
    assert f.name.placeholder == "student07"
    assert f.condition == "NF" and "(for student07)" in f.note.value
    f.go.click()
    assert f.trainee == "student07"
    f.tutors[0].buttons["Demonstrate"].click()  # the run file is written at the first step
    record = RunRecord.from_dict(json.loads(f.tutors[0].run_file.read_text("utf-8")))
    assert (record.trainee.name, record.condition) == ("student07", "NF")


def test_tutor_condition_wins_over_the_plan(plan, person):
    person.setenv("TUTOR_CONDITION", "bf")
    f = form()
    f.name.value = "Ana"
    assert f.condition == "BF" and f.class_plan is None
    assert "TUTOR_CONDITION" in f.note.value and "class plan" not in f.note.value
    plan.write_text("not,a plan\n", encoding="utf-8")  # not even read
    assert form().condition == "BF"


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("trainee,condition\nAna,XF\n", "line 2: 'XF' (for 'Ana') is not a condition"),
        ("name\nAna\n", "must be the header trainee,condition"),
        ("trainee,condition\nAna,RF\nAna ,SF\n", "given two conditions, RF and SF"),
    ],
)
def test_a_bad_plan_is_said_in_plain_words_and_blocks_start(plan, text, fragment):
    plan.write_text(text, encoding="utf-8")
    f = form()
    assert fragment in f.note.value and "Ask your educator" in f.note.value
    assert "Traceback" not in f.note.value and "TUTOR_CLASS_PLAN" in f.note.value
    f.go.click()
    assert f.tutors == [] and f.trainee is None and fragment in f.note.value


def test_a_missing_plan_file_is_said(plan):
    plan.unlink()
    f = form()
    assert "does not exist" in f.note.value
    f.go.click()
    assert f.tutors == []


def test_a_started_condition_is_carried_on_when_the_plan_changes(plan):
    first = form()
    first.name.value = "Ana"
    first.go.click()
    assert first.tutors[0].run_file.name == "pickplace_RF_run1.json"
    first.tutors[0].buttons["Demonstrate"].click()  # the run is begun: its file is written
    assert first.tutors[0].run_file.exists()
    plan.write_text("trainee,condition\nAna,BF\n", encoding="utf-8")
    again = form()
    again.name.value = "Ana"
    assert again.condition == "BF"  # what the plan says now
    again.go.click()
    assert again.tutors[0].condition == "RF"
    assert "already holds runs in RF, so you carry on in RF" in again.note.value
    assert "now assigns you BF" in again.note.value
    practice = form()  # practice runs follow the plan: nothing of them is counted
    practice.name.value = "Ana"
    practice.practice.value = True
    practice.go.click()
    assert practice.tutors[0].run_file.name == "practice_pickplace_BF_run1.json"


def test_without_a_plan_the_trainee_chooses(person):
    f = form()
    assert not f.condition_buttons.disabled and f.class_plan is None
    assert "Choose the condition your educator gave you." in f.note.value


def test_experiment_1_keeps_the_papers_order_whatever_the_plan(plan, person):
    person.setenv("TUTOR_CONDITION", "SF")
    plan.write_text("not a plan\n", encoding="utf-8")
    f = maze_experiment()
    assert [step["condition"] for step in f.plan()] == ["NF", "VF", "VR"]
    assert "class plan" not in f.note.value and "TUTOR_CONDITION" not in f.note.value
    f.name.value = "Ana"
    f.go.click()
    assert [t.condition for t in f.tutors] == ["NF"]
