r"""Teaching failures of Sena & Howard (section "Teaching Failures").

After demo m (eps_m the efficacy after it, :math:`\Delta = \varepsilon_m - \varepsilon_{m-1}`):

incorrect
    The demo is not an example of the task (:math:`b \setminus B \neq \emptyset`: it
    fails the task criteria itself), or its effect marks it as wrong:
    :math:`\Delta \le 0` although it is *not* similar to the earlier demos (a
    similar demo that changes little is ambiguous instead, see below). When eps
    was already 1 nothing can improve, so there only a drop counts.
ambiguous
    The demo is similar to the earlier ones, :math:`s(b, \mathbf b) \le \delta_a`,
    and changes efficacy only a little, :math:`\delta_l \le \Delta \le \delta_u`.
    By default s is the mean distance, sample by sample after aligning in time,
    to the nearest earlier demo.
undemonstrated
    Test points the learner fails and no demo covers:
    :math:`B^ \setminus (R^ \cup b)`, counted and located.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import InvalidParameterError
from .wording import efficacy_change

__all__ = [
    "Thresholds",
    "TeachingWarning",
    "similarity",
    "INCORRECT",
    "AMBIGUOUS",
    "UNDEMONSTRATED",
]

INCORRECT = "incorrect"
AMBIGUOUS = "ambiguous"
UNDEMONSTRATED = "undemonstrated"


@dataclass(frozen=True)
class Thresholds:
    """Thresholds of the failure definitions.

    Attributes
    ----------
    ambiguity_distance : float or None
        delta_a, in the task's units; None takes the task's default.
    delta_lower, delta_upper : float
        delta_l and delta_u: the range of efficacy change that counts as
        "little or no change" for a similar demo (default -0.05 to +0.02, i.e.
        losing at most 5 % or gaining at most 2 % of the test points).
    """

    ambiguity_distance: float | None = None
    delta_lower: float = -0.05
    delta_upper: float = 0.02

    def __post_init__(self):
        if self.ambiguity_distance is not None and not self.ambiguity_distance >= 0:
            raise InvalidParameterError(
                f"ambiguity_distance must be >= 0, got {self.ambiguity_distance}"
            )
        if not self.delta_lower <= self.delta_upper:
            raise InvalidParameterError(
                f"delta_lower ({self.delta_lower}) must not exceed delta_upper ({self.delta_upper})"
            )

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class TeachingWarning:
    """One failure found after a demo.

    Attributes
    ----------
    kind : {"incorrect", "ambiguous", "undemonstrated"}
    message : str
        Plain words for the trainee, saying what to do next.
    demo : int or None
        1-based number of the demo concerned (None for undemonstrated states).
    count : int
        How many test points (undemonstrated) or demos (otherwise) it concerns.
    take_back : tuple of int
        The demos (1-based) the message asks the trainee to take back, so that each view
        can say how it does that (the tutors' Undo button, a list in a notebook cell).
    """

    kind: str
    message: str
    demo: int | None = None
    count: int = 1
    take_back: tuple[int, ...] = ()

    def to_dict(self) -> dict:
        return asdict(self)


def similarity(demo: np.ndarray, others) -> tuple[float, int]:
    """s(b, b_set): mean distance to the nearest earlier demo, aligned sample by sample.

    Parameters
    ----------
    demo : ndarray (T, 1 + d)
    others : sequence of ndarray (T, 1 + d)
        Earlier demos, resampled to the same length as ``demo``.

    Returns
    -------
    distance : float
        inf when there is no earlier demo.
    nearest : int
        Index of the nearest earlier demo (-1 when none).
    """
    if len(others) == 0:
        return float("inf"), -1
    stack = np.asarray(others)[:, :, 1:]
    dist = np.linalg.norm(stack - demo[None, :, 1:], axis=2).mean(axis=1)
    nearest = int(np.argmin(dist))
    return float(dist[nearest]), nearest


def is_ambiguous(similarity: float, delta: float, ambiguity_distance: float, thresholds) -> bool:
    """s(b, b_set) <= delta_a and delta_l <= eps_m - eps_{m-1} <= delta_u; a first demo
    (no earlier one: ``similarity`` inf) repeats nothing, whatever delta_a (even inf, no
    similarity test)."""
    return (
        math.isfinite(similarity)
        and similarity <= ambiguity_distance
        and thresholds.delta_lower <= delta <= thresholds.delta_upper
    )


def demo_warnings(
    m: int,
    *,
    demo_passed: bool,
    demo_reason: str,
    delta: float,
    previous: float,
    similarity: float,
    nearest: int | None,
    ambiguity_distance: float,
    thresholds: Thresholds,
    wrong_earlier=(),
    format_distance: Callable[[float], str] = lambda d: f"{d:.3g}",
) -> list[TeachingWarning]:
    """The incorrect or ambiguous warning for demo ``m``, if any (at most one).

    Parameters
    ----------
    m : int
        1-based number of the demo.
    demo_passed, demo_reason
        The task criteria applied to the demo itself.
    delta, previous : float
        eps_m - eps_{m-1} and eps_{m-1}.
    similarity, nearest
        s(b, b_set) and the 1-based number of the nearest earlier demo.
    ambiguity_distance : float
        delta_a.
    wrong_earlier : sequence of int
        Earlier demos (1-based) that failed the criteria and are still in the set.
    """
    if not demo_passed:
        return [
            TeachingWarning(
                INCORRECT,
                f"Demo {m} is not a correct example: it {demo_reason}. "
                "Take it back and demonstrate that again.",
                demo=m,
                take_back=(m,),
            )
        ]
    if is_ambiguous(similarity, delta, ambiguity_distance, thresholds):
        return [
            TeachingWarning(
                AMBIGUOUS,
                f"Demo {m} is almost the same as demo {nearest} (on average "
                f"{format_distance(similarity)} apart) and {efficacy_change(delta)}: start "
                "further from your other demos.",
                demo=m,
            )
        ]
    if delta < 0 or (delta == 0 and previous < 1.0):
        eps = previous + delta
        change = (
            f"efficacy fell from {previous:.0%} to {eps:.0%}"
            if delta < 0
            else f"efficacy stayed at {eps:.0%}"
        )
        wrong = [int(i) for i in wrong_earlier]
        take_back = tuple(wrong) or (m,)
        if wrong:
            many = len(wrong) > 1
            advice = (
                f"demo{'s' if many else ''} {', '.join(map(str, wrong))} "
                f"{'are' if many else 'is'} not a correct example and still teach"
                f"{'' if many else 'es'} the robot the wrong thing: take "
                f"{'them' if many else 'it'} back first."
            )
        else:
            advice = "check that it shows the task the way you meant; take it back if not."
        if m == 1:
            take_back = ()
            text = (
                f"Demo 1 made things no better ({change}): the robot fails even where you "
                "showed it. Check that the demo shows the task the way you meant; if it does, "
                "one example is not enough here: give another from a different place."
            )
        else:
            text = (
                f"Demo {m} made things no better ({change}) although it differs from your "
                f"other demos: {advice}"
            )
        return [TeachingWarning(INCORRECT, text, demo=m, take_back=take_back)]
    return []


def undemonstrated_warning(
    mask, noun: str, noun_plural: str, describe_where
) -> TeachingWarning | None:
    """The warning for B^ \\ (R^ or b) given its mask over the test points, or None."""
    k = int(np.count_nonzero(mask))
    if k == 0:
        return None
    return TeachingWarning(
        UNDEMONSTRATED,
        f"{k} {noun if k == 1 else noun_plural} still fail{'s' if k == 1 else ''} and no demo "
        f"covers {'it' if k == 1 else 'them'}, {describe_where(mask)}: demonstrate there next.",
        count=k,
    )
