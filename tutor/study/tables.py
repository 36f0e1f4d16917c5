"""Tables as a person reads them: η and ε in %, counts as whole numbers, a dash for none.

The study's tables (:func:`tutor.study.stats.summary_table`,
:func:`tutor.study.class_report.descriptive_table`, the class's ``beside`` table) keep
their numbers as numbers, for the CSV and JSON files. Everything shown to a person (the
cohort report of notebook 04, the class report, the dashboard) goes through
:func:`readable_table` first, so the same η is written the same way in each
(:func:`tutor.framework.wording.percent`), never as 0.329 beside 32.9%, and a cell with
no number is a dash, never ``None`` or ``nan``.
"""

from __future__ import annotations

import numbers

import numpy as np
import pandas as pd

from ..framework.wording import NOT_A_NUMBER, percent

__all__ = ["readable_table", "readable_label", "is_share", "has_no_number"]


def is_share(column) -> bool:
    """Whether a column holds shares a person reads in % (η, ε: "eta", "efficacy")."""
    name = str(column).lower()
    return "eta" in name.split() or name.startswith("eta") or "efficacy" in name


def readable_label(column) -> str:
    """A column's name as a person reads it: "median eta (class)" -> "median η (class)"."""
    words = str(column).split(" ")
    return " ".join("η" if w == "eta" else w for w in words)


def _missing(value) -> bool:
    if value is None or value is pd.NA or value is pd.NaT:
        return True
    return isinstance(value, numbers.Real) and not np.isfinite(float(value))


def _cells(values: pd.Series, share: bool) -> list[str]:
    known = [v for v in values if not _missing(v)]
    numeric = all(isinstance(v, numbers.Real) for v in known)
    whole = numeric and all(float(v).is_integer() for v in known)
    cells = []
    for v in values:
        if _missing(v):
            cells.append(NOT_A_NUMBER)
        elif share and numeric:
            cells.append(percent(v))
        elif isinstance(v, bool | np.bool_):
            cells.append("yes" if v else "no")
        elif whole:
            cells.append(str(int(v)))
        elif numeric:
            cells.append(f"{float(v):.2f}")
        else:
            cells.append(str(v))
    return cells


def readable_table(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` as text cells a person reads (see the module docstring).

    η and ε columns (:func:`is_share`) become percentages by
    :func:`~tutor.framework.wording.percent`; columns of whole numbers (counts) become
    whole numbers; other numbers get two decimals; missing cells (None, NaN) are
    :data:`~tutor.framework.wording.NOT_A_NUMBER`. Column names say η for "eta".

    >>> readable_table(pd.DataFrame({"mean eta": [0.3294, None], "runs": [3.0, 0.0]}))
      mean η runs
    0  32.9%    3
    1      –    0
    """
    out = pd.DataFrame(index=frame.index)
    for column in frame.columns:
        out[readable_label(column)] = _cells(frame[column], is_share(column))
    return out


def has_no_number(table: pd.DataFrame) -> bool:
    """Whether a :func:`readable_table` has a cell with no number (so needs a legend)."""
    return bool((table == NOT_A_NUMBER).to_numpy().any())
