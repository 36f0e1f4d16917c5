"""The paper's two experiments rerun as cohort studies with simulated teachers.

- :mod:`.cohort`: simulate a cohort (:func:`run_experiment`), seeded and on all cores.
- :mod:`.stats`: the paper's statistics with pingouin, the failure table, conclusions.
- :mod:`.figures`: the paper-style figures (they take the result frames only).
- :mod:`.report`: text tables beside the paper's numbers, files, robustness over seeds.
- :mod:`.paper`: the numbers the paper reports.

Command line: ``python -m tutor reproduce --experiment 1|2 --seed S --out DIR``.
"""

from .cohort import CohortResult, StudySettings, run_experiment
from .report import analyse, format_report, robustness, save_result

__all__ = [
    "CohortResult",
    "StudySettings",
    "analyse",
    "format_report",
    "robustness",
    "run_experiment",
    "save_result",
]
