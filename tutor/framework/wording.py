"""Words every layer shares when it talks to a person: counts with their nouns, changes
of efficacy, and shares (η, ε) as percentages, written one way everywhere."""

from __future__ import annotations

import math

__all__ = [
    "plural",
    "sentence",
    "change_points",
    "efficacy_change",
    "percent",
    "listing",
    "REASON_WORDS",
    "NOT_A_NUMBER",
]

#: what a table or a sentence shows where there is no number (a dash, never "None")
NOT_A_NUMBER = "–"


def plural(k: int, noun: str, nouns: str | None = None) -> str:
    """``k`` with its noun: "1 trainee", "36 trainees" (``nouns`` defaults to ``noun`` + "s").

    >>> plural(1, "trainee"), plural(36, "trainee"), plural(2, "pass", "passes")
    ('1 trainee', '36 trainees', '2 passes')
    """
    return f"{k} {noun if k == 1 else (nouns or noun + 's')}"


def change_points(delta: float) -> int:
    """A change of efficacy (a fraction, e.g. eps_m - eps_{m-1}) in whole percentage points,
    as the tutor shows it: 0.0071 -> 1, -0.25 -> -25."""
    return int(round(100 * float(delta)))


def efficacy_change(delta: float) -> str:
    """A change of efficacy in words, its direction read off the points shown.

    >>> efficacy_change(0.0071), efficacy_change(-0.25), efficacy_change(0.001)
    ('efficacy rises by 1 point', 'efficacy drops by 25 points', 'efficacy stays the same')
    """
    points = change_points(delta)
    if points > 0:
        return f"efficacy rises by {plural(points, 'point')}"
    if points < 0:
        return f"efficacy drops by {plural(-points, 'point')}"
    return "efficacy stays the same"


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


def sentence(text, capital: bool = False) -> str:
    """``text`` ending as a sentence does, with one full stop (none added after ".", "!"
    or "?"); with ``capital``, its first letter made upper case.

    >>> sentence("kept untouched"), sentence("start a new run."), sentence("a note", True)
    ('kept untouched.', 'start a new run.', 'A note.')
    """
    text = str(text).strip()
    if capital:
        text = text[:1].upper() + text[1:]
    return text if text.endswith((".", "!", "?")) else text + "."


def listing(parts) -> str:
    """Parts joined as a person lists them: "a", "a and b", "a, b and c".

    >>> listing(["a"]), listing(["a", "b"]), listing(["a", "b", "c"])
    ('a', 'a and b', 'a, b and c')
    """
    parts = list(parts)
    if len(parts) < 2:
        return "".join(parts)
    return ", ".join(parts[:-1]) + " and " + parts[-1]


#: How each kind of failure reason (:class:`tutor.framework.task.Reason`) is said. The
#: slots: ``{at}`` (" at sample k of n", or nothing when sample numbers are left out),
#: ``{distance}`` (in the task's units), ``{obstacle}``, ``{plant}`` and ``{chosen}``
#: (the task's names of two test points).
REASON_WORDS = {
    "start": "did not start in the start zone",
    "obstacle": "hit {obstacle}{at}",
    "outside": "left the workspace{at}",
    "end": "ended {distance} from the target",
    "table": "went through the table{at}",
    "tray": "hit the tray{at}",
    "unreachable": "left the arm's reachable, collision-free workspace{at}",
    "no_grab": "never closed the hand",
    "grab": "grabbed {distance} from the plant",
    "wrong_plant": "grabbed {plant} instead of the chosen {chosen}",
    "no_release": "never opened the hand over the bin",
    "release": "released {distance} from the bin",
    "outside_bin": "released the plant outside the bin",
}
