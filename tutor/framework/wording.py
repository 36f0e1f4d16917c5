"""Words every layer shares when it talks to a person (counts with their nouns)."""

from __future__ import annotations

__all__ = ["plural"]


def plural(k: int, noun: str, nouns: str | None = None) -> str:
    """``k`` with its noun: "1 trainee", "36 trainees" (``nouns`` defaults to ``noun`` + "s").

    >>> plural(1, "trainee"), plural(36, "trainee"), plural(2, "pass", "passes")
    ('1 trainee', '36 trainees', '2 passes')
    """
    return f"{k} {noun if k == 1 else (nouns or noun + 's')}"
