r"""Feedback policies: which realisations :math:`r \subseteq \hat R` a teacher is shown,
and what may be said about the rest (Sena & Howard, "Experiment 1" and "Experiment 2").

After demo :math:`m` the robot has realised every test condition of :math:`\hat B`; a
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
replay     the realisation for the demo's own condition (RF)        no
batch      a fixed subset of :math:`\hat B` (BF: 4 corners, centre)  no
selected   the conditions the teacher asks for (SF)                 no
adaptive   k conditions a selector picks after each demo (AF)       no
========== ======================================================= ===========

The first five are the paper's. ``adaptive`` is beyond it (the paper's open question:
choosing r automatically): the selectors of :mod:`tutor.framework.selectors` pick k
conditions of :math:`\hat B` from the demos and the learner, e.g. where the frames'
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

__all__ = ["FeedbackPolicy", "FEEDBACK_POLICIES", "Visibility", "reveal", "check_indices"]


def check_indices(indices, n: int) -> np.ndarray:
    """Indices into B^ (of size ``n``) as a 1-D int array, sorted and unique."""
    idx = np.asarray(indices, dtype=int).ravel()
    return np.unique(idx[(idx >= 0) & (idx < n)])


@dataclass(frozen=True)
class FeedbackPolicy:
    """One way of choosing r (see the module's table).

    ``shown(n, own, batch, selected)`` gives r as indices into B^: ``n`` = |B^|, ``own``
    the index of the demo's own condition, ``batch`` the fixed subset, ``selected`` the
    conditions asked for (SF) or picked by the selector (adaptive).
    """

    name: str
    totals: bool
    description: str

    @property
    def silent(self) -> bool:
        """Nothing is shown while the teacher teaches (NF, HF)."""
        return self.name == "none"

    @property
    def adaptive(self) -> bool:
        """A selector picks r after each demo (AF, VA)."""
        return self.name == "adaptive"

    def shown(self, n: int, own: int, batch, selected) -> np.ndarray:
        if self.name == "all":
            return np.arange(n)
        pick = {"replay": [own], "batch": batch, "selected": selected, "adaptive": selected}
        pick = pick.get(self.name, [])
        return np.asarray(pick, dtype=int).ravel().copy()


#: the policies by name (the paper's five, then adaptive)
FEEDBACK_POLICIES = {
    p.name: p
    for p in (
        FeedbackPolicy("none", False, "no feedback until the run is over (NF)"),
        FeedbackPolicy("all", True, "every realisation after every demo (VF, VR)"),
        FeedbackPolicy("replay", False, "the demo's own condition replayed (RF)"),
        FeedbackPolicy("batch", False, "a fixed batch of conditions after every demo (BF)"),
        FeedbackPolicy("selected", False, "the conditions the teacher asks for (SF)"),
        FeedbackPolicy("adaptive", False, "k conditions a selector picks after every demo (AF)"),
    )
}


@dataclass(frozen=True)
class Visibility:
    """What the teacher may see now.

    Attributes
    ----------
    shown : ndarray of int
        The conditions of B^ whose realisation (and its pass/fail and reason) is shown.
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
    for); after the run, or in a practice run, every condition and every total."""
    if finished or practice:
        return Visibility(np.arange(n), True, True)
    chosen = FEEDBACK_POLICIES[policy]
    return Visibility(check_indices(shown, n), chosen.totals)
