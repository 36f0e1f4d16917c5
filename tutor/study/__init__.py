"""The paper's two experiments rerun as cohort studies with simulated teachers.

- :mod:`.cohort`: simulate a cohort (:func:`run_experiment`), seeded and on all cores.
- :mod:`.stats`: the paper's statistics with pingouin, the failure table, conclusions.
- :mod:`.figures`: the paper-style figures (they take the result frames only).
- :mod:`.report`: text tables beside the paper's numbers, files, robustness over seeds.
- :mod:`.tables`: any table as a person reads it (η and ε in %, a dash for no number).
- :mod:`.paper`: the numbers the paper reports.
- :mod:`.optimal`: the optimal (greedy machine) teacher, its pair bound and the teaching
  dimension (``python -m tutor.study.optimal --out tutor/assets/optimal.json``).

Command line: ``python -m tutor reproduce --experiment 1|2 --seed S --out DIR``.
"""

import importlib

#: the names the package offers, and the module each comes from (imported on first use,
#: so that the command line can check its arguments before pandas and pingouin load)
_LAZY = {
    "CohortResult": "cohort",
    "StudySettings": "cohort",
    "run_experiment": "cohort",
    "analyse": "report",
    "format_report": "report",
    "robustness": "report",
    "save_result": "report",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
