r"""The next-demo hint (condition HF, beyond the paper): where the robot would learn most.

A hint is one step of the optimal teacher's greedy lookahead
(:func:`tutor.tasks.lookahead.best_next`): of a few candidate plants, the one whose
careful demonstration raises efficacy :math:`\varepsilon` the most once added, computed
exactly as the session would. To stay well within a second in a notebook kernel,
on one core and without forking worker processes, the lookahead is pruned:

- **the bank** is one careful scripted demo per test point (``make_bank(task, draws=1)``,
  about 0.2 s), made once per task object and kept (:func:`hint_bank`);
- **with no demo yet** the hint is the optimal teacher's first greedy pick, read from
  its bundled reference (:mod:`tutor.tasks.optimal_reference`): nothing is computed;
- **after a demo** the candidates are the :data:`HINT_CANDIDATES` test points with the
  highest frame-disagreement score (:class:`tutor.framework.selectors.FrameDisagreement`,
  where the frames disagree or far from every demo; a demonstrated test point scores 0,
  so it comes last), and the hint is the best of them by lookahead (ties: the higher
  score first).

Why 12 candidates: measured on 16 random demo sets of the tray (M = 1, 2, 3, 6 demos,
4 sets each), against the lookahead over all 100 plants, the best eps among the top k
fell short of the best overall by on average 0.018, 0.010, 0.068, 0.023 (k = 6), 0.005,
0.010, 0.000, 0.008 (k = 12) and 0 at every M (k = 24); each candidate costs one refit
(15-35 ms on the shared machine), so 12 keep the hint near a third of a second while
missing the best plant's eps by under 0.01 on average (``benchmarks/bench_hint.py``
measures the time).

A hint costs the trainee no time on the clock: the robot is not moved.
"""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from ..framework.selectors import FarthestPoint, FrameDisagreement, SelectionContext
from .lookahead import Bank, State, best_next, make_bank
from .optimal_reference import optimal_reference

__all__ = ["Hint", "HINT_CANDIDATES", "hint_bank", "hint_candidates", "next_demo_hint"]

#: how many test points the hint's lookahead scores (see the module docstring)
HINT_CANDIDATES = 12

#: the hint's bank of each task object (made on first use, dropped with the task)
_BANKS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass(frozen=True)
class Hint:
    """Where the robot would learn most from next.

    Attributes
    ----------
    plant : int
        The test point to demonstrate next (an index into B^: a plant on the tray).
    efficacy : float
        eps the robot would reach with a careful demo there (the lookahead's; with no
        demo yet, the optimal teacher's eps after its first demo).
    seconds : float
        How long the hint took to compute (wall clock; it costs no time on the
        teaching clock).
    """

    plant: int
    efficacy: float
    seconds: float


def hint_bank(task) -> Bank:
    """One careful scripted demo per test point of ``task`` (made once per task, kept)."""
    try:
        bank = _BANKS.get(task)
    except TypeError:  # a task that cannot be weakly referenced: made each time
        return make_bank(task, draws=1)
    if bank is None:
        bank = make_bank(task, draws=1)
        _BANKS[task] = bank
    return bank


def _session_of(state):
    return getattr(state, "session", state)


def hint_candidates(task, session, n: int = HINT_CANDIDATES) -> np.ndarray:
    """The ``n`` test points the hint's lookahead scores after at least one demo.

    The highest frame-disagreement scores
    (:meth:`~tutor.framework.selectors.FrameDisagreement.scores`), highest first (ties:
    the lower index first). ``session`` is a TeachingSession or a run.

    Raises
    ------
    InvalidParameterError
        ``n`` is not a whole number >= 1, or the session has no demo yet.
    """
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise InvalidParameterError(f"n must be a whole number >= 1, got {n!r}")
    session = _session_of(session)
    if session.n_demos == 0:
        raise InvalidParameterError(
            "the hint's candidates come from what the robot learnt: give a demonstration "
            "first (with none, the hint is the optimal teacher's first pick)"
        )
    context = SelectionContext.of_task(
        task, session.demo_points, session.learner, realisations=session.realisations
    )
    score = FrameDisagreement().scores(context)
    return np.argsort(-score, kind="stable")[: int(n)]


def _first_pick(task) -> tuple[int, float] | None:
    """The optimal teacher's first pick and its eps, when its reference fits ``task``."""
    reference = optimal_reference(task.name)
    if reference is None or not reference.picks or not reference.greedy:
        return None
    if reference.n_conditions != len(task.test_points):
        return None
    return int(reference.picks[0]), float(reference.greedy[0])


def next_demo_hint(task, session, n: int = HINT_CANDIDATES) -> Hint:
    """The hint for the next demo of ``session`` (a TeachingSession or a run).

    No demo yet: the optimal teacher's first pick (from its bundled reference; for a
    task it does not fit, the lookahead over the ``n`` farthest-point test points).
    Otherwise: :func:`~tutor.tasks.lookahead.best_next` over :func:`hint_candidates`
    with the :func:`hint_bank`, on this process alone (``workers=1``).
    """
    started = time.perf_counter()
    session = _session_of(session)
    if session.n_demos == 0:
        first = _first_pick(task)
        if first is not None:
            return Hint(first[0], first[1], time.perf_counter() - started)
        context = SelectionContext(np.asarray(task.test_points), np.zeros((0, 1)))
        candidates = FarthestPoint()(n, context)
    else:
        candidates = hint_candidates(task, session, n)
    bank = hint_bank(task)
    # the bank holds one demo per test point in B^'s order: position = test point index
    positions = np.searchsorted(bank.index, candidates)
    best = best_next(task, State.from_session(session), bank, positions, workers=1)
    return Hint(best.index, best.efficacy, time.perf_counter() - started)
