"""The teaching framework of Sena & Howard, independent of any particular task.

- :mod:`.task`: what a task supplies (test points B^, frames, criteria).
- :mod:`.metrics`: efficacy eps, efficiency eta, the session score.
- :mod:`.failures`: incorrect, ambiguous and undemonstrated failures.
- :mod:`.feedback`: the feedback policies (what r is, what totals may be shown).
- :mod:`.selectors`: adaptive test sets, the k conditions shown after a demo (AF).
- :mod:`.session`: :class:`TeachingSession`, demos in, demo steps out.
- :mod:`.record`: :class:`RunRecord`, the typed, versioned record of one run (its
  attempts, demos and events), the one file format of a teaching run.
- :mod:`.run`: :class:`TeachingRun`, a record kept in step with its session.
"""

from .failures import AMBIGUOUS, INCORRECT, UNDEMONSTRATED, TeachingWarning, Thresholds, similarity
from .feedback import FEEDBACK_POLICIES, Visibility, reveal
from .metrics import SessionScore, efficacy, efficiency, session_score
from .record import Attempt, Demo, Event, RunRecord, Test, Trainee
from .run import RunOverError, TeachingRun
from .selectors import SELECTORS, SelectionContext, Selector, select
from .session import FEEDBACK_MODES, DemoStep, TeachingSession
from .task import Task, Verdict

__all__ = [
    "AMBIGUOUS",
    "Attempt",
    "Demo",
    "Event",
    "RunOverError",
    "RunRecord",
    "TeachingRun",
    "Test",
    "Trainee",
    "INCORRECT",
    "UNDEMONSTRATED",
    "FEEDBACK_MODES",
    "FEEDBACK_POLICIES",
    "SELECTORS",
    "SelectionContext",
    "Selector",
    "select",
    "Visibility",
    "reveal",
    "DemoStep",
    "SessionScore",
    "Task",
    "TeachingSession",
    "TeachingWarning",
    "Thresholds",
    "Verdict",
    "efficacy",
    "efficiency",
    "session_score",
    "similarity",
]
