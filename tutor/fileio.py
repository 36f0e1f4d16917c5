"""Safe reading and writing of the tutor's files.

Reads open the file without blocking, check that it is a regular file no larger
than :data:`MAX_FILE_BYTES` before reading a byte of it (a FIFO, ``/dev/zero`` or a
folder is refused, never read), decode UTF-8 (a leading byte-order mark is
accepted) and parse only JSON (never pickle). Every failure becomes an
:class:`~tutor.errors.InvalidFileError` that says what is wrong.

Writes are atomic: a temporary file in the target's folder, flushed to disk,
renamed over the target, then the folder itself flushed. Every failure (disk
full, no permission, read-only disk, a path through a file, a name too long)
becomes a :class:`~tutor.errors.SaveError` in plain words; the target is left as
it was and no temporary file stays behind.
"""

from __future__ import annotations

import errno
import hashlib
import json
import math
import os
import stat
import tempfile
import time
from pathlib import Path

from .errors import InvalidFileError, InvalidParameterError, LimitError, SaveError
from .limits import MAX_FILE_BYTES

__all__ = [
    "atomic_write_text",
    "write_json",
    "read_json",
    "read_text",
    "decode_text",
    "parse_json",
    "read_bytes",
    "check_file_name",
    "check_path_length",
    "save_error",
    "finite_number",
    "megabytes",
    "MAX_FILE_BYTES",
    "MAX_NAME_BYTES",
    "MAX_PATH_BYTES",
    "STALE_TEMP_SECONDS",
]

#: the longest file or folder name (in UTF-8 bytes) common file systems accept
MAX_NAME_BYTES = 255
#: the longest whole path (in bytes, as absolute path) Linux accepts (PATH_MAX less its NUL)
MAX_PATH_BYTES = 4095
#: temporary files of a save older than this were left by a killed process
STALE_TEMP_SECONDS = 60.0

_READ_FLAGS = (
    os.O_RDONLY
    | getattr(os, "O_NONBLOCK", 0)  # a FIFO opens at once instead of waiting for a writer
    | getattr(os, "O_NOCTTY", 0)  # a terminal device never becomes our terminal
    | getattr(os, "O_BINARY", 0)
)
_CHUNK = 1024 * 1024


# --------------------------------------------------------------------- names


def check_file_name(path) -> str | None:
    """What is wrong with ``path`` as a file name, or None if nothing is.

    Refused: something that is not a path, a NUL character, a file or folder name
    longer than :data:`MAX_NAME_BYTES` bytes in UTF-8, and a whole path (made absolute)
    longer than :data:`MAX_PATH_BYTES` bytes. (:func:`check_path_length` also asks the
    file system for its own limits.)
    """
    if not isinstance(path, (str, os.PathLike)):
        return f"{path!r} is not a file path"
    text = os.fspath(path)
    if not isinstance(text, str):
        return f"{path!r} is not a file path (give it as text)"
    if "\x00" in text:
        return "the name contains a NUL character, which no file name can hold"
    for part in Path(text).parts:
        size = len(part.encode("utf-8", "surrogateescape"))
        if size > MAX_NAME_BYTES:
            return (
                f"the name {part[:40]!r}... is {size} bytes long, more than the "
                f"{MAX_NAME_BYTES} a file name can have: use a shorter name"
            )
    return _whole_path_problem(text, MAX_PATH_BYTES)


def _size(text: str) -> int:
    return len(text.encode("utf-8", "surrogateescape"))


def _whole_path_problem(text: str, limit: int, room: int = 0) -> str | None:
    try:
        whole = _size(os.path.abspath(text))
    except (OSError, ValueError):  # no current folder (it was removed)
        whole = _size(text)
    if whole + room > limit:
        spare = f" (and room for the {room} bytes of names made inside it)" if room else ""
        return (
            f"the path is {whole} bytes long as a full path, more than the {limit} the file "
            f"system allows{spare}: use a folder higher up, or shorter names"
        )
    return None


def _limits(path: Path) -> tuple[int, int]:
    """(longest name, longest path) in bytes on the file system holding ``path``: the
    limits of its nearest existing folder, or the usual ones where it does not say."""
    nearest = Path(os.path.abspath(path))
    while True:
        try:
            if nearest.is_dir():
                break
        except OSError:  # a part of it is itself too long, or unreadable
            pass
        if nearest == nearest.parent:
            return MAX_NAME_BYTES, MAX_PATH_BYTES
        nearest = nearest.parent
    try:
        name = os.pathconf(nearest, "PC_NAME_MAX")
        whole = os.pathconf(nearest, "PC_PATH_MAX") - 1
    except (OSError, ValueError, AttributeError):  # no pathconf (Windows), or no answer
        return MAX_NAME_BYTES, MAX_PATH_BYTES
    return min(name, MAX_NAME_BYTES), min(whole, MAX_PATH_BYTES)


def check_path_length(path, what: str, error: type[Exception] = InvalidParameterError,
                      room: int = 0) -> Path:
    """``path`` as a path, checked against the file system's limits before any use.

    Each file or folder name must fit the file system's longest name (``NAME_MAX``,
    asked of the nearest existing folder; 255 bytes where it does not say) and the whole
    path, made absolute, its longest path (``PATH_MAX``, 4096 bytes on Linux), so that
    no later step fails with ENAMETOOLONG.

    Parameters
    ----------
    path : str or os.PathLike
    what : str
        How to call it in the message (e.g. ``"TUTOR_RUNS_DIR"``, ``"--out"``).
    error : type
        The :mod:`tutor.errors` class to raise.
    room : int
        Bytes to keep free for the names the tutor makes inside it (a folder's files).

    Raises
    ------
    error
        Not a path, a NUL character, a name or the whole path too long.
    """
    problem = check_file_name(path)
    if problem is None:
        text = os.fspath(path)
        longest_name, longest_path = _limits(Path(text))
        for part in Path(text).parts:
            if _size(part) > longest_name:
                problem = (
                    f"the name {part[:40]!r}... is {_size(part)} bytes long, more than the "
                    f"{longest_name} a file name can have there: use a shorter name"
                )
                break
        else:
            problem = _whole_path_problem(text, longest_path, room)
    if problem is not None:
        raise error(f"{what} ({_shown(path)}): {problem}")
    return Path(os.fspath(path))


def _shown(path) -> str:
    """``path`` as text for a message: NUL shown as ``\\0``, cut to 120 characters."""
    try:
        text = os.fspath(path)
    except TypeError:
        text = repr(path)
    if not isinstance(text, str):
        text = repr(text)
    text = text.replace("\x00", "\\0")
    return text if len(text) <= 120 else f"{text[:60]}...{text[-57:]}"


# --------------------------------------------------------------------- reading


def _open_error(path, what: str, exc: OSError) -> InvalidFileError:
    where = _shown(path)
    reasons = {
        errno.ENOENT: f"{what} {where} does not exist: check the name and the folder",
        errno.EISDIR: f"{what} {where} is a folder, not a file: give the file inside it",
        errno.ENOTDIR: f"{what} {where}: part of the path is a file, not a folder",
        errno.EACCES: f"{what} {where} cannot be read (no permission): check its permissions",
        errno.EPERM: f"{what} {where} cannot be read (not permitted): check its permissions",
        errno.ENAMETOOLONG: f"{what} {where}: the path is too long; move the file higher up",
        errno.ELOOP: f"{what} {where}: the path runs through a loop of symbolic links "
        "(links pointing at each other): replace the link with the file itself, or point "
        "it at the real file",
    }
    reason = reasons.get(exc.errno)
    if reason is None:
        reason = f"cannot open {what} {where}: {exc.strerror or exc}"
    return InvalidFileError(reason)


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a pipe (FIFO)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def megabytes(n_bytes: int) -> str:
    """``n_bytes`` in words, e.g. ``"50 MB"`` (1 MB = 1024 * 1024 bytes)."""
    return f"{n_bytes / 2**20:.0f} MB" if n_bytes >= 2**20 else f"{n_bytes} bytes"


def _too_large(path, what: str, size: int, limit: int) -> LimitError:
    return LimitError(
        f"{what} {_shown(path)} is {megabytes(size)} or more, larger than the "
        f"{megabytes(limit)} a {'tutor file' if what == 'file' else what} can be; is it "
        "the right file?"
    )


def read_bytes(path, what: str = "file", limit: int | None = None) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes (default
    :data:`MAX_FILE_BYTES`).

    The file is opened without blocking and checked with ``fstat`` before anything
    is read: a folder, pipe, device or socket is refused unread, and so is a file
    that is too large. At most ``limit`` bytes are read even if the file grows
    meanwhile (then it is refused as too large).

    Raises
    ------
    InvalidFileError
        With what is wrong (missing, a folder, not a regular file, unreadable, a bad
        name); LimitError when it is too large.
    """
    limit = MAX_FILE_BYTES if limit is None else limit
    problem = check_file_name(path)
    if problem is not None:
        raise InvalidFileError(f"cannot open {what} {_shown(path)}: {problem}")
    try:
        fd = os.open(path, _READ_FLAGS)
    except OSError as exc:
        raise _open_error(path, what, exc) from exc
    except ValueError as exc:  # a name the platform refuses outright
        raise InvalidFileError(f"cannot open {what} {_shown(path)}: {exc}") from exc
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise InvalidFileError(
                f"{what} {_shown(path)} is {_kind(info.st_mode)}, not a regular file: "
                "give the path of a saved file"
            )
        if info.st_size > limit:
            raise _too_large(path, what, info.st_size, limit)
        chunks, total = [], 0
        while total <= limit:
            chunk = os.read(fd, min(_CHUNK, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > limit:
            raise _too_large(path, what, total, limit)
        return b"".join(chunks)
    except OSError as exc:
        raise InvalidFileError(
            f"{what} {_shown(path)} could not be read: {exc.strerror or exc}"
        ) from exc
    finally:
        os.close(fd)


def read_text(path, what: str = "file", limit: int | None = None) -> str:
    """A UTF-8 text file (a leading byte-order mark is dropped), checked as :func:`read_bytes`."""
    return decode_text(read_bytes(path, what, limit), _shown(path), what)


def decode_text(data: bytes, shown: str, what: str = "file") -> str:
    """UTF-8 ``data`` as text (a byte-order mark dropped); ``shown`` names it in errors."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InvalidFileError(
            f"{what} {shown} is not UTF-8 text (byte {exc.start} is not): "
            "is it the right file? Save it as UTF-8 text"
        ) from exc


class _Refused(ValueError):
    """A number or key the tutor refuses (raised from the JSON parser's hooks)."""


def _refuse_constant(name):
    raise _Refused(f"{name} is not allowed (write a finite number, or leave the entry out)")


def _parse_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _Refused(
            f"the number {text[:40]} is too large for a floating-point number (the largest "
            "is about 1.8e308): fix or remove it"
        )
    return value


def _parse_int(text: str) -> int:
    try:
        value = int(text)
        float(value)
    except (OverflowError, ValueError) as exc:
        raise _Refused(
            f"the integer {text[:40]}{'...' if len(text) > 40 else ''} ({len(text)} digits) is "
            "too large for a floating-point number (the largest is about 1.8e308): fix or remove it"
        ) from exc
    return value


def _unique_keys(pairs: list) -> dict:
    """An object of the JSON text as a dict, refusing a key given twice.

    ``json`` would keep the last value silently, so a file could say one thing to a
    person reading it from the top and another to the tutor.
    """
    obj = dict(pairs)
    if len(obj) != len(pairs):
        seen = set()
        for key, _ in pairs:
            if key in seen:
                shown = key if len(key) <= 40 else f"{key[:40]}..."
                raise _Refused(
                    f'the key "{shown}" appears twice in one object, so it is unclear which '
                    "value is meant: keep one of them and remove the other"
                )
            seen.add(key)
    return obj


def read_json(path, what: str = "file", limit: int | None = None):
    """Parse a JSON file, with a clear :class:`InvalidFileError` for any problem.

    Besides what :func:`read_text` refuses (``limit`` as there): an empty file, invalid
    JSON, NaN and Infinity, numbers too large for a float (``1e400``, a 400-digit
    integer), an object with a key given twice, and nesting too deep to parse.
    """
    return parse_json(read_text(path, what, limit), _shown(path), what)


def parse_json(text: str, shown: str, what: str = "file"):
    """Parse JSON ``text`` with :func:`read_json`'s checks; ``shown`` names it in errors
    (e.g. a member of a zip file)."""
    if not text.strip():
        raise InvalidFileError(f"{what} {shown} is empty: is it the right file?")
    try:
        return json.loads(
            text,
            parse_constant=_refuse_constant,
            parse_float=_parse_float,
            parse_int=_parse_int,
            object_pairs_hook=_unique_keys,
        )
    except _Refused as exc:
        raise InvalidFileError(f"{what} {shown}: {exc}") from exc
    except RecursionError as exc:
        raise InvalidFileError(
            f"{what} {shown} is nested too deeply to read: is it the right file?"
        ) from exc
    except ValueError as exc:
        raise InvalidFileError(
            f"{what} {shown} is not valid JSON (it may be truncated or corrupt): {exc}"
        ) from exc


def finite_number(value) -> bool:
    """True for an int or float that is finite (bool excluded)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an int too large for a float
        return False


# --------------------------------------------------------------------- writing


def save_error(path, exc: OSError) -> SaveError:
    """A :class:`SaveError` saying in plain words why ``path`` could not be written."""
    where = _shown(path)
    folder = _shown(Path(path).parent) if check_file_name(path) is None else "its folder"
    reasons = {
        errno.ENOSPC: "the disk is full: free some space, then save again",
        errno.EDQUOT: "your disk quota is used up: free some space, then save again",
        errno.EACCES: f"there is no permission to write in {folder}: save somewhere you may "
        "write, or ask for write access",
        errno.EPERM: f"writing in {folder} is not permitted: save somewhere you may write",
        errno.EROFS: f"{folder} is on a read-only disk: save somewhere else",
        errno.ENOTDIR: "part of the path is a file, not a folder: choose another folder",
        errno.EEXIST: "part of the path is a file, not a folder: choose another folder",
        errno.EISDIR: "that is a folder: give a file name inside it",
        errno.ENAMETOOLONG: "the name or the path is too long: choose a shorter one",
        errno.EIO: "the disk reported an error: check it, or save somewhere else",
    }
    reason = reasons.get(exc.errno) or f"{exc.strerror or exc}: try again, or save somewhere else"
    return SaveError(f"could not save {where}: {reason}. Nothing was changed on disk.")


def _temp_prefix(path: Path) -> str:
    """The prefix of ``path``'s temporary files, short enough for any name."""
    name = path.name
    if len(name.encode("utf-8", "surrogateescape")) <= 200:
        return f".{name}."
    digest = hashlib.sha1(name.encode("utf-8", "surrogateescape")).hexdigest()[:12]
    short = name
    while len(short.encode("utf-8", "surrogateescape")) > 180:
        short = short[:-1]
    return f".{short}~{digest}."


def _remove_stale_temps(path: Path, prefix: str) -> None:
    """Remove temporary files of ``path`` left by a process killed while saving."""
    now = time.time()
    try:
        entries = list(os.scandir(path.parent))
    except OSError:
        return
    for entry in entries:
        if not (entry.name.startswith(prefix) and entry.name.endswith(".tmp")):
            continue
        try:
            if entry.is_file(follow_symlinks=False) and (
                now - entry.stat(follow_symlinks=False).st_mtime > STALE_TEMP_SECONDS
            ):
                os.unlink(entry.path)
        except OSError:
            pass  # another process may be removing it too


#: errors meaning "this platform or file system cannot flush a folder"
_NO_DIR_FSYNC = {errno.EINVAL, errno.EBADF, errno.ENOTSUP, errno.EACCES, errno.EPERM, errno.EISDIR}


def _fsync_folder(path: Path) -> None:
    """Flush the folder entry of ``path`` (just renamed) to disk, where the platform can.

    Raises
    ------
    SaveError
        If the disk reports an error (the file was written, but may not survive a
        power cut).
    """
    if os.name == "nt":  # Windows cannot open a folder as a file
        return
    try:
        fd = os.open(path.parent, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError as exc:
        if exc.errno not in _NO_DIR_FSYNC:
            raise SaveError(
                f"{path} was written, but the disk reported an error when asked to keep it "
                f"({exc.strerror or exc}): check the disk, and save again"
            ) from exc
    finally:
        os.close(fd)


#: a new file's permissions: its owner writes, its group reads (on the hub kit, the
#: educators' group, which each trainee folder passes to what is made in it), others nothing
NEW_FILE_MODE = 0o640


def atomic_write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically as UTF-8; returns the path.

    Missing folders are made. An existing target keeps its permissions; a new one gets
    :data:`NEW_FILE_MODE`.

    Raises
    ------
    SaveError
        In plain words (disk full, no permission, read-only disk, a path through a
        file, a name too long); the target is untouched and no temporary file is
        left.
    """
    problem = check_file_name(path)
    if problem is not None:
        raise SaveError(f"could not save {_shown(path)}: {problem}. Nothing was changed on disk.")
    path = Path(path)
    if path.name in ("", ".", ".."):
        raise SaveError(
            f"could not save {path}: that is a folder, not a file name: give a file name "
            "inside it. Nothing was changed on disk."
        )
    try:
        data = text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise SaveError(
            f"could not save {path}: the text holds a character that is not valid Unicode "
            f"(position {exc.start}). Nothing was changed on disk."
        ) from exc
    prefix = _temp_prefix(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        _remove_stale_temps(path, prefix)
        fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=".tmp", dir=path.parent)
        try:
            with os.fdopen(fd, "wb") as fh:
                try:
                    mode = stat.S_IMODE(os.stat(path).st_mode)
                except OSError:
                    mode = NEW_FILE_MODE  # a new file (mkstemp's own mode is 0600)
                try:
                    os.fchmod(fh.fileno(), mode)
                except (OSError, AttributeError):
                    pass  # a platform without fchmod: mkstemp's permissions
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, path)
        except BaseException:
            try:
                os.unlink(tmp)
            except OSError:
                pass
            raise
        _fsync_folder(path)
    except SaveError:
        raise
    except OSError as exc:
        raise save_error(path, exc) from exc
    return path


def write_json(path, data) -> Path:
    """Atomically write ``data`` as JSON (NaN and inf are refused).

    Raises
    ------
    SaveError
        If ``data`` cannot be written as JSON (NaN, inf, an object JSON does not
        know), or as :func:`atomic_write_text`.
    """
    try:
        text = json.dumps(data, allow_nan=False, separators=(",", ":"))
    except (ValueError, TypeError, RecursionError) as exc:
        raise SaveError(
            f"could not save {_shown(path)}: the data cannot be written as JSON ({exc}). "
            "Nothing was changed on disk."
        ) from exc
    return atomic_write_text(path, text)
