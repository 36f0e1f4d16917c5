"""The one registry of experiments and conditions (tutor/framework/protocol.py).

A made-up condition with a made-up feedback policy, added as one registry entry and one
policy class, is offered by the start form, taught in a run, taught by the simulated
teachers, simulated in a cohort and counted, described and compared (with BF) in the
class analysis, beside the paper's tests, which stay on the paper's conditions;
nothing else changes.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tutor.errors import InvalidParameterError
from tutor.framework.feedback import FEEDBACK_POLICIES, FeedbackPolicy, register_policy
from tutor.framework.protocol import EXPERIMENTS, Condition, experiment, register


class CornerFeedback(FeedbackPolicy):
    """A made-up policy: after each demo the robot tries the tray's first and last plant."""

    name = "corners"
    description = "the first and the last condition after every demo (made up)"

    def shown(self, n, own, batch, selected):
        return np.asarray([0, n - 1], dtype=int)


@pytest.fixture
def made_up():
    """Experiment 2 with a made-up condition XF (CornerFeedback), for one test."""
    before, policies = EXPERIMENTS[2], dict(FEEDBACK_POLICIES)
    policy = register_policy(CornerFeedback())
    xf = Condition(
        "XF",
        policy,
        paper=False,
        tip="XF (made up): the robot tries two corner plants",
        example="2. The robot tries two corners",
        compared_with="BF",
        compared_why="shows plants after every demo too",
    )
    register(replace(before, conditions=(*before.conditions, xf)))
    try:
        yield xf
    finally:
        register(before)
        FEEDBACK_POLICIES.clear()
        FEEDBACK_POLICIES.update(policies)


def test_the_registry_holds_the_papers_design():
    one, two = experiment(1), experiment(2)
    assert (one.task, one.paper_codes, one.extra_codes) == ("maze", ("NF", "VF", "VR"), ("VA",))
    assert (one.n_teachers, one.runs, one.within_subjects) == (30, 1, True)
    assert two.paper_codes == ("NF", "RF", "BF", "SF") and two.extra_codes == ("AF", "HF")
    assert (two.n_teachers, two.runs, two.within_subjects) == (36, 3, False)
    assert two.policies == {
        "NF": "none", "RF": "replay", "BF": "batch", "SF": "selected",
        "AF": "adaptive", "HF": "none",
    }
    assert [c.paper_code for c in two.conditions] == ["NF", "RF", "BF", "SF", "BF", "NF"]
    assert one.condition("VR").rules and not one.condition("VF").rules
    assert two.condition("SF").policy.teacher_picks and two.condition("HF").hinted
    with pytest.raises(InvalidParameterError, match="not a condition of Experiment 2"):
        two.condition("VR")
    with pytest.raises(InvalidParameterError, match="experiment must be one of"):
        experiment(3)


def test_a_made_up_condition_is_one_entry_and_one_policy_class(made_up):
    from tutor.study.cohort import check_conditions, run_experiment
    from tutor.tasks.pickplace import PickPlaceTask
    from tutor.tasks.pickplace_protocol import PickPlaceRun
    from tutor.teachers.pickplace import PickPlaceTeacher
    from tutor.teachers.traits import DEFAULT_POPULATION
    from tutor.views.pickplace_app import paper_condition
    from tutor.views.start_pickplace import pick_and_place_experiment

    # the start form offers it, with its tip
    form = pick_and_place_experiment(start=False, scene3d=False)
    buttons = form.condition_buttons
    assert "XF" in buttons.options
    assert buttons.tooltips[list(buttons.options).index("XF")] == made_up.tip

    # a run in it shows the made-up policy's r after each demo, and no totals
    task = PickPlaceTask()
    run = PickPlaceRun("XF", task)
    record = run.demonstrate(44, rng=np.random.default_rng(0))
    assert record.shown.tolist() == [0, len(task.test_points) - 1]
    assert run.feedback == "corners" and not run.visibility().totals
    assert paper_condition("XF") == "BF"

    # a simulated teacher teaches it, and a cohort holds it beside BF
    traits = DEFAULT_POPULATION.sample(np.random.default_rng(1))
    taught = PickPlaceTeacher(traits, task).teach("XF", rng=2)
    assert taught.condition == "XF" and taught.session.n_demos >= 1
    assert check_conditions(2, ("BF", "XF")) == ("BF", "XF")
    cohort = run_experiment(2, seed=0, n=4, workers=1, progress=False, conditions=("BF", "XF"))
    assert set(cohort.runs.condition) == {"BF", "XF"}


def test_a_made_up_condition_is_in_the_class_analysis(made_up, tmp_path):
    import json

    from tutor.study.class_report import analyse_class, save_class
    from tutor.study.classroom import read_class
    from tutor.study.simulated_class import write_simulated_class

    # a class of 6 simulated trainees, 3 in BF and 3 in XF, three runs each
    write_simulated_class(tmp_path / "class", 2, 6, seed=0, workers=1, conditions=("BF", "XF"))
    result = read_class(tmp_path / "class", 2, workers=1)
    assert not result.not_counted
    xf_files = [f for f in result.files if f.condition == "XF"]
    assert len(xf_files) == 9 and all(f.counted for f in xf_files)
    assert result.runs.condition.value_counts().to_dict() == {
        "XF": 9, "BF": 9, "NF": 0, "RF": 0, "SF": 0, "AF": 0, "HF": 0,
    }
    assert list(result.runs.condition.cat.categories) == list(experiment(2).codes)

    analysis = analyse_class(result)
    table = analysis["descriptive"]
    assert list(table.index) == ["NF", "RF", "BF", "SF", "XF"]  # the paper's, then XF
    assert table.loc["XF", ["trainees", "runs"]].tolist() == [3, 9]
    xf = result.runs[result.runs.condition == "XF"]
    assert table.loc["XF", "mean eta"] == pytest.approx(xf.eta.mean())
    assert table.loc["XF", "errors"] == xf.errors.sum()

    # its comparison is with BF, the condition the registry compares it with
    beyond = analysis["beyond"]
    assert list(beyond.index) == ["XF"]
    row = beyond.loc["XF"]
    assert (row["compared with"], row["trainees"], row["trainees (compared)"]) == ("BF", 3, 3)
    assert row["test"] == "Welch t" and np.isfinite(row["T"]) and 0 <= row["p"] <= 1
    bf = result.runs[result.runs.condition == "BF"]
    assert row["mean eta (compared)"] == pytest.approx(bf.eta.mean())

    # the paper's tables and tests keep to the paper's conditions
    assert list(analysis["beside"].index) == ["NF", "RF", "BF", "SF"]
    assert list(analysis["failures"].columns) == ["BF"]
    assert not analysis["class"]["tested"] and "XF" not in analysis["class"]["why_not"]

    # and the saved results hold it
    save_class(result, analysis, tmp_path / "out", figures=False)
    saved = json.loads((tmp_path / "out" / "class.json").read_text())
    assert saved["descriptive"]["XF"]["runs"] == 9
    assert saved["beyond"]["XF"]["compared with"] == "BF"


def test_the_registry_is_left_as_it_was_after_the_made_up_condition():
    assert experiment(2).codes == ("NF", "RF", "BF", "SF", "AF", "HF")
    assert "corners" not in FEEDBACK_POLICIES
