r"""The optimal teacher: how few demonstrations could teach this robot each task?

Sena & Howard score a teacher by efficacy :math:`\varepsilon` and efficiency
:math:`\eta = \varepsilon / |b|`, but say nothing about what a perfect teacher would
reach. This module answers it for the tutor's own learner, tasks and criteria with a
**machine teacher** that knows everything the tutor knows:

- a **bank** of candidate demos (:func:`make_bank`): one per test point of B^ (the 140
  maze start points, the 100 plants) and several draws of a careful teacher's hand each,
  made by the tasks' own generators (the maze stroke of
  :meth:`tutor.teachers.maze.MazeTeacher.stroke` at the population's steadiest hand;
  :meth:`tutor.tasks.pickplace.PickPlaceTask.demonstrate` without mistakes);
- the **greedy step** (:func:`tutor.tasks.lookahead.best_next`, re-exported here): the
  bank demo that maximises eps after it is added to the current demos, exactly as
  :meth:`TeachingSession.add_demo` would score it (same learner, warm start when the
  task's learner warm-starts, same criteria). Ties go to the lowest bank index, so the
  answer is deterministic. It lives below the views, so a next-demo hint in the tutor
  can call it too;
- the **greedy teacher** (:func:`greedy`): greedy steps until eps = 1 or a cap;
- the **pair bound** (:func:`pair_bound`): every pair of bank demos (one draw per
  test point; ordered pairs when the learner warm-starts, since the session's result then
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

Efficacy is computed with the task's realisation (:meth:`~tutor.framework.Task.realise`)
and the lookahead's exact shortcut :func:`judged` (``tests/test_optimal.py`` checks both
against the session); the candidates are scored on both cores.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np

from ..errors import InvalidParameterError, TutorError
from ..framework.metrics import run_score
from ..tasks import lookahead, make_task
from ..tasks.lookahead import (
    EPS_TOL,
    Bank,
    NextDemo,
    Scorer,
    State,
    best_next,
    efficacy_after,
    judged,
)

__all__ = [
    "Bank",
    "State",
    "NextDemo",
    "GreedyResult",
    "PairBound",
    "make_bank",
    "careful_recording",
    "efficacy_after",
    "judged",
    "best_next",
    "Scorer",
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
#: the experiment of each task, and the scoring rule of that experiment
EXPERIMENT = {"maze": 1, "pickplace": 2}
RULES = {1: "target", 2: "final"}


# ---------------------------------------------------------------- the bank


def _steady_stroke(task, index: int, rng) -> np.ndarray:
    from ..teachers.maze import MazeTeacher
    from ..teachers.traits import DEFAULT_POPULATION

    traits = DEFAULT_POPULATION.sample(np.random.default_rng(0))
    steady = dataclasses.replace(traits, motor_noise=DEFAULT_POPULATION.motor_low)
    return MazeTeacher(steady, task).stroke(task.test_points[index], rng)


#: task name -> the careful hand of its optimal teacher, where it is not the task's own
#: scripted demo (:meth:`~tutor.framework.task.Task.scripted_demo`)
CAREFUL_HANDS = {"maze": _steady_stroke}


def careful_recording(task, index: int, rng) -> np.ndarray:
    """A careful teacher's raw recording for test point ``index`` of ``task``.

    Maze: the simulated teacher's stroke (:meth:`tutor.teachers.maze.MazeTeacher.stroke`)
    with the population's steadiest hand (``motor_low``) and no slip. Pick-and-place: the
    task's kinesthetic hand (:meth:`~tutor.tasks.pickplace.PickPlaceTask.demonstrate`)
    with no mistake.
    """
    hand = CAREFUL_HANDS.get(task.name)
    return task.scripted_demo(index, rng) if hand is None else hand(task, index, rng)


def make_bank(task, draws: int = 3, seed: int = 0, indices=None) -> Bank:
    """The optimal teacher's bank: ``draws`` careful demos per test point (all of B^ by
    default), by :func:`careful_recording`; see :func:`tutor.tasks.lookahead.make_bank`."""
    return lookahead.make_bank(task, draws, seed, indices, recording=careful_recording)


#: the most careful demos per test point in the bank (--draws; the paper-sized reference
#: uses 3, and each one more adds a pass over all of B^)
MAX_DRAWS = 20
#: the most demos the greedy teacher may give (--cap; it stops at the target long before)
MAX_CAP = 200


def _whole(value, name: str, lowest: int, highest: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < lowest:
        raise InvalidParameterError(f"{name} must be a whole number >= {lowest}, got {value!r}")
    if highest is not None and value > highest:
        raise InvalidParameterError(
            f"{name} must be at most {highest}, got {value!r}: give a smaller number"
        )
    return int(value)


# ---------------------------------------------------------------- pairs, on the workers


def _pairs_from(first: int, ordered: bool) -> np.ndarray:
    """eps of every pair starting with bank demo ``first`` (nan where not a pair)."""
    task, bank = lookahead.shared()
    state, _, _ = State.empty(task).added(task, bank.demos[first], bank.demo_points[first])
    out = np.full(len(bank), np.nan)
    for j in range(len(bank)) if ordered else range(first + 1, len(bank)):
        if j != first:
            out[j] = efficacy_after(task, state, bank.demos[j], bank.demo_points[j])[0]
    return out


# ---------------------------------------------------------------- the greedy teacher


@dataclass(frozen=True)
class GreedyResult:
    """The greedy teacher's path: bank positions, test points and eps after each demo."""

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
    cap = _whole(cap, "cap", 1, MAX_CAP)
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
                task, bank.demos[choice.position], bank.demo_points[choice.position]
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
    best_pair: tuple[int, int]  #: its test points' indices in B^ (first, second)
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
    n = len(bank)
    with Scorer(task, bank, workers) as scorer:
        rows = scorer.map(partial(_pairs_from, ordered=ordered), range(n if ordered else n - 1))
    if not ordered:
        rows.append(np.full(n, np.nan))
    table = np.array(rows)
    filled = np.where(np.isnan(table), -np.inf, table)
    i, j = np.unravel_index(int(np.argmax(filled)), filled.shape)  # first in row order
    singles = State.empty(task).added(task, bank.demos[i], bank.demo_points[i])[1]
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

    ``indices`` restricts the bank to those test points (a reduced bank, for tests);
    ``log`` (e.g. ``print``) is told each phase's result and time.
    """
    draws = _whole(draws, "draws", 1, MAX_DRAWS)
    pair_draws = _whole(pair_draws, "pair_draws", 1, MAX_DRAWS)
    cap = _whole(cap, "cap", 1, MAX_CAP)
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
        "n_conditions": int(len(task.test_points)),
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
        round(session.add_demo(bank.demos[p], point=bank.demo_points[p]).efficacy, 6)
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
        Careful demos per test point in the bank.
    seed : int
        Seed of the bank's hand.
    pair_draws : int
        Draws per test point in the pair bound's bank (all pairs of it are scored).
    cap : int
        The most demos the greedy teacher gives.
    workers : int, optional
        Processes (default: up to 2).
    indices : dict, optional
        Task name -> the test points of a reduced bank (tests); default all of B^.
    log : callable, optional
        Told each phase's result and time (the command prints them).

    Raises
    ------
    InvalidParameterError
        Before any work: ``draws`` or ``pair_draws`` not from 1 to :data:`MAX_DRAWS`,
        ``cap`` not from 1 to :data:`MAX_CAP`.
    """
    draws = _whole(draws, "draws (--draws)", 1, MAX_DRAWS)
    pair_draws = _whole(pair_draws, "pair_draws (--pair-draws)", 1, MAX_DRAWS)
    cap = _whole(cap, "cap (--cap)", 1, MAX_CAP)
    settings = {"draws": draws, "seed": seed, "pair_draws": pair_draws, "cap": cap}
    out = {
        "format": FORMAT,
        "version": VERSION,
        "command": COMMAND,
        "settings": settings,
        "tasks": {},
    }
    for name in tasks:
        task = make_task(name)
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
    parser.add_argument(
        "--draws", type=int, default=3, help=f"bank demos per test point (at most {MAX_DRAWS})"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--pair-draws", type=int, default=1,
        help=f"draws in the pair bound (at most {MAX_DRAWS})",
    )
    parser.add_argument(
        "--cap", type=int, default=10,
        help=f"most demos the greedy teacher gives (at most {MAX_CAP})",
    )
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
