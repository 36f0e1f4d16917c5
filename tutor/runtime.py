"""How the tutor is being run: by a person or headless, where runs are saved, and by whom.

``TUTOR_HEADLESS=1`` (set by ``scripts/test.sh``) switches the notebooks to headless
mode: cells that would wait for a person instead feed bundled demonstrations.
nbmake runs a real kernel, so "am I in a notebook?" checks cannot tell a test from a
person; the environment variable can.

``TUTOR_RUNS_DIR`` moves where teaching runs are saved (default ``./sessions`` next to
the notebooks); each trainee gets a folder of their own inside it.

Trainee folders. A trainee's folder key is derived from their name *injectively*: the
name is normalised (Unicode NFC, surrounding spaces removed, inner runs of spaces made
one, invisible format characters such as direction marks and zero-width spaces
dropped), then the key is a readable ASCII part of it followed by a short hash of the
whole normalised name. Direction overrides (which reorder text on screen) are refused.
So 'Mai Anh' and 'Mai_Anh', two different Devanagari names or two emoji get different
folders, while 'Zoë' typed as NFC or as NFD gets the same one. Keys are lower-case
ASCII (safe on case-insensitive file systems) and at most 52 characters. An educator
can set the name with ``TUTOR_TRAINEE``; else, on a JupyterHub, ``JUPYTERHUB_USER`` is
the default name.
"""

from __future__ import annotations

import hashlib
import os
import re
import unicodedata
from pathlib import Path

from .errors import InvalidParameterError, SaveError
from .fileio import check_path_length

__all__ = [
    "headless",
    "trainee_dir",
    "runs_root",
    "trainee_key",
    "normalise_name",
    "default_trainee",
    "NO_NAME",
    "safe_text",
    "env_text",
]

#: embedding and override controls: they reorder text on screen, so they are refused
_DIRECTION_CONTROLS = set("\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069")
#: bytes kept free below TUTOR_RUNS_DIR: a trainee's folder and the files in it
RUNS_ROOM = 200
#: the readable part of a folder key is at most this long
_READABLE = 40
_HASH_CHARS = 10


#: lone surrogates: code points UTF-8 cannot write
_SURROGATE = re.compile("[\ud800-\udfff]")
#: how Python's "surrogateescape" keeps the bytes it could not decode (0x80-0xFF)
_ESCAPED = re.compile("[\udc80-\udcff]+")


def _unescape(match: re.Match) -> str:
    """Bytes kept by "surrogateescape", decoded: as UTF-8 if they are that, else as Latin-1
    (its Windows form, cp1252, where 0x80-0x9F are letters and signs, not controls)."""
    raw = bytes(ord(c) - 0xDC00 for c in match.group())
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("cp1252", "replace")


def safe_text(text: str, from_bytes: bool = False) -> str:
    """``text`` as Unicode that UTF-8 can write and a terminal can print.

    A surrogate pair is joined into its character; any other lone surrogate (U+D800 to
    U+DFFF, e.g. ``"a\udcff"`` sent by a page, or ``\udcff`` in a JSON file) becomes
    U+FFFD, the replacement character. With ``from_bytes`` (text Python decoded from the
    operating system with "surrogateescape": the environment, command-line arguments), a
    run of U+DC80 to U+DCFF is the bytes UTF-8 could not decode: they are read as UTF-8 if
    they are that, else as Latin-1, so ``TUTOR_TRAINEE`` set to ``Zo\xeb`` in Latin-1
    reads "Zoë". Text without surrogates is returned as it is.
    """
    if not isinstance(text, str) or not _SURROGATE.search(text):
        return text
    text = text.encode("utf-16-le", "surrogatepass").decode("utf-16-le", "surrogatepass")
    if from_bytes:
        text = _ESCAPED.sub(_unescape, text)
    return _SURROGATE.sub("\ufffd", text)


def env_text(var: str) -> str:
    """The environment variable ``var`` as safe text (:func:`safe_text` of its bytes),
    without surrounding spaces; "" when it is unset."""
    return safe_text(os.environ.get(var, ""), from_bytes=True).strip()


def headless() -> bool:
    """True when TUTOR_HEADLESS is set to a true value (1, true, yes)."""
    return os.environ.get("TUTOR_HEADLESS", "").strip().lower() in ("1", "true", "yes")


def normalise_name(name) -> str:
    """The trainee's name as stored: NFC, trimmed, single spaces, lone surrogates replaced
    (:func:`safe_text`); refuses empty names."""
    if not isinstance(name, str):
        raise InvalidParameterError(
            f"the trainee's name must be text, e.g. trainee = \"Mai Anh\"; got {name!r}"
        )
    name = safe_text(name)
    if any(c in _DIRECTION_CONTROLS for c in name):
        raise InvalidParameterError(
            "the trainee's name holds invisible direction controls (U+202A-U+202E, "
            "U+2066-U+2069) that would reorder it on screen: remove them and type the name "
            "again"
        )
    # invisible format characters (direction marks, zero-width spaces) are dropped, so a
    # name copied from a chat or a right-to-left document finds the same folder
    visible = "".join(c for c in name if unicodedata.category(c) != "Cf")
    text = " ".join(unicodedata.normalize("NFC", visible).split())
    if not text or any(unicodedata.category(c) == "Cc" for c in text):
        raise InvalidParameterError(
            "the trainee's name is empty or holds control characters: type a name, e.g. "
            'trainee = "Mai Anh"'
        )
    if len(text) > 200:
        raise InvalidParameterError(
            f"the trainee's name is {len(text)} characters long; use at most 200"
        )
    return text


def trainee_key(name) -> str:
    """The folder key of a trainee (see the module docstring), e.g. ``mai-anh-1c9e5b2f0a``."""
    text = normalise_name(name)
    ascii_part = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode()
    readable = re.sub(r"[^a-z0-9]+", "-", ascii_part.lower()).strip("-")[:_READABLE].strip("-")
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:_HASH_CHARS]
    return f"{readable}-{digest}" if readable else f"t-{digest}"


def default_trainee() -> str | None:
    """The trainee's name when none is typed, or None.

    ``TUTOR_TRAINEE`` when an educator set it, else ``JUPYTERHUB_USER`` on a hub, else
    None: there is no made-up name, so runs of trainees who left the name blank never
    share one folder under it (the start form then asks for a name).
    """
    for var in ("TUTOR_TRAINEE", "JUPYTERHUB_USER"):
        user = env_text(var)
        if user:
            return user
    return None


#: what is said when no name was given and none is set
NO_NAME = (
    "no name was given: type your name (a blank one is not used, so that runs of "
    "trainees who leave it blank never mix under one name), or ask your educator to set "
    "TUTOR_TRAINEE"
)


def runs_root() -> Path:
    """The folder that holds every trainee's folder (``TUTOR_RUNS_DIR`` or ./runs).

    Raises
    ------
    InvalidParameterError
        ``TUTOR_RUNS_DIR`` holds a NUL character, or it is too long for the file
        system with room for a trainee's folder and files
        (:func:`tutor.fileio.check_path_length`).
    """
    base = os.environ.get("TUTOR_RUNS_DIR", "").strip() or "runs"
    if "\x00" in base:
        raise InvalidParameterError("TUTOR_RUNS_DIR holds a NUL character: set it to a folder")
    return check_path_length(base, "TUTOR_RUNS_DIR", room=RUNS_ROOM)


def trainee_dir(trainee=None) -> Path:
    """The folder for one trainee's run files (created if needed).

    ``trainee`` None is :func:`default_trainee`'s name (refused when there is none).

    Raises
    ------
    InvalidParameterError
        The name is empty or missing, or ``TUTOR_RUNS_DIR`` is a file rather than a folder, or
        too long.
    SaveError
        The folder cannot be made (no permission, a read-only disk).
    """
    root = runs_root()
    if root.exists() and not root.is_dir():
        raise InvalidParameterError(
            f"TUTOR_RUNS_DIR is {root}, which is a file, not a folder: point it at a "
            "folder (it is made if missing)"
        )
    name = default_trainee() if trainee is None else trainee
    if name is None:
        raise InvalidParameterError(NO_NAME)
    folder = root / trainee_key(name)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SaveError(
            f"cannot make the folder {folder} for the trainee's runs ({exc.strerror or exc}); "
            "set TUTOR_RUNS_DIR to a folder you can write to"
        ) from exc
    return folder
