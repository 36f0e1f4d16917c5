r"""Feedback policies: which realisations :math:`r \subseteq \hat R` a teacher is shown,
and what may be said about the rest (Sena & Howard, "Experiment 1" and "Experiment 2").

After demo :math:`m` the robot has realised every test point of :math:`\hat B`; a
*policy* decides the set :math:`r` the teacher sees, and whether the totals over all of
:math:`\hat B` (the efficacy :math:`\varepsilon`, its change :math:`\delta`, the
efficiency :math:`\eta = \varepsilon / |b|` and the count of undemonstrated states) may
be shown. The totals are what the conditions without full feedback withhold: a
trainee who can read :math:`\varepsilon` knows when to stop.

========== ======================================================= ===========
policy     r after each demo                                        totals
========== ======================================================= ===========
none       nothing (NF)                                             no
all        every realisation, :math:`r = \hat R` (VF, VR)            yes
replay     the realisation for the demo's own test point (RF)       no
batch      a fixed subset of :math:`\hat B` (BF: 4 corners, centre)  no
selected   the test points the teacher asks for (SF)                no
adaptive   k test points a selector picks after each demo (AF)      no
========== ======================================================= ===========

The first five are the paper's. ``adaptive`` is beyond it (the paper's open question:
choosing r automatically): the selectors of :mod:`tutor.framework.selectors` pick k
test points of :math:`\hat B` from the demos and the learner, e.g. where the frames'
regressions disagree most,

.. math::

    D(c) = \frac{1}{T} \sum_{t} \sum_{j} (\xi_j - \mu)^\top \Sigma_j^{-1} (\xi_j - \mu),

combined with the distance to the demos. Like BF it withholds the totals.

After the run (and in a practice run) everything is revealed: :func:`reveal`.
Warnings about the demo itself (incorrect, ambiguous) need only the demo and stay in
every policy; their wording drops the numbers a policy withholds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError

__all__ = [
    "FeedbackPolicy",
    "FEEDBACK_POLICIES",
    "Visibility",
    "check_indices",
    "register_policy",
    "reveal",
]


def check_indices(indices, n: int) -> np.ndarray:
    """Indices into B^ (of size ``n``) as a 1-D int array, sorted and unique."""
    idx = np.asarray(indices, dtype=int).ravel()
    return np.unique(idx[(idx >= 0) & (idx < n)])


class FeedbackPolicy:
    """One way of choosing r (see the module's table); a subclass per policy.

    ``shown(n, own, batch, selected)`` gives r as indices into B^: ``n`` = |B^|, ``own``
    the index of the demo's own test point (-1 when the policy does not use it, see
    :attr:`uses_own`), ``batch`` the fixed subset, ``selected`` the test points asked for
    (SF) or picked by the selector (adaptive).

    Class attributes say what else the policy decides: whether the totals may be shown,
    whether a selector picks r (and takes ``selector=``, ``k=``), whether it needs a batch,
    whether each demo's r is kept as shown (a replay of the run shows the same r).
    """

    #: the policy's name, as run records store it
    name: str = ""
    #: efficacy, its change, efficiency and the undemonstrated count may be shown
    totals: bool = False
    description: str = ""
    #: r is the demo's own test point (the session finds its index)
    uses_own: bool = False
    #: r is the fixed batch, which the run must give
    needs_batch: bool = False
    #: a selector picks r after each demo
    adaptive: bool = False
    #: r was chosen when the demo was given (by the teacher or a selector): kept as shown
    keeps_picks: bool = False
    #: nothing is shown while the teacher teaches (NF, HF)
    silent: bool = False
    #: the teacher chooses which test points the robot tries (SF)
    teacher_picks: bool = False

    def shown(self, n: int, own: int, batch, selected) -> np.ndarray:
        return np.zeros(0, dtype=int)

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class NoFeedback(FeedbackPolicy):
    name, silent = "none", True
    description = "no feedback until the run is over (NF)"


class AllFeedback(FeedbackPolicy):
    name, totals = "all", True
    description = "every realisation after every demo (VF, VR)"

    def shown(self, n, own, batch, selected):
        return np.arange(n)


class ReplayFeedback(FeedbackPolicy):
    name, uses_own = "replay", True
    description = "the demo's own test point replayed (RF)"

    def shown(self, n, own, batch, selected):
        return np.asarray([own], dtype=int)


class BatchFeedback(FeedbackPolicy):
    name, needs_batch = "batch", True
    description = "a fixed batch of test points after every demo (BF)"

    def shown(self, n, own, batch, selected):
        return np.asarray(batch, dtype=int).ravel().copy()


class SelectedFeedback(FeedbackPolicy):
    name, keeps_picks, teacher_picks = "selected", True, True
    description = "the test points the teacher asks for (SF)"

    def shown(self, n, own, batch, selected):
        return np.asarray(selected, dtype=int).ravel().copy()


class AdaptiveFeedback(SelectedFeedback):
    name, adaptive, teacher_picks = "adaptive", True, False
    description = "k test points a selector picks after every demo (AF)"


#: the policies by name (the paper's five, then adaptive)
FEEDBACK_POLICIES: dict[str, FeedbackPolicy] = {
    p.name: p
    for p in (
        NoFeedback(),
        AllFeedback(),
        ReplayFeedback(),
        BatchFeedback(),
        SelectedFeedback(),
        AdaptiveFeedback(),
    )
}


def register_policy(policy: FeedbackPolicy) -> FeedbackPolicy:
    """Add a policy (an instance of a :class:`FeedbackPolicy` subclass) by its name."""
    if not isinstance(policy, FeedbackPolicy) or not policy.name:
        raise InvalidParameterError(
            f"register_policy takes a named FeedbackPolicy, got {policy!r}"
        )
    FEEDBACK_POLICIES[policy.name] = policy
    return policy


@dataclass(frozen=True)
class Visibility:
    """What the teacher may see now.

    Attributes
    ----------
    shown : ndarray of int
        The test points of B^ whose realisation (and its pass/fail and reason) is shown.
    totals : bool
        Whether efficacy, its change, efficiency and the undemonstrated count over all
        of B^ may be shown.
    everything : bool
        The run is over (or a practice run): nothing is withheld.
    """

    shown: np.ndarray
    totals: bool
    everything: bool = False

    def sees(self, index: int) -> bool:
        return bool(np.isin(index, self.shown))


def reveal(policy: str, n: int, shown, finished: bool = False, practice: bool = False):
    """The :class:`Visibility` of a step: ``shown`` is r for ``policy`` (plus tests asked
    for); after the run, or in a practice run, every test point and every total."""
    if finished or practice:
        return Visibility(np.arange(n), True, True)
    chosen = FEEDBACK_POLICIES[policy]
    return Visibility(check_indices(shown, n), chosen.totals)
