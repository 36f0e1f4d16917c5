r"""The experiments and their conditions: one registry that everything else reads.

Sena & Howard, "Quantifying Teaching Behaviour in Robot Learning from Demonstration", run
two experiments (their data: http://doi.org/10.18742/RDM01-242).
An *experiment* is a task taught under a set of *conditions*; a condition fixes the
feedback policy (:mod:`tutor.framework.feedback`) that chooses the realisations
:math:`r \subseteq \hat R` a teacher sees after each demonstration:

.. math::

    \text{condition} \;\mapsto\; \text{policy} \;\mapsto\; r_m \subseteq \hat R_m
    \quad (m = 1, \dots, |b|).

============ ========= =========== ==============================================
experiment   task      condition   policy (beyond the paper: compared with)
============ ========= =========== ==============================================
1            maze      NF VF VR    none, all, all (VR adds the paper's rules)
1            maze      VA          adaptive (against VF)
2            pickplace NF RF BF SF none, replay, batch, selected
2            pickplace AF          adaptive, BF's cost (against BF)
2            pickplace HF          none, with a next-demo hint (against NF)
============ ========= =========== ==============================================

A form that lists conditions, a run that checks one, a simulated teacher, a cohort, the
class analysis and the command line all read :data:`EXPERIMENTS`; a new condition is one
:class:`Condition` added to its experiment. The paper's own lists and numbers stay in
:mod:`tutor.paper`, which this module reads.

Examples
--------
>>> from tutor.framework.protocol import experiment
>>> [c.code for c in experiment(2).conditions if c.paper]
['NF', 'RF', 'BF', 'SF']
>>> experiment(2).condition("AF").compared_with
'BF'
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..errors import InvalidParameterError
from ..paper import (
    MAZE_CONDITIONS,
    MAZE_N_TEACHERS,
    PICKPLACE_CONDITIONS,
    PICKPLACE_N_RUNS,
    PICKPLACE_N_TEACHERS,
)
from .feedback import FEEDBACK_POLICIES, FeedbackPolicy
from .wording import listing

__all__ = ["Condition", "Experiment", "EXPERIMENTS", "experiment", "register", "run_file_name"]


@dataclass(frozen=True)
class Condition:
    """One condition of an experiment.

    Attributes
    ----------
    code : str
        Its short name ("NF", "AF", ...), unique within its experiment.
    policy : FeedbackPolicy
        What the teacher is shown after each demo.
    paper : bool
        One of the paper's conditions (False: beyond the paper).
    tip : str
        One line saying what a trainee sees in it (a button's hover text).
    selector : tuple of (str, int) or None
        An ``"adaptive"`` policy's selector name and k (:mod:`.selectors`).
    hinted : bool
        The tutor names the plant (or start) the robot would learn most from next.
    rules : bool
        The tutor gives the paper's rule for where the next demonstration starts (VR).
    instruction : str
        What the trainee is told to do in it, in a few plain sentences (the worked
        example and the start of a run show it).
    example : str
        The worked example's caption of what the trainee sees after a demo ("{plant}":
        the plant the example demonstrates next).
    compared_with : str or None
        Beyond the paper: the paper's condition it is judged against.
    compared_why : str
        Why that one, completing "<compared_with> ..." ("costs the same").
    """

    code: str
    policy: FeedbackPolicy
    paper: bool = True
    tip: str = ""
    selector: tuple[str, int] | None = None
    hinted: bool = False
    rules: bool = False
    instruction: str = ""
    example: str = ""
    compared_with: str | None = None
    compared_why: str = ""

    @property
    def paper_code(self) -> str:
        """The paper's condition a run in this one is compared with: itself, or for a
        condition beyond the paper, :attr:`compared_with`."""
        return self.code if self.paper else self.compared_with


@dataclass(frozen=True)
class Experiment:
    """One of the paper's experiments: its task, conditions and design.

    Attributes
    ----------
    number : int
        1 (the maze) or 2 (pick-and-place), as in the paper.
    task : str
        The task's name (``Task.name``).
    title : str
        What a person calls it ("maze", "pick-and-place").
    conditions : tuple of Condition
        The paper's first, in the paper's order, then those beyond it.
    n_teachers : int
        The paper's cohort size.
    runs : int
        Runs per trainee and condition (the maze: one per condition, within subjects;
        pick-and-place: three of one condition, between subjects).
    within_subjects : bool
        Every trainee teaches in every condition (Experiment 1).
    score_rule : str
        How a run is scored (:func:`tutor.framework.metrics.run_score`): ``"target"``,
        the demos to first reach 90 % coverage (Experiment 1); ``"final"``, efficacy
        after the last demo over the demos given (Experiment 2).
    beyond_note : str
        What the conditions beyond the paper are, in a trainee's words.
    file_stem : str
        A run file's name in the trainee's folder, without ``.json``: a template with
        ``{condition}`` and ``{run}`` (:func:`run_file_name`).
    """

    number: int
    task: str
    title: str
    conditions: tuple[Condition, ...]
    n_teachers: int
    runs: int
    within_subjects: bool
    score_rule: str
    beyond_note: str = ""
    file_stem: str = "{condition}"
    _by_code: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        self._by_code.update({c.code: c for c in self.conditions})

    @property
    def codes(self) -> tuple[str, ...]:
        """Every condition's code, the paper's first."""
        return tuple(c.code for c in self.conditions)

    @property
    def paper_codes(self) -> tuple[str, ...]:
        """The paper's conditions, in its order."""
        return tuple(c.code for c in self.conditions if c.paper)

    @property
    def without_feedback(self) -> str:
        """The paper's condition in which the teacher sees nothing while teaching (NF)."""
        return next(c.code for c in self.conditions if c.paper and c.policy.silent)

    @property
    def with_feedback(self) -> tuple[str, ...]:
        """The paper's conditions in which the teacher sees the robot's attempts."""
        return tuple(c.code for c in self.conditions if c.paper and not c.policy.silent)

    @property
    def extra_codes(self) -> tuple[str, ...]:
        """The conditions beyond the paper."""
        return tuple(c.code for c in self.conditions if not c.paper)

    @property
    def policies(self) -> dict[str, str]:
        """Condition code -> its feedback policy's name."""
        return {c.code: c.policy.name for c in self.conditions}

    @property
    def selectors(self) -> dict[str, tuple[str, int]]:
        """The adaptive conditions: code -> (selector name, k)."""
        return {c.code: c.selector for c in self.conditions if c.selector is not None}

    @property
    def design(self) -> str:
        """Who teaches what, in words ("every trainee teaches NF, VF and VR")."""
        if self.within_subjects:
            return f"every trainee teaches {listing(self.paper_codes)}"
        runs = ("two", "three", "four", "five")[self.runs - 2] if 2 <= self.runs <= 5 else self.runs
        return f"each trainee teaches {runs} runs of one condition"

    @property
    def unit(self) -> str:
        """What a trainee finishes: a "condition" (within subjects) or a "run"."""
        return "condition" if self.within_subjects else "run"

    def condition(self, code) -> Condition:
        """The condition called ``code``, or a named error listing this experiment's."""
        if isinstance(code, str) and code in self._by_code:
            return self._by_code[code]
        raise InvalidParameterError(
            f"{code!r} is not a condition of Experiment {self.number}: use one of "
            f"{', '.join(self.paper_codes)}"
            + (f" (or {', '.join(self.extra_codes)}, beyond the paper)" if self.extra_codes else "")
        )


def run_file_name(experiment: int, condition: str, run: int = 1, practice: bool = False) -> str:
    """The file name of a run in the trainee's folder, e.g. ``VF.json`` (Experiment 1)
    or ``pickplace_SF_run3.json``; practice runs get the prefix ``practice_``."""
    stem = EXPERIMENTS[experiment].file_stem.format(condition=condition, run=run)
    return f"{'practice_' if practice else ''}{stem}.json"


def _policy(name: str) -> FeedbackPolicy:
    return FEEDBACK_POLICIES[name]


#: The experiments by number (the one registry of experiments and conditions).
EXPERIMENTS: dict[int, Experiment] = {}


def register(new: Experiment) -> Experiment:
    """Add (or replace) an experiment in :data:`EXPERIMENTS`; returns it."""
    if not isinstance(new, Experiment):
        raise InvalidParameterError(f"register takes an Experiment, got {type(new).__name__}")
    EXPERIMENTS[new.number] = new
    return new


def experiment(number) -> Experiment:
    """Experiment ``number`` (1 or 2), or a named error."""
    if isinstance(number, int) and not isinstance(number, bool) and number in EXPERIMENTS:
        return EXPERIMENTS[number]
    raise InvalidParameterError(
        f"experiment must be one of {', '.join(map(str, EXPERIMENTS))}, got {number!r}"
    )


_MAZE_POLICIES = {"NF": "none", "VF": "all", "VR": "all"}
_MAZE_TIPS = {
    "NF": "NF: no feedback while teaching",
    "VF": "VF: you see every attempt of the robot after each demonstration",
    "VR": "VR: every attempt, and the rule to follow for the next demonstration",
}
_MAZE_INSTRUCTIONS = {
    "NF": (
        "No feedback. Draw a path from the shaded start zone to the purple target. "
        "You will not see what the robot learned until you press Finish, so decide "
        "yourself where your next demonstration should start."
    ),
    "VF": (
        "Visual feedback. After each demonstration the robot tries the maze from 140 "
        "start points: solid green lines succeed, dashed dark red ones fail. Start "
        "your next demonstration where the lines fail."
    ),
    "VR": (
        "Visual feedback and rules. You see the same lines, and a dashed circle marks"
        " where the paper's rules say your next demonstration should start. Start "
        "inside the circle."
    ),
}
_PICKPLACE_POLICIES = {"NF": "none", "RF": "replay", "BF": "batch", "SF": "selected"}
_PICKPLACE_EXAMPLES = {
    "NF": "2. You see nothing more",
    "RF": "2. The robot tries that plant",
    "BF": "2. The robot tries five plants",
    "SF": "2. You see the plants you test",
}
_PICKPLACE_INSTRUCTIONS = {
    "NF": (
        "No feedback. Pick a plant on the tray map and demonstrate to it. You will "
        "not see what the robot learned until you finish the run, so choose the "
        "plants yourself."
    ),
    "RF": (
        "Replay. After each demonstration the robot tries the plant you just showed "
        "it: green if it succeeds, dark red if it fails. It costs 25 s of your 15 "
        "minutes."
    ),
    "BF": (
        "Batch. After each demonstration the robot tries five plants, the four "
        "corners and the centre: green succeeds, dark red fails. It costs 125 s of "
        "your 15 minutes."
    ),
    "SF": (
        "You choose the tests. After a demonstration, select a plant and press Test "
        "plant to see whether the robot can pick it (25 s each). You see only the "
        "plants you ask for."
    ),
}
_PICKPLACE_TIPS = {
    "NF": "NF: no feedback while teaching",
    "RF": "RF: the robot replays the plant you demonstrated",
    "BF": "BF: the robot tries five sample plants after each demo",
    "SF": "SF: you choose which plants the robot tries",
}

register(
    Experiment(
        number=1,
        task="maze",
        title="maze",
        conditions=(
            *(
                Condition(
                    c,
                    _policy(_MAZE_POLICIES[c]),
                    tip=_MAZE_TIPS[c],
                    rules=c == "VR",
                    instruction=_MAZE_INSTRUCTIONS[c],
                )
                for c in MAZE_CONDITIONS
            ),
            Condition(
                "VA",
                _policy("adaptive"),
                paper=False,
                tip="VA (beyond the paper): the robot shows the five attempts it picks itself",
                selector=("disagreement", 5),
                instruction=(
                    "Adaptive visual feedback (beyond the paper). After each demonstration "
                    "the robot shows the five attempts it is least sure of, out of 140 start "
                    "points: solid green lines succeed, dashed dark red ones fail. Start your "
                    "next demonstration where the lines fail."
                ),
                compared_with="VF",
                compared_why="shows the robot's attempts after every demonstration too",
            ),
        ),
        n_teachers=MAZE_N_TEACHERS,
        runs=1,
        within_subjects=True,
        score_rule="target",
        beyond_note=(
            "VA is beyond the paper: after each demonstration the robot shows the five "
            "attempts it finds least certain, instead of all of them as in VF."
        ),
    )
)

register(
    Experiment(
        number=2,
        task="pickplace",
        title="pick-and-place",
        conditions=(
            *(
                Condition(
                    c,
                    _policy(_PICKPLACE_POLICIES[c]),
                    tip=_PICKPLACE_TIPS[c],
                    instruction=_PICKPLACE_INSTRUCTIONS[c],
                    example=_PICKPLACE_EXAMPLES[c],
                )
                for c in PICKPLACE_CONDITIONS
            ),
            Condition(
                "AF",
                _policy("adaptive"),
                paper=False,
                tip="AF (beyond the paper): the robot tries the five plants it picks itself",
                selector=("disagreement", 5),  # k = 5 plants: BF's cost
                instruction=(
                    "Adaptive (beyond the paper). After each demonstration the robot tries "
                    "the five plants it picks itself, where it is least sure of what it "
                    "learnt: green succeeds, dark red fails. It costs 125 s of your 15 "
                    "minutes, like BF."
                ),
                example="2. The robot tries five plants it picks",
                compared_with="BF",
                compared_why="costs the same",
            ),
            Condition(
                "HF",
                _policy("none"),
                paper=False,
                tip="HF (beyond the paper): no feedback, but a hint of where to demonstrate next",
                hinted=True,
                instruction=(
                    "Hint (beyond the paper). As in NF you see nothing while teaching, but "
                    "before each demonstration the tutor names the plant the robot would "
                    "learn most from next, marked ★ on the tray map. Follow it or choose "
                    "yourself; it costs no time."
                ),
                example="2. The hint: {plant} ★",
                compared_with="NF",
                compared_why="shows nothing either, only without the hint",
            ),
        ),
        n_teachers=PICKPLACE_N_TEACHERS,
        runs=PICKPLACE_N_RUNS,
        within_subjects=False,
        score_rule="final",
        file_stem="pickplace_{condition}_run{run}",
        beyond_note=(
            "AF and HF are beyond the paper. AF, adaptive feedback: after each demonstration "
            "the robot tries the five plants it finds least certain (where what it learnt "
            "from the start, the plant and the bin disagrees, or far from your "
            "demonstrations), at BF's cost. HF, a next-demo hint: as in NF you see nothing "
            "while teaching, but the tutor names the plant the robot would learn most from "
            "next (it costs no time). The paper's four conditions are NF, RF, BF and SF."
        ),
    )
)
