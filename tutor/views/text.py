"""Feedback in plain words, for the trainee (the text beside the pictures).

Uses the paper's quantities: efficacy eps (share of the test conditions B^ the
robot now performs correctly), efficiency eta = eps / |b|, and the failure
warnings (incorrect, ambiguous, undemonstrated) of :mod:`tutor.framework.failures`.
"""

from __future__ import annotations

__all__ = ["summary", "session_report"]


def summary(record) -> str:
    """A few lines about one step: the numbers, then each warning."""
    if record is None:
        return "No demonstration yet: show the robot the task once."
    lines = [
        f"After demo {record.n_demos}: efficacy {record.efficacy:.0%} "
        f"({100 * record.delta:+.0f} points), efficiency {record.efficiency:.1%}."
    ]
    lines += [f"- {w.message}" for w in record.warnings]
    if not record.warnings:
        lines.append("- No failures: every test condition succeeds or was demonstrated.")
    return "\n".join(lines)


def session_report(session, target: float = 0.9) -> str:
    """The paper's score of a run, in words."""
    if not session.history:
        return "No demonstrations yet."
    s = session.score(target)
    if s.reached:
        head = (
            f"{target:.0%} coverage reached after {s.n_demos} demo{'s' if s.n_demos > 1 else ''}"
            f" (efficacy {s.efficacy:.0%})"
        )
    else:
        head = (
            f"{target:.0%} coverage not reached; after all {s.n_demos} demos "
            f"efficacy is {s.efficacy:.0%}"
        )
    return f"{head}: efficiency eta = {s.efficiency:.1%}."
