r"""Teaching metrics of Sena & Howard (section "Evaluating Teaching").

Notation: B^ the test points, R^ the realisations from every test point,
b the demonstration set with M = |b| demos.

- Teaching efficacy :math:`\varepsilon = |R^ \cap B^| / |B^|` in [0, 1]: the share of
  test points whose realisation meets the task criteria.
- Teaching efficiency :math:`\eta = \varepsilon / |b|`.
- The paper's session scores, one rule per experiment (:data:`SCORING_RULES`):

  ``"target"`` (Experiment 1): M is the number of demos needed to first reach 90 %
  coverage, or all demos if 90 % is never reached; eta is taken there.

  ``"final"`` (Experiment 2): the paper states no 90 % rule; eta = eps / |b| of the
  whole session, eps judged after the last demo and |b| every demo given.

Every score of a run (the after-Finish summary, the results cell, the simulated
cohorts', a class's) is :meth:`tutor.framework.run.TeachingRun.score`, which calls
:func:`run_score` with the rule of the run's own experiment (:func:`rule_of`), so they
agree; no caller picks a rule by default.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError

__all__ = [
    "efficacy",
    "efficiency",
    "SessionScore",
    "session_score",
    "final_score",
    "run_score",
    "SCORING_RULES",
    "rule_of",
]


def efficacy(passed) -> float:
    """Share of test points passed: eps = |R^ and B^| / |B^|.

    Parameters
    ----------
    passed : array-like of bool, shape (n_conditions,)
    """
    passed = np.asarray(passed, dtype=bool)
    if passed.ndim != 1 or passed.size == 0:
        raise InvalidParameterError(
            f"passed must be a non-empty 1-D array of booleans, got shape {passed.shape}"
        )
    return float(passed.mean())


def efficiency(eps: float, n_demos: int) -> float:
    """eta = eps / |b|; 0 when no demo was given."""
    if n_demos < 0:
        raise InvalidParameterError(f"n_demos must be >= 0, got {n_demos}")
    return 0.0 if n_demos == 0 else float(eps) / n_demos


@dataclass(frozen=True)
class SessionScore:
    """The paper's score of one teaching run."""

    n_demos: int  #: M: demos to first reach the target coverage, or all demos
    efficacy: float  #: eps after those M demos
    efficiency: float  #: eta = eps / M
    reached: bool  #: whether the target coverage was reached


def session_score(efficacies, target: float = 0.9) -> SessionScore:
    """Score a run from the efficacy after each demo (eps_1, ..., eps_M).

    Parameters
    ----------
    efficacies : array-like, shape (M,)
        eps after demo 1, 2, ..., M.
    target : float
        Coverage to reach (the paper uses 0.9).
    """
    eps = np.asarray(efficacies, dtype=float)
    if eps.ndim != 1 or eps.size == 0:
        raise InvalidParameterError(
            "a run needs at least one demo to be scored; efficacies must be a non-empty 1-D array"
        )
    if not 0.0 < target <= 1.0:
        raise InvalidParameterError(f"target coverage must be in (0, 1], got {target}")
    hits = np.flatnonzero(eps >= target - 1e-12)
    m = int(hits[0]) + 1 if hits.size else eps.size
    return SessionScore(m, float(eps[m - 1]), float(eps[m - 1]) / m, bool(hits.size))


def final_score(efficacies, target: float = 0.9) -> SessionScore:
    """Experiment 2's score: eta = eps after the last demo / every demo given.

    ``reached`` still says whether ``target`` coverage was reached at some demo.
    """
    eps = np.asarray(efficacies, dtype=float)
    first = session_score(eps, target)  # the same checks, and whether it was reached
    m = int(eps.size)
    return SessionScore(m, float(eps[-1]), float(eps[-1]) / m, first.reached)


#: the paper's scoring rule of each experiment, by name
SCORING_RULES = {"target": session_score, "final": final_score}


#: the scoring rule of each of the paper's experiments (a run's rule comes from here)
def rule_of(experiment) -> str:
    """The scoring rule of the paper's ``experiment`` (1: ``"target"``, 2: ``"final"``),
    as the registry (:mod:`tutor.framework.protocol`) holds it.

    Raises
    ------
    InvalidParameterError
        ``experiment`` is not 1 or 2.
    """
    from .protocol import EXPERIMENTS  # the registry reads the policies, not the metrics

    if isinstance(experiment, bool) or experiment not in EXPERIMENTS:
        raise InvalidParameterError(
            f"experiment must be 1 (maze) or 2 (pick-and-place) to have a scoring rule, "
            f"got {experiment!r}"
        )
    return EXPERIMENTS[experiment].score_rule


def run_score(efficacies, rule: str, target: float = 0.9) -> SessionScore:
    """Score a run with the named rule (``"target"``: Experiment 1, ``"final"``: 2)."""
    if rule not in SCORING_RULES:
        raise InvalidParameterError(
            f"scoring rule must be one of {', '.join(SCORING_RULES)}, got {rule!r}"
        )
    return SCORING_RULES[rule](efficacies, target)
