"""Assigning a between-subjects experiment's conditions to a class: the class plan.

Experiment 2 is between subjects: each trainee teaches in one condition, and the paper
had 9 trainees per condition. An educator says who gets which condition in a *class
plan*, a CSV or JSON file named by ``TUTOR_CLASS_PLAN`` in the environment of each
trainee's notebook server. The plan may name a condition for a trainee, or say
"balanced": the tutor then deals the conditions out evenly. (``TUTOR_CONDITION``, read
by the start form, fixes one condition for a whole server and wins over the plan.)

This module knows conditions only as strings: the caller passes the experiment's
conditions (e.g. ``("NF", "RF", "BF", "SF")``).

Trainees are matched by their folder key (:func:`tutor.runtime.trainee_key`), the same
key that names their run folder: ``"Zoë "``, ``"Zoë"`` and ``"Zoe\\u0308"`` (NFD) are one
trainee, while ``"Mai Anh"`` and ``"Mai_Anh"`` are two.

CSV format (``*.csv``, UTF-8; ``,`` ``;`` or tab separated, as found in the header)::

    trainee,condition
    Mai Anh,RF
    Zoë,balanced
    Ana,

The header names a ``trainee`` column and, optionally, a ``condition`` column (in any
order, any case; other columns, e.g. an e-mail address, are ignored). A condition is
one of the experiment's conditions (any case), or ``balanced`` or blank: balanced.
A name holding the separator must be in double quotes (``"Smith, Jo",SF``). Blank lines
are skipped. A file with only a ``trainee`` column is a roster, balanced throughout.

An optional ``hand`` column says who moves the arm in Experiment 2 (the hands are
:data:`tutor.views.hand.HANDS`): ``own``, the trainee guides it themself, or ``guided``,
the tutor guides it for them (e.g. for a trainee who cannot use a mouse or keyboard);
blank is not set (the trainee may choose on the start form)::

    trainee,condition,hand
    Mai Anh,RF,guided
    Zoë,balanced,

JSON format (``*.json``)::

    {"format": "lfd-tutor-class-plan", "version": 1, "experiment": 2,
     "assign": "balanced",
     "trainees": ["Mai Anh", "Zoë", "Ana"]}

``assign`` is ``"balanced"`` or an object mapping names to a condition or
``"balanced"``; ``trainees`` (optional) is the class roster, and a roster name that
``assign`` does not mention is balanced. ``hands`` (optional) maps names to a hand
(``{"Mai Anh": "guided"}``; ``""`` is not set).

This module knows hands only as strings too: the caller passes the hands to check the
column against (``hands=``); without them the column is ignored, like any other column.

How "balanced" deals. Each trainee to balance is ranked by a stable hash (SHA-256) of
their folder key; in that order each takes the condition with the fewest trainees so
far (those the plan names a condition for counted too; ties in the experiment's order
of conditions). Without named conditions this is round-robin, so 36 balanced trainees
get exactly 9 per condition, whatever order the file lists them in. (A hash alone, key
mod 4, would give 9 each only with the multinomial probability
36! / (9!^4 4^36) = 0.45 %, about 1 class in 220.) A trainee whom the plan does not list
at all gets the condition ``hash mod k`` of their key (k conditions), and the start
form says so.

Keep the roster fixed once trainees have started: dealing depends on the whole roster,
so adding or removing a name may move others to another condition.

Every problem with a plan (unreadable, not a plan, a wrong header, an unknown
condition or hand, one trainee listed twice with two conditions or hands, a bad name) raises
:class:`~tutor.errors.InvalidPlanError`, whose message names the file and the line or
entry and says how to fix it. Files are read with :mod:`tutor.fileio` (size-limited,
JSON only, never pickle).
"""

from __future__ import annotations

import csv
import hashlib
import io
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InvalidFileError, InvalidPlanError, TutorError
from ..fileio import read_json, read_text
from ..runtime import normalise_name, trainee_key

__all__ = [
    "Assignment",
    "ClassPlan",
    "load_plan",
    "plan_from_env",
    "hash_rank",
    "PLAN_ENV",
    "PLAN_FORMAT",
    "PLAN_VERSION",
    "BALANCED",
]

#: the environment variable naming the class plan file
PLAN_ENV = "TUTOR_CLASS_PLAN"
#: the JSON plan's ``format`` field
PLAN_FORMAT = "lfd-tutor-class-plan"
PLAN_VERSION = 1
#: the word (or a blank cell) asking the tutor to balance the conditions
BALANCED = "balanced"

#: how a trainee got their condition
LISTED, DEALT, HASHED = "listed", "balanced", "hashed"
_SEPARATORS = (",", ";", "\t")


def hash_rank(key: str) -> int:
    """A stable number for a trainee's folder key (SHA-256, the same on every machine)."""
    return int.from_bytes(hashlib.sha256(key.encode("utf-8")).digest(), "big")


@dataclass(frozen=True)
class Assignment:
    """One trainee's condition and why they have it.

    Attributes
    ----------
    trainee : str
        The name as normalised (:func:`tutor.runtime.normalise_name`).
    key : str
        Its folder key.
    condition : str
    how : {"listed", "balanced", "hashed"}
        Named in the plan; dealt from the plan's balanced trainees; not on the plan, so
        ``hash mod k``.
    reason : str
        The same in plain words, to show the trainee, e.g. "your educator's class plan
        assigns you RF".
    hand : str or None
        The hand the plan's ``hand`` column gives the trainee; None when it sets none.
    """

    trainee: str
    key: str
    condition: str
    how: str
    reason: str
    hand: str | None = None


@dataclass(frozen=True)
class ClassPlan:
    """Who teaches in which condition (build with :meth:`from_entries` or :func:`load_plan`).

    Attributes
    ----------
    conditions : tuple of str
        The experiment's conditions, in the order ties are dealt.
    table : dict
        Folder key -> (condition, how) for every trainee the plan lists.
    names : dict
        Folder key -> the name as the plan gives it.
    source : str
        Where the plan came from (a file path), for messages.
    hands : dict
        Folder key -> hand, for the trainees whose ``hand`` the plan sets.
    """

    conditions: tuple[str, ...]
    table: dict
    names: dict
    source: str = "the class plan"
    hands: dict = field(default_factory=dict)

    @classmethod
    def from_entries(
        cls, entries, conditions, source: str = "the class plan", hands=None
    ) -> ClassPlan:
        """A plan from ``(where, name, value)`` or ``(where, name, value, hand)`` entries.

        Parameters
        ----------
        entries : iterable of (str, str, str or None[, str or None])
            ``where`` says where the entry is for messages (e.g. "line 3"); ``value`` is a
            condition (any case), "balanced" or blank (balanced), or None: listed without
            a condition (a roster name), balanced unless another entry names one;
            ``hand`` (optional) one of ``hands`` (any case), or blank or None: not set.
        conditions : sequence of str
            The experiment's conditions.
        source : str
            The plan's file, for messages.
        hands : sequence of str, optional
            The hands a plan may set; None: hands are not read (ignored).

        Raises
        ------
        InvalidPlanError
            A bad name, an unknown condition or hand, or one trainee given two
            conditions or two hands.
        """
        conditions = tuple(conditions)
        if not conditions or len(set(conditions)) != len(conditions):
            raise InvalidPlanError(
                f"a class plan needs the experiment's distinct conditions, got {conditions!r}"
            )
        by_upper = {c.upper(): c for c in conditions}
        wanted: dict[str, tuple[str | None, str]] = {}  # key -> (condition/BALANCED/None, where)
        names: dict[str, str] = {}
        chosen_hands: dict[str, tuple[str, str]] = {}  # key -> (hand, where)
        for entry in entries:
            where, name, value, *rest = entry
            try:
                key = trainee_key(name)
            except TutorError as exc:
                raise InvalidPlanError(f"{source}, {where}: {exc}") from exc
            choice = None if value is None else _condition(value, by_upper, source, where, name)
            hand = _hand(rest[0] if rest else None, hands, source, where, name)
            if hand is not None:
                before = chosen_hands.setdefault(key, (hand, where))
                if before[0] != hand:
                    raise InvalidPlanError(
                        f"{source}: {name!r} ({where}) is given the hand {hand!r}, but "
                        f"{before[1]} gives the same trainee (folder {key}) {before[0]!r}: "
                        "keep one of the two"
                    )
            if key not in wanted or wanted[key][0] is None:
                wanted[key] = (choice, where)
                names.setdefault(key, normalise_name(name))
                continue
            before, before_where = wanted[key]
            if choice is not None and choice != before:
                raise InvalidPlanError(
                    f"{source}: {names[key]!r} ({before_where}) and {name!r} ({where}) are one "
                    f"trainee (folder {key}), given two conditions, {before} and {choice}: "
                    "keep one of the two entries"
                )
        table = {k: (c, LISTED) for k, (c, _) in wanted.items() if c not in (None, BALANCED)}
        counts = {c: 0 for c in conditions}
        for condition, _ in table.values():
            counts[condition] += 1
        to_deal = sorted(
            (k for k, (c, _) in wanted.items() if c in (None, BALANCED)),
            key=lambda k: (hash_rank(k), k),
        )
        for key in to_deal:
            fewest = min(conditions, key=lambda c: counts[c])  # ties: the first in order
            counts[fewest] += 1
            table[key] = (fewest, DEALT)
        return cls(
            conditions=conditions,
            table=table,
            names=names,
            source=source,
            hands={k: h for k, (h, _) in chosen_hands.items()},
        )

    def counts(self) -> dict[str, int]:
        """How many of the plan's trainees teach in each condition."""
        counts = {c: 0 for c in self.conditions}
        for condition, _ in self.table.values():
            counts[condition] += 1
        return counts

    def assign(self, name) -> Assignment:
        """The condition of the trainee called ``name`` (matched by folder key).

        Raises
        ------
        InvalidParameterError
            ``name`` is not a usable name (see :func:`tutor.runtime.normalise_name`).
        """
        trainee = normalise_name(name)
        key = trainee_key(trainee)
        if key in self.table:
            condition, how = self.table[key]
            if how == LISTED:
                reason = f"your educator's class plan assigns you {condition}"
            else:
                n = sum(h == DEALT for _, h in self.table.values())
                reason = (
                    f"your educator's class plan shares the conditions evenly among its {n} "
                    f"trainees and assigns you {condition}"
                )
            return Assignment(trainee, key, condition, how, reason, self.hands.get(key))
        condition = self.conditions[hash_rank(key) % len(self.conditions)]
        if self.table:
            reason = (
                f"you are not on your educator's class plan, so a hash of your name assigns "
                f"you {condition}; if you should be on it (a name typed differently?), tell "
                "your educator"
            )
        else:
            reason = (
                f"your educator's class plan shares the conditions out by a hash of each "
                f"trainee's name, and yours assigns you {condition}"
            )
        return Assignment(trainee, key, condition, HASHED, reason, self.hands.get(key))


def _condition(value, by_upper: dict, source: str, where: str, name) -> str:
    """A plan's condition cell as the experiment's condition, or BALANCED."""
    if not isinstance(value, str):
        raise InvalidPlanError(
            f"{source}, {where}: the condition of {name!r} must be text such as "
            f'"{next(iter(by_upper.values()))}" or "{BALANCED}", got {value!r}'
        )
    text = value.strip()
    if not text or text.lower() == BALANCED:
        return BALANCED
    if text.upper() in by_upper:
        return by_upper[text.upper()]
    raise InvalidPlanError(
        f"{source}, {where}: {text!r} (for {name!r}) is not a condition of this experiment: "
        f"write one of {', '.join(by_upper.values())}, or {BALANCED!r} (or leave it blank) "
        "to let the tutor balance the conditions"
    )


def _hand(value, hands, source: str, where: str, name) -> str | None:
    """A plan's hand cell as one of ``hands`` (lower case), or None (blank: not set)."""
    if hands is None or value is None:
        return None
    choices = ", ".join(repr(h) for h in hands)
    if not isinstance(value, str):
        raise InvalidPlanError(
            f"{source}, {where}: the hand of {name!r} must be text, one of {choices} (or "
            f"blank), got {value!r:.40}"
        )
    text = value.strip()
    if not text:
        return None
    if text.lower() in hands:
        return text.lower()
    raise InvalidPlanError(
        f"{source}, {where}: {text[:40]!r} (the hand of {name!r}) is not a hand: write one "
        f"of {choices}, or leave it blank to let the trainee choose"
    )


# --------------------------------------------------------------------- reading files


def load_plan(path, conditions, experiment: int = 2, hands=None) -> ClassPlan:
    """Read a class plan file (``.csv`` or ``.json``, see the module docstring).

    Parameters
    ----------
    path : str or Path
    conditions : sequence of str
        The experiment's conditions.
    experiment : int
        The experiment the plan is for (a JSON plan's ``experiment`` must match).
    hands : sequence of str, optional
        The hands the ``hand`` column may name (None: the column is ignored).

    Raises
    ------
    InvalidPlanError
        The file cannot be read or is not a valid plan; the message says why and how
        to fix it.
    """
    source = f"the class plan {os.fspath(path) if isinstance(path, (str, os.PathLike)) else path}"
    suffix = Path(path).suffix.lower() if isinstance(path, (str, os.PathLike)) else ""
    if suffix not in (".csv", ".json"):
        raise InvalidPlanError(
            f"{source} must be a .csv file (header trainee,condition) or a .json file "
            f'(format "{PLAN_FORMAT}"): rename it or point {PLAN_ENV} at such a file'
        )
    try:
        if suffix == ".csv":
            entries = _csv_entries(read_text(path, "class plan"), source)
        else:
            entries = _json_entries(read_json(path, "class plan"), source, experiment)
    except InvalidPlanError:
        raise
    except InvalidFileError as exc:
        raise InvalidPlanError(str(exc)) from exc
    return ClassPlan.from_entries(entries, conditions, source=source, hands=hands)


def plan_from_env(conditions, experiment: int = 2, hands=None) -> ClassPlan | None:
    """The plan named by ``TUTOR_CLASS_PLAN``, or None when it is unset.

    Raises
    ------
    InvalidPlanError
        As :func:`load_plan`; the message adds that ``TUTOR_CLASS_PLAN`` names the file.
    """
    path = os.environ.get(PLAN_ENV, "").strip()
    if not path:
        return None
    try:
        return load_plan(path, conditions, experiment, hands)
    except InvalidPlanError as exc:
        raise InvalidPlanError(
            f"{exc} ({PLAN_ENV} names this file; unset it to let trainees choose)"
        ) from exc


def _csv_entries(text: str, source: str) -> list[tuple]:
    lines = text.splitlines()
    first = next((i for i, line in enumerate(lines) if line.strip()), None)
    if first is None:
        raise InvalidPlanError(
            f"{source} is empty: write a header line trainee,condition and then one line "
            "per trainee"
        )
    header_line = lines[first]
    sep = next((s for s in _SEPARATORS if s in header_line), ",")
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=sep, strict=True)
    rows = []
    try:
        rows.extend(reader)
    except csv.Error as exc:
        raise InvalidPlanError(
            f"{source}, line {reader.line_num} is not readable as CSV ({exc}): a name in "
            'double quotes must end with a closing quote, e.g. "Smith, Jo"'
        ) from exc
    header = [cell.strip().lower() for cell in rows[first]]
    if "trainee" not in header or len(set(header)) != len(header):
        raise InvalidPlanError(
            f"{source}: the first line is {header_line.strip()[:80]!r}, but it must be the "
            "header trainee,condition (a 'trainee' column, optionally a 'condition' column, "
            "each once)"
        )
    name_at = header.index("trainee")
    condition_at = header.index("condition") if "condition" in header else None
    hand_at = header.index("hand") if "hand" in header else None
    entries = []
    for number, row in enumerate(rows[first + 1 :], start=first + 2):
        if not any(cell.strip() for cell in row):
            continue
        where = f"line {number}"
        if len(row) > len(header):
            raise InvalidPlanError(
                f"{source}, {where} has {len(row)} cells but the header has {len(header)}: "
                f'a name holding {sep!r} must be in double quotes, e.g. "Smith{sep} Jo"'
            )
        name = row[name_at] if name_at < len(row) else ""
        if not name.strip():
            raise InvalidPlanError(f"{source}, {where} has no trainee name: add one or remove it")
        value = row[condition_at] if condition_at is not None and condition_at < len(row) else ""
        hand = row[hand_at] if hand_at is not None and hand_at < len(row) else None
        entries.append((where, name, value, hand))
    return entries


def _json_entries(data, source: str, experiment: int) -> list[tuple]:
    example = (
        f'{{"format": "{PLAN_FORMAT}", "version": {PLAN_VERSION}, "experiment": {experiment}, '
        f'"assign": "{BALANCED}", "trainees": ["Mai Anh", "Zoë"]}}'
    )
    if not isinstance(data, dict) or data.get("format") != PLAN_FORMAT:
        raise InvalidPlanError(
            f'{source} is not a class plan (it needs "format": "{PLAN_FORMAT}"), e.g. {example}'
        )
    if data.get("version") != PLAN_VERSION:
        raise InvalidPlanError(
            f"{source} is version {data.get('version')!r} of the class plan; this tutor reads "
            f"version {PLAN_VERSION}: update the tutor, or write the plan as version 1"
        )
    fields = ("format", "version", "experiment", "assign", "trainees", "hands")
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise InvalidPlanError(
            f"{source} holds fields a class plan does not have: {', '.join(unknown)}; "
            f"remove them (the fields are {', '.join(fields)})"
        )
    if data.get("experiment") != experiment:
        raise InvalidPlanError(
            f"{source} is for experiment {data.get('experiment')!r}, not {experiment}: only "
            "Experiment 2 assigns conditions (in Experiment 1 every trainee teaches NF, VF "
            f'and VR); write "experiment": {experiment}'
        )
    assign = data.get("assign", BALANCED)
    roster = data.get("trainees", [])
    if not isinstance(roster, list):
        raise InvalidPlanError(
            f'{source}: "trainees" must be a list of names, e.g. ["Mai Anh", "Zoë"]'
        )
    hands = data.get("hands", {})
    if not isinstance(hands, dict):
        raise InvalidPlanError(
            f'{source}: "hands" must be an object of names and hands, e.g. '
            f'{{"Mai Anh": "guided"}}; got {type(hands).__name__}'
        )
    entries: list[tuple] = []
    if isinstance(assign, dict):
        entries += [(f'"assign" entry {name!r}', name, value) for name, value in assign.items()]
    elif assign != BALANCED:
        raise InvalidPlanError(
            f'{source}: "assign" must be "{BALANCED}" or an object of names and conditions, '
            f'e.g. {{"Mai Anh": "RF", "Zoë": "{BALANCED}"}}; got {assign!r}'
        )
    for k, name in enumerate(roster):
        if not isinstance(name, str):
            raise InvalidPlanError(
                f'{source}: entry {k} of "trainees" must be a name in quotes, got {name!r}'
            )
        entries.append((f'"trainees" entry {k}', name, None))
    entries += [(f'"hands" entry {name!r}', name, None, hand) for name, hand in hands.items()]
    return entries
