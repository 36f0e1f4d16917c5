"""Named errors of the tutor.

Every error a user can provoke with bad input is one of these classes, and its
message says what was wrong and how to fix it. Each class also derives from the
matching built-in (``ValueError`` or ``RuntimeError``) so that generic handlers
keep working.
"""

from __future__ import annotations

__all__ = [
    "TutorError",
    "InvalidDemoError",
    "InvalidRecordingError",
    "InvalidFrameError",
    "DemoFrameMismatchError",
    "TooFewSamplesError",
    "InvalidParameterError",
    "InvalidPayloadError",
    "NotFittedError",
    "InvalidFileError",
    "InvalidPlanError",
    "LimitError",
    "SaveError",
    "SessionInUseError",
    "LockError",
    "WrongRunError",
]


class TutorError(Exception):
    """Base class of every error raised on purpose by :mod:`tutor`."""


class InvalidDemoError(TutorError, ValueError):
    """A demonstration cannot be used: NaN/inf, too short, wrong columns, time not increasing."""


class InvalidRecordingError(InvalidDemoError):
    """A recording of the trainee's own hand guiding the arm (t, x, y, z, g) cannot be a
    demonstration: not a table of 5 numbers a row, NaN/inf, a single sample, time not
    increasing, a jump, a hand value outside [0, 1], a hand that never closes or never
    opens again, a target out of the arm's reach, or too long."""


class InvalidFrameError(TutorError, ValueError):
    """A task frame is malformed: wrong shape, not finite, or a singular matrix ``A``."""


class DemoFrameMismatchError(TutorError, ValueError):
    """Demonstrations and their task frames do not correspond (counts or sizes differ)."""


class TooFewSamplesError(TutorError, ValueError):
    """There is not enough data for the requested model (e.g. more components than samples)."""


class InvalidParameterError(TutorError, ValueError):
    """A setting is impossible (e.g. a negative number of components)."""


class InvalidPayloadError(TutorError, ValueError):
    """What a page sent to the kernel cannot be used: a stroke that is not a list of
    points, a field that is not text, a choice not offered, an upload without its bytes."""


class NotFittedError(TutorError, RuntimeError):
    """A model was asked to reproduce before it was fitted."""


class InvalidFileError(TutorError, ValueError):
    """A session or demonstration file is corrupt, truncated, of the wrong kind or hostile."""


class InvalidPlanError(InvalidFileError):
    """A class plan (``TUTOR_CLASS_PLAN``) cannot be used: unreadable, a wrong header or
    format, an unknown condition, or one trainee listed with two conditions."""


class LimitError(InvalidFileError):
    """Something goes over one of the tutor's caps (:mod:`tutor.limits`): a file too
    large, too many files or zip entries, a zip that unpacks to too much, too many
    demonstrations or samples. The message names the cap and what to do."""


class SaveError(TutorError, OSError):
    """A file could not be written (disk full, no permission, a folder that is a file).

    Nothing in memory is lost: the caller keeps its state and may try again.
    """


class SessionInUseError(TutorError, RuntimeError):
    """Another tutor or kernel is writing this run file (it holds the file's lock)."""


class LockError(TutorError, RuntimeError):
    """A run file's lock cannot be taken at all (its lock file is a folder or another
    user's, or the folder is read-only), so the run is shown read-only and nothing is saved."""


class WrongRunError(InvalidFileError):
    """A file holds a different run (another experiment, condition or trainee), or the run
    it would change is finished."""
