"""The next-demo hint (condition HF, beyond the paper): tasks.hint, the run, the teacher,
the tutor."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from tutor.errors import InvalidParameterError
from tutor.framework import RunRecord
from tutor.tasks.hint import (
    HINT_CANDIDATES,
    Hint,
    hint_bank,
    hint_candidates,
    next_demo_hint,
)
from tutor.tasks.lookahead import State, best_next
from tutor.tasks.optimal_reference import optimal_reference
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.teachers.pickplace import PickPlaceTeacher
from tutor.teachers.traits import DEFAULT_POPULATION, Population, TeacherTraits


def demonstrated(task, plants, condition="HF", seed=0) -> PickPlaceRun:
    run = PickPlaceRun(condition, task)
    rng = np.random.default_rng(seed)
    for plant in plants:
        run.demonstrate(plant, rng=rng)
    return run


# ---------------------------------------------------------------- the condition


def test_hf_is_nf_plus_a_hint_beyond_the_paper(pickplace_task):
    design = PickPlaceRun.protocol()
    assert design.extra_codes == ("AF", "HF") and design.codes[-2:] == ("AF", "HF")
    hf = design.condition("HF")
    assert hf.policy.silent and hf.hinted and not hf.paper and hf.paper_code == "NF"
    run = PickPlaceRun("HF", pickplace_task)
    assert run.hinted and not PickPlaceRun("NF", pickplace_task).hinted
    assert run.feedback_seconds == 0.0
    rng = np.random.default_rng(3)
    raw = pickplace_task.demonstrate(12, rng)
    nf = PickPlaceRun("NF", pickplace_task)
    nf.demonstrate(12, raw=raw)
    run.hint()
    run.demonstrate(12, raw=raw)
    run.hint()
    assert run.elapsed == pytest.approx(nf.elapsed)  # a hint costs no time on the clock
    vis = run.visibility()
    assert not vis.totals and len(vis.shown) == 0  # nothing shown while teaching, as NF


# ---------------------------------------------------------------- the hint


def test_with_no_demo_the_hint_is_the_optimal_teachers_first_pick(pickplace_task):
    reference = optimal_reference("pickplace")
    hint = PickPlaceRun("HF", pickplace_task).hint()
    assert isinstance(hint, Hint)
    assert hint.plant == reference.picks[0] and hint.efficacy == reference.greedy[0]
    assert hint.seconds < 0.05  # read, not computed
    assert reference.n_conditions == len(pickplace_task.test_points)


def test_after_demos_the_hint_is_the_best_of_the_pruned_candidates(pickplace_task):
    run = demonstrated(pickplace_task, [44, 3])
    hint = run.hint()
    candidates = hint_candidates(pickplace_task, run)
    assert len(candidates) == HINT_CANDIDATES == len(set(candidates.tolist()))
    assert not {44, 3} & set(candidates.tolist())  # a demonstrated plant scores 0: last
    assert hint.plant in candidates
    best = best_next(
        pickplace_task, State.from_session(run), hint_bank(pickplace_task), candidates, workers=1
    )
    assert (hint.plant, hint.efficacy) == (best.index, best.efficacy)
    # the efficacy is the session's own once that careful demo is given
    run.add_demo(
        hint_bank(pickplace_task).demos[hint.plant], point=pickplace_task.test_points[hint.plant]
    )
    assert run.session.latest.efficacy == pytest.approx(hint.efficacy, abs=1e-12)


def test_the_candidates_need_a_demo_and_a_count(pickplace_task):
    with pytest.raises(InvalidParameterError, match="give a demonstration first"):
        hint_candidates(pickplace_task, PickPlaceRun("HF", pickplace_task))
    with pytest.raises(InvalidParameterError, match="whole number"):
        hint_candidates(pickplace_task, demonstrated(pickplace_task, [5]), n=0)


def test_the_hint_is_cached_and_undo_and_reset_invalidate_it(pickplace_task):
    run = demonstrated(pickplace_task, [44])
    first = run.hint()
    assert run.hint() is first  # computed once per demo state
    run.demonstrate(first.plant, rng=np.random.default_rng(9))
    after = run.hint()
    assert after is not first
    run.undo()
    again = run.hint()
    assert again is not first  # recomputed for the state undo went back to ...
    assert (again.plant, again.efficacy) == (first.plant, first.efficacy)  # ... the same
    run.reset()
    assert run.hint().plant == optimal_reference("pickplace").picks[0]


def test_the_bank_is_one_careful_demo_per_plant_made_once(pickplace_task):
    bank = hint_bank(pickplace_task)
    assert hint_bank(pickplace_task) is bank
    assert bank.index.tolist() == list(range(len(pickplace_task.test_points)))
    assert set(bank.draw.tolist()) == {0}


def test_next_demo_hint_works_on_a_session_too(pickplace_task):
    run = demonstrated(pickplace_task, [0, 99], condition="NF")
    assert next_demo_hint(pickplace_task, run.session).plant == run.hint().plant


# ---------------------------------------------------------------- the record


def test_an_hf_run_records_hint_following_and_round_trips(pickplace_task, tmp_path):
    run = PickPlaceRun("HF", pickplace_task)
    rng = np.random.default_rng(5)
    hinted = run.hint().plant
    run.demonstrate(hinted, rng=rng)
    other = next(p for p in (44, 45, 46) if p != run.hint().plant)
    run.demonstrate(other, rng=rng)
    run.demonstrate(run.hint().plant, rng=rng)
    flags = [d.followed_rule for d in run.attempt.demos]
    assert flags == [True, False, True]
    path = run.save(tmp_path / "hf.json")
    back = PickPlaceRun.load(path, pickplace_task)
    assert [d.followed_rule for d in back.attempt.demos] == flags
    assert back.condition == "HF" and back.elapsed == pytest.approx(run.elapsed)
    again = RunRecord.from_dict(json.loads(path.read_text(encoding="utf-8")))
    assert [d.followed_rule for d in again.current.demos] == flags
    jsonschema = pytest.importorskip("jsonschema")
    schema_path = Path(__file__).resolve().parents[1] / "tutor/framework/run_record.schema.json"
    schema = json.loads(schema_path.read_text(encoding="utf-8"))
    jsonschema.validate(json.loads(path.read_text(encoding="utf-8")), schema)
    # outside HF nothing is recorded
    nf = demonstrated(pickplace_task, [44], condition="NF")
    assert nf.attempt.demos[0].followed_rule is None


def test_a_plant_outside_the_candidates_did_not_follow_the_hint_and_costs_no_lookahead(
    pickplace_task, monkeypatch
):
    """After a demo the hint is one of hint_candidates: a plant outside them is recorded
    as not following it without the lookahead running; one inside asks the lookahead."""
    import tutor.tasks.hint as hint_module

    run = demonstrated(pickplace_task, [44])
    candidates = hint_candidates(pickplace_task, run).tolist()
    hinted = run.hint().plant  # what the lookahead picks, for the check below
    run._hint = None  # forget it: the records below must not lean on it
    asked = []
    real = hint_module.best_next
    monkeypatch.setattr(
        hint_module, "best_next", lambda *a, **k: asked.append(1) or real(*a, **k)
    )
    outside = next(p for p in range(100) if p not in candidates and p != 44)
    run.demonstrate(outside, rng=np.random.default_rng(1))
    assert run.attempt.demos[-1].followed_rule is False and asked == []
    second = demonstrated(pickplace_task, [44])
    second.demonstrate(hinted, rng=np.random.default_rng(1))
    assert second.attempt.demos[-1].followed_rule is True and asked == [1]


# ---------------------------------------------------------------- the simulated teacher


class Recording(np.random.Generator):
    """A generator that notes each draw's method and arguments, in order."""

    def __init__(self, seed):
        super().__init__(np.random.PCG64(seed))
        self.calls = []

    def __getattribute__(self, name):
        attr = super().__getattribute__(name)
        if name in ("lognormal", "normal", "uniform", "beta", "integers"):
            calls = super().__getattribute__("calls")

            def noted(*args, **kwargs):
                calls.append((name, args))
                return attr(*args, **kwargs)

            return noted
        return attr


def test_compliance_is_a_population_trait_drawn_last():
    traits = DEFAULT_POPULATION.sample(np.random.default_rng(3))
    assert 0.4 <= traits.compliance <= 1.0
    fixed = Population(compliance_low=0.2, compliance_high=0.2).sample(np.random.default_rng(3))
    assert fixed.compliance == 0.2
    assert dataclasses.replace(fixed, compliance=traits.compliance) == traits
    rng = Recording(3)
    assert DEFAULT_POPULATION.sample(rng) == traits  # the same draws, noted
    heed = (DEFAULT_POPULATION.heed_low, DEFAULT_POPULATION.heed_high)
    assert rng.calls[-1] == ("uniform", heed)  # heed, added after it, is drawn after it
    assert rng.calls[-2] == ("uniform", (0.4, 1.0))  # compliance: the last draw before
    assert [c for c in rng.calls[:-2] if c == ("uniform", (0.4, 1.0))] == []
    with pytest.raises(InvalidParameterError, match="compliance_low"):
        Population(compliance_low=0.9, compliance_high=0.5)
    assert "compliance" in traits.to_dict()
    assert TeacherTraits.__dataclass_params__.frozen


@pytest.mark.parametrize("compliance", [1.0, 0.0])
def test_the_simulated_hf_teacher_follows_the_hint_with_its_compliance(pickplace_task, compliance):
    traits = dataclasses.replace(
        DEFAULT_POPULATION.sample(np.random.default_rng(3)), compliance=compliance
    )
    run = PickPlaceTeacher(traits, pickplace_task).teach("HF", np.random.default_rng(4))
    demos = run.attempt.demos
    assert run.finished and demos
    assert all(d.followed_rule is (compliance == 1.0) for d in demos)
    assert all((d.chosen_by == "hint") is (compliance == 1.0) for d in demos)
    assert not run.attempt.undone  # nothing shown, so nothing seen failing and redone
    assert all(len(r.shown) == 0 for r in run.session.history)
    # as in NF: a few plants of their choice tried only after the run
    assert run.attempt.tests and all(t.after_run for t in run.attempt.tests)


# ---------------------------------------------------------------- the tutor


def test_the_tutor_says_the_hint_and_marks_the_plant(pickplace_task):
    from tutor.views.pickplace_app import PickPlaceTutor, compare_runs

    tutor = PickPlaceTutor("HF", task=pickplace_task, seed=1)
    first = tutor.run.hint().plant
    assert "The robot would learn most from plant row 1, column 1 next" in tutor.panel.value
    tutor.demonstrate(44)
    hint = tutor.run.hint()
    r, c = divmod(hint.plant, pickplace_task.scene.cols)
    assert f"plant row {r + 1}, column {c + 1} next" in tutor.panel.value
    marked = [i for i, b in enumerate(tutor.plant_buttons) if "lfd-hint" in b._dom_classes]
    assert marked == [hint.plant] != [first]
    button = tutor.plant_buttons[hint.plant]
    assert "★" in button.description and "learn most from here next" in button.tooltip
    assert "★" not in tutor.plant_buttons[first].description
    # the selected highlight is still one plant, and the hint is not it
    selected = [i for i, b in enumerate(tutor.plant_buttons) if "lfd-selected" in b._dom_classes]
    assert selected == [tutor.selected] == [44]
    assert "efficacy" not in tutor.panel.value  # totals withheld, as in NF
    assert tutor.run.attempt.demos[0].followed_rule is (first == 44)
    tutor.finish()
    assert "for NF was" in tutor.panel.value and "HF is beyond the paper" in tutor.panel.value
    assert not [b for b in tutor.plant_buttons if "lfd-hint" in b._dom_classes]
    assert "NF shows nothing either" in compare_runs([tutor])


def test_no_hint_in_the_papers_conditions(pickplace_task):
    from tutor.views.pickplace_app import PickPlaceTutor

    tutor = PickPlaceTutor("NF", task=pickplace_task, seed=1)
    tutor.demonstrate(44)
    assert "learn most from" not in tutor.panel.value
    assert not [b for b in tutor.plant_buttons if "lfd-hint" in b._dom_classes]


def test_a_hint_that_fails_is_said_not_raised(pickplace_task, monkeypatch):
    from tutor.views.pickplace_app import PickPlaceTutor

    tutor = PickPlaceTutor("HF", task=pickplace_task, seed=1)

    def broken(self):
        raise InvalidParameterError("the bank is empty")

    monkeypatch.setattr(PickPlaceRun, "hint", broken)
    tutor.demonstrate(44)  # no traceback from the callback, and the demo is given
    assert "No hint this time: the bank is empty" in tutor.panel.value
    assert tutor.run.session.n_demos == 1
    assert tutor.run.attempt.demos[0].followed_rule is None  # there was no hint to follow
    assert not [b for b in tutor.plant_buttons if "lfd-hint" in b._dom_classes]


def test_the_start_form_offers_hf_and_the_educator_can_fix_it(person):
    from tutor.views.start_pickplace import condition_from_env, pick_and_place_experiment

    form = pick_and_place_experiment(scene3d=False)
    buttons = form.condition_buttons
    assert list(buttons.options) == ["NF", "RF", "BF", "SF", "AF", "HF"]
    assert "beyond the paper" in buttons.tooltips[-1] and "HF" in form.beyond_note.value
    person.setenv("TUTOR_CONDITION", "hf")
    assert condition_from_env() == "HF"
    locked = pick_and_place_experiment(scene3d=False)
    assert locked.condition == "HF" and locked.condition_buttons.disabled
    assert "set by your educator (TUTOR_CONDITION)" in locked.note.value


def test_hf_has_its_instruction_and_worked_example():
    from tutor.views.worked_example import example_png, instruction_text

    words = instruction_text(2, "HF")
    assert "beyond the paper" in words and "★" in words and len(words.split()) <= 45
    assert example_png(2, "HF")[:8] == b"\x89PNG\r\n\x1a\n"
