"""What the browser sends, checked before the tutor uses it: one ``check_*`` per kind.

Everything a page can send to the kernel is someone's input and may be anything JSON
can hold (or, for uploads, any bytes), whatever the page's own script would send:

- a stroke on the maze sketchpad (``Sketchpad.stroke``): :func:`check_stroke`;
- a text field (the start form's name, the dashboard's class folder): :func:`check_text`;
- a choice from buttons or a list (a condition, a mistake, an experiment):
  :func:`check_choice`;
- a file from a ``FileUpload`` button: :func:`check_upload`;
- a message from the 3-D view (its "hello" when it opens): :func:`check_view_message`;
- while the trainee guides the arm: a move of the handle, :func:`check_guide_move`, and
  the recording at the end, :func:`check_guide_end`.

Each returns the value in the form the tutor needs, or raises
:class:`~tutor.errors.InvalidPayloadError` saying in plain words what was wrong.
The observers and callbacks that receive these payloads catch it and show the message
in their panel; nothing the page sends raises out of a callback.
"""

from __future__ import annotations

import logging
import numbers
import re
from collections.abc import Callable

import numpy as np

from .errors import InvalidDemoError, InvalidPayloadError, TutorError
from .fileio import megabytes
from .limits import MAX_STROKE_POINTS, MAX_TEXT_CHARS, MAX_UPLOAD_BYTES
from .tpgmm.checks import check_demo

__all__ = [
    "check_stroke",
    "check_text",
    "check_choice",
    "check_upload",
    "check_view_message",
    "check_guide_move",
    "check_guide_end",
    "MAX_GUIDE_SAMPLES",
    "MAX_SETUP_SECONDS",
    "shown_upload_name",
    "safely",
    "MAX_STROKE_POINTS",
    "MAX_TEXT_CHARS",
]

#: a 3-D view's id: what its script makes (letters and digits), at most 32 of them
_VIEW_ID = re.compile(r"[A-Za-z0-9]{1,32}")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")
#: the most samples one guided recording may arrive with: 30 minutes at 40 Hz (the
#: 15-minute clock stops a run long before; :mod:`tutor.tasks.recording` judges the rest)
MAX_GUIDE_SAMPLES = 30 * 60 * 40
#: the longest set-up (seconds from arming the guide to the first move) a page may report
MAX_SETUP_SECONDS = 120.0
#: the largest move sequence number a page may send (a JavaScript safe integer)
_MAX_SEQ = 2**53 - 1

log = logging.getLogger(__name__)


def _kind(value) -> str:
    """What ``value`` is, in words for a message."""
    if value is None:
        return "empty (null)"
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, str):
        return "text"
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)}"
    if isinstance(value, numbers.Real):
        return "a number"
    return f"a {type(value).__name__}"


def _is_number(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def check_stroke(value, columns: int = 3, max_points: int = MAX_STROKE_POINTS) -> np.ndarray:
    """A stroke from the sketchpad as a float array (T, ``columns``): [t, x, y] rows.

    Parameters
    ----------
    value
        What arrived: a list of points, each a list of ``columns`` finite numbers
        (seconds, then metres), time increasing.
    columns : int
        Numbers per point.
    max_points : int
        The most points a stroke may have (:data:`MAX_STROKE_POINTS`).

    Raises
    ------
    InvalidPayloadError
        Not a list of points; more than ``max_points``; a point that is not a list of
        ``columns`` numbers (text, an object, null, too few or too many numbers); NaN or
        inf; fewer than 2 points; time not increasing.
    """
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)):
        raise InvalidPayloadError(
            f"the stroke arrived as {_kind(value)}, not as a list of points: draw it again"
        )
    if len(value) > max_points:
        raise InvalidPayloadError(
            f"the stroke has {len(value)} points, more than the {max_points} one stroke may "
            "have: draw it again in one shorter movement"
        )
    for i, row in enumerate(value, start=1):
        if not isinstance(row, (list, tuple)):
            raise InvalidPayloadError(
                f"point {i} of the stroke is {_kind(row)}, not a list of {columns} numbers "
                "(time, x, y): draw it again"
            )
        if len(row) != columns:
            raise InvalidPayloadError(
                f"point {i} of the stroke has {len(row)} values, not {columns} (time, x, y): "
                "draw it again"
            )
        for cell in row:
            if not _is_number(cell):
                raise InvalidPayloadError(
                    f"point {i} of the stroke holds {_kind(cell)} where a number should be: "
                    "draw it again"
                )
    try:
        return check_demo(np.array(value, dtype=float), "the stroke", n_columns=columns)
    except InvalidDemoError as exc:
        raise InvalidPayloadError(str(exc)) from exc


def check_text(value, what: str, max_chars: int = MAX_TEXT_CHARS) -> str:
    """A text field's value, as text of at most ``max_chars`` characters.

    Raises
    ------
    InvalidPayloadError
        Not text, or longer than ``max_chars``.
    """
    if not isinstance(value, str):
        raise InvalidPayloadError(f"{what} arrived as {_kind(value)}, not as text: type it again")
    if len(value) > max_chars:
        raise InvalidPayloadError(
            f"{what} is {len(value)} characters long, more than the {max_chars} it may have: "
            "type a shorter one"
        )
    return value


def check_choice(value, what: str, choices):
    """``value`` if it is one of ``choices`` (compared with its type: ``True`` is not 1).

    Raises
    ------
    InvalidPayloadError
        ``value`` is not one of the choices offered.
    """
    for choice in choices:
        if type(value) is type(choice) and value == choice:
            return value
    offered = ", ".join(str(c) for c in choices)
    shown = repr(value) if len(repr(value)) <= 40 else f"{repr(value)[:40]}..."
    raise InvalidPayloadError(
        f"{what} {shown} is not one of those offered ({offered}): choose again"
    )


def shown_upload_name(name) -> str:
    """An uploaded file's name as it can be shown in a message (printable, at most 120)."""
    if not isinstance(name, str) or not name.strip():
        return "the uploaded file"
    shown = _CONTROL.sub("?", name)
    shown = shown.encode("utf-8", "replace").decode("utf-8")  # lone surrogates: "?"
    return shown if len(shown) <= 120 else f"{shown[:60]}...{shown[-57:]}"


def check_upload(value) -> tuple[str | None, bytes]:
    """The first file of a ``FileUpload`` value: (its name as sent, or None; its bytes).

    Raises
    ------
    InvalidPayloadError
        No file, a file without its content, or one larger than
        :data:`~tutor.limits.MAX_UPLOAD_BYTES`; the message names the file as
        :func:`shown_upload_name` shows it.
    """
    try:
        item = value[0]
    except (KeyError, IndexError, TypeError):
        raise InvalidPayloadError("the upload arrived without a file: upload it again") from None
    name = item.get("name") if isinstance(item, dict) else None
    name = name if isinstance(name, str) else None
    shown = shown_upload_name(name)
    raw = item.get("content") if isinstance(item, dict) else None
    if not isinstance(raw, (bytes, bytearray, memoryview)):
        raise InvalidPayloadError(f"{shown} arrived without its content; upload it again")
    size = memoryview(raw).nbytes
    if size > MAX_UPLOAD_BYTES:
        raise InvalidPayloadError(
            f"{shown} is {megabytes(size)}, larger than the {megabytes(MAX_UPLOAD_BYTES)} an "
            "upload can be (a run of 100 demonstrations is about 2 MB); is it the right file?"
        )
    return name, bytes(raw)


def check_view_message(content) -> str | None:
    """The view id of a 3-D view's "hello" (sent when it opens), or None for any other
    message type.

    Raises
    ------
    InvalidPayloadError
        Not an object with a text ``type``, or a hello whose id is not 1 to 32 letters
        and digits.
    """
    if not isinstance(content, dict) or not isinstance(content.get("type"), str):
        raise InvalidPayloadError(
            f"the 3-D view sent {_kind(content)}, not a message the tutor knows: reload the page"
        )
    if content["type"] != "hello":
        return None
    view = content.get("id")
    if not isinstance(view, str) or not _VIEW_ID.fullmatch(view):
        raise InvalidPayloadError(
            "the 3-D view said hello without a proper id (1 to 32 letters and digits): "
            "reload the page"
        )
    return view


def _guide_number(content: dict, key: str, what: str) -> float:
    value = content.get(key)
    if not _is_number(value) or not np.isfinite(float(value)):
        raise InvalidPayloadError(
            f"the guide sent {_kind(value)} as {what} ({key!r}), not a finite number: "
            "move the handle again"
        )
    return float(value)


def _guide_message(content, kind: str) -> dict:
    if not isinstance(content, dict) or content.get("type") != kind:
        raise InvalidPayloadError(
            f"the guide sent {_kind(content)} where a {kind!r} message should be: reload the page"
        )
    return content


def check_guide_move(content) -> tuple[int, np.ndarray, float]:
    """A move of the guide's handle, ``{"type": "guide-move", "seq", "x", "y", "z", "g"}``,
    as (seq, the target (3,) in metres, the hand g 0 open .. 1 closed).

    Raises
    ------
    InvalidPayloadError
        Not such an object; ``seq`` not a whole number from 0 to 2**53 - 1; a coordinate
        or ``g`` that is not a finite number; ``g`` outside 0..1.
    """
    content = _guide_message(content, "guide-move")
    seq = content.get("seq")
    if not isinstance(seq, int) or isinstance(seq, bool) or not 0 <= seq <= _MAX_SEQ:
        raise InvalidPayloadError(
            f"the guide sent {_kind(seq)} as the move's number ('seq'), not a whole number "
            "from 0: reload the page"
        )
    xyz = np.array([_guide_number(content, k, f"the handle's {k}") for k in "xyz"])
    g = _guide_number(content, "g", "the hand")
    if not 0.0 <= g <= 1.0:
        raise InvalidPayloadError(
            f"the guide sent the hand as {g}, outside 0 (open) .. 1 (closed): reload the page"
        )
    return seq, xyz, g


def check_guide_end(content, buffers) -> tuple[np.ndarray, float]:
    """The end of a guided demonstration, ``{"type": "guide-end", "n": T, "setup": s}``
    with one buffer of T * 5 float64 (t, x, y, z, g per sample), as (the raw recording
    (T, 5), the set-up seconds).

    Only the form is checked here (sizes, numbers); whether the recording makes a
    demonstration (finite, time increasing, in reach, ...) is for
    :func:`tutor.tasks.recording.check_recording`.

    Raises
    ------
    InvalidPayloadError
        Not such an object; ``n`` not a whole number from 1 to :data:`MAX_GUIDE_SAMPLES`;
        not exactly one buffer of ``n`` * 5 * 8 bytes; ``setup`` not a number from 0 to
        :data:`MAX_SETUP_SECONDS`.
    """
    content = _guide_message(content, "guide-end")
    n = content.get("n")
    if not isinstance(n, int) or isinstance(n, bool) or not 1 <= n <= MAX_GUIDE_SAMPLES:
        raise InvalidPayloadError(
            f"the guide sent {_kind(n)} as the number of samples ('n'), not a whole number "
            f"from 1 to {MAX_GUIDE_SAMPLES}: guide the arm again"
        )
    setup = _guide_number(content, "setup", "the set-up time")
    if not 0.0 <= setup <= MAX_SETUP_SECONDS:
        raise InvalidPayloadError(
            f"the guide sent a set-up time of {setup:g} s, outside 0 to "
            f"{MAX_SETUP_SECONDS:g} s: guide the arm again"
        )
    if not isinstance(buffers, (list, tuple)) or len(buffers) != 1:
        count = len(buffers) if isinstance(buffers, (list, tuple)) else 0
        raise InvalidPayloadError(
            f"the guide's recording arrived in {count} parts, not 1: guide the arm again"
        )
    try:
        raw = memoryview(buffers[0]).cast("B")
    except TypeError:
        raise InvalidPayloadError(
            "the guide's recording arrived as something other than bytes: guide the arm again"
        ) from None
    if raw.nbytes != n * 5 * 8:
        raise InvalidPayloadError(
            f"the guide's recording has {raw.nbytes} bytes, not the {n * 40} of {n} samples "
            "(t, x, y, z, g as 8-byte numbers): guide the arm again"
        )
    return np.frombuffer(raw, dtype="<f8").reshape(n, 5).copy(), setup


def safely(action: Callable[[], object], say: Callable[[str], None]) -> None:
    """Run what a click or a keystroke asked for, so that nothing raises out of the widget's
    callback: a :class:`~tutor.errors.TutorError` is said with ``say`` in its own words,
    anything else (a bug) is logged and said as such."""
    try:
        action()
    except TutorError as exc:
        say(str(exc))
    except Exception as exc:  # a bug must not leave the page without a word
        log.exception("%s failed", getattr(action, "__name__", "a callback"))
        say(
            f"Something went wrong inside the tutor ({type(exc).__name__}: {exc}). Nothing "
            "saved was lost; please tell your educator."
        )
