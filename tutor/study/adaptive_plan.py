"""The adaptive-feedback study's arms, teacher-model variants and plan (how big it is).

:data:`POLICIES` names every arm the study knows (:class:`Policy`: the Experiment 2
condition its runs are in, AF's selector and k, HF's compliance), :data:`VARIANTS` the
teacher-model variants of the robustness check, and :class:`StudyPlan` the sizes of a
study, checked by :func:`check_plan`. :mod:`.adaptive_arm` teaches one arm,
:mod:`.adaptive` runs the whole study; every name is importable from there too.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from ..framework.protocol import EXPERIMENTS
from ..teachers.traits import DEFAULT_POPULATION, Population, TeacherTraits
from .cohort import StudySettings
from .limits import MAX_SEEDS, MAX_TEACHERS

__all__ = [
    "Policy",
    "POLICIES",
    "DEFAULT_POLICIES",
    "VARIANTS",
    "ROBUSTNESS_POLICIES",
    "BASELINE",
    "DEFAULT_VARIANT",
    "StudyPlan",
    "QUICK",
    "SETTINGS",
    "available_policies",
    "check_plan",
    "policy_available",
    "is_secondary",
    "EXPERIMENT",
    "TEACHERS_RANGE",
]

#: the study's analysis settings (the cohort's defaults)
SETTINGS = StudySettings()
#: the experiment whose teachers, task and clock the study uses (pick-and-place)
EXPERIMENT = 2
#: the cohort sizes the full study accepts (the paper's 36 to 60)
TEACHERS_RANGE = (36, 60)


@dataclass(frozen=True)
class Policy:
    """How a teacher is taught in one arm of the study.

    Attributes
    ----------
    name : str
        The arm's label (a key of :data:`POLICIES`).
    condition : str
        The Experiment 2 condition the runs are in ("BF", "AF" or "HF").
    selector : str, optional
        AF's selector (a key of :data:`tutor.framework.selectors.SELECTORS`).
    k : int, optional
        AF's plants shown after each demo.
    compliance : float, optional
        HF: the probability that the teacher follows the hint (replaces the trait).
    reference : bool
        Kept for reference only (the oracle): not a policy a real robot could follow.
    description : str
    """

    name: str
    condition: str
    selector: str | None = None
    k: int | None = None
    compliance: float | None = None
    reference: bool = False
    description: str = ""

    @property
    def spec(self):
        """The arm's condition in the registry (:mod:`tutor.framework.protocol`)."""
        return EXPERIMENTS[2].condition(self.condition)

    @property
    def hinted(self) -> bool:
        """The arm's teachers are offered the next-demo hint (HF)."""
        return self.spec.hinted

    @property
    def options(self) -> dict:
        """The keyword arguments of ``PickPlaceTeacher.teach`` for this arm."""
        if self.spec.policy.adaptive:
            return {"selector": self.selector, "k": self.k}
        return {}

    def traits(self, traits: TeacherTraits) -> TeacherTraits:
        """The teacher's traits in this arm (HF replaces ``compliance``, nothing else)."""
        if self.compliance is None:
            return traits
        return dataclasses.replace(traits, compliance=self.compliance)


def _af(name: str, selector: str, k: int, text: str, reference: bool = False) -> Policy:
    return Policy(name, "AF", selector=selector, k=k, reference=reference, description=text)


#: every policy the study knows (name -> Policy)
POLICIES: dict[str, Policy] = {
    p.name: p
    for p in (
        Policy("BF", "BF", description="the paper's batch: four corners and the centre"),
        _af("KC5", "farthest", 5, "farthest point, 5 plants (BF's cost)"),
        _af("KC2", "farthest", 2, "farthest point, 2 plants"),
        _af("DIS2", "disagreement", 2, "frame disagreement and distance, 2 plants"),
        _af("DIS5", "disagreement", 5, "frame disagreement and distance, 5 plants (AF)"),
        _af("RAND2", "random", 2, "2 plants at random (the control)"),
        _af("RAND5", "random", 5, "5 plants at random (the control)"),
        _af("ORC2", "failures", 2, "the oracle: 2 plants the robot fails at", reference=True),
        Policy("HF0.5", "HF", compliance=0.5, description="next-demo hint, followed half the time"),
        Policy("HF1", "HF", compliance=1.0, description="next-demo hint, always followed"),
    )
}
#: the issue's arms, in the order they are reported (HF only where available)
DEFAULT_POLICIES = ("BF", "KC5", "KC2", "DIS2", "RAND2", "ORC2", "HF0.5", "HF1")
#: the arms rerun under the teacher-model variants: BF and the pilot's best (two arms, so
#: that four variants fit beside the main study on the shared machine)
ROBUSTNESS_POLICIES = ("BF", "DIS2")
#: the baseline every delta is taken against
BASELINE = "BF"

#: teacher-model variants for the robustness check (name -> Population)
VARIANTS: dict[str, Population] = {
    "less patient": dataclasses.replace(DEFAULT_POPULATION, patience_low=4, patience_high=8),
    "noisier aim": dataclasses.replace(DEFAULT_POPULATION, aim_low=0.06, aim_high=0.15),
    "more repeats": dataclasses.replace(DEFAULT_POPULATION, repeat_a=4.0, repeat_b=6.0),
    "fewer believed enough": dataclasses.replace(
        DEFAULT_POPULATION, enough_median_pickplace=4.0, satisfaction_low=0.85,
        satisfaction_high=0.95,
    ),
}
#: the main study's population
DEFAULT_VARIANT = "default"
#: seeds per teacher-model variant in the full study (see StudyPlan.variant_seeds)
VARIANT_SEEDS = 3


def is_secondary(policy: str) -> bool:
    """The oracle (reference only) and the HF arms: run on fewer seeds when the plan says."""
    p = POLICIES[policy]
    return p.reference or p.hinted


def policy_available(policy: Policy) -> bool:
    """Whether this tutor can teach ``policy`` (HF needs the HF condition and the
    ``compliance`` trait, added beside this study)."""
    if policy.condition not in EXPERIMENTS[2].codes:
        return False
    if policy.compliance is not None:
        return "compliance" in {f.name for f in dataclasses.fields(TeacherTraits)}
    return True


def available_policies(names=DEFAULT_POLICIES) -> tuple[str, ...]:
    """The names among ``names`` this tutor can teach (in order)."""
    return tuple(n for n in names if policy_available(POLICIES[n]))


@dataclass(frozen=True)
class StudyPlan:
    """How big the study is (validated by :func:`check_plan`).

    Attributes
    ----------
    n : int
        Teachers per seed (36-60; the quick plan fewer).
    runs : int
        Runs per teacher (the paper's 3).
    seeds : int
        Seeds 0 .. seeds - 1 of the main study (the claims are stated over them).
    policies : tuple of str
        The arms (keys of :data:`POLICIES`; BF must be one).
    variants : tuple of str
        Teacher-model variants (keys of :data:`VARIANTS`) for the robustness check.
    variant_seeds : int
        Seeds per variant (0: no robustness check).
    variant_policies : tuple of str
        The arms rerun under each variant (BF must be one).
    n_boot : int
        Bootstrap draws of every CI and replication rate.
    hf_teachers : int or None
        The HF arms teach only teachers 0 .. hf_teachers - 1 of each seed (None: all,
        the default). The hint's lookahead refits the learner for up to 12 candidate
        plants before every demo, so an HF run costs about 0.7 s against 0.1 s for the
        others (``benchmarks/bench_adaptive.py``); fewer HF teachers make a quicker
        study, their deltas paired with BF on the same teachers.
    secondary_seeds : int or None
        The oracle and the HF arms run on seeds 0 .. secondary_seeds - 1 only (None: all
        seeds, the default).
    quick : bool
        The test switch's plan (smaller sizes allowed; not a result).
    """

    n: int = 36
    runs: int = 3
    seeds: int = 10
    policies: tuple = DEFAULT_POLICIES
    variants: tuple = tuple(VARIANTS)
    variant_seeds: int = VARIANT_SEEDS
    variant_policies: tuple = ROBUSTNESS_POLICIES
    n_boot: int = 2000
    hf_teachers: int | None = None
    secondary_seeds: int | None = None
    quick: bool = False

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


#: the test switch's plan: 4 teachers x 1 run x 2 seeds in every arm, one variant on one
#: seed (a check that everything runs and is written, not a result)
QUICK = StudyPlan(
    n=4, runs=1, seeds=2, variants=("less patient",), variant_seeds=1,
    variant_policies=("BF", "KC2"), n_boot=200, hf_teachers=2, secondary_seeds=None,
    quick=True,
)


#: how a bad ``hf_teachers`` is named in its error (it is also the CLI's --hf-teachers)
HF_TEACHERS_NAME = "the HF teachers per seed (--hf-teachers, at most --n)"


def _whole(value, name: str, low: int, high: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise InvalidParameterError(f"{name} must be a whole number, got {value!r}")
    if value < low or (high is not None and value > high):
        span = f">= {low}" if high is None else f"from {low} to {high}"
        raise InvalidParameterError(f"{name} must be {span}, got {value}")
    return int(value)


def _names(names, known: dict, what: str) -> tuple[str, ...]:
    if isinstance(names, str):
        names = (names,)
    chosen = tuple(names)
    unknown = [n for n in chosen if n not in known]
    if not chosen or unknown or len(set(chosen)) != len(chosen):
        raise InvalidParameterError(
            f"{what} must be distinct names from {', '.join(known)}; got {names!r}"
        )
    return chosen


def check_plan(plan: StudyPlan) -> StudyPlan:
    """Validate a plan; drop the arms this tutor cannot teach (HF before it lands).

    Raises
    ------
    InvalidParameterError
        A size out of range, an unknown arm or variant, or no BF arm.
    """
    if not isinstance(plan, StudyPlan):
        raise InvalidParameterError(f"plan must be a StudyPlan, got {plan!r}")
    low, high = (2, MAX_TEACHERS) if plan.quick else TEACHERS_RANGE
    n = _whole(plan.n, "the number of teachers (--n)", low, high)
    runs = _whole(plan.runs, "runs", 1, 10)
    seeds = _whole(plan.seeds, "the number of seeds (--seeds)", 2, MAX_SEEDS)
    policies = _names(plan.policies, POLICIES, "policies")
    variant_policies = _names(plan.variant_policies, POLICIES, "variant_policies")
    variants = _names(plan.variants, VARIANTS, "variants") if plan.variants else ()
    for what, arms in (("policies", policies), ("variant_policies", variant_policies)):
        if BASELINE not in arms:
            raise InvalidParameterError(
                f"{what} must include {BASELINE}: every delta is taken against it"
            )
    return dataclasses.replace(
        plan,
        n=n,
        runs=runs,
        seeds=seeds,
        policies=available_policies(policies),
        variants=variants,
        variant_seeds=_whole(plan.variant_seeds, "variant_seeds", 0, MAX_SEEDS),
        variant_policies=available_policies(variant_policies),
        n_boot=_whole(plan.n_boot, "n_boot", 100, 100_000),
        hf_teachers=None if plan.hf_teachers is None
        else _whole(plan.hf_teachers, HF_TEACHERS_NAME, 2, n),
        secondary_seeds=None if plan.secondary_seeds is None
        else _whole(plan.secondary_seeds, "secondary_seeds", 2, MAX_SEEDS),
    )
