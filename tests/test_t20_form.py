"""Issue 20's polish of notebook 03: the start form never preselects a condition and
warns about runs in another condition (tutor.views.start_pickplace); the clock and the cap speak
with one voice (tutor.tasks.pickplace_protocol.ClockState, tutor.views.pickplace_app)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from tutor.framework import RunOverError
from tutor.tasks.pickplace_protocol import SHORTEST_DEMO_SECONDS, PickPlaceRun
from tutor.views.pickplace_app import PickPlaceTutor
from tutor.views.start_pickplace import counted_runs, pick_and_place_experiment


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


def start_practice(condition: str, name: str):
    """A new form whose practice run of ``condition`` ``name`` has started."""
    practice = form()
    practice.condition_buttons.value = condition
    practice.name.value = name
    practice.practice.value = True
    practice.go.click()
    return practice


def test_counted_runs_reads_the_run_records(person):
    begin("BF", finish=True)
    practice = start_practice("SF", "Ana")
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
    assert f.tutors[0].run_file.name == "pickplace_SF_run1.json"
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
    practice = start_practice("SF", "Ana")
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


# ------------------------------------------------------------------ the clock and the cap

#: m:ss on the clock
TIME = r"\d+:\d\d"


def seconds_of(text: str) -> int:
    minutes, secs = text.split(":")
    return 60 * int(minutes) + int(secs)


def clock_line(value: str) -> tuple[int, int, int]:
    """(used, cap, left) in seconds, from the clock line."""
    m = re.search(rf"({TIME}) of ({TIME}) used, ({TIME}) left", value)
    assert m, value
    return seconds_of(m[1]), seconds_of(m[2]), seconds_of(m[3])


def cap_numbers(text: str) -> dict:
    """The demo, when it would have ended, the demos kept and the time used and left, from
    the panel's cap message (or the message alone)."""
    cap = re.search(r"<div class='lfd-cap'[^>]*>(.*?)</div>", text)
    text = cap[1] if cap else text
    m = re.search(
        r"[Dd]emo (\d+) .*?would have ended at (\d+:\d\d), past the 15 minutes: the run "
        r"(?:ends here|is over) with (\d+) demos? \((\d+:\d\d) used, (\d+:\d\d) left\)",
        text,
    )
    assert m, text
    return {
        "demo": int(m[1]),
        "ends": seconds_of(m[2]),
        "kept": int(m[3]),
        "used": seconds_of(m[4]),
        "left": seconds_of(m[5]),
    }


def test_used_and_left_add_up_to_the_cap_whatever_the_fraction(pickplace_task):
    run = PickPlaceRun("BF", pickplace_task)
    for spent in (0.2, 0.5, 99.999, 123.4567, 0.0):
        run.spend(spent)
        state = run.clock_state()
        used, cap, left = clock_line(run.clock_text())
        assert (used, cap, left) == (state.used, state.cap, state.left)
        assert used + left == cap == 900
        assert used >= run.elapsed - 1e-6 and used - run.elapsed < 1  # rounded up
    run.spend(2000.0)  # more than the cap: never more than 15:00 used
    assert clock_line(run.clock_text()) == (900, 900, 0)


def test_the_cap_that_ends_a_run_names_the_demo_and_agrees_with_the_clock(pickplace_task, tmp_path):
    app = PickPlaceTutor("BF", task=pickplace_task, seed=0, run_file=tmp_path / "bf.json")
    app.demonstrate(44)
    assert "lfd-cap" not in app.panel.value  # far from the cap: nothing said
    app.run.spend(app.run.remaining - 160.0)  # one demo and its 5 attempts fit, not two
    app.demonstrate(0)
    assert app.run.n_demos == 2 and app.run.attempt.stopped == "time"
    used, cap, left = clock_line(app.clock.value)
    said = cap_numbers(app.panel.value)
    assert (said["used"], said["left"]) == (used, left)  # one voice
    assert said["demo"] == 3 and said["kept"] == 2
    shortest = int(SHORTEST_DEMO_SECONDS)
    assert said["ends"] == used + shortest + 125 > cap
    assert left < shortest + 125  # why it would not have fit
    assert app.buttons["Demonstrate"].disabled


def test_a_refused_demo_gives_the_clock_lines_numbers(pickplace_task):
    rng = np.random.default_rng(3)
    raw = pickplace_task.demonstrate(44, rng)
    seconds = pickplace_task.duration(raw)
    run = PickPlaceRun("RF", pickplace_task)
    run.spend(run.cap - (seconds + 25.0) + 0.7)  # 0.7 s short of this demo and its replay
    used, cap, left = clock_line(run.clock_text())
    with pytest.raises(RunOverError) as refused:
        run.demonstrate(44, raw=raw)
    text = str(refused.value)
    m = re.search(rf"Only ({TIME}) of the 15 minutes.*demo 1 .*?ended at ({TIME})", text)
    assert m and seconds_of(m[1]) == left, text
    assert seconds_of(m[2]) > cap
    assert re.search(rf"\(({TIME}) used\)", text)[1] == run.clock_text().split()[0]
    assert run.n_demos == 0  # nothing changed


def test_a_resumed_run_over_the_cap_says_so_before_finish(pickplace_task, tmp_path):
    run = PickPlaceRun("BF", pickplace_task)
    run.demonstrate(5, rng=np.random.default_rng(4))
    run.spend(run.remaining - 100.0)  # 1:40 left: less than a demo and 5 attempts
    path = run.save(tmp_path / "run.json")
    app = PickPlaceTutor("BF", task=pickplace_task, run_file=path)
    assert app.run.out_of_time and app.run.attempt.stopped == ""
    said = cap_numbers(app.panel.value)
    assert (said["demo"], said["kept"], said["left"]) == (2, 1, 100)
    assert "is over with 1 demo" in app.panel.value
    assert (said["used"], said["left"]) == clock_line(app.clock.value)[::2]
    app.finish()
    assert app.run.attempt.stopped == "time" and "ends here" in app.panel.value


def test_a_run_finished_early_says_nothing_of_the_cap(pickplace_task):
    app = PickPlaceTutor("NF", task=pickplace_task, seed=1)
    app.demonstrate(12)
    app.finish()
    assert app.run.attempt.stopped == "finish" and "lfd-cap" not in app.panel.value
