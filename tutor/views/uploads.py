"""Files a trainee uploads with an ``ipywidgets.FileUpload`` button.

The browser sends a name and the bytes; both are the trainee's (or anyone's) and
are treated as hostile. The bytes are written under a safe name in a fresh
temporary folder (the name's unsafe characters replaced, cut to fit a file name,
the extension kept so ``.json`` and ``.csv`` are told apart), handed to a ``load``
callable with the file's name as the trainee knows it (the tutor's controller names
the file so: :meth:`tutor.framework.controller.RunController.load`), and removed.
Nothing raised by a :class:`~tutor.errors.TutorError` leaves the widget callback: its
message goes to the ``report`` callable (the tutor's message line).
"""

from __future__ import annotations

import datetime as dt
import re
import tempfile
from collections.abc import Callable
from pathlib import Path

import ipywidgets as w
from ipywidgets.widgets.trait_types import TypedTuple
from traitlets import Bunch, Dict

from ..errors import InvalidPayloadError, SaveError, TutorError
from ..fileio import MAX_NAME_BYTES, finite_number, save_error
from ..payloads import check_upload, shown_upload_name

__all__ = ["Upload", "on_upload", "safe_upload_name", "shown_upload_name"]

#: characters never kept in a stored name: NUL and control characters, path
#: separators, and what Windows refuses in names
_UNSAFE = re.compile(r'[\x00-\x1f\x7f/\\:*?"<>|]')
#: the longest extension kept (longer ones are cut off with the rest of the name)
_MAX_SUFFIX = 16
_DEFAULT_STEM = "upload"
_DEFAULT_SUFFIX = ".json"


_FILE_KEYS = ("name", "type", "size", "content")


def _files_from_page(js, _widget) -> list:
    """The page's files as ``FileUpload`` reads them, without raising on a malformed one:
    what is missing stays missing, for :func:`~tutor.payloads.check_upload` to refuse
    in words (ipywidgets' own reader raises KeyError inside the widget's message handler)."""
    files = []
    for entry in js if isinstance(js, list) else [js]:
        entry = entry if isinstance(entry, dict) else {}
        item = Bunch({k: entry[k] for k in _FILE_KEYS if k in entry})
        stamp = entry.get("last_modified")
        if finite_number(stamp):
            try:
                item["last_modified"] = dt.datetime.fromtimestamp(stamp / 1000, tz=dt.UTC)
            except (OverflowError, OSError, ValueError):
                pass  # a time no calendar holds: left out, as if not sent
        files.append(item)
    return files


def _files_to_page(value, _widget) -> list:
    """The files as ``FileUpload`` sends them back to the page (what is missing as null)."""
    out = []
    for item in value:
        js = {k: item.get(k) for k in _FILE_KEYS}
        stamp = item.get("last_modified")
        js["last_modified"] = int(stamp.timestamp() * 1000) if isinstance(stamp, dt.datetime) else 0
        out.append(js)
    return out


class Upload(w.FileUpload):
    """``ipywidgets.FileUpload`` whose value, as the page sends it, is read without raising:
    a malformed file reaches :func:`on_upload`, which says what is wrong."""

    value = TypedTuple(Dict(), help="The file upload value").tag(
        sync=True, echo_update=False, from_json=_files_from_page, to_json=_files_to_page
    )


def _fit(text: str, n_bytes: int) -> str:
    """``text`` cut (at a character boundary) to at most ``n_bytes`` bytes of UTF-8."""
    data = text.encode("utf-8", "replace")[:n_bytes]
    return data.decode("utf-8", "ignore")


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


def on_upload(
    load: Callable[[Path, str], None], report: Callable[[str], None]
) -> Callable[[dict], None]:
    """An observer for ``FileUpload.value`` that hands the first file to ``load``.

    Parameters
    ----------
    load : callable
        ``load(path, name)``: ``path`` is the stored upload, whose name is the
        trainee's unless that was unsafe; ``name`` is the file as the trainee knows it
        (:func:`~tutor.payloads.shown_upload_name`), for ``load``'s messages to name.
        A tutor passes its ``load``, which forwards to its controller.
    report : callable
        ``report(text)`` shows a message to the trainee (a tutor's ``tell``: its
        message line).

    Notes
    -----
    The upload is written to a temporary folder of its own and removed after
    ``load`` returns. What arrives is checked first
    (:func:`~tutor.payloads.check_upload`): a file without its content, or larger
    than :data:`~tutor.limits.MAX_UPLOAD_BYTES`, is refused unwritten. A
    :class:`~tutor.errors.TutorError` raised by ``load`` (or a failure to store the
    upload) is reported, never raised out of the callback.
    """

    def observer(change: dict) -> None:
        files = change.get("new") if isinstance(change, dict) else None
        if not files:
            return
        try:
            raw_name, content = check_upload(files)  # what the page sent, checked
        except InvalidPayloadError as exc:
            report(f"Nothing was loaded: {exc}")
            return
        shown = shown_upload_name(raw_name)
        name = safe_upload_name(raw_name)
        try:
            with tempfile.TemporaryDirectory(
                prefix="lfd-upload-", ignore_cleanup_errors=True
            ) as tmp:
                path = Path(tmp) / name
                try:
                    path.write_bytes(content)
                except OSError as exc:
                    raise save_error(shown, exc) from exc
                load(path, shown)
        except SaveError as exc:  # the upload, or the tutor's autosave, could not be written
            report(str(exc))
        except TutorError as exc:
            said = getattr(exc, "nothing_loaded", False)  # the controller's refusal says it
            report(str(exc) if said else f"Nothing was loaded: {exc}")
        except OSError as exc:  # the temporary folder could not be made
            report(f"Nothing was loaded: {shown} could not be stored for reading ({exc.strerror}).")

    return observer
