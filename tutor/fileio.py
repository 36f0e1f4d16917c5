"""Safe reading and writing of the tutor's JSON files.

Writes are atomic (a temporary file in the same folder, flushed to disk, then
renamed over the target), so a crash never leaves a half-written session.
Reads only ever parse JSON (never pickle) and turn every failure into an
:class:`~tutor.errors.InvalidFileError` that says what is wrong.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

from .errors import InvalidFileError

__all__ = ["atomic_write_text", "write_json", "read_json", "MAX_FILE_BYTES"]

#: files larger than this are refused (a session of 1000 demos is about 10 MB)
MAX_FILE_BYTES = 50 * 1024 * 1024


def atomic_write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_json(path, data) -> Path:
    """Atomically write ``data`` as JSON (NaN and inf are refused)."""
    return atomic_write_text(path, json.dumps(data, allow_nan=False, separators=(",", ":")))


def _refuse_constant(name):
    raise ValueError(f"{name} is not allowed")


def read_json(path, what: str = "file"):
    """Parse a JSON file, with a clear :class:`InvalidFileError` for any problem."""
    path = Path(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise InvalidFileError(f"cannot open {what} {path}: {exc.strerror or exc}") from exc
    if size > MAX_FILE_BYTES:
        raise InvalidFileError(
            f"{what} {path} is {size / 1e6:.0f} MB, more than the {MAX_FILE_BYTES / 1e6:.0f} MB "
            "a tutor file can be; is it the right file?"
        )
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidFileError(f"{what} {path} is not a readable UTF-8 text file ({exc})") from exc
    if not text.strip():
        raise InvalidFileError(f"{what} {path} is empty")
    try:
        return json.loads(text, parse_constant=_refuse_constant)
    except (ValueError, RecursionError) as exc:
        raise InvalidFileError(
            f"{what} {path} is not valid JSON (it may be truncated or corrupt): {exc}"
        ) from exc


def finite_number(value) -> bool:
    """True for an int or float that is finite (bool excluded)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
