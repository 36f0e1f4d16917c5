"""Reading and writing demonstration sets (JSON or CSV; never pickle).

JSON (``*.json``)::

    {"format": "lfd-tutor-demos", "version": 1, "task": "maze",
     "columns": ["t", "x", "y"], "units": {"t": "s", "x": "m", "y": "m"},
     "description": "free text",
     "demos": [[[t, x, y], [t, x, y], ...], ...],
     "conditions": [[...], null, ...]}

``version`` may be left out (it is then 1); other versions are refused.
``conditions`` is optional: the test point the teacher meant each demo for (for
pick-and-place the chosen plant's grasp point), ``null`` where not recorded. It lets a
session tell a demo to the wrong place from a demo to the right one.

CSV (``*.csv``): a header line naming the columns, e.g. ``demo,t,x,y``, then one row
per sample; rows with the same ``demo`` label form one demonstration, in the order the
labels first appear. Commas separate the values; a file separated by ``;`` or tabs
(as Excel writes in some languages) is read too, as long as its numbers use a decimal
point. A UTF-8 byte-order mark is accepted.

Columns are matched by name, in any order, in both formats: ``demo`` (CSV only), and
:data:`KNOWN_COLUMNS` (``t`` time in s, required; ``x``, ``y``, ``z`` in m; ``g`` the
hand, 0 open and 1 closed). A loaded set has them in the order :data:`KNOWN_COLUMNS`
lists them, or in the order the caller asks for (``load_demos(path, columns=...)``).

Values are checked here only for being a table of finite numbers; the task's
``preprocess`` checks the rest when a demo is added to a session. A file may hold at
most :data:`~tutor.limits.MAX_DEMOS_PER_RUN` demonstrations (the most a run can have),
each of at most :data:`~tutor.limits.MAX_SAMPLES_PER_DEMO` samples, and
:data:`~tutor.limits.MAX_SAMPLES_PER_FILE` samples in all; a larger file is refused
(:class:`~tutor.errors.LimitError`) as soon as reading it finds so.
"""

from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

import numpy as np

from .errors import InvalidDemoError, InvalidFileError, InvalidParameterError, LimitError
from .fileio import (
    atomic_write_text,
    check_file_name,
    finite_number,
    read_json,
    read_text,
    write_json,
)
from .limits import MAX_DEMOS_PER_RUN, MAX_SAMPLES_PER_DEMO, MAX_SAMPLES_PER_FILE
from .resources import asset

__all__ = [
    "DemoSet",
    "load_demos",
    "save_demos",
    "bundled_demos",
    "bundled_names",
    "BUNDLED_DIR",
    "DEMOS_FORMAT",
    "SUPPORTED_VERSIONS",
    "KNOWN_COLUMNS",
    "LABEL_COLUMN",
]

DEMOS_FORMAT = "lfd-tutor-demos"
#: the versions of the JSON format this tutor reads (a file without one is version 1)
SUPPORTED_VERSIONS = (1,)
#: the columns a demonstration may have, in the order a loaded set keeps them
KNOWN_COLUMNS = ("t", "x", "y", "z", "g")
#: the CSV column telling which demonstration a row belongs to
LABEL_COLUMN = "demo"
#: where the demonstration sets shipped with the tutor live
BUNDLED_DIR = asset("demos")

_SEPARATORS = {",": "','", ";": "';'", "\t": "tab"}
#: a plain decimal number: digits with an optional decimal point and exponent
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
#: a number written with a decimal comma (optionally with '.' or ' ' grouping)
_DECIMAL_COMMA = re.compile(r"[+-]?[0-9][0-9. ]*,[0-9]+(?:[eE][+-]?[0-9]+)?")
_NOT_FINITE = {"nan", "inf", "infinity"}


class DemoSet:
    """Demonstrations with their metadata.

    Attributes
    ----------
    demos : list of ndarray (T_m, n_columns)
    columns : list of str
        Column names, time first.
    task : str or None
    description : str
    points : list of (ndarray or None)
        The test point each demo was meant for, None where not recorded (the file's
        ``"conditions"``).
    """

    def __init__(self, demos, columns=("t", "x", "y"), task=None, description="", points=None):
        self.demos = [np.asarray(d, dtype=float) for d in demos]
        self.columns = list(columns)
        self.task = task
        self.description = description
        if points is None:
            points = [None] * len(self.demos)
        if len(points) != len(self.demos):
            raise InvalidFileError(
                f"{len(points)} test points for {len(self.demos)} demos: give one per demo"
            )
        self.demo_points = [None if c is None else np.asarray(c, float) for c in points]

    def __len__(self) -> int:
        return len(self.demos)

    def __iter__(self):
        return iter(self.demos)

    def __getitem__(self, i):
        return self.demos[i]


# --------------------------------------------------------------------- columns


def _known_list() -> str:
    return ", ".join((LABEL_COLUMN, *KNOWN_COLUMNS))


def check_columns(names, where: str, error=InvalidFileError) -> list[str]:
    """Column names checked and normalised (stripped, lower case).

    Each must be one of :data:`KNOWN_COLUMNS`, none twice, and ``t`` among them.

    Raises
    ------
    InvalidFileError (or ``error``)
        Naming the unknown, repeated or missing column and listing the known ones.
    """
    if isinstance(names, str):
        names = list(names)
    try:
        names = list(names)
    except TypeError:
        raise error(f"{where}: the columns must be a list of names such as t, x, y") from None
    if not all(isinstance(n, str) for n in names):
        raise error(f"{where}: the columns must be a list of names such as t, x, y")
    clean = [n.strip().lower() for n in names]
    for name in clean:
        if name not in KNOWN_COLUMNS:
            raise error(f"{where}: unknown column {name!r}; the known columns are {_known_list()}")
        if clean.count(name) > 1:
            raise error(f"{where}: the column {name!r} appears twice; keep one")
    if "t" not in clean:
        raise error(f"{where}: there is no 't' column (the time in s); every demo needs one")
    return clean


def _arrangement(found: list[str], expected, where: str) -> tuple[list[int], list[str]]:
    """Where each column of the result is in ``found``, and the result's names."""
    if expected is None:
        names = [c for c in KNOWN_COLUMNS if c in found]
    else:
        names = list(expected)
        missing = [c for c in names if c not in found]
        if missing:
            raise InvalidFileError(
                f"{where} has no {', '.join(repr(c) for c in missing)} column; this task's "
                f"demonstrations have the columns {', '.join(names)} (it has {', '.join(found)})"
            )
        extra = [c for c in found if c not in names]
        if extra:
            raise InvalidFileError(
                f"{where} has the column(s) {', '.join(repr(c) for c in extra)}, which this "
                f"task does not use: its demonstrations have the columns {', '.join(names)}; "
                "is it a file for another task?"
            )
    return [found.index(c) for c in names], names


# --------------------------------------------------------------------- saving


def save_demos(
    path, demos, task=None, columns=("t", "x", "y"), description="", points=None
) -> Path:
    """Write demos atomically as JSON or CSV (chosen by the file's suffix).

    ``points`` (each demo's test point, or None) is kept in JSON only (as
    ``"conditions"``).

    Raises
    ------
    InvalidParameterError
        Unknown or repeated column names.
    InvalidDemoError
        A demo that is not a non-empty table of finite numbers with one value per column.
    SaveError
        The file could not be written (see :func:`tutor.fileio.atomic_write_text`).
    """
    path = Path(path)
    columns = check_columns(columns, "save_demos", InvalidParameterError)
    demos = [_demo_to_save(d, len(columns), i) for i, d in enumerate(demos, start=1)]
    if path.suffix.lower() == ".csv":
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow([LABEL_COLUMN, *columns])
        for i, demo in enumerate(demos, start=1):
            writer.writerows([i, *map(repr, row.tolist())] for row in demo)
        return atomic_write_text(path, buf.getvalue())
    record = {
        "format": DEMOS_FORMAT,
        "version": SUPPORTED_VERSIONS[-1],
        "task": task,
        "columns": columns,
        "description": description,
        "demos": [d.tolist() for d in demos],
    }
    if points is not None:
        record["conditions"] = [
            None if c is None else np.asarray(c, float).tolist() for c in points
        ]
    return write_json(path, record)


def _demo_to_save(demo, n_columns: int, number: int) -> np.ndarray:
    try:
        array = np.asarray(demo, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidDemoError(f"demo {number} is not a table of numbers ({exc})") from exc
    if array.ndim != 2 or array.shape[1] != n_columns or array.shape[0] == 0:
        raise InvalidDemoError(
            f"demo {number} has shape {array.shape}; it must have at least one sample of "
            f"{n_columns} values (one per column)"
        )
    if not np.isfinite(array).all():
        raise InvalidDemoError(f"demo {number} holds NaN or inf; only finite numbers are saved")
    return array


# --------------------------------------------------------------------- caps


def _too_many_demos(where: str) -> LimitError:
    return LimitError(
        f"{where} holds more than {MAX_DEMOS_PER_RUN} demonstrations, the most a run can "
        f"have: keep the ones you mean to teach, at most {MAX_DEMOS_PER_RUN} in one file"
    )


def _too_many_samples(where: str) -> LimitError:
    return LimitError(
        f"{where} has more than {MAX_SAMPLES_PER_DEMO} samples (rows), the most one "
        "demonstration may have (the tutor resamples each to 200): keep every 10th "
        "row, or record at a lower rate"
    )


def _too_many_in_all(where: str) -> LimitError:
    return LimitError(
        f"{where} holds more than {MAX_SAMPLES_PER_FILE} samples (rows) in all, the most "
        "one demonstration file may have: split it into smaller files, or keep every "
        "10th row"
    )


def _check_json_caps(raw: list, name: str) -> None:
    """Refuse a JSON file's ``demos`` over the caps before any of them is read."""
    if len(raw) > MAX_DEMOS_PER_RUN:
        raise _too_many_demos(name)
    total = 0
    for i, demo in enumerate(raw, start=1):
        n = len(demo) if isinstance(demo, list) else 0
        if n > MAX_SAMPLES_PER_DEMO:
            raise _too_many_samples(f"{name}, demo {i}")
        total += n
    if total > MAX_SAMPLES_PER_FILE:
        raise _too_many_in_all(name)


# --------------------------------------------------------------------- loading


def load_demos(path, columns=None) -> DemoSet:
    """Read demos written by :func:`save_demos` (or by hand in the same formats).

    Parameters
    ----------
    path : str or Path
        A ``.json`` or ``.csv`` file.
    columns : sequence of str, optional
        The columns the task expects, e.g. ``("t", "x", "y")``. The demos come back in
        exactly this order; a file lacking one of them, or having others, is refused.
        By default the file's columns are kept, in the order of :data:`KNOWN_COLUMNS`.

    Raises
    ------
    InvalidFileError
        Saying what is wrong with the file and how to fix it.
    LimitError
        The file goes over a cap (see the module).
    InvalidParameterError
        ``columns`` names an unknown column.
    """
    problem = check_file_name(path)
    if problem is not None:
        raise InvalidFileError(f"cannot open the demonstration file: {problem}")
    path = Path(path)
    if columns is not None:
        columns = check_columns(columns, "load_demos(columns=...)", InvalidParameterError)
    if path.suffix.lower() == ".csv":
        return _load_csv(path, columns)
    if path.suffix.lower() != ".json":
        raise InvalidFileError(f"{path.name}: demonstration files must end in .json or .csv")
    return _load_json(path, columns)


def _load_json(path: Path, expected) -> DemoSet:
    data = read_json(path, "demonstration file")
    if not isinstance(data, dict) or data.get("format") != DEMOS_FORMAT:
        raise InvalidFileError(
            f"{path.name} is not an lfd-tutor demonstration file "
            f'(it needs "format": "{DEMOS_FORMAT}")'
        )
    version = data.get("version", 1)
    if type(version) is not int or version not in SUPPORTED_VERSIONS:
        raise InvalidFileError(
            f"{path.name} has version {version!r}, which this tutor cannot read; it reads "
            f"version {', '.join(map(str, SUPPORTED_VERSIONS))} (a whole number). Save the "
            "demos again with this tutor, or update the tutor"
        )
    listed = data.get("columns", ["t", "x", "y"])
    if not isinstance(listed, list):
        raise InvalidFileError(f"{path.name}: 'columns' must be a list of names such as t, x, y")
    found = check_columns(listed, f"{path.name}, 'columns'")
    order, names = _arrangement(found, expected, path.name)
    raw = data.get("demos")
    if not isinstance(raw, list):
        raise InvalidFileError(f"{path.name}: 'demos' must be a list of demonstrations")
    _check_json_caps(raw, path.name)
    demos = [
        _table(d, len(found), f"{path.name}, demo {i + 1}")[:, order] for i, d in enumerate(raw)
    ]
    task = data.get("task")
    conditions = data.get("conditions")
    if conditions is not None:
        if not (isinstance(conditions, list) and len(conditions) == len(demos)):
            raise InvalidFileError(
                f"{path.name}: 'conditions' must be a list with one entry per demo "
                f"({len(demos)}), each a list of numbers or null"
            )
        conditions = [
            _condition(c, f"{path.name}, condition {i + 1}") for i, c in enumerate(conditions)
        ]
    return DemoSet(
        demos,
        names,
        task if isinstance(task, str) else None,
        str(data.get("description", "")),
        conditions,
    )


def _condition(value, where: str) -> np.ndarray | None:
    """One entry of 'conditions': None, or a non-empty list of finite numbers."""
    if value is None:
        return None
    if not isinstance(value, list) or not value:
        shown = str(value).lower() if isinstance(value, bool) else repr(value)[:40]
        raise InvalidFileError(
            f"{where} is {shown}, not a list of numbers; write the condition as a list of "
            "numbers (e.g. [0.3, -0.2, 0.05]), or null where it was not recorded"
        )
    return _table([value], len(value), where)[0]


def _table(rows, n_columns: int, where: str) -> np.ndarray:
    if not isinstance(rows, list) or not all(
        isinstance(r, list) and len(r) == n_columns for r in rows
    ):
        raise InvalidFileError(f"{where}: every sample must be a list of {n_columns} numbers")
    for k, row in enumerate(rows, start=1):
        for value in row:
            if not finite_number(value):
                shown = str(value).lower() if isinstance(value, bool) else repr(value)[:40]
                raise InvalidFileError(
                    f"{where}, sample {k}: holds {shown}, something that is not a finite "
                    "number; write a plain number there"
                )
    return np.array(rows, dtype=float).reshape(len(rows), n_columns)


def _separator(line: str) -> str:
    """The separator that splits the header line into the most fields (',' on a tie)."""
    best, most = ",", 0
    for sep in _SEPARATORS:
        try:
            fields = next(csv.reader([line], delimiter=sep), [])
        except csv.Error:
            continue
        if len(fields) > most:
            best, most = sep, len(fields)
    return best


def _csv_number(cell: str, where: str, sep: str) -> float:
    text = cell.strip()
    if _NUMBER.fullmatch(text):
        value = float(text)
        if not math.isfinite(value):
            raise InvalidFileError(
                f"{where}: the number {text[:40]} is too large for a floating-point number "
                "(the largest is about 1.8e308): fix or remove it"
            )
        return value
    if text.lower().lstrip("+-") in _NOT_FINITE:
        raise InvalidFileError(f"{where}: NaN or inf is not allowed ({text!r}); write a number")
    if _DECIMAL_COMMA.fullmatch(text):
        raise InvalidFileError(
            f"{where}: {text!r} has a decimal comma, and the values are separated by "
            f"{_SEPARATORS[sep]}. Re-export the file with a decimal point (e.g. 0.5): in Excel "
            "or LibreOffice set the decimal separator to '.' (or the language to English), "
            "or save as 'CSV (comma delimited)'"
        )
    if text.lower().endswith("j"):
        raise InvalidFileError(f"{where}: {text!r} is a complex number; write a real number")
    raise InvalidFileError(f"{where}: {text[:40]!r} is not a number; write a plain number")


def _load_csv(path: Path, expected) -> DemoSet:
    text = read_text(path, "demonstration file")
    header_line = re.split(r"\r\n|\r|\n", text, maxsplit=1)[0]
    sep = _separator(header_line)
    where = path.name if sep == "," else f"{path.name} (values separated by {_SEPARATORS[sep]})"
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=sep)
    try:
        header = next(reader, None)
    except csv.Error as exc:
        raise InvalidFileError(f"{where}, line 1: {exc}") from exc
    if not header or len(header) < 2:
        raise InvalidFileError(
            f"{where}: the first line must be a header naming the columns, like "
            "'demo,t,x,y' (separated by commas, ';' or tabs)"
        )
    names = [h.strip().lower() for h in header]
    if names.count(LABEL_COLUMN) != 1:
        raise InvalidFileError(
            f"{where}: the header {','.join(header)[:80]!r} needs one 'demo' column telling "
            f"which demonstration each row belongs to (known columns: {_known_list()})"
        )
    label_at = names.index(LABEL_COLUMN)
    value_at = [k for k in range(len(names)) if k != label_at]
    found = check_columns([names[k] for k in value_at], f"{where}, header")
    order, columns = _arrangement(found, expected, where)
    groups: dict[str, list[list[float]]] = {}
    samples = 0
    try:
        for row in reader:
            line_no = reader.line_num
            if not row or all(not c.strip() for c in row):
                continue
            if len(row) != len(header):
                raise InvalidFileError(
                    f"{where}, line {line_no}: {len(row)} values but the header has "
                    f"{len(header)} ({', '.join(header)}); every line needs one value per "
                    "column: fix that line"
                )
            label = row[label_at].strip()
            if not label:
                raise InvalidFileError(f"{where}, line {line_no}: the 'demo' label is empty")
            at = f"{where}, line {line_no}"
            group = groups.get(label)
            if group is None:
                if len(groups) == MAX_DEMOS_PER_RUN:
                    raise _too_many_demos(f"{where} (line {line_no} begins one more)")
                group = groups[label] = []
            elif len(group) == MAX_SAMPLES_PER_DEMO:
                raise _too_many_samples(f"{where}, demo {label[:40]!r} (line {line_no})")
            samples += 1
            if samples > MAX_SAMPLES_PER_FILE:
                raise _too_many_in_all(f"{where} (line {line_no})")
            group.append([_csv_number(row[k], at, sep) for k in value_at])
    except csv.Error as exc:
        raise InvalidFileError(f"{where}, line {reader.line_num}: {exc}") from exc
    if not groups:
        raise InvalidFileError(
            f"{where} holds no samples, only the header: add the rows below it, one per "
            "sample and at least 2 per demonstration"
        )
    return DemoSet([np.array(g)[:, order] for g in groups.values()], columns)


# --------------------------------------------------------------------- bundled sets


def bundled_names() -> list[str]:
    """The names of the demonstration sets shipped with the tutor."""
    return sorted(p.stem for p in BUNDLED_DIR.glob("*.json"))


def bundled_demos(name: str, columns=None) -> DemoSet:
    """A demonstration set shipped in ``assets/demos`` (e.g. ``"maze_good"``).

    Only the names :func:`bundled_names` lists are accepted (no paths).

    Raises
    ------
    InvalidFileError
        ``name`` is not one of them; the message lists them.
    """
    known = bundled_names()
    if not isinstance(name, str) or name not in known:
        raise InvalidFileError(
            f"no bundled demonstration set {name!r}; give one of these names (without a "
            f"folder or .json): {', '.join(known)}"
        )
    return load_demos(BUNDLED_DIR / f"{name}.json", columns)
