r"""The run record: everything one teaching run holds, typed and versioned.

A *run* is one trainee teaching one task under one feedback condition (Sena & Howard,
"Experiment 1" and "Experiment 2"). Its record is what is saved, resumed, collected by
an educator and read back by the class analysis. It holds:

- who taught (:class:`Trainee`: the display name and the folder key derived from it),
  the experiment, the task, the condition and the run number (Experiment 2 has three);
- every *attempt*: Reset, or a Load that replaces the run, starts a new attempt and
  keeps the old one, so nothing a trainee did is ever deleted (:class:`Attempt`);
- in each attempt the demonstration set :math:`b` in order (:class:`Demo`: the samples,
  the condition it was meant for, what the trainee asked to see (SF) or the selector
  picked (AF), its cost on the Experiment 2 clock, whether it followed VR's rule or HF's hint), the
  robot tests asked for (:class:`Test`), other clock time and the finished flag;
- every event in order (:class:`Event`: add, undo, load, reset, test, finish, ...), with a
  wall-clock stamp;
- whether it was a practice run (the class analysis leaves those out) and the version
  of the tool that wrote it.

A record read back is checked whole: besides every field, its events are replayed
against its attempts (times never go backwards, demo counts follow from event to event
and end at the demos stored, a finish only in a finished attempt), so a file whose history
contradicts its demos is refused, never resumed.

The record is immutable (frozen dataclasses of tuples): a change makes a new record with
:func:`dataclasses.replace`, so an old value can be kept while a new one is tried (all or
nothing). :meth:`RunRecord.to_dict` and :meth:`RunRecord.from_dict` are the one way to
and from JSON; ``run_record.schema.json`` beside this module publishes the same format
as a JSON Schema, and the tests hold the two in agreement.

The learner's state (:math:`\lambda`, :math:`\hat R` and the feedback after each demo) is
not stored: it is recomputed by replaying the demos (:mod:`tutor.framework.run`).
"""

from __future__ import annotations

import math
import re
import uuid
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime

import numpy as np

from ..errors import InvalidFileError, InvalidParameterError
from ..limits import MAX_RECORDING_SAMPLES
from ..runtime import default_trainee, normalise_name, safe_text, trainee_key

__all__ = [
    "RECORD_FORMAT",
    "RECORD_VERSION",
    "SUPPORTED_VERSIONS",
    "EVENT_KINDS",
    "HOW_GIVEN",
    "check_given",
    "round_recording",
    "Trainee",
    "CODE_TRAINEE",
    "Demo",
    "Test",
    "Event",
    "Attempt",
    "RunRecord",
    "utc_now",
    "tool_version",
]

RECORD_FORMAT = "lfd-tutor-run"
#: a trainee's folder key (see :func:`tutor.runtime.trainee_key`)
_KEY = re.compile(r"[a-z0-9][a-z0-9-]{0,63}")
RUN_ID = re.compile(r"[0-9a-fA-F]{32}|[0-9a-fA-F]{8}(-[0-9a-fA-F]{4}){3}-[0-9a-fA-F]{12}")
RECORD_VERSION = 1
SUPPORTED_VERSIONS = (1,)

#: what a trainee (or the tutor on their behalf) can do in a run
EVENT_KINDS = (
    "start",  # the run (or a new attempt) began
    "add",  # a demonstration was added
    "undo",  # the latest demonstration was taken back
    "load",  # demonstrations came from a file
    "reset",  # a new, empty attempt replaced the current one (the old one is kept)
    "restore",  # an earlier attempt was brought back as a new attempt
    "test",  # the robot tried chosen test conditions
    "spend",  # clock time besides demos and robot attempts (Experiment 2)
    "finish",  # the trainee ended the run
)
#: how a demonstration was given: the trainee's own hand on the arm, the tutor guiding
#: the arm for them, loaded from a file, drawn (the maze's sketchpad), or a simulated
#: teacher's; "" is an old record that did not say
HOW_GIVEN = ("own", "guided", "loaded", "drawn", "simulated")
#: decimals a stored recording keeps per column: t to 1 ms, x, y, z to 0.1 mm, g to 0.001
RECORDING_DECIMALS = (3, 4, 4, 4, 3)


def check_given(value) -> str:
    """How a demo was given (one of :data:`HOW_GIVEN`, or "" for unknown), or a named error."""
    if not isinstance(value, str) or (value and value not in HOW_GIVEN):
        raise InvalidParameterError(
            f"how a demonstration was given must be one of {', '.join(map(repr, HOW_GIVEN))}, "
            f"got {value!r}"
        )
    return value


def round_recording(recording) -> tuple[tuple[float, ...], ...]:
    """A raw recording (T, C) as the rows a record stores, each column rounded by
    :data:`RECORDING_DECIMALS` (columns beyond them keep 4 decimals)."""
    a = np.asarray(recording, dtype=float)
    decimals = [
        RECORDING_DECIMALS[j] if j < len(RECORDING_DECIMALS) else 4 for j in range(a.shape[1])
    ]
    rounded = np.column_stack([np.round(a[:, j], d) for j, d in enumerate(decimals)])
    return tuple(tuple(row) for row in rounded.tolist())


#: why an attempt ended
END_REASONS = ("", "reset", "load", "restore")
#: events that begin a new attempt (``load`` also happens inside one)
_BEGINS = ("start", "reset", "load", "restore")
#: events that change no demo count
_KEEPS_COUNT = ("start", "test", "spend", "finish")
#: a wall clock set back by less than this (an NTP correction) is not time going backwards
CLOCK_SLACK_SECONDS = 1.0


def utc_now() -> str:
    """The wall clock as an ISO 8601 UTC stamp, e.g. ``2026-12-01T09:14:03.123Z``."""
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


def tool_version() -> str:
    from .. import __version__

    return __version__


# ---------------------------------------------------------------- checks of loaded values


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


# ---------------------------------------------------------------- the record's parts


#: the name of a run made from code without one (tests, scripts): never a typed name
CODE_TRAINEE = "trainee"


@dataclass(frozen=True)
class Trainee:
    """Who taught: the name as typed (NFC-normalised) and the folder key derived from it."""

    name: str
    key: str

    @classmethod
    def from_name(cls, name=None) -> Trainee:
        """The trainee called ``name``, with the folder key :func:`tutor.runtime.trainee_key`
        derives.

        ``name`` None (a run made from code without a name) is
        :func:`tutor.runtime.default_trainee`'s name (``TUTOR_TRAINEE``, or
        ``JUPYTERHUB_USER`` on a hub), else :data:`CODE_TRAINEE`. A blank or empty name is
        refused; the start form never passes None (it asks for a name instead).
        """
        if name is None:
            name = default_trainee() or CODE_TRAINEE
        text = normalise_name(name)
        return cls(text, trainee_key(text))

    def to_dict(self) -> dict:
        return {"name": self.name, "key": self.key}

    @classmethod
    def from_dict(cls, data, path: str = "trainee") -> Trainee:
        d = _obj(data, path, ("name", "key"))
        name, key = _str(d["name"], f"{path}.name"), _str(d["key"], f"{path}.key")
        try:
            clean = normalise_name(name)
        except InvalidParameterError as exc:
            _fail(f"{path}.name", str(exc))
        if clean != name:
            _fail(f"{path}.name", "is not written the way the tutor writes names")
        if not _KEY.fullmatch(key):
            _fail(f"{path}.key", "must be lower-case letters, digits and '-' (at most 64)")
        return cls(name, key)


@dataclass(frozen=True)
class Demo:
    """One demonstration of the set :math:`b`.

    Attributes
    ----------
    samples : tuple of tuple of float
        The demonstration as the task preprocessed it, one row per sample (time first).
    condition : tuple of float or None
        The test condition it was meant for (e.g. the plant chosen); None when the task
        reads it off the demo.
    shown : tuple of int or None
        SF: the test conditions the trainee asked to see after it; AF (an "adaptive"
        condition): the conditions the selector picked after it, in the order picked;
        None otherwise.
    seconds : float or None
        Experiment 2: what the demo cost on the clock (its duration).
    followed_rule : bool or None
        Whether it followed the advice in force when it was given: VR's rule
        compliance (it started inside the rules' circle), or HF's hint following (it
        went to the plant the next-demo hint named); None in the other conditions.
    chosen_by : str
        Simulated teachers: why this condition was chosen ("plan", "red", "rule 2", ...).
    mistake : str
        A mistake made on purpose or by a simulated hand ("wrong_plant", "sloppy_grab",
        "slip"); "" for none.
    given : str
        How it was given (:data:`HOW_GIVEN`): "own" (the trainee's hand guided the arm),
        "guided" (the tutor guided the arm for them), "loaded", "drawn" or "simulated";
        "" in records written before the tutor kept it.
    recording : tuple of tuple of float or None
        The raw recording as it came from the hand (an own-hand demo's (T, 5) t, x, y,
        z, g, rounded by :data:`RECORDING_DECIMALS`); None when there is none.
    """

    samples: tuple[tuple[float, ...], ...]
    condition: tuple[float, ...] | None = None
    shown: tuple[int, ...] | None = None
    seconds: float | None = None
    followed_rule: bool | None = None
    chosen_by: str = ""
    mistake: str = ""
    given: str = ""
    recording: tuple[tuple[float, ...], ...] | None = None

    def to_dict(self) -> dict:
        return {
            "samples": [list(r) for r in self.samples],
            "condition": None if self.condition is None else list(self.condition),
            "shown": None if self.shown is None else list(self.shown),
            "seconds": self.seconds,
            "followed_rule": self.followed_rule,
            "chosen_by": self.chosen_by,
            "mistake": self.mistake,
            "given": self.given,
            "recording": None if self.recording is None else [list(r) for r in self.recording],
        }

    @classmethod
    def from_dict(cls, data, path: str) -> Demo:
        d = _obj(
            data,
            path,
            ("samples",),
            (
                "condition",
                "shown",
                "seconds",
                "followed_rule",
                "chosen_by",
                "mistake",
                "given",
                "recording",
            ),
        )
        samples = _table(d["samples"], f"{path}.samples")
        recording = d.get("recording")
        if recording is not None:
            rows = _list(recording, f"{path}.recording")
            if len(rows) > MAX_RECORDING_SAMPLES:
                _fail(
                    f"{path}.recording",
                    f"holds {len(rows)} samples, more than the {MAX_RECORDING_SAMPLES} a "
                    "recording may have",
                )
            recording = _table(rows, f"{path}.recording")
        cond = d.get("condition")
        shown = d.get("shown")
        seconds = d.get("seconds")
        rule = d.get("followed_rule")
        return cls(
            samples=samples,
            condition=None if cond is None else _numbers(cond, f"{path}.condition"),
            shown=None if shown is None else _indices(shown, f"{path}.shown"),
            seconds=None if seconds is None else _num(seconds, f"{path}.seconds", 0.0),
            followed_rule=None if rule is None else _bool(rule, f"{path}.followed_rule"),
            chosen_by=_str(d.get("chosen_by", ""), f"{path}.chosen_by"),
            mistake=_str(d.get("mistake", ""), f"{path}.mistake"),
            given=_str(d.get("given", ""), f"{path}.given", ("", *HOW_GIVEN)),
            recording=recording,
        )


@dataclass(frozen=True)
class Test:
    """The robot tried ``plants`` (indices into B^) after demo ``after_demo``."""

    after_demo: int
    plants: tuple[int, ...]
    after_run: bool = False

    def to_dict(self) -> dict:
        return {
            "after_demo": self.after_demo,
            "plants": list(self.plants),
            "after_run": self.after_run,
        }

    @classmethod
    def from_dict(cls, data, path: str) -> Test:
        d = _obj(data, path, ("after_demo", "plants"), ("after_run",))
        return cls(
            _int(d["after_demo"], f"{path}.after_demo"),
            _indices(d["plants"], f"{path}.plants"),
            _bool(d.get("after_run", False), f"{path}.after_run"),
        )


@dataclass(frozen=True)
class Event:
    """One thing that happened, stamped with the wall clock.

    ``n_demos`` is the number of demos in the attempt after the event; ``attempt`` the
    attempt it happened in (0-based; a reset, a Load that replaces the run and a restore
    name the attempt they begin); ``detail`` a short note (a file's name, a number).
    """

    kind: str
    at: str
    attempt: int
    n_demos: int
    detail: str = ""

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "at": self.at,
            "attempt": self.attempt,
            "n_demos": self.n_demos,
            "detail": self.detail,
        }

    @classmethod
    def from_dict(cls, data, path: str) -> Event:
        d = _obj(data, path, ("kind", "at", "attempt", "n_demos"), ("detail",))
        return cls(
            _str(d["kind"], f"{path}.kind", EVENT_KINDS),
            _stamp(d["at"], f"{path}.at"),
            _int(d["attempt"], f"{path}.attempt"),
            _int(d["n_demos"], f"{path}.n_demos"),
            _str(d.get("detail", ""), f"{path}.detail"),
        )


@dataclass(frozen=True)
class Attempt:
    """One go at the run: its demos, robot tests, clock time and whether it was finished.

    ``demos`` is the demonstration set b as it stands; ``undone`` the demos taken back
    with Undo, oldest first (kept, never deleted). ``other_seconds`` is Experiment 2 clock
    time besides the demos and the robot's attempts (setting up, and the time of demos
    taken back). ``stopped`` says why teaching stopped ("finish": the trainee pressed
    Finish; "time": the clock ran out; a simulated teacher's "satisfied" or "patience").
    ``ended`` says why a later attempt replaced this one ("" for the current attempt, or
    "reset", "load", "restore").
    """

    started: str
    demos: tuple[Demo, ...] = ()
    undone: tuple[Demo, ...] = ()
    tests: tuple[Test, ...] = ()
    other_seconds: float = 0.0
    finished: bool = False
    stopped: str = ""
    ended: str = ""

    @property
    def n_demos(self) -> int:
        return len(self.demos)

    def to_dict(self) -> dict:
        return {
            "started": self.started,
            "demos": [d.to_dict() for d in self.demos],
            "undone": [d.to_dict() for d in self.undone],
            "tests": [t.to_dict() for t in self.tests],
            "other_seconds": self.other_seconds,
            "finished": self.finished,
            "stopped": self.stopped,
            "ended": self.ended,
        }

    @classmethod
    def from_dict(cls, data, path: str) -> Attempt:
        d = _obj(
            data,
            path,
            ("started", "demos"),
            ("undone", "tests", "other_seconds", "finished", "stopped", "ended"),
        )
        demos = _list(d["demos"], f"{path}.demos")
        undone = _list(d.get("undone", []), f"{path}.undone")
        tests = _list(d.get("tests", []), f"{path}.tests")
        attempt = cls(
            started=_stamp(d["started"], f"{path}.started"),
            demos=tuple(Demo.from_dict(x, f"{path}.demos[{i}]") for i, x in enumerate(demos)),
            undone=tuple(
                Demo.from_dict(x, f"{path}.undone[{i}]") for i, x in enumerate(undone)
            ),
            tests=tuple(Test.from_dict(x, f"{path}.tests[{i}]") for i, x in enumerate(tests)),
            other_seconds=_num(d.get("other_seconds", 0.0), f"{path}.other_seconds", 0.0),
            finished=_bool(d.get("finished", False), f"{path}.finished"),
            stopped=_str(d.get("stopped", ""), f"{path}.stopped"),
            ended=_str(d.get("ended", ""), f"{path}.ended", END_REASONS),
        )
        for i, t in enumerate(attempt.tests):
            if t.after_demo > attempt.n_demos:
                _fail(f"{path}.tests[{i}]", f"is after demo {t.after_demo} of {attempt.n_demos}")
        return attempt


@dataclass(frozen=True)
class RunRecord:
    """One trainee's run in one condition: every attempt and every event (see the module).

    Examples
    --------
    >>> rec = RunRecord.new(1, "maze", "VF", Trainee("Zoë", "zoe-3f1c2a9b0d"))
    >>> rec.current.n_demos, rec.finished
    (0, False)
    >>> RunRecord.from_dict(rec.to_dict()) == rec
    True
    """

    experiment: int
    task: str
    condition: str
    trainee: Trainee
    attempts: tuple[Attempt, ...]
    events: tuple[Event, ...] = ()
    run: int = 1
    practice: bool = False
    tool_version: str = field(default_factory=tool_version)
    created: str = field(default_factory=utc_now)
    run_id: str | None = None

    @classmethod
    def new(
        cls,
        experiment: int,
        task: str,
        condition: str,
        trainee: Trainee,
        run: int = 1,
        practice: bool = False,
        at: str | None = None,
    ) -> RunRecord:
        """A run with one empty attempt and its start event."""
        at = utc_now() if at is None else at
        return cls(
            experiment=experiment,
            task=task,
            condition=condition,
            trainee=trainee,
            attempts=(Attempt(started=at),),
            events=(Event("start", at, 0, 0),),
            run=run,
            practice=practice,
            created=at,
            run_id=uuid.uuid4().hex,
        )

    # ------------------------------------------------------------ reading

    @property
    def current(self) -> Attempt:
        """The attempt in progress (the last one)."""
        return self.attempts[-1]

    @property
    def finished(self) -> bool:
        return self.current.finished

    @property
    def label(self) -> str:
        """E.g. "experiment 1, VF run" or "experiment 2, BF run 2", for messages."""
        number = f" {self.run}" if self.experiment == 2 else ""
        practice = " (practice)" if self.practice else ""
        return f"experiment {self.experiment}, {self.condition} run{number}{practice}"

    def same_run(self, other: RunRecord) -> bool:
        """True when ``other`` is a record of the same experiment, condition and run number."""
        return (self.experiment, self.task, self.condition, self.run, self.practice) == (
            other.experiment,
            other.task,
            other.condition,
            other.run,
            other.practice,
        )

    # ------------------------------------------------------------ changing (new records)

    def with_current(self, attempt: Attempt, event: Event | None = None) -> RunRecord:
        """This record with the current attempt replaced (and ``event`` appended)."""
        events = self.events if event is None else (*self.events, event)
        return replace(self, attempts=(*self.attempts[:-1], attempt), events=events)

    def with_new_attempt(self, attempt: Attempt, reason: str, event: Event) -> RunRecord:
        """This record with the current attempt closed (``reason``) and ``attempt`` begun."""
        closed = replace(self.current, ended=reason)
        return replace(
            self,
            attempts=(*self.attempts[:-1], closed, attempt),
            events=(*self.events, event),
        )

    # ------------------------------------------------------------ files

    def to_dict(self) -> dict:
        """JSON-ready form; :meth:`from_dict` gives an equal record back."""
        return {
            "format": RECORD_FORMAT,
            "version": RECORD_VERSION,
            "experiment": self.experiment,
            "task": self.task,
            "condition": self.condition,
            "run": self.run,
            "practice": self.practice,
            "trainee": self.trainee.to_dict(),
            "tool_version": self.tool_version,
            "created": self.created,
            "run_id": self.run_id,
            "attempts": [a.to_dict() for a in self.attempts],
            "events": [e.to_dict() for e in self.events],
        }

    @classmethod
    def from_dict(cls, data) -> RunRecord:
        """Check and read a record (raises InvalidFileError saying what is wrong)."""
        if not isinstance(data, dict) or data.get("format") != RECORD_FORMAT:
            found = data.get("format") if isinstance(data, dict) else None
            hint = (
                " It is a file of an older lfd-tutor (format 'lfd-tutor-session'): open it "
                "with that version, or start a new run."
                if found == "lfd-tutor-session"
                else ""
            )
            raise InvalidFileError(
                f"this is not an lfd-tutor run record (it needs \"format\": "
                f"\"{RECORD_FORMAT}\", found {found!r}).{hint}"
            )
        version = data.get("version")
        if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
            raise InvalidFileError(
                f"run record version {version!r} is not supported; this lfd-tutor reads "
                f"version {', '.join(map(str, SUPPORTED_VERSIONS))}. Update lfd-tutor "
                "(pip install -U lfd-tutor) to open newer files."
            )
        d = _obj(
            data,
            "",
            (
                "format",
                "version",
                "experiment",
                "task",
                "condition",
                "trainee",
                "attempts",
                "events",
            ),
            ("run", "practice", "tool_version", "created", "run_id"),
        )
        attempts = _list(d["attempts"], "attempts")
        if not attempts:
            _fail("attempts", "must hold at least one attempt")
        events = _list(d["events"], "events")
        record = cls(
            experiment=_int(d["experiment"], "experiment", 1),
            task=_str(d["task"], "task"),
            condition=_str(d["condition"], "condition"),
            trainee=Trainee.from_dict(d["trainee"]),
            attempts=tuple(
                Attempt.from_dict(a, f"attempts[{i}]") for i, a in enumerate(attempts)
            ),
            events=tuple(Event.from_dict(e, f"events[{i}]") for i, e in enumerate(events)),
            run=_int(d.get("run", 1), "run", 1),
            practice=_bool(d.get("practice", False), "practice"),
            tool_version=_str(d.get("tool_version", ""), "tool_version"),
            created=_stamp(d.get("created", record_start(attempts)), "created"),
            run_id=_run_id(d.get("run_id"), "run_id"),
        )
        for i, e in enumerate(record.events):
            if e.attempt >= len(record.attempts):
                _fail(f"events[{i}]", f"names attempt {e.attempt + 1} of {len(record.attempts)}")
        _check_history(record)
        return record
