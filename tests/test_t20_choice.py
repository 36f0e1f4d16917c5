"""Issue 20, part C: choosing the hand (tutor.views.hand, the class plan's hand column, the
start form's checkbox), learning the controls (Try the controls) and the cap's one Undo."""

from __future__ import annotations

import html
import json
import re

import numpy as np
import pytest

from tutor.errors import InvalidParameterError, InvalidPlanError
from tutor.framework import RunOverError
from tutor.framework.assignment import ClassPlan, load_plan
from tutor.framework.record import RunRecord
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.views.hand import (
    DEFAULT_HAND,
    HAND_ENV,
    HANDS,
    check_hand,
    choose_hand,
    controls_html,
)
from tutor.views.pickplace_app import PickPlaceTutor
from tutor.views.start_pickplace import GUIDED_CHECKBOX, pick_and_place_experiment
from tutor.views.worked_example import (
    PRACTICE_CONTROLS,
    TRY_THE_CONTROLS,
    controls_step,
    instruction_widget,
)

CONDITIONS = PickPlaceRun.protocol().paper_codes


def form():
    """The start form with a 3-D view to guide in (the notebook viewer: no server)."""
    return pick_and_place_experiment(scene3d="static")


def test_without_a_3d_view_the_tutor_guides_the_arm():
    bare = pick_and_place_experiment(scene3d=False)
    assert bare.hand == "guided"
    assert bare.guided_box.layout.display == "none"
    assert "3-D view" in bare.hand_line()


def start(f, name: str = "Ana", condition: str | None = "BF"):
    if condition is not None and not f.condition_buttons.disabled:
        f.condition_buttons.value = condition
    f.name.value = name
    f.go.click()
    return f


def write_plan(person, tmp_path, text: str, name: str = "plan.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    person.setenv("TUTOR_CLASS_PLAN", str(path))
    return path


# ------------------------------------------------------------------ the registry


def test_the_two_hands_and_what_differs_between_them():
    assert list(HANDS) == ["own", "guided"] and DEFAULT_HAND == "own"
    assert HAND_ENV == "TUTOR_HAND"
    own, guided = HANDS["own"], HANDS["guided"]
    assert own.label == "Guide the arm yourself"
    assert guided.label == "The tutor guides the arm for you"
    assert (own.mistake_menu, guided.mistake_menu) == (False, True)
    for word in ("drag the ball", "Shift", "E", "Q", "Space", "Enter", "Escape", "gamepad"):
        assert word in own.how, word
    assert "Demonstrate" in guided.how and "Mistake" in guided.how
    assert "5 minutes" in own.try_it and "Escape" in own.try_it
    for hand in HANDS.values():
        assert hand.code in HANDS and hand.words.endswith(".")
        with pytest.raises(AttributeError):
            hand.code = "feet"  # frozen


@pytest.mark.parametrize("value", ["own", "OWN", " guided ", "Guided"])
def test_check_hand_takes_any_case(value):
    assert check_hand(value) == value.strip().lower()


@pytest.mark.parametrize("value", ["", "feet", "guided hand", "x" * 10_000, "own\x00", "ówn"])
def test_check_hand_refuses_other_words_and_lists_the_hands(value):
    with pytest.raises(InvalidParameterError) as refused:
        check_hand(value)
    text = str(refused.value)
    assert "'own'" in text and "'guided'" in text and len(text) < 400


@pytest.mark.parametrize("value", [None, 3, True, 1.5, ["own"], {"hand": "own"}, b"own"])
def test_check_hand_refuses_what_is_not_text(value):
    with pytest.raises(InvalidParameterError, match="must be text"):
        check_hand(value)


def test_choose_hand_explicit_then_plan_then_env_then_default(person):
    assert choose_hand() == "own"
    person.setenv(HAND_ENV, " Guided ")
    assert choose_hand() == "guided"
    assert choose_hand(plan_hand="own") == "own"
    assert choose_hand(plan_hand="own", explicit="guided") == "guided"
    assert choose_hand(plan_hand="", explicit=None) == "guided"  # blank is not set
    person.setenv(HAND_ENV, "")
    assert choose_hand() == DEFAULT_HAND


def test_a_bad_tutor_hand_is_named(person):
    person.setenv(HAND_ENV, "left")
    with pytest.raises(InvalidParameterError, match=r"TUTOR_HAND .*'left'.*'own'"):
        choose_hand()
    assert choose_hand(explicit="own") == "own"  # an explicit choice does not read it
    with pytest.raises(InvalidParameterError, match="the class plan's hand"):
        choose_hand(plan_hand="both")


def test_controls_html_is_an_accessible_list_of_keys():
    page = controls_html("own")
    n = len(HANDS["own"].controls)
    assert len(re.findall(r"<dt[ >]", page)) == len(re.findall(r"<dd[ >]", page)) == n
    assert len(re.findall(r"<dl[ >]", page)) == 1
    assert "<kbd>Space</kbd>" in page and "<kbd>Enter</kbd>" in page
    # two columns of its own, so the page's CSS for lists cannot push the rows out of line
    assert "display: grid" in page and page.count("float: none") == 2 * n
    assert "aria-label='Guide the arm yourself: controls'" in page
    assert "&#x27;" in page  # "a gamepad's sticks", escaped
    assert controls_html(HANDS["guided"]) == controls_html("GUIDED")
    assert "<kbd>" not in controls_html("guided")  # buttons and clicks, no keys
    with pytest.raises(InvalidParameterError):
        controls_html("<script>")


# ------------------------------------------------------------------ the class plan


def test_the_plans_hand_column(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text(
        "trainee;hand;condition\nAna;Guided;RF\nBen;;SF\nZoë; own ;\n", encoding="utf-8"
    )
    plan = load_plan(path, CONDITIONS, hands=HANDS)
    assert plan.assign("Ana").hand == "guided" and plan.assign("Ana").condition == "RF"
    assert plan.assign("Ben").hand is None  # blank: not set
    assert plan.assign("Zoë").hand == "own"
    assert plan.assign("Late Arrival").hand is None
    ignored = load_plan(path, CONDITIONS)  # a caller without hands ignores the column
    assert ignored.hands == {} and ignored.assign("Ana").condition == "RF"


@pytest.mark.parametrize(
    "cell, fragment",
    [
        ("feet", "'feet' (the hand of 'Ana') is not a hand"),
        ("own guided", "'own guided'"),
        ("x" * 5000, "is not a hand"),
        ("0", "'0'"),
    ],
)
def test_a_bad_hand_in_the_plan_names_the_line(tmp_path, cell, fragment):
    path = tmp_path / "p.csv"
    path.write_text(f'trainee,condition,hand\nBen,SF,own\nAna,RF,"{cell}"\n', encoding="utf-8")
    with pytest.raises(InvalidPlanError) as refused:
        load_plan(path, CONDITIONS, hands=HANDS)
    text = str(refused.value)
    assert "line 3" in text and fragment in text and "'own', 'guided'" in text
    assert len(text) < 500


def test_one_trainee_given_two_hands_is_refused():
    entries = [("line 2", "Zoë", "RF", "own"), ("line 5", " Zoë ", "RF", "guided")]
    with pytest.raises(InvalidPlanError, match=r"line 5.*'guided'.*line 2.*'own'"):
        ClassPlan.from_entries(entries, CONDITIONS, hands=HANDS)
    same = [("line 2", "Zoë", "RF", "own"), ("line 5", "Zoë", None, "OWN")]
    assert ClassPlan.from_entries(same, CONDITIONS, hands=HANDS).assign("Zoë").hand == "own"


@pytest.mark.parametrize(
    "hands, fragment",
    [
        ({"Ana": 3}, "must be text"),
        ({"Ana": ["own"]}, "must be text"),
        ({"Ana": "walk"}, "is not a hand"),
        (["Ana", "own"], '"hands" must be an object'),
        ("guided", '"hands" must be an object'),
    ],
)
def test_hostile_json_hands(tmp_path, hands, fragment):
    data = {"format": "lfd-tutor-class-plan", "version": 1, "experiment": 2, "hands": hands}
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(InvalidPlanError, match=re.escape(fragment)):
        load_plan(path, CONDITIONS, hands=HANDS)


def test_json_hands(tmp_path):
    data = {
        "format": "lfd-tutor-class-plan",
        "version": 1,
        "experiment": 2,
        "assign": {"Ana": "RF"},
        "hands": {"Ana": "guided", "Ben": "", "Mai": None},
    }
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    plan = load_plan(path, CONDITIONS, hands=HANDS)
    assert plan.assign("Ana").hand == "guided" and plan.assign("Ana").condition == "RF"
    assert plan.assign("Ben").hand is None and plan.assign("Mai").hand is None


# ------------------------------------------------------------------ the start form


def test_the_checkbox_is_unticked_and_the_summary_names_the_own_hand(person):
    f = form()
    assert (
        f.guided_box.description == GUIDED_CHECKBOX
        and "lfd-start-hand" in f.guided_box._dom_classes
    )
    assert f.guided_box.value is False and f.guided_box.layout.display is None
    assert f.guided_box in f._extra_fields and f.hand == "own"
    start(f)
    assert f.trainee == "Ana" and f.guided_box.disabled
    assert "Guide the arm yourself (the default)." in f.note.value
    assert f.hand == "own"


def test_the_checkbox_passes_the_guided_hand_to_every_run(person):
    f = form()
    f.guided_box.value = True
    assert f.hand == "guided"
    start(f)
    assert "The tutor guides the arm for you (you chose it)." in f.note.value
    run1 = f.tutors[0]
    assert run1.hand == "guided"
    run1.buttons["Finish run"].click()
    assert f.tutors[1].hand == "guided"
    f.guided_box.value = False  # after Start (the page may still send it): nothing changes
    assert f.hand == "guided"


def test_tutor_hand_ticks_the_box_and_the_trainee_may_untick_it(person):
    person.setenv(HAND_ENV, "guided")
    f = form()
    assert f.guided_box.value is True and f.hand == "guided"
    assert "Who moves the arm: The tutor guides the arm for you (your educator set it " in (
        f.note.value
    )
    f.guided_box.value = False
    assert f.hand == "own"
    start(f)
    assert "Guide the arm yourself (you chose it)." in f.note.value
    assert f.hand == "own" and f.tutors  # asked for explicitly, over TUTOR_HAND


def test_a_bad_tutor_hand_blocks_start(person):
    person.setenv(HAND_ENV, "robotic")
    f = form()
    assert "TUTOR_HAND" in f.note.value and "Ask your educator" in f.note.value
    start(f)
    assert f.trainee is None and f.tutors == []
    assert "TUTOR_HAND" in f.problem and "Traceback" not in f.note.value


def test_the_plans_hand_hides_the_box_and_is_used(person, tmp_path):
    write_plan(person, tmp_path, "trainee,condition,hand\nAna,RF,guided\nBen,SF,\n")
    f = form()
    f.guided_box.value = False
    f.name.value = "Ana"
    assert f.guided_box.layout.display == "none" and f.hand == "guided"
    assert "your educator's class plan sets it" in f.note.value
    f.name.value = "Ben"  # the plan sets no hand for Ben: the box is back
    assert f.guided_box.layout.display is None and f.hand == "own"
    f.guided_box.value = True
    assert f.hand == "guided"
    f.name.value = "Ana"
    f.guided_box.value = False  # the box, hidden, cannot win over the plan
    start(f, "Ana", condition=None)
    assert f.trainee == "Ana" and f.tutors[0].condition == "RF"
    assert f.tutors[0].hand == "guided"
    assert "The tutor guides the arm for you (your educator's class plan sets it)." in (
        f.note.value
    )


def test_a_bad_hand_in_the_plan_is_said_and_start_waits(person, tmp_path):
    write_plan(person, tmp_path, "trainee,condition,hand\nAna,RF,sideways\n")
    f = form()
    start(f, condition=None)
    assert f.trainee is None and f.tutors == []
    assert "line 2" in f.note.value and "sideways" in f.note.value
    assert "Ask your educator" in f.note.value


# ------------------------------------------------------------------ Try the controls


def _controls_of(intro):
    found = [c for c in intro.children if "lfd-try-controls" in c._dom_classes]
    assert len(found) == 1
    return found[0].value


def test_run_1_begins_with_try_the_controls(person):
    f = start(form())
    intro = f.stage.children[1]
    text = _controls_of(intro)
    assert TRY_THE_CONTROLS in text and "5 minutes" in text and "<kbd>Space</kbd>" in text
    assert controls_html("own") in text and PRACTICE_CONTROLS not in text
    f.tutors[0].buttons["Finish run"].click()
    again = _controls_of(f.stage.children[4])  # run 2: the keys, not the 5 minutes
    assert "<kbd>Space</kbd>" in again and "5 minutes" not in again


def test_a_practice_run_teaches_the_controls(person):
    f = form()
    f.practice.value = True
    start(f)
    text = _controls_of(f.stage.children[1])
    assert html.escape(PRACTICE_CONTROLS) in text and html.escape(HANDS["own"].try_it) in text


def test_the_guided_hand_is_taught_its_own_controls(person):
    f = form()
    f.guided_box.value = True
    start(f)
    text = _controls_of(f.stage.children[1])
    assert html.escape(HANDS["guided"].try_it) in text and "Demonstrate" in text
    assert "<kbd>" not in text


def test_controls_step_and_the_worked_example():
    assert "lfd-try-controls" in controls_step("own")._dom_classes
    assert html.escape(HANDS["own"].try_it) in controls_step("own").value
    assert html.escape(HANDS["own"].try_it) not in controls_step("own", first=False).value
    with pytest.raises(InvalidParameterError):
        controls_step("tentacle")
    assert len(instruction_widget(2, "BF").children) == 2  # no hand: no step
    assert len(instruction_widget(1, "NF", hand="own").children) == 2  # the maze has none
    assert len(instruction_widget(2, "BF", hand="own").children) == 3


# ------------------------------------------------------------------ the cap's undo


def capped(task, tmp_path):
    """A BF tutor whose second demo the 15-minute cap ended the run with."""
    app = PickPlaceTutor("BF", task=task, seed=0, run_file=tmp_path / "bf.json")
    app.demonstrate(44)
    app.run.spend(app.run.remaining - 160.0)  # one more demo and its 5 attempts fit
    app.demonstrate(0)
    assert app.run.attempt.stopped == "time" and app.run.n_demos == 2
    return app


def test_one_undo_after_the_cap_ended_the_run(pickplace_task, tmp_path):
    app = capped(pickplace_task, tmp_path)
    run = app.run
    assert run.cap_undo_left and run.can_undo
    used, eps_before = run.elapsed, run.session.latest.efficacy
    app.undo()
    assert run.n_demos == 1 and run.finished and run.attempt.stopped == "time"
    assert run.elapsed == pytest.approx(used)  # the time stays spent
    assert run.session.latest.efficacy != eps_before  # back to what demo 1 taught
    assert not run.cap_undo_left and not run.can_undo
    assert "Took back the latest demonstration" in app.panel.value
    assert "the run ends here with 1 demo " in app.panel.value
    before = run.record
    app.undo()  # only one
    assert "its one Undo is used" in app.panel.value and run.record == before
    with pytest.raises(RunOverError, match="its one Undo is used"):
        run.undo()
    # the saved file holds the undo after the finish, and reads back
    saved = RunRecord.from_dict(json.loads(app.run_file.read_text(encoding="utf-8")))
    assert saved.current.n_demos == 1 and [e.kind for e in saved.events][-2:] == [
        "finish",
        "undo",
    ]
    resumed = PickPlaceTutor("BF", task=pickplace_task, run_file=app.run_file)
    assert resumed.run.n_demos == 1 and not resumed.run.can_undo


def test_no_undo_after_the_trainee_finished(pickplace_task):
    run = PickPlaceRun("RF", pickplace_task)
    run.demonstrate(12, rng=np.random.default_rng(0))
    run.finish()
    assert run.attempt.stopped == "finish" and not run.can_undo
    with pytest.raises(RunOverError, match="this run is finished"):
        run.undo()
    assert run.n_demos == 1


def test_a_record_with_two_undos_after_the_cap_is_refused(pickplace_task, tmp_path):
    app = capped(pickplace_task, tmp_path)
    app.undo()
    data = app.run.record.to_dict()
    second = dict(data["events"][-1], n_demos=0)
    data["events"].append(second)
    data["attempts"][-1]["demos"] = []
    with pytest.raises(Exception, match=r"'undo' after attempt 1 was finished"):
        RunRecord.from_dict(data)


def test_after_run_tests_go_with_the_demo_taken_back(pickplace_task):
    run = PickPlaceRun("NF", pickplace_task)
    rng = np.random.default_rng(5)
    run.demonstrate(5, rng=rng)
    run.spend(run.remaining - 2.0)
    assert run.out_of_time and not run.record.finished
    run.test([3])  # after the run (the clock is out)
    run.undo()
    assert run.attempt.tests == ()
    assert RunRecord.from_dict(run.record.to_dict()).current.n_demos == 0
