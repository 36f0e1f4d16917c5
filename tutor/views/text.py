r"""Feedback in plain words: one voice for every step of a run.

One composer (:func:`compose`) writes what the tutor says after each step, in this
order: **what the robot did**, **what it means**, **what to do next**. It follows the
run's feedback policy (:mod:`tutor.framework.feedback`): it speaks only of the
realisations r the trainee was shown, and of the totals (efficacy
:math:`\varepsilon`, its change, efficiency :math:`\eta = \varepsilon / |b|`, the
undemonstrated states) only where the condition shows them. Warnings about the demo
itself (it fails the task; it repeats an earlier demo) need only the demo and are
always given, without the numbers a condition withholds.

It never contradicts itself: a demo that fails the task but raises coverage gets both
facts said plainly; VR gets one next step, the rule's; a demonstration the tutor
generated (the simulated hand) is never blamed on the trainee; and the words are
plain ("start point", "plant"; no sample numbers).

:func:`finish_summary` gives the one score of a finished run, by its experiment's
rule (:func:`tutor.framework.metrics.run_score`), beside the paper's figure.
"""

from __future__ import annotations

import numpy as np

from ..framework import AMBIGUOUS, INCORRECT, UNDEMONSTRATED
from ..framework.wording import change_points, efficacy_change, percent, plural
from ..tasks.optimal_reference import optimal_reference

__all__ = [
    "compose",
    "finish_summary",
    "optimal_sentence",
    "summary",
    "incorrect_mark",
    "session_report",
    "plain_reason",
    "hint_sentence",
    "HINT_GLYPH",
]

#: the mark of the hinted plant on the tray map (HF), besides its tooltip
HINT_GLYPH = "★"

#: the paper's coverage target (Experiment 1's 90 %)
TARGET = 0.9


def plain_reason(task, causes) -> str:
    """Why a path fails (its causes, a tuple of :class:`~tutor.framework.task.Reason`),
    in plain words without sample numbers: "hit obstacle 2 (right-hand)"."""
    return task.reason_words(causes, samples=False)


def hint_sentence(task, plant: int) -> str:
    """HF's next-demo hint in words, e.g. "The robot would learn most from plant row 3,
    column 7 next (★ on the tray map)"."""
    cols = getattr(getattr(task, "scene", None), "cols", None)
    if cols:
        r, c = divmod(int(plant), cols)
        where = f"{task.point_noun} row {r + 1}, column {c + 1}"
    else:
        where = _name(task, plant)
    return f"The robot would learn most from {where} next ({HINT_GLYPH} on the tray map)."


def _name(task, index: int) -> str:
    namer = getattr(task, "plant_name", None)
    return namer(index) if namer is not None else f"{task.point_noun} {index + 1}"


def _did(task, record, vis, n_demos: int) -> str:
    """What the robot did after the demo, as far as the trainee may see it."""
    n = len(record.passed)
    if vis.totals:
        k = int(np.count_nonzero(record.passed))
        change = "" if n_demos == 1 else f", {100 * record.delta:+.0f} points"
        return (
            f"After demo {n_demos} the robot succeeds from {k} of the {n} "
            f"{task.point_noun_plural} (efficacy ε = {record.efficacy:.0%}{change})."
        )
    shown = [int(i) for i in vis.shown]
    if not shown:
        return f"Demo {n_demos} is recorded. In this condition the robot shows nothing yet."
    ok = [i for i in shown if record.passed[i]]
    bad = [i for i in shown if not record.passed[i]]
    if len(shown) == 1:
        i = shown[0]
        why = "" if record.passed[i] else plain_reason(task, record.causes[i])
        verdict = "succeeds" if record.passed[i] else f"fails: {why}"
        return f"The robot tried {_name(task, i)}: it {verdict}."
    text = (
        f"The robot tried {len(shown)} {task.point_noun_plural}: {len(ok)} "
        f"succeed{'s' if len(ok) == 1 else ''}"
    )
    if bad:
        fails = "; ".join(f"{_name(task, i)} {plain_reason(task, record.causes[i])}" for i in bad)
        text += f", {len(bad)} fail{'s' if len(bad) == 1 else ''} ({fails})"
    return text + "."


def _means(task, record, vis, *, generated: bool, mistake: str, wrong_earlier) -> list[str]:
    """What the step means: the demo's own warnings, and the totals' where shown."""
    m = record.n_demos
    lines = []
    for w in record.warnings:
        if w.kind == INCORRECT and not record.demo_passed:
            why = plain_reason(task, record.demo_causes)
            if mistake:
                fact = f"Demo {m} does not do the task (it {why}): the mistake you chose to show."
                advice = "See what it does to the robot, then undo it."
            elif generated:
                fact = f"Guided demo {m} went wrong (it {why}): the hand slipped, not you."
                advice = "Undo it and demonstrate again."
            else:
                fact = f"Demo {m} does not do the task: it {why}."
                advice = "Undo it and demonstrate that again."
            if vis.totals and m > 1 and record.delta > 0:
                fact += (
                    f" It still raised coverage by {100 * record.delta:.0f} points, but the "
                    "robot also learns the mistake."
                )
            lines.append(f"{fact} {advice}")
        elif w.kind == AMBIGUOUS:
            near = record.nearest_demo
            points = round(100 * record.delta)
            changed = ""
            if vis.totals:
                changed = (
                    " and did not change efficacy"
                    if points == 0
                    else f" and changed efficacy by {points:+d} points"
                )
            lines.append(
                f"Demo {m} is almost the same as demo {near}{changed}: it teaches the robot "
                "little that is new. Start your next one further from your other demos."
            )
        elif w.kind == INCORRECT and vis.totals:  # judged by its effect on the totals
            eps = record.efficacy
            verb = "fell to" if record.delta < 0 else "stayed at"
            change = f"efficacy {verb} {eps:.0%}"
            if wrong_earlier:
                many = len(wrong_earlier) > 1
                nums = ", ".join(map(str, wrong_earlier))
                advice = (
                    f"demo{'s' if many else ''} {nums} {'do' if many else 'does'} not do the "
                    f"task and still mislead{'' if many else 's'} the robot: undo "
                    f"{'them' if many else 'it'} first."
                )
            elif generated:
                advice = "give the next one from a different place."
            else:
                advice = "check it shows the task the way you meant, or try a different place."
            lines.append(f"Demo {m} made things no better ({change}): {advice}")
    return lines


def _next(task, record, vis, *, rule_message: str | None, first_reached: bool) -> list[str]:
    """One next step: the rule's in VR; else the target prompt or where to demonstrate."""
    if rule_message is not None:
        return [rule_message]
    if not vis.totals:
        return []
    if any(w.kind in (INCORRECT, AMBIGUOUS) for w in record.warnings):
        return []  # the warning above already says what to do next (undo, move away)
    if first_reached:
        return [f"{TARGET:.0%} of the {task.point_noun_plural} succeed: you may finish."]
    if record.efficacy >= TARGET:
        return []
    for w in record.warnings:
        if w.kind == UNDEMONSTRATED:
            return [w.message]
    return []


def compose(
    task,
    record,
    vis,
    history=(),
    *,
    rule_message: str | None = None,
    generated: bool = False,
    mistake: str = "",
    finished: bool = False,
) -> list[str]:
    """What the tutor says after a step, in order: did, means, next.

    Parameters
    ----------
    task : Task
    record : DemoStep or None
        The feedback after the latest demo (None before the first).
    vis : Visibility
        What the trainee may see (:meth:`tutor.framework.TeachingRun.visibility`).
    history : sequence of DemoStep
        The earlier records (for "90 % reached" said once, and earlier wrong demos).
    rule_message : str, optional
        VR: the rule that applies next; HF: the next-demo hint (:func:`hint_sentence`).
        It is then the only next step.
    generated : bool
        The demo was made by the tutor's simulated hand, not drawn by the trainee.
    mistake : str
        The mistake the trainee chose to show ("" for none).
    finished : bool
        The run is over: only what the robot now does is said (the score follows it).
    """
    if record is None:
        noun = task.point_noun
        first = f"No demonstration yet: show the robot the task once, from any {noun}."
        return [rule_message or first]
    earlier = [r for r in history if r.n_demos < record.n_demos]
    reached_before = any(r.efficacy >= TARGET for r in earlier)
    wrong_earlier = [r.n_demos for r in earlier if not r.demo_passed]
    lines = [_did(task, record, vis, record.n_demos)]
    if finished:
        return lines
    lines += _means(
        task, record, vis, generated=generated, mistake=mistake, wrong_earlier=wrong_earlier
    )
    lines += _next(
        task,
        record,
        vis,
        rule_message=rule_message,
        first_reached=record.efficacy >= TARGET and not reached_before,
    )
    return lines


def finish_summary(run, paper: float, statistic: str, condition: str | None = None) -> str:
    """The one score of a finished run, by its experiment's rule, beside the paper's.

    ``paper`` is the paper's figure for ``condition`` (default the run's) and
    ``statistic`` its kind ("median" or "mean"). A condition beyond the paper is
    compared with the paper's condition it extends: AF with BF (the same cost), HF with
    NF (nothing shown either; HF adds the hint).
    """
    if run.n_demos == 0:
        return "No demonstrations were given."
    beyond = ""
    if condition is not None and condition != run.condition:
        beyond = (
            f" {run.condition} is beyond the paper; it is compared with {condition}, the "
            "paper's condition closest to it."
        )
    s = run.score(TARGET)
    if run.score_rule == "target":
        how = (
            f"{TARGET:.0%} coverage was reached after "
            f"{plural(s.n_demos, 'demonstration', 'demonstrations')}"
            if s.reached
            else f"{TARGET:.0%} was not reached; after all {s.n_demos} demonstrations the "
            f"robot succeeds from {s.efficacy:.0%} of the {run.task.point_noun_plural}"
        )
    else:
        how = (
            f"after {plural(s.n_demos, 'demonstration', 'demonstrations')} the robot "
            f"succeeds at {s.efficacy:.0%} of the {run.task.point_noun_plural}"
        )
    text = (
        f"{how[0].upper()}{how[1:]}: your teaching efficiency is η = {percent(s.efficiency)} "
        f"(efficacy divided by the number of demonstrations). The paper's {statistic} for "
        f"{condition or run.condition} was {percent(paper)}.{beyond}"
    )
    best = optimal_sentence(run.task, s.n_demos)
    return f"{text} {best}" if best else text


def optimal_sentence(task, n_demos: int | None = None) -> str:
    """The optimal teacher beside the trainee: "You used 6 demonstrations; the fewest this
    robot needs to reach 90% is 3, so the best possible η by this experiment's score is
    33.3%." ("" when the tutor has no reference for the task).

    Parameters
    ----------
    task : Task
    n_demos : int, optional
        The demonstrations the trainee's score counts (left out when None).
    """
    ref = optimal_reference(task.name)
    if ref is None or ref.n_demos is None:
        return ""
    goal = (
        f"to reach {ref.coverage:.0%}"
        if ref.coverage < 1
        else f"to succeed at every one of the {len(task.test_points)} {task.point_noun_plural}"
    )
    fewest = "the fewest this robot needs" if ref.is_proven else "the fewest found"
    head = f"{fewest} {goal} is {ref.n_demos}"
    if n_demos is not None:
        head = f"you used {plural(n_demos, 'demonstration', 'demonstrations')}; {head}"
    return (
        f"{head[0].upper()}{head[1:]}, so the best possible η by this experiment's score is "
        f"{percent(ref.best_eta)}."
    )


# ---------------------------------------------------------------- short forms (notebook 01)


def summary(record, starts: str = "") -> str:
    """A few lines about one step with everything shown (for the framework's notebook).

    The change of efficacy is put in words read off the same number the line shows
    (:func:`tutor.framework.wording.efficacy_change`). ``starts`` names the list of start
    points the cell demonstrates from, one demo each in order (e.g. ``"my_starts"``): a
    demo the tutor asks to take back is then taken back by removing its start point there
    and running the cell again. Without it the demos are bundled ones, and the line says
    how the tutors of notebooks 02 and 03 take a demo back (their Undo button).
    """
    if record is None:
        return "No demonstration yet: show the robot the task once."
    lines = [
        f"After demo {record.n_demos}: {efficacy_change(record.delta)} "
        f"(ε = {record.efficacy:.0%}); efficiency η = {record.efficiency:.1%}."
    ]
    lines += [f"- {w.message}" for w in record.warnings]
    back = sorted({i for w in record.warnings for i in w.take_back})
    if back:
        lines.append(f"- {_how_to_take_back(back, starts)}")
    if not record.warnings:
        lines.append("- No failures: every test point succeeds or was demonstrated.")
    return "\n".join(lines)


def _how_to_take_back(demos: list[int], starts: str) -> str:
    """How notebook 01 takes back ``demos`` (1-based): from the cell's list ``starts``."""
    many = len(demos) > 1
    names = ", ".join(f"demo {i}" for i in demos)
    if starts:
        where = ", ".join(f"{starts}[{i - 1}]" for i in demos)
        return (
            f"To take {names} back, remove {'their start points' if many else 'its start point'}"
            f" ({where}) from {starts} and run the cell again."
        )
    return (
        f"These are bundled demonstrations, so {names} stay{'' if many else 's'} here; in the "
        "tutors of notebooks 02 and 03 the Undo button takes your latest demo back."
    )


def incorrect_mark(record, task) -> str:
    """Whether the paper's mark of an incorrect demo (its efficacy change is at most 0)
    shows on this step, read off the change of efficacy the step shows, and the tutor's
    own check of the demo against the task's rules beside it (for the framework's
    notebook)."""
    m = record.n_demos
    change = efficacy_change(record.delta)
    mark = "The paper's mark of an incorrect demonstration (εₘ − εₘ₋₁ ≤ 0)"
    if change_points(record.delta) <= 0:
        head = f"{mark} shows here: {change}."
    else:
        head = (
            f"{mark} does not show here: {change}, since the robot now succeeds from more "
            "of the test set than before."
        )
    if record.demo_passed:
        return f"{head} Demo {m} itself keeps to the task's rules."
    still = "still " if change_points(record.delta) > 0 else "also "
    return (
        f"{head} The tutor {still}flags demo {m}, because it breaks the task's rules: it "
        f"{plain_reason(task, record.demo_causes)}."
    )


def session_report(session, target: float = TARGET) -> str:
    """The paper's Experiment 1 score of a maze session, in words (for the framework's
    notebook, whose sessions are Experiment 1's maze)."""
    if not session.history:
        return "No demonstrations yet."
    s = session.score(rule="target", target=target)
    if s.reached:
        head = (
            f"{target:.0%} coverage reached after {s.n_demos} demo{'s' if s.n_demos > 1 else ''}"
            f" (efficacy {s.efficacy:.0%})"
        )
    else:
        head = (
            f"{target:.0%} coverage not reached; after all {s.n_demos} demos "
            f"efficacy is {s.efficacy:.0%}"
        )
    return f"{head}: efficiency η = {percent(s.efficiency)}."
