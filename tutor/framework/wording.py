"""Words every layer shares when it talks to a person: counts with their nouns, and
shares (η, ε) as percentages, written one way everywhere."""

from __future__ import annotations

import math

__all__ = ["plural", "percent", "NOT_A_NUMBER"]

#: what a table or a sentence shows where there is no number (a dash, never "None")
NOT_A_NUMBER = "–"


def plural(k: int, noun: str, nouns: str | None = None) -> str:
    """``k`` with its noun: "1 trainee", "36 trainees" (``nouns`` defaults to ``noun`` + "s").

    >>> plural(1, "trainee"), plural(36, "trainee"), plural(2, "pass", "passes")
    ('1 trainee', '36 trainees', '2 passes')
    """
    return f"{k} {noun if k == 1 else (nouns or noun + 's')}"


def percent(share) -> str:
    """A share (η, ε) as a person reads it: a percentage with one decimal, "32.9%".

    Every η the tutor shows (the after-Finish summary, the results cell, the class
    analysis, the dashboard, the cohort tables) is written by this function, so the same
    run reads the same everywhere. No number (None, NaN) is :data:`NOT_A_NUMBER`.

    >>> percent(0.3294), percent(0.076), percent(None)
    ('32.9%', '7.6%', '–')
    """
    if share is None:
        return NOT_A_NUMBER
    value = float(share)
    if not math.isfinite(value):
        return NOT_A_NUMBER
    return f"{value:.1%}"
