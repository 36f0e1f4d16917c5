r"""The optimal teacher: how few demonstrations could teach this robot each task?

Sena & Howard score a teacher by efficacy :math:`\varepsilon` and efficiency
:math:`\eta = \varepsilon / |b|`, but say nothing about what a perfect teacher would
reach. This module answers it for the tutor's own learner, tasks and criteria with a
**machine teacher** that knows everything the tutor knows:

- a **bank** of candidate demos (:func:`make_bank`): one per condition of B^ (the 140
  maze start points, the 100 plants) and several draws of a careful teacher's hand each,
  made by the tasks' own generators (the maze stroke of
  :meth:`tutor.teachers.maze.MazeTeacher.stroke` at the population's steadiest hand;
  :meth:`tutor.tasks.pickplace.PickPlaceTask.demonstrate` without mistakes);
- the **greedy step** (:func:`best_next`): the bank demo that maximises eps after it is
  added to the current demos, exactly as :meth:`TeachingSession.add_demo` would score
  it (same learner, warm start when the task's learner warm-starts, same criteria). Ties
  go to the lowest bank index, so the answer is deterministic. The lead's next-demo
  hint (HF) reuses it;
- the **greedy teacher** (:func:`greedy`): greedy steps until eps = 1 or a cap;
- the **pair bound** (:func:`pair_bound`): every pair of bank demos (one draw per
  condition; ordered pairs when the learner warm-starts, since the session's result then
  depends on the order), so whether 2 demos could ever reach 0.9 or 1 is known rather
  than guessed.

The teaching dimension :math:`TD_x` is the fewest demos found that reach eps >= x (1 or 2
when a single demo or a pair does, else the greedy teacher's count, which the pair bound
then shows to be the fewest over the bank's pairs when it is 3). The best possible eta
follows by each experiment's scoring rule (:mod:`tutor.framework.metrics`):
Experiment 1's ``"target"`` rule takes eps where 90 % is first reached over the demos
needed; Experiment 2's ``"final"`` rule takes the final eps over every demo given.

The result is cached in ``tutor/assets/optimal.json`` (read by
:mod:`tutor.tasks.optimal_reference`, so the tutor's screens and notebooks never
recompute it). Regenerate it after any change to the learner, the tasks or the hand::

    python -m tutor.study.optimal --out tutor/assets/optimal.json

Efficacy is computed with a fast product of the frames' Gaussians when every frame's
rotation is the same for all conditions (true of both tasks: every frame is axis
aligned), which :func:`realise` checks; it equals ``learner.reproduce_batch`` to
rounding (``tests/test_optimal.py``). Candidates are scored on both cores.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError, TutorError
from ..framework.metrics import run_score
from ..tpgmm.linalg import inv_small, sym

__all__ = [
    "Bank",
    "State",
    "NextDemo",
    "GreedyResult",
    "PairBound",
    "make_bank",
    "careful_recording",
    "realise",
    "efficacy_after",
    "judged",
    "best_next",
    "greedy",
    "pair_bound",
    "teaching_dimension",
    "task_reference",
    "compute_reference",
    "main",
    "FORMAT",
    "VERSION",
    "TARGETS",
]

FORMAT = "lfd-tutor-optimal"
VERSION = 1
#: the coverages whose teaching dimension is reported: the paper's 90 % and everything
TARGETS = (0.9, 1.0)
#: how many tries a careful teacher gets to make a correct bank demo for one condition
MAX_TRIES = 5
#: exact efficacies compare equal within this (eps is a share of at most a few hundred)
EPS_TOL = 1e-12
#: the experiment of each task, and the scoring rule of that experiment
EXPERIMENT = {"maze": 1, "pickplace": 2}
RULES = {1: "target", 2: "final"}


# ---------------------------------------------------------------- the bank


@dataclass(frozen=True)
class Bank:
    """Candidate demonstrations: several careful draws for each condition of B^.

    Attributes
    ----------
    demos : ndarray (n, T, 1 + d)
        Preprocessed demos (``task.preprocess``), in bank order.
    conditions : ndarray (n, c)
        The condition each demo was given under (a row of ``task.conditions``).
    index : ndarray of int (n,)
        Its index in B^.
    draw : ndarray of int (n,)
        Which draw of the hand it is (0, 1, ...).
    """

    demos: np.ndarray
    conditions: np.ndarray
    index: np.ndarray
    draw: np.ndarray

    def __len__(self) -> int:
        return len(self.index)

    def subset(self, keep) -> Bank:
        """The bank demos at positions ``keep`` (in that order)."""
        keep = np.asarray(keep, dtype=int)
        return Bank(self.demos[keep], self.conditions[keep], self.index[keep], self.draw[keep])

    def first_draws(self, n_draws: int = 1) -> Bank:
        """The demos of the first ``n_draws`` draws only (the pair bound's bank)."""
        return self.subset(np.flatnonzero(self.draw < n_draws))


def careful_recording(task, index: int, rng) -> np.ndarray:
    """A careful teacher's raw recording for condition ``index`` of ``task``.

    Maze: the simulated teacher's stroke (:meth:`tutor.teachers.maze.MazeTeacher.stroke`)
    with the population's steadiest hand (``motor_low``) and no slip. Pick-and-place: the
    task's kinesthetic hand (:meth:`~tutor.tasks.pickplace.PickPlaceTask.demonstrate`)
    with no mistake.
    """
    if task.name == "maze":
        from ..teachers.maze import MazeTeacher
        from ..teachers.traits import DEFAULT_POPULATION

        traits = DEFAULT_POPULATION.sample(np.random.default_rng(0))
        steady = dataclasses.replace(traits, motor_noise=DEFAULT_POPULATION.motor_low)
        return MazeTeacher(steady, task).stroke(task.conditions[index], rng)
    if task.name == "pickplace":
        return task.demonstrate(int(index), rng)
    raise InvalidParameterError(
        f"the optimal teacher knows the tasks 'maze' and 'pickplace', got {task.name!r}"
    )


def make_bank(task, draws: int = 3, seed: int = 0, indices=None) -> Bank:
    """The bank: ``draws`` careful demos for each condition (all of B^ by default).

    Each demo is drawn with its own generator, seeded by (seed, index, draw, try), so a
    bank of fewer conditions or draws holds the same demos as the full one. A draw that
    is not a correct demo (``task.judge_demo``) is drawn again (at most ``MAX_TRIES``).

    Raises
    ------
    InvalidParameterError
        ``draws`` or ``seed`` is not a whole number (>= 1, >= 0), an index is outside
        B^, or a careful teacher could not make a correct demo for a condition.
    """
    draws, seed = _whole(draws, "draws", 1), _whole(seed, "seed", 0)
    n = len(task.conditions)
    idx = np.arange(n) if indices is None else np.asarray(indices, dtype=int).ravel()
    if idx.size == 0 or np.any((idx < 0) | (idx >= n)):
        raise InvalidParameterError(f"bank indices must be in 0..{n - 1}, got {idx.tolist()}")
    demos, conds, index, draw = [], [], [], []
    for k in range(draws):
        for i in idx:
            demo = _correct_demo(task, int(i), seed, k)
            demos.append(demo)
            conds.append(task.conditions[i])
            index.append(int(i))
            draw.append(k)
    return Bank(np.array(demos), np.array(conds, dtype=float), np.array(index), np.array(draw))


def _correct_demo(task, i: int, seed: int, k: int) -> np.ndarray:
    for attempt in range(MAX_TRIES):
        rng = np.random.default_rng(np.random.SeedSequence([seed, i, k, attempt]))
        demo = task.preprocess(careful_recording(task, i, rng))
        if task.judge_demo(demo, task.conditions[i]).passed[0]:
            return demo
    raise InvalidParameterError(
        f"a careful teacher made no correct demo for {task.condition_noun} {i} in "
        f"{MAX_TRIES} tries: check the task's geometry and criteria"
    )


def _whole(value, name: str, lowest: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < lowest:
        raise InvalidParameterError(f"{name} must be a whole number >= {lowest}, got {value!r}")
    return int(value)


# ---------------------------------------------------------------- efficacy, fast


def realise(task, learner) -> np.ndarray:
    """R^: the learner's mean realisation from every condition of B^, (n, T, d).

    The same as ``learner.reproduce_batch(task.frame_batch(task.conditions), task.times)``
    (the session's), computed as an affine map of the frame origins when every frame's
    rotation is the same for all conditions: the product's precision is then one per
    time step, shared by every condition.
    """
    batch = task.frame_batch(task.conditions)
    W = batch.A_inv  # (B, P, d, d)
    if not np.array_equal(W, np.broadcast_to(W[:1], W.shape)):
        return learner.reproduce_batch(batch, task.times)[0]
    W = W[0][:, None]  # (P, 1, d, d): one per frame, shared by every time step
    Wt = np.swapaxes(W, -1, -2)
    mean, cov = learner.regress_local(task.times)  # (P, T, d), (P, T, d, d)
    L = sym(inv_small(cov))
    world = Wt @ L @ W  # each frame's precision in the world, (P, T, d, d)
    prec_cov = sym(inv_small(world.sum(axis=0)))  # the product's covariance, (T, d, d)
    base = (prec_cov @ (Wt @ (L @ mean[..., None])).sum(axis=0))[..., 0]  # (T, d)
    gain = prec_cov @ world  # how each frame's origin moves the mean, (P, T, d, d)
    P, T, d, _ = gain.shape
    B = batch.b.shape[0]
    shift = gain.transpose(1, 2, 0, 3).reshape(T * d, P * d) @ batch.b.reshape(B, P * d).T
    return base[None] + shift.reshape(T, d, B).transpose(2, 0, 1)


@dataclass
class State:
    """What the session knows before the next demo: its demos, conditions and learner.

    ``learner`` is the one fitted on ``demos`` (a fresh one before any demo); adding a
    demo fits a copy of it, as :meth:`TeachingSession.add_demo` does.
    """

    demos: list
    conditions: list
    learner: object

    @classmethod
    def empty(cls, task) -> State:
        return cls([], [], task.make_learner())

    @classmethod
    def from_session(cls, session) -> State:
        """The state of a :class:`~tutor.framework.TeachingSession` (or a run's session)."""
        session = getattr(session, "session", session)
        return cls(session.demos, session.conditions, session.learner)

    def added(self, task, demo, condition) -> tuple[State, float, np.ndarray]:
        """The state after ``demo``, its eps and the passed mask (n,)."""
        eps, passed, learner = efficacy_after(task, self, demo, condition)
        return State([*self.demos, demo], [*self.conditions, condition], learner), eps, passed


def efficacy_after(task, state: State, demo, condition):
    """eps after adding ``demo`` (preprocessed) under ``condition`` to ``state``.

    Exactly the session's eps (:meth:`TeachingSession.add_demo`): a copy of the learner
    refitted on every demo, R^ judged by the task's criteria with the demos' context.

    Returns
    -------
    eps : float
    passed : ndarray of bool (n,)
    learner : the fitted copy
    """
    demos = [*state.demos, demo]
    conds = np.array([*state.conditions, condition], dtype=float)
    learner = copy.deepcopy(state.learner)
    learner.fit(demos, [task.frames(c) for c in conds])
    context = task.criteria_context(demos, conds)
    passed = judged(task, realise(task, learner), context)
    return float(passed.mean()), passed, learner


def judged(task, trajectories, context) -> np.ndarray:
    """``task.judge(trajectories, task.conditions, context).passed``, sooner.

    A task whose criterion (i) follows the arm (``task.feasibility``, pick-and-place) is
    judged first without it, then with it only where every other criterion holds: a
    realisation is in B iff it meets them all, so the mask is the same, but the arm's
    inverse kinematics run only for the realisations they can decide.
    """
    conditions = task.conditions
    if getattr(task, "feasibility", None) is None:
        return task.judge(trajectories, conditions, context).passed
    lenient = copy.copy(task)  # shallow: the same scene, without criterion (i)'s arm
    lenient.feasibility = None
    passed = np.array(lenient.judge(trajectories, conditions, context).passed, dtype=bool)
    if passed.any():
        rows = np.flatnonzero(passed)
        passed[rows] = task.judge(trajectories[rows], conditions[rows], context).passed
    return passed


# ---------------------------------------------------------------- scoring on both cores

#: what the worker processes score against (set before they fork, inherited by them)
_SHARED: dict = {}


def _score_positions(state: State, positions) -> list[float]:
    """eps after each bank demo at ``positions`` (a worker's share)."""
    task, bank = _SHARED["task"], _SHARED["bank"]
    return [efficacy_after(task, state, bank.demos[i], bank.conditions[i])[0] for i in positions]


def _pairs_from(first: int, ordered: bool) -> np.ndarray:
    """eps of every pair starting with bank demo ``first`` (nan where not a pair)."""
    task, bank = _SHARED["task"], _SHARED["bank"]
    state, _, _ = State.empty(task).added(task, bank.demos[first], bank.conditions[first])
    out = np.full(len(bank), np.nan)
    for j in range(len(bank)) if ordered else range(first + 1, len(bank)):
        if j != first:
            out[j] = efficacy_after(task, state, bank.demos[j], bank.conditions[j])[0]
    return out


class Scorer:
    """Scores bank demos for one task, on ``workers`` processes (or here, for one).

    Use it as a context manager; :func:`best_next`, :func:`greedy` and
    :func:`pair_bound` make their own when none is given. The workers fork from this
    process (they inherit the task and the bank); where the platform cannot fork, the
    scoring runs here.
    """

    def __init__(self, task, bank: Bank, workers: int | None = None):
        import multiprocessing as mp

        if workers is None:
            workers = min(os.cpu_count() or 1, 2)
        self.workers = _whole(workers, "workers", 1)
        if "fork" not in mp.get_all_start_methods():
            self.workers = 1
        self.task, self.bank, self._pool = task, bank, None

    def __enter__(self) -> Scorer:
        from .cohort import _limit_threads

        _limit_threads()  # the same arithmetic here and in every worker
        _SHARED.update(task=self.task, bank=self.bank)
        if self.workers > 1:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(
                self.workers, mp_context=mp.get_context("fork"), initializer=_limit_threads
            )
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

    def pair_rows(self, ordered: bool) -> np.ndarray:
        """eps of every pair of bank demos, (n, n): row i, column j is i then j."""
        n = len(self.bank)
        firsts = range(n) if ordered else range(n - 1)
        if self._pool is None:
            rows = [_pairs_from(i, ordered) for i in firsts]
        else:
            rows = list(self._pool.map(_pairs_from, firsts, [ordered] * len(firsts)))
        if not ordered:
            rows.append(np.full(n, np.nan))
        return np.array(rows)


# ---------------------------------------------------------------- the greedy step (HF)


@dataclass(frozen=True)
class NextDemo:
    """The greedy choice of the next demo.

    Attributes
    ----------
    position : int
        Its position in the bank (``bank.demos[position]``).
    index : int
        Its condition's index in B^ (the start point or plant to demonstrate).
    draw : int
        Which of the bank's draws for that condition it is.
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
        The candidates (e.g. :func:`make_bank`, or one draw per condition for speed).
    candidates : sequence of int, optional
        Bank positions to consider (default: all), e.g. the failing conditions only.
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


# ---------------------------------------------------------------- the greedy teacher


@dataclass(frozen=True)
class GreedyResult:
    """The greedy teacher's path: bank positions, conditions and eps after each demo."""

    positions: tuple[int, ...]
    indices: tuple[int, ...]
    draws: tuple[int, ...]
    efficacies: tuple[float, ...]
    best_single: float  #: the highest eps of any one bank demo (greedy's first step)
    seconds: float

    def to_dict(self) -> dict:
        return {
            "indices": list(self.indices),
            "draws": list(self.draws),
            "efficacy": [round(e, 6) for e in self.efficacies],
            "best_single": round(self.best_single, 6),
        }


def greedy(task, bank: Bank, cap: int = 10, target: float = 1.0, workers=None) -> GreedyResult:
    """Add the greedy step's demo until eps reaches ``target`` or ``cap`` demos are given.

    Raises
    ------
    InvalidParameterError
        ``cap`` is not a whole number >= 1 or ``target`` is not in (0, 1].
    """
    cap = _whole(cap, "cap", 1)
    if not 0 < target <= 1:
        raise InvalidParameterError(f"target must be in (0, 1], got {target!r}")
    start = time.perf_counter()
    state = State.empty(task)
    path, effs, best_single = [], [], 0.0
    with Scorer(task, bank, workers) as scorer:
        while len(path) < cap:
            choice = best_next(task, state, bank, scorer=scorer)
            if not path:
                best_single = choice.efficacy
            state, eps, _ = state.added(
                task, bank.demos[choice.position], bank.conditions[choice.position]
            )
            path.append(choice.position)
            effs.append(eps)
            if eps >= target - EPS_TOL:
                break
    return GreedyResult(
        tuple(path),
        tuple(int(bank.index[p]) for p in path),
        tuple(int(bank.draw[p]) for p in path),
        tuple(effs),
        best_single,
        time.perf_counter() - start,
    )


# ---------------------------------------------------------------- the pair bound


@dataclass(frozen=True)
class PairBound:
    """The best any pair of bank demos reaches, and how many pairs reach each target."""

    ordered: bool  #: pairs in both orders (the learner warm-starts, so order matters)
    n_pairs: int
    best: float  #: the highest eps of any pair
    best_pair: tuple[int, int]  #: its conditions' indices in B^ (first, second)
    best_path: tuple[float, float]  #: eps after its first demo and after both
    reaching: dict  #: target -> number of pairs reaching it
    bank_size: int
    seconds: float

    def to_dict(self) -> dict:
        return {
            "ordered": self.ordered,
            "bank_size": self.bank_size,
            "n_pairs": self.n_pairs,
            "best_efficacy": round(self.best, 6),
            "best_pair": list(self.best_pair),
            "best_path": [round(e, 6) for e in self.best_path],
            "reaching": {_key(t): n for t, n in self.reaching.items()},
        }


def pair_bound(task, bank: Bank, workers=None) -> PairBound:
    """eps of every pair of bank demos, as the session would score them.

    When the task's learner warm-starts (the maze) the second fit starts from the first
    demo's model, so both orders of each pair are tried; otherwise (pick-and-place refits
    from scratch) each unordered pair once.
    """
    start = time.perf_counter()
    ordered = bool(task.make_learner().warm_start)
    with Scorer(task, bank, workers) as scorer:
        table = scorer.pair_rows(ordered)
    filled = np.where(np.isnan(table), -np.inf, table)
    i, j = np.unravel_index(int(np.argmax(filled)), filled.shape)  # first in row order
    singles = State.empty(task).added(task, bank.demos[i], bank.conditions[i])[1]
    reaching = {t: int(np.sum(filled >= t - EPS_TOL)) for t in TARGETS}
    return PairBound(
        ordered,
        int(np.isfinite(filled).sum()),
        float(filled[i, j]),
        (int(bank.index[i]), int(bank.index[j])),
        (float(singles), float(filled[i, j])),
        reaching,
        len(bank),
        time.perf_counter() - start,
    )


# ---------------------------------------------------------------- teaching dimension, eta


def _key(target: float) -> str:
    return f"{target:g}"


def teaching_dimension(target: float, greedy_result: GreedyResult, pairs: PairBound) -> dict:
    """TD_target: the fewest demos found reaching ``target``, with its path and bound.

    Returns
    -------
    dict
        ``n_demos`` (None when nothing found reached it), ``efficacy`` (eps along the
        path that reached it), ``found_by`` ("greedy" or "pair"), ``lower_bound`` (the
        fewest demos any teacher could need over the bank: 3 when no single demo and no
        pair of the pair bank reaches it) and ``exact`` (the two agree).
    """
    reach = [m for m, e in enumerate(greedy_result.efficacies, 1) if e >= target - EPS_TOL]
    found, path, how = None, None, None
    if reach:
        found, how = reach[0], "greedy"
        path = list(greedy_result.efficacies[: reach[0]])
    if pairs.best >= target - EPS_TOL and (found is None or found > 2):
        found, how, path = 2, "pair", list(pairs.best_path)
    if greedy_result.best_single >= target - EPS_TOL:
        found, how, path = 1, "greedy", [greedy_result.best_single]
    if greedy_result.best_single >= target - EPS_TOL:
        lower = 1
    elif pairs.best >= target - EPS_TOL or (found is not None and found <= 2):
        lower = 2
    else:
        lower = 3
    out = {
        "n_demos": found,
        "efficacy": None if path is None else [round(e, 6) for e in path],
        "found_by": how,
        "lower_bound": lower,
        "exact": found == lower,
    }
    if path is not None:
        out["eta"] = {rule: round(run_score(path, rule).efficiency, 6) for rule in RULES.values()}
    return out


# ---------------------------------------------------------------- the reference file


def _make_task(name: str):
    if name == "maze":
        from ..tasks.maze import MazeTask

        return MazeTask()
    if name == "pickplace":
        from ..tasks.pickplace import PickPlaceTask

        return PickPlaceTask()
    raise InvalidParameterError(f"task must be 'maze' or 'pickplace', got {name!r}")


def task_reference(
    task,
    draws: int = 3,
    seed: int = 0,
    pair_draws: int = 1,
    cap: int = 10,
    workers=None,
    indices=None,
    log=None,
) -> dict:
    """Everything the reference file says about one task (see :func:`compute_reference`).

    ``indices`` restricts the bank to those conditions (a reduced bank, for tests);
    ``log`` (e.g. ``print``) is told each phase's result and time.
    """
    pair_draws = _whole(pair_draws, "pair_draws", 1)
    bank = make_bank(task, draws, seed, indices)
    found = greedy(task, bank, cap, workers=workers)
    if log is not None:
        log(f"{task.name}: greedy eps {found.efficacies} in {found.seconds:.1f} s")
    pairs = pair_bound(task, bank.first_draws(min(pair_draws, draws)), workers)
    if log is not None:
        log(f"{task.name}: {pairs.n_pairs} pairs, best {pairs.best:.3f}, {pairs.seconds:.0f} s")
    experiment = EXPERIMENT[task.name]
    return {
        "experiment": experiment,
        "rule": RULES[experiment],
        "n_conditions": int(len(task.conditions)),
        "bank": {"conditions": int(len(np.unique(bank.index))), "draws": draws, "size": len(bank)},
        "greedy": {**found.to_dict(), "session_efficacy": _replayed(task, bank, found)},
        "pairs": pairs.to_dict(),
        "td": {_key(t): teaching_dimension(t, found, pairs) for t in TARGETS},
    }


def _replayed(task, bank: Bank, found: GreedyResult) -> list[float]:
    """eps after each greedy demo as a :class:`TeachingSession` computes it (a check)."""
    from ..framework.session import TeachingSession

    session = TeachingSession(task, feedback="none")
    return [
        round(session.add_demo(bank.demos[p], condition=bank.conditions[p]).efficacy, 6)
        for p in found.positions
    ]


def compute_reference(
    tasks: Sequence[str] = ("maze", "pickplace"),
    draws: int = 3,
    seed: int = 0,
    pair_draws: int = 1,
    cap: int = 10,
    workers=None,
    indices: dict | None = None,
    log=None,
) -> dict:
    """The optimal teacher's reference for each task, as written to ``optimal.json``.

    Parameters
    ----------
    tasks : sequence of {"maze", "pickplace"}
    draws : int
        Careful demos per condition in the bank.
    seed : int
        Seed of the bank's hand.
    pair_draws : int
        Draws per condition in the pair bound's bank (all pairs of it are scored).
    cap : int
        The most demos the greedy teacher gives.
    workers : int, optional
        Processes (default: up to 2).
    indices : dict, optional
        Task name -> the conditions of a reduced bank (tests); default all of B^.
    log : callable, optional
        Told each phase's result and time (the command prints them).
    """
    settings = {"draws": draws, "seed": seed, "pair_draws": pair_draws, "cap": cap}
    out = {
        "format": FORMAT,
        "version": VERSION,
        "command": COMMAND,
        "settings": settings,
        "tasks": {},
    }
    for name in tasks:
        task = _make_task(name)
        subset = None if indices is None else indices.get(name)
        out["tasks"][name] = task_reference(
            task, draws, seed, pair_draws, cap, workers, indices=subset, log=log
        )
        if subset is not None:
            out["tasks"][name]["bank"]["indices"] = [int(i) for i in subset]
    return out


#: the command that writes the bundled file
COMMAND = "python -m tutor.study.optimal --out tutor/assets/optimal.json"


def main(argv=None) -> int:
    """``python -m tutor.study.optimal --out FILE``: compute and write the reference."""
    parser = argparse.ArgumentParser(
        prog="python -m tutor.study.optimal",
        description="The optimal (greedy machine) teacher: teaching dimension TD_0.9 and "
        "TD_1 and the best possible eta per task, written as JSON.",
    )
    parser.add_argument("--out", required=True, help="the JSON file to write")
    parser.add_argument(
        "--tasks", nargs="+", default=["maze", "pickplace"], choices=["maze", "pickplace"]
    )
    parser.add_argument("--draws", type=int, default=3, help="bank demos per condition")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--pair-draws", type=int, default=1, help="draws in the pair bound")
    parser.add_argument("--cap", type=int, default=10, help="most demos the greedy teacher gives")
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    from ..fileio import write_json

    start = time.perf_counter()
    try:
        ref = compute_reference(
            args.tasks,
            args.draws,
            args.seed,
            args.pair_draws,
            args.cap,
            args.workers,
            log=lambda text: print(text, flush=True),
        )
        path = write_json(args.out, ref)
    except TutorError as exc:
        parser.error(str(exc))
    for name, r in ref["tasks"].items():
        td = r["td"]
        print(
            f"{name}: greedy eps {r['greedy']['efficacy']}; best pair "
            f"{r['pairs']['best_efficacy']:.3f}; TD_0.9 = {td['0.9']['n_demos']}, "
            f"TD_1 = {td['1']['n_demos']}"
        )
    print(f"wrote {path} in {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
