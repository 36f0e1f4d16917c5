"""Reading and writing demonstration sets (JSON or CSV; never pickle).

JSON (``*.json``)::

    {"format": "lfd-tutor-demos", "version": 1, "task": "maze",
     "columns": ["t", "x", "y"], "units": {"t": "s", "x": "m", "y": "m"},
     "description": "free text",
     "demos": [[[t, x, y], [t, x, y], ...], ...],
     "conditions": [[...], null, ...]}

``conditions`` is optional: the test condition the teacher meant each demo for (for
pick-and-place the chosen plant's grasp point), ``null`` where not recorded. It lets a
session tell a demo to the wrong place from a demo to the right one.

CSV (``*.csv``): a header line ``demo,t,x,y`` (further coordinate columns
allowed), then one row per sample; rows with the same ``demo`` label form one
demonstration, in the order the labels first appear.

Values are checked here only for being a table of finite numbers; the task's
``preprocess`` checks the rest when a demo is added to a session.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from .errors import InvalidFileError
from .fileio import MAX_FILE_BYTES, atomic_write_text, read_json, write_json
from .resources import asset

__all__ = ["DemoSet", "load_demos", "save_demos", "bundled_demos", "BUNDLED_DIR", "DEMOS_FORMAT"]

DEMOS_FORMAT = "lfd-tutor-demos"
#: where the demonstration sets shipped with the tutor live
BUNDLED_DIR = asset("demos")


class DemoSet:
    """Demonstrations with their metadata.

    Attributes
    ----------
    demos : list of ndarray (T_m, n_columns)
    columns : list of str
        Column names, time first.
    task : str or None
    description : str
    conditions : list of (ndarray or None)
        The condition each demo was meant for, None where not recorded.
    """

    def __init__(self, demos, columns=("t", "x", "y"), task=None, description="", conditions=None):
        self.demos = [np.asarray(d, dtype=float) for d in demos]
        self.columns = list(columns)
        self.task = task
        self.description = description
        if conditions is None:
            conditions = [None] * len(self.demos)
        if len(conditions) != len(self.demos):
            raise InvalidFileError(
                f"{len(conditions)} conditions for {len(self.demos)} demos: give one per demo"
            )
        self.conditions = [None if c is None else np.asarray(c, float) for c in conditions]

    def __len__(self) -> int:
        return len(self.demos)

    def __iter__(self):
        return iter(self.demos)

    def __getitem__(self, i):
        return self.demos[i]


def save_demos(
    path, demos, task=None, columns=("t", "x", "y"), description="", conditions=None
) -> Path:
    """Write demos atomically as JSON or CSV (chosen by the file's suffix).

    ``conditions`` (one per demo, or None) is kept in JSON only.
    """
    path = Path(path)
    demos = [np.asarray(d, dtype=float) for d in demos]
    if path.suffix.lower() == ".csv":
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(["demo", *columns])
        for i, demo in enumerate(demos, start=1):
            writer.writerows([i, *map(repr, row.tolist())] for row in demo)
        return atomic_write_text(path, buf.getvalue())
    return write_json(
        path,
        {
            "format": DEMOS_FORMAT,
            "version": 1,
            "task": task,
            "columns": list(columns),
            "description": description,
            "demos": [d.tolist() for d in demos],
            **(
                {}
                if conditions is None
                else {
                    "conditions": [
                        None if c is None else np.asarray(c, float).tolist() for c in conditions
                    ]
                }
            ),
        },
    )


def load_demos(path) -> DemoSet:
    """Read demos written by :func:`save_demos` (or by hand in the same formats)."""
    path = Path(path)
    if path.suffix.lower() == ".csv":
        return _load_csv(path)
    if path.suffix.lower() != ".json":
        raise InvalidFileError(f"{path.name}: demonstration files must end in .json or .csv")
    data = read_json(path, "demonstration file")
    if not isinstance(data, dict) or data.get("format") != DEMOS_FORMAT:
        raise InvalidFileError(
            f"{path.name} is not an lfd-tutor demonstration file "
            f'(it needs "format": "{DEMOS_FORMAT}")'
        )
    columns = data.get("columns", ["t", "x", "y"])
    if not (isinstance(columns, list) and all(isinstance(c, str) for c in columns)):
        raise InvalidFileError(f"{path.name}: 'columns' must be a list of names")
    raw = data.get("demos")
    if not isinstance(raw, list):
        raise InvalidFileError(f"{path.name}: 'demos' must be a list of demonstrations")
    demos = [_table(d, len(columns), f"{path.name}, demo {i + 1}") for i, d in enumerate(raw)]
    task = data.get("task")
    conditions = data.get("conditions")
    if conditions is not None:
        if not (isinstance(conditions, list) and len(conditions) == len(demos)):
            raise InvalidFileError(
                f"{path.name}: 'conditions' must be a list with one entry per demo "
                f"({len(demos)}), each a list of numbers or null"
            )
        conditions = [
            None
            if c is None
            else _table(
                [c], len(c) if isinstance(c, list) else 0, f"{path.name}, condition {i + 1}"
            )[0]
            for i, c in enumerate(conditions)
        ]
    return DemoSet(
        demos,
        columns,
        task if isinstance(task, str) else None,
        str(data.get("description", "")),
        conditions,
    )


def _table(rows, n_columns: int, where: str) -> np.ndarray:
    if not isinstance(rows, list) or not all(
        isinstance(r, list) and len(r) == n_columns for r in rows
    ):
        raise InvalidFileError(f"{where}: every sample must be a list of {n_columns} numbers")
    if not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        for r in rows
        for v in r
    ):
        raise InvalidFileError(f"{where}: holds something that is not a finite number")
    return np.array(rows, dtype=float).reshape(len(rows), n_columns)


def _load_csv(path: Path) -> DemoSet:
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise InvalidFileError(f"{path.name} is too large to be a demonstration file")
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidFileError(f"cannot read {path}: {exc}") from exc
    reader = csv.reader(io.StringIO(text))
    header = next(reader, None)
    if not header or header[0].strip().lower() != "demo" or len(header) < 3:
        raise InvalidFileError(f"{path.name}: the first line must be a header like 'demo,t,x,y'")
    columns = [h.strip() for h in header[1:]]
    groups: dict[str, list[list[float]]] = {}
    for line_no, row in enumerate(reader, start=2):
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise InvalidFileError(
                f"{path.name}, line {line_no}: {len(row)} values but the header has {len(header)}"
            )
        try:
            values = [float(c) for c in row[1:]]
        except ValueError as exc:
            raise InvalidFileError(f"{path.name}, line {line_no}: {exc}") from exc
        if not all(math.isfinite(v) for v in values):
            raise InvalidFileError(f"{path.name}, line {line_no}: NaN or inf is not allowed")
        groups.setdefault(row[0].strip(), []).append(values)
    if not groups:
        raise InvalidFileError(f"{path.name} holds no samples")
    return DemoSet([np.array(g) for g in groups.values()], columns)


def bundled_demos(name: str) -> DemoSet:
    """A demonstration set shipped in ``assets/demos`` (e.g. ``"maze_good"``)."""
    path = BUNDLED_DIR / f"{name}.json"
    if not path.exists():
        known = ", ".join(sorted(p.stem for p in BUNDLED_DIR.glob("*.json")))
        raise InvalidFileError(f"no bundled demonstration set {name!r}; choose one of: {known}")
    return load_demos(path)
