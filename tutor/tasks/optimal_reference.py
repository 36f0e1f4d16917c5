r"""How few demonstrations this robot needs: the optimal teacher's bundled reference.

:mod:`tutor.study.optimal` (a greedy machine teacher over a bank of careful demos, and
every pair of them) computes, per task, the teaching dimension :math:`TD_x` (the fewest
demos found that reach efficacy x) and the best possible efficiency
:math:`\eta = \varepsilon / |b|` there. It is cached in ``tutor/assets/optimal.json``
(regenerate it with ``python -m tutor.study.optimal --out tutor/assets/optimal.json``)
and read here, below the views, so a trainee's results can be put beside it ("you used
6 demonstrations; the fewest this robot needs is 3") without recomputing anything.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from ..errors import InvalidFileError
from ..fileio import finite_number, read_json
from ..resources import asset

__all__ = ["OptimalReference", "optimal_reference", "load_references", "REFERENCE_PATH"]

REFERENCE_PATH = asset("optimal.json")
FORMAT, VERSION = "lfd-tutor-optimal", 1
#: the coverage each experiment's reference is stated at: Experiment 1 scores at the
#: paper's 90 % rule, Experiment 2 by the final efficacy, so the line there is all plants
STATED_AT = {1: "0.9", 2: "1"}
RULES = {1: "target", 2: "final"}


@dataclass(frozen=True)
class OptimalReference:
    """The optimal teacher's numbers for one task.

    Attributes
    ----------
    task : str
        "maze" or "pickplace".
    experiment : int
        1 (maze, scored by the 90 % rule) or 2 (pick-and-place, scored by final eps).
    fewest : dict
        Coverage ("0.9", "1") -> TD: the fewest demos found reaching it (None: none did).
    proven : dict
        Coverage -> whether that TD is also the lower bound (no single demo and no pair
        of the bank's demos reaches it, so fewer cannot do).
    efficacy : dict
        Coverage -> eps reached with those TD demos.
    eta : dict
        Coverage -> eta there under this experiment's scoring rule.
    best_pair : float
        The highest eps any pair of bank demos reaches.
    best_single : float
        The highest eps any one bank demo reaches.
    greedy : tuple of float
        eps after each of the greedy teacher's demos.
    picks : tuple of int
        The condition (index into B^) of each of the greedy teacher's demos, in order:
        the first is the best first demo (the next-demo hint with no demo yet).
    n_conditions : int
        |B^| of the task the reference was computed for (0: not stated).
    """

    task: str
    experiment: int
    fewest: dict
    proven: dict
    efficacy: dict
    eta: dict
    best_pair: float
    best_single: float = 0.0
    greedy: tuple = ()
    picks: tuple = ()
    n_conditions: int = 0

    @property
    def coverage(self) -> float:
        """The coverage the reference is stated at (0.9 in Experiment 1, 1 in 2)."""
        return float(STATED_AT[self.experiment])

    @property
    def n_demos(self) -> int | None:
        """TD at :attr:`coverage`: the fewest demos the robot needs there."""
        return self.fewest[STATED_AT[self.experiment]]

    @property
    def is_proven(self) -> bool:
        """Whether fewer than :attr:`n_demos` demos cannot reach :attr:`coverage`."""
        return self.proven[STATED_AT[self.experiment]]

    @property
    def best_eta(self) -> float | None:
        """The best possible eta by this experiment's rule, at :attr:`coverage`."""
        return self.eta[STATED_AT[self.experiment]]

    @property
    def eta_any_stop(self) -> float:
        """The best eta of a run of any length, stopped anywhere: the highest eps found
        with M demos over M (one demo, the best pair, then the greedy path).

        Under both scoring rules a run of M demos scores at most its best eps over M, so
        when this equals :attr:`best_eta` no teacher beats the reference by stopping
        early (over the bank's demos).
        """
        best = {1: self.best_single, 2: self.best_pair}
        for m, eps in enumerate(self.greedy, start=1):
            best[m] = max(best.get(m, 0.0), eps)
        return max(eps / m for m, eps in best.items())


def _reference(name: str, entry) -> OptimalReference:
    where = f"optimal teacher's reference for {name!r}"
    try:
        experiment = int(entry["experiment"])
        td = entry["td"]
        fewest, proven, efficacy, eta = {}, {}, {}, {}
        for key in ("0.9", "1"):
            item = td[key]
            n = item["n_demos"]
            if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
                raise InvalidFileError(f"{where}: TD_{key} must be a whole number >= 1")
            fewest[key] = n
            proven[key] = bool(item["exact"])
            efficacy[key] = None if n is None else float(item["efficacy"][-1])
            eta[key] = None if n is None else float(item["eta"][RULES[experiment]])
        best_pair = entry["pairs"]["best_efficacy"]
        best_single = float(entry["greedy"]["best_single"])
        path = tuple(float(e) for e in entry["greedy"]["efficacy"])
        picks = tuple(_index(i, where) for i in entry["greedy"].get("indices", ()))
        n_conditions = _index(entry.get("n_conditions", 0), where)
    except (KeyError, TypeError, IndexError, ValueError) as exc:
        raise InvalidFileError(
            f"the {where} is incomplete ({exc!r}); regenerate the file with "
            "python -m tutor.study.optimal --out tutor/assets/optimal.json"
        ) from exc
    if experiment not in RULES or not finite_number(best_pair):
        raise InvalidFileError(f"the {where} has an unknown experiment or a bad pair bound")
    if n_conditions and any(i >= n_conditions for i in picks):
        raise InvalidFileError(f"the {where} picks a condition beyond its {n_conditions}")
    return OptimalReference(
        name,
        experiment,
        fewest,
        proven,
        efficacy,
        eta,
        float(best_pair),
        best_single,
        path,
        picks,
        n_conditions,
    )


def _index(value, where: str) -> int:
    """A whole number >= 0 of the reference (a condition's index, or how many there are)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise InvalidFileError(f"the {where} holds {value!r} where a whole number >= 0 belongs")
    return value


def load_references(path=None) -> dict[str, OptimalReference]:
    """Every task's reference in the file (default: the bundled ``optimal.json``).

    Raises
    ------
    InvalidFileError
        The file is missing, not the optimal teacher's JSON, or incomplete.
    """
    path = REFERENCE_PATH if path is None else Path(path)
    data = read_json(path, "optimal teacher's reference")
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise InvalidFileError(f"{path} is not the optimal teacher's reference ({FORMAT})")
    if data.get("version") != VERSION:
        raise InvalidFileError(
            f"{path} is version {data.get('version')!r} of {FORMAT}, this tutor reads "
            f"version {VERSION}: regenerate it with python -m tutor.study.optimal"
        )
    tasks = data.get("tasks")
    if not isinstance(tasks, dict):
        raise InvalidFileError(f"{path} holds no tasks")
    return {name: _reference(name, entry) for name, entry in tasks.items()}


@lru_cache(maxsize=1)
def _bundled() -> dict[str, OptimalReference]:
    return load_references()


def optimal_reference(task: str) -> OptimalReference | None:
    """The bundled reference for ``task`` ("maze" or "pickplace"), or None if it has none."""
    return _bundled().get(task)
