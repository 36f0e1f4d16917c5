"""The parts of a run record: who taught, the demos, the robot tests, the events and the
attempts (:mod:`.record` holds :class:`~.record.RunRecord`, which is made of them).

Each part is a frozen dataclass with ``to_dict`` and a checked ``from_dict``
(:mod:`.record_checks`); the vocabulary they are written in (:data:`EVENT_KINDS`,
:data:`HOW_GIVEN`, :data:`END_REASONS`) and the rounding of a stored recording
(:func:`round_recording`) are here too. Every name is also importable from
:mod:`tutor.framework.record`, where the record format is documented.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from ..limits import MAX_RECORDING_SAMPLES
from ..runtime import default_trainee, normalise_name, trainee_key
from .record_checks import (
    _bool,
    _fail,
    _indices,
    _int,
    _list,
    _num,
    _numbers,
    _obj,
    _stamp,
    _str,
    _table,
)

__all__ = [
    "EVENT_KINDS",
    "HOW_GIVEN",
    "RECORDING_DECIMALS",
    "END_REASONS",
    "CODE_TRAINEE",
    "check_given",
    "round_recording",
    "Trainee",
    "Demo",
    "Test",
    "Event",
    "Attempt",
]

#: a trainee's folder key (see :func:`tutor.runtime.trainee_key`)
_KEY = re.compile(r"[a-z0-9][a-z0-9-]{0,63}")

#: what a trainee (or the tutor on their behalf) can do in a run
EVENT_KINDS = (
    "start",  # the run (or a new attempt) began
    "add",  # a demonstration was added
    "undo",  # the latest demonstration was taken back
    "load",  # demonstrations came from a file
    "reset",  # a new, empty attempt replaced the current one (the old one is kept)
    "restore",  # an earlier attempt was brought back as a new attempt
    "test",  # the robot tried chosen test points
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
    point : tuple of float or None
        The test point it was meant for (e.g. the plant chosen; stored under the file's
        key ``"condition"``, as format version 1 has it); None when the task
        reads it off the demo.
    shown : tuple of int or None
        SF: the test points the trainee asked to see after it; AF (an "adaptive"
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
    point: tuple[float, ...] | None = None
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
            "condition": None if self.point is None else list(self.point),
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
            point=None if cond is None else _numbers(cond, f"{path}.condition"),
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


