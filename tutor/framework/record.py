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

The record's parts (:class:`Trainee`, :class:`Attempt`, :class:`Demo`, :class:`Test`,
:class:`Event`) live in :mod:`.record_parts` and the checks of a file read back in
:mod:`.record_checks`; the parts are importable from here too.

The learner's state (:math:`\lambda`, :math:`\hat R` and the feedback after each demo) is
not stored: it is recomputed by replaying the demos (:mod:`tutor.framework.run`).
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime

from ..errors import InvalidFileError
from .protocol import EXPERIMENTS
from .record_checks import (
    _bool,
    _check_history,
    _fail,
    _int,
    _list,
    _obj,
    _run_id,
    _stamp,
    _str,
    record_start,
)
from .record_parts import (
    CODE_TRAINEE,
    END_REASONS,
    EVENT_KINDS,
    HOW_GIVEN,
    RECORDING_DECIMALS,
    Attempt,
    Demo,
    Event,
    Test,
    Trainee,
    check_given,
    round_recording,
)

__all__ = [
    "RECORD_FORMAT",
    "RECORD_VERSION",
    "SUPPORTED_VERSIONS",
    "EVENT_KINDS",
    "HOW_GIVEN",
    "RECORDING_DECIMALS",
    "END_REASONS",
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
RECORD_VERSION = 1
SUPPORTED_VERSIONS = (1,)


def utc_now() -> str:
    """The wall clock as an ISO 8601 UTC stamp, e.g. ``2026-12-01T09:14:03.123Z``."""
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


def tool_version() -> str:
    from .. import __version__

    return __version__


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
        spec = EXPERIMENTS.get(self.experiment)
        number = f" {self.run}" if spec is not None and spec.runs > 1 else ""
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
