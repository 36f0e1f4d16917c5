r"""Adaptive test sets: which k test points of :math:`\hat B` the robot shows after a demo.

Sena & Howard end on an open problem: choosing the set :math:`r` of shown realisations
automatically and economically for a general task (their BF fixed four corners and the
centre by hand). A *selector* answers it: after each demo it picks k test points (indices
into :math:`\hat B`, in the order picked) from what the framework knows then, passed in
as a :class:`SelectionContext`: the test points of :math:`\hat B`, the demos' test points,
the fitted learner and its frames, the realisations, and (for the oracle only) the
task's verdict. The framework knows no task: distances are taken in the *normalised
test-point space*, each column of the test point array scaled to [0, 1] over
:math:`\hat B` (a constant column is left as it is).

============== ===== ==================================================================
selector       short picks
============== ===== ==================================================================
farthest       KC    greedily the test point farthest from the demos' test points and the
                     test points already picked (k-centre)
disagreement   DIS   the highest score :math:`s` below (frame disagreement and distance),
                     each pick at least ``min_distance`` from the others
failures       ORC   k of the test points whose realisation fails the task's criteria,
                     nearest to the demos first (an oracle, for reference only: no real
                     robot knows where it fails without trying)
random         RAND  k test points uniformly at random (the run's generator; the control)
============== ===== ==================================================================

The disagreement score of a test point :math:`c` combines the frames' disagreement
:math:`D(c)` (:func:`tutor.tpgmm.frame_views.frame_disagreement`)

.. math::

    D(c) = \frac{1}{T} \sum_{t=1}^{T} \sum_{j=1}^{P}
        (\xi_j - \mu)^\top \Sigma_j^{-1} (\xi_j - \mu),

with :math:`(\xi_j, \Sigma_j)` frame :math:`j`'s regression mapped into the world for
:math:`c` and :math:`\mu` the product-of-frames mean, and the distance :math:`d(c)` from
:math:`c` to the nearest demo's test point, each scaled to [0, 1] over :math:`\hat B`:

.. math::

    s(c) = \frac{d(c)}{\max_{\hat B} d}
        \left(1 + \frac{D(c)}{\max_{\hat B} D}\right).

Why a product with the distance: :math:`D` alone misses the gaps *between* clusters of
demos and points at the demos themselves. In a gap the fixed frames (the start, the
bin) see the clusters averaged, a mean between them with a wide covariance, and the
frame of the test point agrees with that mean, so :math:`D` is near 0 where the robot
has never been shown anything; at a demonstrated test point the fixed frames still see
that average while the test point's frame is sure, so :math:`D` is large where the
robot has been shown exactly what to do (``tests/test_selectors.py`` measures both).
The distance finds the gaps and scores a demonstrated test point 0; :math:`D` at most
doubles the score where the frames disagree, so of two test points as far from the
demos the one the learner generalises to worse comes first (e.g. across, rather than
along, a line of demos). Where the frames agree everywhere (one frame, or frames that
coincide) :math:`D = 0` and the score is the distance alone.
When no test point is ``min_distance`` from every pick, the next pick is the best of the
rest, so a selector always shows :math:`\min(k, |\hat B|)` test points (the same cost
after every demo); only the oracle shows fewer, when fewer realisations fail.

Selectors are deterministic given their context (``random`` given its generator); a run
record stores the picks anyway (:class:`tutor.framework.record.Demo.shown`), so a replay
shows what the trainee was shown.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from ..tpgmm import check_count, check_number
from ..tpgmm.frame_views import frame_disagreement

__all__ = [
    "SelectionContext",
    "Selector",
    "FarthestPoint",
    "FrameDisagreement",
    "PredictedFailures",
    "RandomPick",
    "SELECTORS",
    "DEFAULT_SELECTOR",
    "DEFAULT_K",
    "check_k",
    "check_selector",
    "normalised_space",
    "select",
]

#: the selector AF uses unless told otherwise
DEFAULT_SELECTOR = "disagreement"
#: test points shown after each demo unless told otherwise (BF's five: the same cost)
DEFAULT_K = 5


@dataclass(frozen=True)
class SelectionContext:
    r"""What a selector may look at after a demo (see the module docstring).

    Attributes
    ----------
    test_points : ndarray (n, c)
        :math:`\hat B`, the task's test points.
    demo_points : ndarray (M, c)
        The test point each demo so far was given for.
    learner : TPGMM, optional
        The learner fitted on those demos (``disagreement``).
    frames : FrameBatch, optional
        The frames of every test point of :math:`\hat B` (``disagreement``).
    times : ndarray (T,), optional
        The times of the realisations (``disagreement``).
    realisations : ndarray (n, T, d), optional
        The product-of-frames means :math:`\\mu` for every test point (``disagreement``
        recomputes them when missing).
    passed : ndarray of bool (n,), optional
        The task's criteria applied to the realisations (``failures``, the oracle).
    rng : numpy.random.Generator, optional
        The run's generator (``random``, and the oracle's ``order="random"``).
    """

    test_points: np.ndarray
    demo_points: np.ndarray
    learner: object = None
    frames: object = None
    times: np.ndarray | None = None
    realisations: np.ndarray | None = None
    passed: np.ndarray | None = None
    rng: np.random.Generator | None = None

    @classmethod
    def of_task(cls, task, demo_points, learner, **known) -> SelectionContext:
        """The context after a demo of ``task`` (its B^, frames and times filled in);
        ``known`` gives the other fields the caller has (``realisations``, ``passed``,
        ``rng``)."""
        return cls(
            test_points=np.asarray(task.test_points),
            demo_points=np.array(demo_points),
            learner=learner,
            frames=task.frame_batch(task.test_points),
            times=task.times,
            **known,
        )

    @property
    def n(self) -> int:
        return len(self.test_points)

    def need(self, selector: str, *names: str) -> None:
        """Raise InvalidParameterError unless every field ``names`` is given."""
        missing = [name for name in names if getattr(self, name) is None]
        if missing:
            raise InvalidParameterError(
                f"the {selector!r} selector needs {', '.join(missing)} in its "
                "SelectionContext; pass them in (a TeachingSession does so itself)"
            )


def normalised_space(test_points, points=None):
    """Test points (and ``points``) in the normalised test-point space.

    Each column of ``test points`` (n, ...) is scaled to [0, 1] over its rows; a constant
    column is only shifted. Returns ``(X (n, c), Y (m, c))``, ``Y`` empty without points.
    """
    X = np.asarray(test_points, dtype=float).reshape(len(test_points), -1)
    lo, span = X.min(axis=0), np.ptp(X, axis=0)
    span = np.where(span > 0, span, 1.0)
    if points is None:
        Y = np.zeros((0, X.shape[1]))
    else:
        Y = np.asarray(points, dtype=float).reshape(-1, X.shape[1])
    return (X - lo) / span, (Y - lo) / span


def _distance_to(X, Y) -> np.ndarray:
    """Distance from each row of X to the nearest row of Y (inf when Y is empty)."""
    if len(Y) == 0:
        return np.full(len(X), np.inf)
    return np.sqrt(((X[:, None, :] - Y[None, :, :]) ** 2).sum(axis=-1)).min(axis=1)


class Selector:
    """A way of picking k test points of B^ after a demo (see the module docstring).

    Subclasses set ``name``, ``short`` (the study's label) and ``description`` and
    implement :meth:`pick`; call a selector as ``selector(k, context)``.
    """

    name = ""
    short = ""
    description = ""

    def __call__(self, k: int, context: SelectionContext) -> np.ndarray:
        k = min(check_k(k), context.n)
        picks = np.asarray(self.pick(k, context), dtype=int).ravel()
        return picks[:k]

    def pick(self, k: int, context: SelectionContext) -> np.ndarray:
        """The picks, indices into B^ in the order picked (``k`` <= |B^|)."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class FarthestPoint(Selector):
    """Greedy k-centre: the test point farthest from the demos and the picks so far."""

    name, short = "farthest", "KC"
    description = "the test points farthest from the demos (and from each other)"

    def pick(self, k, context):
        X, Y = normalised_space(context.test_points, context.demo_points)
        gap = _distance_to(X, Y)
        picks: list[int] = []
        for _ in range(k):
            i = int(np.argmax(gap))  # ties: the lowest index
            picks.append(i)
            gap = np.minimum(gap, np.sqrt(((X - X[i]) ** 2).sum(axis=1)))
            gap[picks] = -np.inf
        return np.array(picks, dtype=int)


class FrameDisagreement(Selector):
    """The highest frame-disagreement-and-distance score, picks ``min_distance`` apart.

    Parameters
    ----------
    min_distance : float
        The least distance between two picks in the normalised test-point space (0.3: on
        a 10 x 10 tray about three plants apart, so five picks fit with room to spare).
    """

    name, short = "disagreement", "DIS"
    description = "where the frames disagree most, or far from every demo"

    def __init__(self, min_distance: float = 0.3):
        self.min_distance = check_number(min_distance, "min_distance")

    def __repr__(self) -> str:
        return f"FrameDisagreement(min_distance={self.min_distance:g})"

    def scores(self, context: SelectionContext) -> np.ndarray:
        """:math:`s(c)` of every test point of B^ (the module docstring), shape (n,)."""
        context.need(self.name, "learner", "frames", "times")
        D = frame_disagreement(
            context.learner, context.frames, context.times, context.realisations
        )
        X, Y = normalised_space(context.test_points, context.demo_points)
        gap = _distance_to(X, Y)
        gap = np.where(np.isfinite(gap), gap, 0.0)
        return _unit(gap) * (1.0 + _unit(D))

    def pick(self, k, context):
        score = self.scores(context)
        X, _ = normalised_space(context.test_points)
        order = np.argsort(-score, kind="stable")
        apart = np.full(len(X), np.inf)  # distance to the nearest pick
        picks: list[int] = []
        for _ in range(k):
            free = [i for i in order if i not in picks]
            spaced = [i for i in free if apart[i] >= self.min_distance]
            i = int((spaced or free)[0])
            picks.append(i)
            apart = np.minimum(apart, np.sqrt(((X - X[i]) ** 2).sum(axis=1)))
        return np.array(picks, dtype=int)


def _unit(values) -> np.ndarray:
    """``values`` divided by their largest (all zeros stay zeros; non-finite count 0)."""
    v = np.where(np.isfinite(values), np.asarray(values, dtype=float), 0.0)
    top = v.max() if v.size else 0.0
    return v / top if top > 0 else np.zeros_like(v)


class PredictedFailures(Selector):
    """The oracle: k test points whose realisation fails (the task's criteria).

    Parameters
    ----------
    order : {"nearest", "random"}
        Which failures first: nearest to the demos' test points, or at random with the
        run's generator.
    """

    name, short = "failures", "ORC"
    description = "test points the robot fails at (an oracle, for reference only)"

    def __init__(self, order: str = "nearest"):
        if order not in ("nearest", "random"):
            raise InvalidParameterError(f"order must be 'nearest' or 'random', got {order!r}")
        self.order = order

    def __repr__(self) -> str:
        return f"PredictedFailures(order={self.order!r})"

    def pick(self, k, context):
        context.need(self.name, "passed")
        passed = np.asarray(context.passed, dtype=bool).ravel()
        if passed.shape != (context.n,):
            raise InvalidParameterError(
                f"passed must hold one verdict per test point of B^ ({context.n}), "
                f"got {passed.size}"
            )
        failing = np.flatnonzero(~passed)
        if self.order == "random":
            context.need(self.name, "rng")
            return context.rng.permutation(failing)[:k]
        X, Y = normalised_space(context.test_points, context.demo_points)
        gap = _distance_to(X[failing], Y)
        return failing[np.argsort(gap, kind="stable")][:k]


class RandomPick(Selector):
    """k test points uniformly at random, without repeats (the study's control)."""

    name, short = "random", "RAND"
    description = "test points chosen at random (the control)"

    def pick(self, k, context):
        context.need(self.name, "rng")
        return context.rng.choice(context.n, size=k, replace=False)


#: the selectors by name (see the module's table)
SELECTORS: dict[str, Selector] = {
    s.name: s for s in (FarthestPoint(), FrameDisagreement(), PredictedFailures(), RandomPick())
}


def check_k(k) -> int:
    """``k`` as an int >= 1 (how many test points are shown after each demo)."""
    try:
        return check_count(k, "k")
    except InvalidParameterError as exc:
        raise InvalidParameterError(
            f"{exc}: k is how many test points the robot shows after each demo "
            f"(AF shows {DEFAULT_K}, BF's cost); a k above |B^| shows every test point"
        ) from None


def check_selector(selector) -> Selector:
    """A selector by name (a key of :data:`SELECTORS`) or a :class:`Selector` itself."""
    if isinstance(selector, Selector):
        return selector
    if isinstance(selector, str) and selector in SELECTORS:
        return SELECTORS[selector]
    raise InvalidParameterError(
        f"selector must be one of {', '.join(SELECTORS)} (or a Selector), got {selector!r}"
    )


def select(selector, k, context: SelectionContext) -> np.ndarray:
    """The picks of ``selector`` (a name or a :class:`Selector`): at most k indices into B^."""
    return check_selector(selector)(k, context)
