r"""One step of greedy lookahead: which demo would raise efficacy the most?

Given the current demonstrations and learner (a :class:`State`, e.g. of a trainee's
session) and a **bank** of candidate demos, :func:`best_next` returns the candidate that
maximises efficacy eps once added, computed exactly as
:meth:`tutor.framework.TeachingSession.add_demo` would (the same learner refitted on a
copy, warm-started when the task's learner warm-starts, the same criteria). Ties go to
the first candidate, so the answer is deterministic. It is the step of the optimal
teacher (:mod:`tutor.study.optimal`) and of a next-demo hint.

A candidate costs one refit (about 10-20 ms) and little else: R^ is the robot's
attempts (:meth:`tutor.framework.Task.realise`: the batch reproduction, with
axis-aligned frames an affine map of the frames' origins, tracked from each start), and
:func:`judged` follows the pick-and-place arm (criterion (i)) only for realisations that
meet criteria (ii) and (iii): a realisation is in B iff it meets them all.

:class:`Scorer` spreads the candidates over worker processes (both cores by default)
and stops at the first candidate reaching eps = 1.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidParameterError
from ..workers import can_fork, one_blas_thread, process_pool

__all__ = [
    "Bank",
    "State",
    "NextDemo",
    "Scorer",
    "make_bank",
    "scripted_recording",
    "judged",
    "efficacy_after",
    "best_next",
    "shared",
    "EPS_TOL",
]

#: how many tries a careful hand gets to make a correct bank demo for one test point
MAX_TRIES = 5
#: exact efficacies compare equal within this (eps is a share of at most a few hundred)
EPS_TOL = 1e-12


# ---------------------------------------------------------------- the bank


@dataclass(frozen=True)
class Bank:
    """Candidate demonstrations: several careful draws for each test point of B^.

    Attributes
    ----------
    demos : ndarray (n, T, 1 + d)
        Preprocessed demos (``task.preprocess``), in bank order.
    demo_points : ndarray (n, c)
        The test point each demo was given for (a row of ``task.test_points``).
    index : ndarray of int (n,)
        Its index in B^.
    draw : ndarray of int (n,)
        Which draw of the hand it is (0, 1, ...).
    """

    demos: np.ndarray
    demo_points: np.ndarray
    index: np.ndarray
    draw: np.ndarray

    def __len__(self) -> int:
        return len(self.index)

    def subset(self, keep) -> Bank:
        """The bank demos at positions ``keep`` (in that order)."""
        keep = np.asarray(keep, dtype=int)
        return Bank(self.demos[keep], self.demo_points[keep], self.index[keep], self.draw[keep])

    def first_draws(self, n_draws: int = 1) -> Bank:
        """The demos of the first ``n_draws`` draws only (the pair bound's bank)."""
        return self.subset(np.flatnonzero(self.draw < n_draws))


def scripted_recording(task, index: int, rng) -> np.ndarray:
    """A careful scripted recording for test point ``index``, made by the task itself
    (:meth:`~tutor.framework.task.Task.scripted_demo`): the maze's reference path with
    2 mm of hand jitter, pick-and-place's kinesthetic hand with no mistake."""
    return task.scripted_demo(index, rng)


def make_bank(task, draws: int = 3, seed: int = 0, indices=None, recording=None) -> Bank:
    """The bank: ``draws`` careful demos for each test point (all of B^ by default).

    Each demo is drawn with its own generator, seeded by (seed, index, draw, try), so a
    bank of fewer test points or draws holds the same demos as the full one. A draw that
    is not a correct demo (``task.judge_demo``) is drawn again (at most ``MAX_TRIES``).
    ``recording(task, index, rng)`` makes one raw recording (default
    :func:`scripted_recording`).

    Raises
    ------
    InvalidParameterError
        ``draws`` or ``seed`` is not a whole number (>= 1, >= 0), an index is outside
        B^, or a careful teacher could not make a correct demo for a test point.
    """
    draws, seed = _whole(draws, "draws", 1), _whole(seed, "seed", 0)
    recording = scripted_recording if recording is None else recording
    n = len(task.test_points)
    idx = np.arange(n) if indices is None else np.asarray(indices, dtype=int).ravel()
    if idx.size == 0 or np.any((idx < 0) | (idx >= n)):
        raise InvalidParameterError(f"bank indices must be in 0..{n - 1}, got {idx.tolist()}")
    demos, points, index, draw = [], [], [], []
    for k in range(draws):
        for i in idx:
            demo = _correct_demo(task, recording, int(i), seed, k)
            demos.append(demo)
            points.append(task.test_points[i])
            index.append(int(i))
            draw.append(k)
    return Bank(np.array(demos), np.array(points, dtype=float), np.array(index), np.array(draw))


def _correct_demo(task, recording, i: int, seed: int, k: int) -> np.ndarray:
    for attempt in range(MAX_TRIES):
        rng = np.random.default_rng(np.random.SeedSequence([seed, i, k, attempt]))
        demo = task.preprocess(recording(task, i, rng))
        if task.judge_demo(demo, task.test_points[i]).passed[0]:
            return demo
    raise InvalidParameterError(
        f"a careful teacher made no correct demo for {task.point_noun} {i} in "
        f"{MAX_TRIES} tries: check the task's geometry and criteria"
    )


def _whole(value, name: str, lowest: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < lowest:
        raise InvalidParameterError(f"{name} must be a whole number >= {lowest}, got {value!r}")
    return int(value)


# ---------------------------------------------------------------- efficacy, fast


@dataclass
class State:
    """What the session knows before the next demo: its demos, test points and learner.

    ``learner`` is the one fitted on ``demos`` (a fresh one before any demo); adding a
    demo fits a copy of it, as :meth:`TeachingSession.add_demo` does.
    """

    demos: list
    demo_points: list
    learner: object
    #: the frames of each demo's test point (made on first use, see :meth:`frames`)
    demo_frames: list | None = field(default=None, repr=False, compare=False)

    def frames(self, task) -> list:
        """``task.frames`` of each demo's test point, made once per state."""
        if self.demo_frames is None or len(self.demo_frames) != len(self.demo_points):
            self.demo_frames = [task.frames(c) for c in self.demo_points]
        return self.demo_frames

    @classmethod
    def empty(cls, task) -> State:
        return cls([], [], task.make_learner())

    @classmethod
    def from_session(cls, session) -> State:
        """The state of a :class:`~tutor.framework.TeachingSession` (or a run's session)."""
        session = getattr(session, "session", session)
        return cls(session.demos, session.demo_points, session.learner)

    def added(self, task, demo, point) -> tuple[State, float, np.ndarray]:
        """The state after ``demo``, its eps and the passed mask (n,)."""
        eps, passed, learner = efficacy_after(task, self, demo, point)
        frames = [*self.frames(task), task.frames(point)]
        state = State([*self.demos, demo], [*self.demo_points, point], learner, frames)
        return state, eps, passed


def efficacy_after(task, state: State, demo, point):
    """eps after adding ``demo`` (preprocessed) under ``test point`` to ``state``.

    Exactly the session's eps (:meth:`TeachingSession.add_demo`): a copy of the learner
    refitted on every demo, R^ judged by the task's criteria with the demos' context.

    Returns
    -------
    eps : float
    passed : ndarray of bool (n,)
    learner : the fitted copy
    """
    demos = [*state.demos, demo]
    points = np.array([*state.demo_points, point], dtype=float)
    learner = copy.deepcopy(state.learner)
    learner.fit(demos, [*state.frames(task), task.frames(point)])
    context = task.criteria_context(demos, points)
    passed = judged(task, task.realise(learner), context)
    return float(passed.mean()), passed, learner


def judged(task, trajectories, context) -> np.ndarray:
    """``task.judge(trajectories, task.test_points, context).passed``, sooner.

    A task whose criterion (i) follows the arm (``task.feasibility``, pick-and-place) is
    judged first without it, then with it only where every other criterion holds: a
    realisation is in B iff it meets them all, so the mask is the same, but the arm's
    inverse kinematics run only for the realisations they can decide.
    """
    points = task.test_points
    if getattr(task, "feasibility", None) is None:
        return task.judge(trajectories, points, context).passed
    lenient = copy.copy(task)  # shallow: the same scene, without criterion (i)'s arm
    lenient.feasibility = None
    passed = np.array(lenient.judge(trajectories, points, context).passed, dtype=bool)
    if passed.any():
        rows = np.flatnonzero(passed)
        passed[rows] = task.judge(trajectories[rows], points[rows], context).passed
    return passed


# ---------------------------------------------------------------- scoring on both cores

#: what the worker processes score against (set before they fork, inherited by them)
_SHARED: dict = {}


def _score_positions(state: State, positions) -> list[float]:
    """eps after each bank demo at ``positions`` (a worker's share)."""
    task, bank = _SHARED["task"], _SHARED["bank"]
    return [efficacy_after(task, state, bank.demos[i], bank.demo_points[i])[0] for i in positions]


def shared():
    """The task and bank the open :class:`Scorer` scores against (in a worker too)."""
    return _SHARED["task"], _SHARED["bank"]


class Scorer:
    """Scores bank demos for one task, on ``workers`` processes (or here, for one).

    Use it as a context manager; :func:`best_next` (and the optimal teacher's
    :func:`tutor.study.optimal.greedy` and ``pair_bound``) make their own when none is
    given. The workers fork from this
    process (they inherit the task and the bank); where the platform cannot fork, the
    scoring runs here.
    """

    def __init__(self, task, bank: Bank, workers: int | None = None):
        if workers is None:
            workers = min(os.cpu_count() or 1, 2)
        self.workers = _whole(workers, "workers", 1)
        if not can_fork():  # the workers must inherit the task and the bank
            self.workers = 1
        self.task, self.bank, self._pool = task, bank, None

    def __enter__(self) -> Scorer:
        one_blas_thread()
        _SHARED.update(task=self.task, bank=self.bank)
        if self.workers > 1:
            self._pool = process_pool(self.workers)
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None

    def scores(self, state: State, positions, stop_at: float | None = None) -> np.ndarray:
        """eps after each bank demo at ``positions`` (nan for those left unscored).

        With ``stop_at``, scoring stops once a demo reaches it (those after it in
        ``positions`` are left unscored): the first to reach the highest possible eps
        is the greedy choice anyway.
        """
        positions = np.asarray(positions, dtype=int)
        out = np.full(len(positions), np.nan)
        # here, one at a time: scoring stops at the very first demo reaching stop_at
        # (the answer is the same for any chunk: the first best wins); on the workers,
        # chunks big enough to keep both busy
        if self._pool is None:
            chunk = 1
        else:
            chunk = max(1, min(12, len(positions) // (4 * self.workers) or 1))
        parts = [positions[k : k + chunk] for k in range(0, len(positions), chunk)]
        if self._pool is None:
            futures = None
        else:
            futures = [self._pool.submit(_score_positions, state, p) for p in parts]
        done = 0
        for k, part in enumerate(parts):
            got = _score_positions(state, part) if futures is None else futures[k].result()
            out[done : done + len(part)] = got
            done += len(part)
            if stop_at is not None and max(got) >= stop_at - EPS_TOL:
                break
        if futures is not None:
            for fut in futures[k + 1 :]:
                fut.cancel()
        return out

    def map(self, fn, items) -> list:
        """``fn(item)`` for each item, in order, on the workers; ``fn`` is a module-level
        function reading the task and bank with :func:`shared`."""
        items = list(items)
        if self._pool is None:
            return [fn(item) for item in items]
        return list(self._pool.map(fn, items))


# ---------------------------------------------------------------- the greedy step (HF)


@dataclass(frozen=True)
class NextDemo:
    """The greedy choice of the next demo.

    Attributes
    ----------
    position : int
        Its position in the bank (``bank.demos[position]``).
    index : int
        Its test point's index in B^ (the start point or plant to demonstrate).
    draw : int
        Which of the bank's draws for that test point it is.
    efficacy : float
        eps after adding it (the session's eps).
    scores : ndarray (k,)
        eps after each candidate scored, in candidate order (nan: not scored, as a
        candidate before it already reached eps = 1).
    candidates : ndarray of int (k,)
        The bank positions considered.
    """

    position: int
    index: int
    draw: int
    efficacy: float
    scores: np.ndarray
    candidates: np.ndarray


def best_next(
    task, state, bank: Bank, candidates=None, scorer: Scorer | None = None, workers=None
) -> NextDemo:
    """The bank demo that maximises eps once added to ``state`` (the greedy step).

    Parameters
    ----------
    task : Task
        The session's task (the bank's demos were made for it).
    state : State, TeachingSession or run
        The current demos and learner (:meth:`State.from_session` for a session or a run).
    bank : Bank
        The candidates (e.g. :func:`make_bank`, or one draw per test point for speed).
    candidates : sequence of int, optional
        Bank positions to consider (default: all), e.g. the failing test points only.
    scorer : Scorer, optional
        An open :class:`Scorer` for this task and bank (its worker processes are reused).
    workers : int, optional
        Processes when no scorer is given (default: up to 2).

    Returns
    -------
    NextDemo
        Ties go to the first candidate in order (the lowest bank position by default).

    Notes
    -----
    Each candidate costs one refit and one judgement of B^: about 15-20 ms on one core
    for both tasks, so one draw per plant (100 candidates) takes about 1 s on two cores.
    """
    if not isinstance(state, State):
        state = State.from_session(state)
    positions = np.arange(len(bank)) if candidates is None else np.asarray(candidates, int)
    if (
        positions.ndim != 1
        or positions.size == 0
        or np.any((positions < 0) | (positions >= len(bank)))
    ):
        raise InvalidParameterError(
            f"candidates must be bank positions in 0..{len(bank) - 1}, got {positions.tolist()}"
        )
    if scorer is None:
        with Scorer(task, bank, workers) as own:
            scores = own.scores(state, positions, stop_at=1.0)
    else:
        scores = scorer.scores(state, positions, stop_at=1.0)
    best = int(np.nanargmax(np.where(np.isnan(scores), -np.inf, scores)))
    p = int(positions[best])
    index, draw = int(bank.index[p]), int(bank.draw[p])
    return NextDemo(p, index, draw, float(scores[best]), scores, positions)
