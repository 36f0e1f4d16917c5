"""Files a trainee uploads with an ``ipywidgets.FileUpload`` button.

The browser sends a name and the bytes; both are the trainee's (or anyone's) and
are treated as hostile. The bytes are written under a safe name in a fresh
temporary folder (the name's unsafe characters replaced, cut to fit a file name,
the extension kept so ``.json`` and ``.csv`` are told apart), handed to the tutor's
``load``, and removed. Nothing raised by a :class:`~tutor.errors.TutorError` leaves
the widget callback: its message goes to the tutor's message line.
"""

from __future__ import annotations

import logging
import re
import tempfile
from collections.abc import Callable
from pathlib import Path

from ..errors import SaveError, TutorError
from ..fileio import MAX_NAME_BYTES, megabytes, save_error
from ..limits import MAX_UPLOAD_BYTES

__all__ = ["on_upload", "safe_upload_name", "shown_upload_name"]

_log = logging.getLogger(__name__)

#: characters never kept in a stored name: NUL and control characters, path
#: separators, and what Windows refuses in names
_UNSAFE = re.compile(r'[\x00-\x1f\x7f/\\:*?"<>|]')
#: the longest extension kept (longer ones are cut off with the rest of the name)
_MAX_SUFFIX = 16
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")
_DEFAULT_STEM = "upload"
_DEFAULT_SUFFIX = ".json"


def _fit(text: str, n_bytes: int) -> str:
    """``text`` cut (at a character boundary) to at most ``n_bytes`` bytes of UTF-8."""
    data = text.encode("utf-8", "replace")[:n_bytes]
    return data.decode("utf-8", "ignore")


def shown_upload_name(name) -> str:
    """The trainee's file name as it can be shown in a message (printable, at most 120)."""
    if not isinstance(name, str) or not name.strip():
        return "the uploaded file"
    shown = _CONTROL.sub("?", name)
    return shown if len(shown) <= 120 else f"{shown[:60]}...{shown[-57:]}"


def safe_upload_name(name) -> str:
    """A name under which an upload called ``name`` can be stored in a folder of its own.

    Unsafe characters become ``_``, leading dots are dropped (no hidden files, no
    ``..``), the extension is kept (``.json`` if there is none) and the whole fits in
    :data:`~tutor.fileio.MAX_NAME_BYTES` bytes.
    """
    text = name if isinstance(name, str) else ""
    text = _UNSAFE.sub("_", text).strip().lstrip(".").strip()
    text = text.encode("utf-8", "replace").decode("utf-8")  # lone surrogates become U+FFFD
    stem, dot, suffix = text.rpartition(".")
    if not dot:
        stem, suffix = text, _DEFAULT_SUFFIX[1:]
    suffix = "." + _fit(suffix, _MAX_SUFFIX - 1) if suffix.strip() else _DEFAULT_SUFFIX
    stem = stem.rstrip(". ") or _DEFAULT_STEM
    stem = _fit(stem, MAX_NAME_BYTES - len(suffix.encode("utf-8")))
    return stem + suffix


def _message_line(load: Callable) -> Callable[[str], None]:
    """Where ``load``'s messages go: the tutor's ``message`` and ``refresh()``.

    ``load`` is normally a tutor's bound ``load`` method; a tutor shows its
    ``message`` in its panel when it refreshes. Anything else gets a log warning.
    """
    owner = getattr(load, "__self__", None)
    if hasattr(owner, "message") and callable(getattr(owner, "refresh", None)):

        def show(text: str) -> None:
            owner.message = text
            owner.refresh()

        return show
    return _log.warning


def _retitle(load: Callable, stored: str, shown: str) -> None:
    """Put the trainee's file name back into the tutor's message where it names the stored one."""
    owner = getattr(load, "__self__", None)
    message = getattr(owner, "message", None)
    if stored != shown and isinstance(message, str) and stored in message:
        owner.message = message.replace(stored, shown)
        owner.refresh()


def on_upload(
    load: Callable[[Path], None], report: Callable[[str], None] | None = None
) -> Callable[[dict], None]:
    """An observer for ``FileUpload.value`` that hands the first file to ``load(path)``.

    Parameters
    ----------
    load : callable
        Takes the path of the stored upload, whose name is the trainee's unless
        that was unsafe. Where the tutor's message names the stored file, the
        trainee's own name is put back.
    report : callable, optional
        Shows a message to the trainee; by default the tutor's message line (the
        ``message`` attribute and ``refresh()`` of the object ``load`` is bound to).

    Notes
    -----
    The upload is written to a temporary folder of its own and removed after
    ``load`` returns. A file larger than :data:`~tutor.limits.MAX_UPLOAD_BYTES` is
    refused unwritten. A :class:`~tutor.errors.TutorError` raised by ``load`` (or a
    failure to store the upload) is reported, never raised out of the callback.
    """
    show = report if report is not None else _message_line(load)

    def observer(change: dict) -> None:
        files = change.get("new") if isinstance(change, dict) else None
        if not files:
            return
        try:
            item = files[0]
            raw_name = item.get("name")
        except (KeyError, IndexError, TypeError, AttributeError):
            item, raw_name = None, None
        shown = shown_upload_name(raw_name)
        try:
            raw = item["content"]
        except (KeyError, TypeError):
            raw = None
        if not isinstance(raw, (bytes, bytearray, memoryview)):
            show(f"Nothing was loaded: {shown} arrived without its content; upload it again.")
            return
        size = memoryview(raw).nbytes
        if size > MAX_UPLOAD_BYTES:
            show(
                f"Nothing was loaded: {shown} is {megabytes(size)}, larger than the "
                f"{megabytes(MAX_UPLOAD_BYTES)} an upload can be (a run of 100 "
                "demonstrations is about 2 MB); is it the right file?"
            )
            return
        content = bytes(raw)
        name = safe_upload_name(raw_name)
        try:
            with tempfile.TemporaryDirectory(
                prefix="lfd-upload-", ignore_cleanup_errors=True
            ) as tmp:
                path = Path(tmp) / name
                try:
                    path.write_bytes(content)
                except OSError as exc:
                    raise save_error(name, exc) from exc
                load(path)
            _retitle(load, name, shown)
        except SaveError as exc:  # the upload, or the tutor's autosave, could not be written
            show(str(exc).replace(name, shown))
        except TutorError as exc:
            text = str(exc).replace(name, shown)
            show(text if text.startswith("Nothing was loaded") else f"Nothing was loaded: {text}")
        except OSError as exc:  # the temporary folder could not be made
            show(f"Nothing was loaded: {shown} could not be stored for reading ({exc.strerror}).")

    return observer
