"""Finding and reading the run files of a class: a folder tree, a zip of one, and the
trainees' own zips inside either (how Binder trainees hand in their runs).

:func:`list_class` finds every run file (``.json``) of a class and :func:`read_run_file`
reads one; :mod:`.classroom` checks and scores them. A zip in the class folder (or in
the class zip) is read as that trainee's folder: its run files are listed under the
zip's name (``ann.zip/NF.json``, ``ann.zip/ann/NF.json`` with a top folder), so the
zip's name, or its top folder, tells its trainee apart. Zips are read in memory, never
unpacked to disk, and one entry at a time.

Nothing is trusted: a zip entry whose name leads out of its folder (``..``, an absolute
path), a link, an encrypted entry or one packed other than the usual way (stored or
deflate) is refused unread and listed with the reason, as is one that is too large or
unpacks to far more than it packs to (a "zip bomb"). The caps are
:mod:`tutor.limits`': run files in a class (:data:`~tutor.limits.MAX_CLASS_FILES`, over
it the class is refused), entries in one zip and what they unpack to together
(:data:`~tutor.limits.MAX_ZIP_MEMBERS`, :data:`~tutor.limits.MAX_ZIP_BYTES`, checked
before the zip's entries are read), the size of a run file
(:data:`~tutor.limits.MAX_RUN_FILE_BYTES`) and of a trainee's zip inside the class zip
(:data:`~tutor.limits.MAX_FILE_BYTES`), and the packing ratio
(:data:`~tutor.limits.MAX_ZIP_RATIO`). Zips inside a trainee's zip are not opened.
"""

from __future__ import annotations

import io
import os
import re
import stat
import struct
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InvalidFileError, LimitError, TutorError
from ..fileio import decode_text, megabytes, parse_json, read_json
from ..framework.wording import sentence
from ..limits import (
    MAX_CLASS_FILES,
    MAX_FILE_BYTES,
    MAX_RUN_FILE_BYTES,
    MAX_ZIP_BYTES,
    MAX_ZIP_MEMBERS,
    MAX_ZIP_RATIO,
    ZIP_RATIO_FROM_BYTES,
)

__all__ = ["RunFile", "Listing", "list_class", "read_run_file", "close_zips", "ZIP_AGAIN"]

#: what to do about a trainee's zip that cannot be used
ZIP_AGAIN = "Ask the trainee to zip their run files again and hand the zip in."
#: control characters, shown as "?" in the name of a zip entry refused for them
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")
#: ways of packing a zip entry that are read (what every zip tool makes by default)
_PACKINGS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED)


@dataclass(frozen=True)
class RunFile:
    """Where one run file of a class is.

    Attributes
    ----------
    label : str
        Its path as shown, relative to the class folder; inside a zip, under the zip's
        own path (``ann.zip/NF.json``).
    path : str
        The file on disk: the run file itself, or the zip holding it.
    members : tuple of str
        The zip entry names leading to it, outermost first (empty for a file on disk;
        two for a trainee's zip inside the class zip).
    """

    label: str
    path: str
    members: tuple[str, ...] = ()


@dataclass
class Listing:
    """What :func:`list_class` found: the run files, and the entries refused unread
    (``(label, reason)``)."""

    files: list[RunFile] = field(default_factory=list)
    refused: list[tuple[str, str]] = field(default_factory=list)

    def add(self, run_file: RunFile, source) -> None:
        self.files.append(run_file)
        if len(self.files) > MAX_CLASS_FILES:
            raise _TooManyRunFiles(
                f"{source} holds more than {MAX_CLASS_FILES} run files (.json files, those "
                "in zips too), more than one class analysis reads "
                "(tutor.limits.MAX_CLASS_FILES): read one class at a time (e.g. the folder "
                "of one workshop), or move old runs out of it"
            )


class _TooManyRunFiles(LimitError):
    """The class as a whole holds too many run files (never a reason to skip one zip)."""


def hidden(parts) -> bool:
    """True for a path with a hidden part (``.NF.lock``, ``.ipynb_checkpoints``) or a
    macOS ``__MACOSX`` folder."""
    return any(p.startswith(".") or p == "__MACOSX" for p in parts)


# ---------------------------------------------------------------- finding them


def list_class(path: Path) -> Listing:
    """The run files of the class folder or class zip ``path``, in label order.

    Raises
    ------
    LimitError
        More than :data:`~tutor.limits.MAX_CLASS_FILES` run files, or a class zip over
        a zip cap.
    InvalidFileError
        A class zip that cannot be read.
    """
    if path.is_dir():
        listing = _list_folder(path)
    else:
        listing = Listing()
        try:
            _check_entries(path, f"the zip file {path}")
            with zipfile.ZipFile(path) as archive:
                _list_archive(listing, archive, str(path), (), "", path, nested=True)
        except TutorError:
            raise
        except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
            raise InvalidFileError(f"the zip file {path} cannot be read: {exc}") from exc
    listing.files.sort(key=lambda f: f.label)
    listing.refused.sort()
    return listing


def _list_folder(root: Path) -> Listing:
    listing = Listing()
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not hidden([d]))
        for name in sorted(filenames):
            if name.startswith("."):
                continue
            where = Path(dirpath) / name
            label = where.relative_to(root).as_posix()
            suffix = name.lower().rpartition(".")[2]
            if suffix == "json":
                listing.add(RunFile(label, str(where)), root)
            elif suffix == "zip":
                _list_hand_in(listing, root, where, label)
    return listing


def _list_hand_in(listing: Listing, root: Path, where: Path, label: str) -> None:
    """A trainee's zip in the class folder: its run files, or why it cannot be used."""
    if not where.resolve().is_relative_to(root.resolve()):
        listing.refused.append(
            (label, "a link to a file outside the class folder: links out are not followed")
        )
        return
    try:
        _check_entries(where, f"the zip {label}")
        with zipfile.ZipFile(where) as archive:
            _list_archive(listing, archive, str(where), (), f"{label}/", root, nested=False)
    except _TooManyRunFiles:
        raise
    except TutorError as exc:
        listing.refused.append((label, f"{sentence(exc)} {ZIP_AGAIN}"))
    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
        why = f"it is not a zip file that can be read ({exc})"
        listing.refused.append((label, f"{sentence(why)} {ZIP_AGAIN}"))


def _list_archive(listing, archive, path, members, prefix, source, nested) -> None:
    """The run files of an open zip (entries ``members`` lead to it) into ``listing``;
    with ``nested``, also those of the trainees' zips in it."""
    infos = archive.infolist()
    shown = f"the zip {prefix.rstrip('/')}" if prefix else f"the zip file {path}"
    _check_totals(infos, shown)
    for info in infos:
        name = info.filename
        suffix = name.lower().rpartition(".")[2]
        if info.is_dir() or suffix not in ("json", "zip"):
            continue
        label = prefix + _CONTROL.sub("?", name)
        why = _unsafe(info)
        if why is None and hidden(re.split(r"[/\\]", name)):
            continue
        is_zip = suffix == "zip"
        if why is None:
            why = _over_caps(info, *(_ZIP_CAP if is_zip else _RUN_CAP))
        if why is None and is_zip and not nested:
            why = "a zip inside a trainee's zip is not opened: unzip it, and zip the run files"
        if why is not None:
            listing.refused.append((label, f"{sentence(why)} {ZIP_AGAIN}"))
        elif not is_zip:
            listing.add(RunFile(label, path, (*members, name)), source)
        else:
            try:
                data = io.BytesIO(_entry_bytes(archive, info, _ZIP_CAP))
                _check_entries(data, f"the zip {label}")
                with zipfile.ZipFile(data) as inner:
                    _list_archive(
                        listing, inner, path, (*members, name), f"{label}/", source, False
                    )
            except _TooManyRunFiles:
                raise
            except TutorError as exc:
                listing.refused.append((label, f"{sentence(exc)} {ZIP_AGAIN}"))
            except (zipfile.BadZipFile, OSError, ValueError, EOFError, RuntimeError) as exc:
                why = f"it is not a zip file that can be read ({exc})"
                listing.refused.append((label, f"{sentence(why)} {ZIP_AGAIN}"))


# ---------------------------------------------------------------- the caps


#: the end of a zip's central directory: its signature, and the record after it
_END = b"PK\x05\x06"
_END_RECORD = struct.Struct("<4s4H2LH")


def _entries_said(fh) -> int | None:
    """The number of entries a zip's last record says it has (None if none is found),
    read before ``zipfile`` parses the whole directory; 0xFFFF (a zip64 archive) is
    taken as that many."""
    fh.seek(0, io.SEEK_END)
    size = fh.tell()
    back = min(size, _END_RECORD.size + 0xFFFF)  # the record, and a comment of any length
    fh.seek(size - back)
    tail = fh.read(back)
    at = tail.rfind(_END)
    if at < 0 or at + _END_RECORD.size > len(tail):
        return None
    return _END_RECORD.unpack_from(tail, at)[4]


def _check_entries(source, shown: str) -> None:
    """Refuse the zip ``source`` (a path or an open binary file) when its last record
    says it has more than :data:`~tutor.limits.MAX_ZIP_MEMBERS` entries (before
    ``zipfile`` reads its whole directory)."""
    if isinstance(source, (str, os.PathLike)):
        with open(source, "rb") as fh:
            said = _entries_said(fh)
    else:
        said = _entries_said(source)
        source.seek(0)
    if said is not None and said > MAX_ZIP_MEMBERS:
        raise _too_many_entries(shown, said)


def _too_many_entries(shown: str, n: int) -> LimitError:
    return LimitError(
        f"{shown} has {n} entries, more than the {MAX_ZIP_MEMBERS} a zip may have "
        "(tutor.limits.MAX_ZIP_MEMBERS): zip only the run files (the .json files), or split it"
    )


def _check_totals(infos, shown: str) -> None:
    """Refuse a zip with too many entries, or that unpacks to too much in all."""
    if len(infos) > MAX_ZIP_MEMBERS:
        raise _too_many_entries(shown, len(infos))
    total = sum(info.file_size for info in infos)
    if total > MAX_ZIP_BYTES:
        raise LimitError(
            f"{shown} unpacks to {megabytes(total)}, more than the {megabytes(MAX_ZIP_BYTES)} "
            "a zip may unpack to (tutor.limits.MAX_ZIP_BYTES): zip only the run files, or "
            "split it"
        )


def _unsafe(info: zipfile.ZipInfo) -> str | None:
    """Why a zip entry is refused for its name or kind, or None."""
    name = info.filename
    parts = re.split(r"[/\\]", name)
    if name.startswith(("/", "\\")) or re.match(r"[A-Za-z]:", name) or ".." in parts:
        return (
            "its name leads out of the zip's folder ('..' or an absolute path): refused, not read"
        )
    if _CONTROL.search(name):
        return "its name holds control characters: refused, not read"
    if stat.S_ISLNK(info.external_attr >> 16):
        return "a symbolic link inside the zip: links are not followed"
    if info.flag_bits & 0x1:
        return "it is encrypted (a zip with a password): zip the files without a password"
    if info.compress_type not in _PACKINGS:
        return (
            "it is packed in a way the tutor does not unpack (only stored or deflate, what "
            "zip tools make by default, are read)"
        )
    return None


#: the cap on what a run file, and a trainee's zip in the class zip, unpack to
_RUN_CAP = (MAX_RUN_FILE_BYTES, "MAX_RUN_FILE_BYTES", "a run file")
_ZIP_CAP = (MAX_FILE_BYTES, "MAX_FILE_BYTES", "a trainee's zip")


def _over_caps(info: zipfile.ZipInfo, limit: int, cap: str, what: str) -> str | None:
    """Why a zip entry is refused for what it unpacks to (over ``limit``, the cap
    ``cap`` on ``what``), or None."""
    if info.file_size > limit:
        return (
            f"it unpacks to {megabytes(info.file_size)}, more than the {megabytes(limit)} "
            f"{what} may be (tutor.limits.{cap}): is it the right file?"
        )
    if info.file_size > ZIP_RATIO_FROM_BYTES and info.file_size > MAX_ZIP_RATIO * max(
        info.compress_size, 1
    ):
        return (
            f"it unpacks to {megabytes(info.file_size)} from "
            f"{megabytes(info.compress_size)}, more than {MAX_ZIP_RATIO} times its packed "
            'size (tutor.limits.MAX_ZIP_RATIO), as a "zip bomb" does: it is not unpacked'
        )
    return None


def _entry_bytes(archive: zipfile.ZipFile, info: zipfile.ZipInfo, cap: tuple) -> bytes:
    """The unpacked bytes of one zip entry, checked against the caps first (never more
    than the cap's bytes are unpacked)."""
    why = _unsafe(info) or _over_caps(info, *cap)
    if why is not None:
        raise LimitError(f"{info.filename} (in the zip): {why}")
    limit = cap[0]
    with archive.open(info) as entry:
        data = entry.read(limit + 1)
    if len(data) > limit:
        raise LimitError(f"{info.filename} (in the zip) is larger than it says: is it a zip bomb?")
    return data


# ---------------------------------------------------------------- reading one


#: zips kept open in this process between reads: (path, (mtime, size, inode), the entry
#: names of a zip inside it) -> ZipFile
_OPEN: dict = {}
_KEEP_OPEN = 4


def _zip_at(path: str, inner: tuple[str, ...] = ()) -> zipfile.ZipFile:
    """The zip at ``path`` (or the zip its entries ``inner`` lead to), opened once per
    process while the file is unchanged: a zip of many run files is not read again for
    each of them."""
    info = os.stat(path)
    key = (path, (info.st_mtime_ns, info.st_size, info.st_ino), inner)
    archive = _OPEN.get(key)
    if archive is None:
        if inner:
            outer = _zip_at(path, inner[:-1])
            data = io.BytesIO(_entry_bytes(outer, outer.getinfo(inner[-1]), _ZIP_CAP))
            _check_entries(data, f"the zip {inner[-1]}")
            archive = zipfile.ZipFile(data)
        else:
            _check_entries(path, f"the zip file {path}")
            archive = zipfile.ZipFile(path)
        if len(_OPEN) >= _KEEP_OPEN:
            close_zips()
        _OPEN[key] = archive
    return archive


def close_zips() -> None:
    """Close the zips :func:`read_run_file` keeps open in this process."""
    while _OPEN:
        _, archive = _OPEN.popitem()
        archive.close()


def read_run_file(root: Path, run_file: RunFile):
    """The JSON data of one run file of the class ``root``.

    Raises
    ------
    InvalidFileError
        It cannot be read, is not JSON, or is a link out of the class folder (LimitError:
        larger than :data:`~tutor.limits.MAX_RUN_FILE_BYTES`, or a zip entry over a cap).
    """
    if not run_file.members:
        where = Path(run_file.path)
        if not where.resolve().is_relative_to(root.resolve()):
            raise InvalidFileError(
                "a link to a file outside the class folder: links out are not followed"
            )
        return read_json(where, "run file", MAX_RUN_FILE_BYTES)
    shown = f"{run_file.label} (in the zip)"
    try:
        archive = _zip_at(run_file.path, run_file.members[:-1])
        data = _entry_bytes(archive, archive.getinfo(run_file.members[-1]), _RUN_CAP)
    except LimitError as exc:
        raise LimitError(f"run file {shown}: {exc}") from exc
    except TutorError:
        raise
    except (zipfile.BadZipFile, OSError, RuntimeError, ValueError, KeyError, EOFError) as exc:
        raise InvalidFileError(f"run file {shown} cannot be unpacked: {exc}") from exc
    return parse_json(decode_text(data, shown, "run file"), shown, "run file")
