"""Validators of the learner's inputs: one ``check_*`` per kind of input.

Each returns the value in the form the maths needs (a float array, an int, a float)
or raises the named error of :mod:`tutor.errors` with what was wrong and how to fix it.
"""

from __future__ import annotations

import numbers

import numpy as np

from ..errors import InvalidDemoError, InvalidParameterError

__all__ = [
    "check_real_array",
    "check_demo",
    "check_times",
    "check_count",
    "check_number",
    "check_flag",
    "check_choice",
    "check_seed",
]


def check_real_array(value, name: str, error: type[Exception], what: str) -> np.ndarray:
    """Return ``value`` as a new float array, refusing text and complex numbers.

    ``np.array(x, dtype=float)`` alone would read the text "1e-3" as a number and drop
    the imaginary part of a complex array (with only a warning); both are refused here.

    Parameters
    ----------
    value : array-like
    name : str
        How to call the value in error messages.
    error : type
        The :mod:`tutor.errors` class to raise (e.g. ``InvalidDemoError``).
    what : str
        What the value should be, for the message (e.g. "an array of shape (T, 1 + d)").

    Raises
    ------
    error
        The value is text, complex, ragged or otherwise not a table of real numbers, or
        holds an integer too large for a float (such as ``10**400``).
    """
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nested lists
        raise error(f"{name} is not a numeric table; give {what}") from exc
    if raw.dtype.kind in "US" or _holds_text(raw):
        raise error(
            f"{name} is not a numeric table: it holds text, not numbers; give {what} "
            "(convert with float first)"
        )
    if raw.dtype.kind == "c" or _holds_complex(raw):
        raise error(
            f"{name} holds complex numbers; give real numbers: {what} "
            "(take .real only if the imaginary parts are truly zero)"
        )
    try:
        return np.array(raw, dtype=float)
    except OverflowError as exc:  # a Python int beyond float range, e.g. 10**400
        raise error(
            f"{name} holds a number too large for a float (above about 1.8e308, so not a "
            "finite number); fix or remove that value"
        ) from exc
    except (TypeError, ValueError) as exc:
        raise error(f"{name} is not a numeric table; give {what}") from exc


def _holds_text(raw: np.ndarray) -> bool:
    return raw.dtype.kind == "O" and any(isinstance(v, (str, bytes)) for v in raw.flat)


def _holds_complex(raw: np.ndarray) -> bool:
    return raw.dtype.kind == "O" and any(
        isinstance(v, numbers.Complex) and not isinstance(v, numbers.Real) for v in raw.flat
    )


def check_demo(demo, name: str = "demo", n_columns: int | None = None) -> np.ndarray:
    """Validate one demonstration and return it as a float array (T, 1 + d).

    Parameters
    ----------
    demo : array-like, shape (T, 1 + d)
        Column 0 is time, the rest world coordinates.
    name : str
        How to call the demo in error messages.
    n_columns : int, optional
        Required number of columns ``1 + d``.

    Raises
    ------
    InvalidDemoError
        Text or complex values, wrong shape, fewer than 2 samples, NaN/inf, or time not
        strictly increasing.
    """
    arr = check_real_array(
        demo, name, InvalidDemoError, "an array of shape (T, 1 + d) with time in column 0"
    )
    if arr.ndim != 2:
        raise InvalidDemoError(
            f"{name} must be a 2-D array (T samples, 1 + d columns: time then position), "
            f"got shape {arr.shape}"
        )
    if n_columns is not None and arr.shape[1] != n_columns:
        raise InvalidDemoError(
            f"{name} has {arr.shape[1]} columns but {n_columns} are needed "
            f"(time and {n_columns - 1} coordinates); check the column order and drop extras"
        )
    if arr.shape[1] < 2:
        raise InvalidDemoError(
            f"{name} has {arr.shape[1]} column(s); it needs time plus at least one coordinate"
        )
    if arr.shape[0] < 2:
        raise InvalidDemoError(
            f"{name} has {arr.shape[0]} sample(s); a demonstration needs at least 2 "
            "(record a longer movement)"
        )
    bad = ~np.isfinite(arr).all(axis=1)
    if bad.any():
        rows = np.flatnonzero(bad)
        raise InvalidDemoError(
            f"{name} has NaN or inf in {rows.size} sample(s) (rows {_list_rows(rows)}); "
            "remove or interpolate those samples"
        )
    steps = np.diff(arr[:, 0])
    if np.any(steps <= 0):
        row = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise InvalidDemoError(
            f"time in {name} is not strictly increasing (row {row}: {arr[row - 1, 0]:g} then "
            f"{arr[row, 0]:g}); sort the samples by time and drop repeated time stamps"
        )
    return arr


def check_times(times, name: str = "times") -> np.ndarray:
    """Validate query times and return them as a float array (T,)."""
    t = check_real_array(times, name, InvalidParameterError, "a 1-D array of numbers")
    if t.ndim != 1 or t.size < 1:
        raise InvalidParameterError(f"{name} must be a non-empty 1-D array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise InvalidParameterError(f"{name} contains NaN or inf")
    return t


def _list_rows(rows: np.ndarray, limit: int = 5) -> str:
    shown = ", ".join(str(int(r)) for r in rows[:limit])
    return shown + (", ..." if rows.size > limit else "")


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


def check_count(value, name: str, minimum: int = 1) -> int:
    """Return ``value`` as an int >= ``minimum``; refuse bools, floats and text.

    Raises
    ------
    InvalidParameterError
        ``value`` is not a whole number (``True``, ``2.5`` and ``"3"`` are refused) or is
        below ``minimum``.
    """
    if _is_bool(value) or not isinstance(value, numbers.Integral):
        raise InvalidParameterError(
            f"{name} must be a whole number >= {minimum}, got {value!r} "
            f"({type(value).__name__}); write it as a plain number, e.g. {name}={max(minimum, 3)}"
        )
    if value < minimum:
        raise InvalidParameterError(f"{name} must be a whole number >= {minimum}, got {value!r}")
    return int(value)


def check_number(value, name: str, minimum: float = 0.0, strict: bool = False) -> float:
    """Return ``value`` as a finite float >= ``minimum`` (> if ``strict``).

    Raises
    ------
    InvalidParameterError
        ``value`` is a bool, text, complex, NaN or inf, or out of range.
    """
    bound = f"> {minimum:g}" if strict else f">= {minimum:g}"
    wanted = (
        "a finite positive number (> 0)" if strict and minimum == 0 else f"a finite number {bound}"
    )
    if _is_bool(value) or not isinstance(value, numbers.Real):
        hint = "; write it as a number, e.g. 1e-3, not the text '1e-3'" * isinstance(value, str)
        raise InvalidParameterError(
            f"{name} must be {wanted}, got {value!r} ({type(value).__name__}){hint}"
        )
    try:
        number = float(value)
    except OverflowError:  # an int beyond float range, e.g. 10**400
        raise InvalidParameterError(
            f"{name} must be {wanted} below 1e308, got an integer too large for a float"
        ) from None
    if not np.isfinite(number) or number < minimum or (strict and number == minimum):
        raise InvalidParameterError(f"{name} must be {wanted}, got {value!r}")
    return number


def check_flag(value, name: str) -> bool:
    """Return ``value`` as a bool; refuse anything but ``True`` and ``False``.

    A text such as ``"no"`` would otherwise count as true.
    """
    if not _is_bool(value):
        raise InvalidParameterError(
            f"{name} must be True or False, got {value!r} ({type(value).__name__})"
        )
    return bool(value)


def check_choice(value, name: str, choices: tuple[str, ...]) -> str:
    """Return ``value`` if it is one of the strings ``choices``."""
    if not isinstance(value, str) or value not in choices:
        options = " or ".join(repr(c) for c in choices)
        raise InvalidParameterError(f"{name} must be {options}, got {value!r}")
    return value


def check_seed(value, name: str = "random_state"):
    """Return ``value`` if :func:`numpy.random.default_rng` can seed from it reproducibly.

    Accepted: None, an integer >= 0, a :class:`numpy.random.Generator`,
    :class:`~numpy.random.SeedSequence` or :class:`~numpy.random.BitGenerator`.

    Raises
    ------
    InvalidParameterError
        Bools, floats, text (``"3"``) and negative integers.
    """
    if value is None or isinstance(
        value, (np.random.Generator, np.random.SeedSequence, np.random.BitGenerator)
    ):
        return value
    if _is_bool(value) or not isinstance(value, numbers.Integral) or value < 0:
        raise InvalidParameterError(
            f"{name} must be None, an integer >= 0 or a numpy Generator, got {value!r} "
            f"({type(value).__name__}); e.g. {name}=3"
        )
    return int(value)
