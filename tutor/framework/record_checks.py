"""Checks of a run record read back: each JSON value, and its events against its attempts.

:meth:`tutor.framework.record.RunRecord.from_dict` and the ``from_dict`` of its parts
(:mod:`.record_parts`) read every value through these checks: a value of the wrong kind,
out of range or not written the way the tutor writes it is refused with an
:class:`~tutor.errors.InvalidFileError` naming where it is in the file (``run record,
attempts[0].demos[2].seconds: ...``) and what to do. :func:`_check_history` then replays
the record's events against its attempts, so a file whose history contradicts its demos
is refused, never resumed.

The helpers are private to the run record's modules (hence their leading underscore).
"""

from __future__ import annotations

import math
import re
import uuid
from datetime import UTC, datetime

from ..errors import InvalidFileError
from ..runtime import safe_text

#: a run id: 32 hex digits or a canonical UUID string
RUN_ID = re.compile(r"[0-9a-fA-F]{32}|[0-9a-fA-F]{8}(-[0-9a-fA-F]{4}){3}-[0-9a-fA-F]{12}")
#: events that begin a new attempt (``load`` also happens inside one)
_BEGINS = ("start", "reset", "load", "restore")
#: events that change no demo count
_KEEPS_COUNT = ("start", "test", "spend", "finish")
#: a wall clock set back by less than this (an NTP correction) is not time going backwards
CLOCK_SLACK_SECONDS = 1.0


def _where(path: str) -> str:
    return f"run record, {path}" if path else "run record"


def _fail(path: str, what: str):
    raise InvalidFileError(
        f"{_where(path)}: {what}. The file may have been edited by hand or written by "
        "another program; open the original file or start a new run."
    )


def _obj(data, path: str, required: tuple[str, ...], optional: tuple[str, ...] = ()) -> dict:
    if not isinstance(data, dict):
        _fail(path, f"must be an object, got {type(data).__name__}")
    missing = [k for k in required if k not in data]
    if missing:
        _fail(path, f"has no {', '.join(repr(k) for k in missing)}")
    unknown = sorted(set(data) - set(required) - set(optional))
    if unknown:
        _fail(path, f"has unknown entries {', '.join(repr(k) for k in unknown)}")
    return data


def _str(value, path: str, choices=None) -> str:
    """Text of a record, made safe to write and print (lone surrogates, as a JSON
    ``\\udcff`` gives them, become U+FFFD: :func:`tutor.runtime.safe_text`)."""
    if not isinstance(value, str):
        _fail(path, f"must be text, got {type(value).__name__}")
    if choices is not None and value not in choices:
        _fail(path, f"must be one of {', '.join(repr(c) for c in choices)}, got {value!r}")
    return safe_text(value)


def _bool(value, path: str) -> bool:
    if not isinstance(value, bool):
        _fail(path, f"must be true or false, got {value!r}")
    return value


def _int(value, path: str, low: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        _fail(path, f"must be a whole number >= {low}, got {value!r}")
    return value


def _num(value, path: str, low: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        _fail(path, f"must be a number, got {type(value).__name__}")
    try:
        value = float(value)
    except OverflowError:
        _fail(path, "is a number too large for the tutor")
    if not math.isfinite(value) or (low is not None and value < low):
        bound = "" if low is None else f" >= {low:g}"
        _fail(path, f"must be a finite number{bound}, got {value!r}")
    return value


def _list(value, path: str) -> list:
    if not isinstance(value, list):
        _fail(path, f"must be a list, got {type(value).__name__}")
    return value


def _numbers(value, path: str) -> tuple[float, ...]:
    return tuple(_num(v, f"{path}[{i}]") for i, v in enumerate(_list(value, path)))


def _table(value, path: str) -> tuple[tuple[float, ...], ...]:
    """A non-empty table of numbers, the same number of columns in every row."""
    rows = _list(value, path)
    table = tuple(_numbers(r, f"{path}[{i}]") for i, r in enumerate(rows))
    if not table or len({len(r) for r in table}) != 1 or not table[0]:
        _fail(path, "must be a table of numbers with the same columns in each row")
    return table


def _indices(value, path: str) -> tuple[int, ...]:
    return tuple(_int(v, f"{path}[{i}]") for i, v in enumerate(_list(value, path)))


def _stamp(value, path: str) -> str:
    text = _str(value, path)
    try:
        datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        _fail(path, f"must be a date and time like 2026-12-01T09:14:03.123Z, got {text!r}")
    return text


def _moment(text: str) -> datetime:
    """A checked stamp as an aware datetime (a stamp without a zone is UTC)."""
    moment = datetime.fromisoformat(text.replace("Z", "+00:00"))
    return moment if moment.tzinfo is not None else moment.replace(tzinfo=UTC)


def _check_history(record) -> None:
    """Refuse a record whose events contradict each other or its attempts.

    Replays the events: their times never go backwards (by more than
    :data:`CLOCK_SLACK_SECONDS`); each names the attempt in progress or begins the next
    one (a reset, a Load that replaces the run, a restore); each event's demo count
    follows from the one before (an add one more, an undo one fewer, a test, spend or
    finish the same); a finish is in a finished attempt and no demo is added or taken
    back after it, except one undo after a finish by the clock (``detail`` "time",
    Experiment 2's cap); and the counts end where the attempts' stored demos do.
    """
    events = record.events
    if not events:
        return
    attempts = record.attempts
    current, count, finished = 0, 0, False
    cap_undo = False  # the one undo allowed after the cap ended the attempt is still due
    ends: dict[int, int] = {}
    last = None
    for i, e in enumerate(events):
        where = f"events[{i}]"
        moment = _moment(e.at)
        if last is not None and (last - moment).total_seconds() > CLOCK_SLACK_SECONDS:
            _fail(where, f"is stamped {e.at}, before the event ahead of it: time goes backwards")
        last = moment if last is None else max(last, moment)
        if e.attempt < current:
            _fail(where, f"names attempt {e.attempt + 1} after attempt {current + 1} began")
        if e.attempt > current + 1 or (i == 0 and e.attempt > 0):
            _fail(where, f"names attempt {e.attempt + 1}, but attempt {current + 1} was the last")
        if e.attempt == current + 1:
            if e.kind not in _BEGINS:
                _fail(where, f"a {e.kind!r} cannot begin attempt {e.attempt + 1}")
            if e.kind in ("start", "reset") and e.n_demos != 0:
                _fail(where, f"a {e.kind!r} begins an empty attempt, not one of {e.n_demos} demos")
            current, count, finished = e.attempt, e.n_demos, False
            ends[current] = count
            continue
        if e.kind in ("reset", "restore"):
            _fail(where, f"a {e.kind!r} must begin a new attempt, not be in attempt {current + 1}")
        if finished and e.kind == "undo" and cap_undo:
            cap_undo = False
        elif finished and e.kind in ("add", "undo", "load"):
            _fail(where, f"an {e.kind!r} after attempt {current + 1} was finished")
        expected = {"add": count + 1, "undo": count - 1}.get(e.kind, count)
        if e.kind == "load" and e.n_demos >= count:
            expected = e.n_demos  # the demos of a file, added all at once
        if e.n_demos != expected or expected < 0:
            _fail(
                where,
                f"an {e.kind!r} event claims {e.n_demos} demo(s) in attempt {current + 1}, "
                f"which held {count} before it",
            )
        if e.kind == "finish":
            if not attempts[current].finished:
                _fail(where, f"finishes attempt {current + 1}, which is not finished")
            finished, cap_undo = True, e.detail == "time"
        count = e.n_demos
        ends[current] = count
    if current != len(attempts) - 1:
        _fail("events", f"end in attempt {current + 1} of the record's {len(attempts)}")
    for k, n in ends.items():
        if attempts[k].n_demos != n:
            _fail(
                "events",
                f"count {n} demo(s) in attempt {k + 1}, but it holds {attempts[k].n_demos}",
            )


def _run_id(value, path: str) -> str | None:
    """A run id: 32 hex digits or a canonical UUID string (None: an old record without one)."""
    if value is None:
        return None
    if isinstance(value, str) and RUN_ID.fullmatch(value):
        return value.replace("-", "").lower()
    _fail(path, f"must be 32 hex digits or a UUID like {uuid.UUID(int=0)}, found {value!r}")


def record_start(attempts: list):
    """When a record without a ``created`` stamp began: its first attempt's start."""
    first = attempts[0] if attempts else None
    return first.get("started") if isinstance(first, dict) else None
