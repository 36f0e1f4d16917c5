"""What reading a class gives: each file's outcome, and the class's counted runs.

:func:`.classroom.read_class` returns a :class:`ClassResult`: the counted runs and their
demonstrations (the simulated cohort's columns), what became of every file
(:class:`FileOutcome`, counted or one of :data:`PROBLEMS` with the reason), and, from
them, the trainees, who is still to finish and which runs are whole. These names are
importable from :mod:`.classroom` too.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import pandas as pd

from ..framework.protocol import EXPERIMENTS
from ..framework.wording import plural
from .cohort import StudySettings

__all__ = ["ClassResult", "FileOutcome", "PROBLEMS"]

#: the reasons a file is not counted (``FileOutcome.kind``), in the order reports list them
PROBLEMS = (
    "unreadable",
    "not a run record",
    "cannot be replayed",
    "duplicate",
    "practice",
    "unfinished",
    "no demonstrations",
)



@dataclass(frozen=True)
class FileOutcome:
    """What became of one file of the class.

    Attributes
    ----------
    file : str
        Its path relative to the class folder (or inside the class zip); a file in a
        trainee's zip is under the zip's path (``ann.zip/NF.json``).
    kind : str
        ``"counted"``, ``"other experiment"`` or one of :data:`PROBLEMS`.
    reason : str
        In plain words, with what to do when it is a problem.
    trainee, trainee_key, condition, run, n_demos, finished, practice
        What the record says (empty when it could not be read).
    """

    file: str
    kind: str
    reason: str = ""
    trainee: str = ""
    trainee_key: str = ""
    condition: str = ""
    run: int = 0
    n_demos: int = 0
    finished: bool = False
    practice: bool = False

    @property
    def counted(self) -> bool:
        return self.kind == "counted"

    def to_dict(self) -> dict:
        return {
            "file": self.file,
            "kind": self.kind,
            "reason": self.reason,
            "trainee": self.trainee,
            "trainee_key": self.trainee_key,
            "condition": self.condition,
            "run": self.run,
            "n_demos": self.n_demos,
            "finished": self.finished,
            "practice": self.practice,
            "counted": self.counted,
        }


@dataclass
class ClassResult:
    """A class read back by :func:`read_class`.

    Attributes
    ----------
    experiment : int
    source : str
        The folder or zip that was read.
    runs : pandas.DataFrame
        One row per counted run, with the simulated cohort's columns (see the module).
    demos : pandas.DataFrame
        One row per demonstration of each counted run.
    files : list of FileOutcome
        Every run file looked at, counted or not, in path order.
    """

    experiment: int
    source: str
    runs: pd.DataFrame
    demos: pd.DataFrame
    files: list[FileOutcome] = field(default_factory=list)
    settings: StudySettings = field(default_factory=StudySettings)
    #: the class plan's trainees (folder key -> (name, Experiment 2 condition or "")), when
    #: a plan was given: those without a file are listed as missing
    roster: dict = field(default_factory=dict)
    #: runs read from old records without a run id (copies judged by trainee, condition
    #: and run number, as before run ids)
    old_runs: int = 0

    @property
    def old_runs_note(self) -> str:
        """E.g. "2 old runs without a run id: duplicates judged by name, condition and
        run", or "" when every record has an id."""
        if not self.old_runs:
            return ""
        runs = plural(self.old_runs, "old run")
        return f"{runs} without a run id: duplicates judged by name, condition and run"

    @property
    def name_clashes(self) -> list[FileOutcome]:
        """The counted files whose trainee shares a name with a trainee in another folder."""
        return [f for f in self.files if f.counted and "@" in f.trainee_key]

    @property
    def notes(self) -> list[str]:
        """What the educator should know about how files were told apart (name clashes,
        old records without a run id), one sentence each."""
        notes = []
        clashing = sorted({f.trainee_key.split("@")[0] for f in self.name_clashes})
        if clashing:
            names = sorted({f.trainee.rsplit(" (", 1)[0] for f in self.name_clashes})
            notes.append(
                f"name clash: {len(clashing)} name(s) ({', '.join(names)}) typed by "
                "different trainees in different folders, with different runs; each is "
                "counted as its own trainee, told apart by the folder"
            )
        if self.old_runs_note:
            notes.append(self.old_runs_note)
        return notes

    @property
    def not_counted(self) -> list[FileOutcome]:
        """The files of this experiment that were not counted, each with its reason."""
        return [f for f in self.files if f.kind in PROBLEMS]

    @property
    def unreadable_folders(self) -> list[FileOutcome]:
        """The trainee folders this account could not read (their runs are unknown)."""
        return [f for f in self.files if f.kind == "unreadable" and f.file.endswith("/")]

    @property
    def cannot_read_note(self) -> str:
        """ "You cannot read N trainee folders ..." when there are any, else ""."""
        n = len(self.unreadable_folders)
        if not n:
            return ""
        return (
            f"You cannot read {plural(n, 'trainee folder')} (listed below): their runs are not "
            "counted. Read the class as root or from an account in the educators' group."
        )

    @property
    def other_experiment(self) -> list[FileOutcome]:
        return [f for f in self.files if f.kind == "other experiment"]

    @property
    def trainees(self) -> pd.DataFrame:
        """One row per trainee with a file of this experiment: key, name, counted runs,
        demos in them, runs not counted and what the trainee still lacks."""
        conditions = EXPERIMENTS[self.experiment].paper_codes
        want_runs = EXPERIMENTS[self.experiment].runs
        mine = [f for f in self.files if f.trainee_key and f.kind != "other experiment"]
        rows = []
        for key in sorted({f.trainee_key for f in mine} | set(self.roster)):
            theirs = [f for f in mine if f.trainee_key == key]
            counted = [f for f in theirs if f.counted]
            names = Counter(f.trainee for f in theirs) or Counter([self.roster[key][0]])
            within = EXPERIMENTS[self.experiment].within_subjects
            assigned = "" if within else self.roster.get(key, ("", ""))[1]
            taught = {f.condition for f in counted}
            if not theirs:
                missing = "no run file yet"
            elif assigned and taught and taught != {assigned}:
                missing = (
                    f"taught {', '.join(sorted(taught))}, but the class plan assigns {assigned}"
                )
            elif within:
                done = {f.condition for f in counted}
                lacking = [c for c in conditions if c not in done]
                missing = ("still to do: " + ", ".join(lacking)) if lacking else ""
            else:
                runs_by_condition = Counter(f.condition for f in counted)
                if len(runs_by_condition) > 1:
                    missing = "runs in more than one condition: " + ", ".join(
                        sorted(runs_by_condition)
                    )
                else:
                    have = {f.run for f in counted}
                    lacking = [str(r) for r in range(1, want_runs + 1) if r not in have]
                    missing = ("still to do: run " + ", ".join(lacking)) if lacking else ""
            rows.append(
                {
                    "trainee_key": key,
                    "trainee": names.most_common(1)[0][0],
                    "counted_runs": len(counted),
                    "demos": sum(f.n_demos for f in counted),
                    "not_counted": len(theirs) - len(counted),
                    "missing": missing,
                    "complete": not missing,
                    "on_plan": key in self.roster,
                }
            )
        return pd.DataFrame(
            rows,
            columns=[
                "trainee_key",
                "trainee",
                "counted_runs",
                "demos",
                "not_counted",
                "missing",
                "complete",
                "on_plan",
            ],
        )

    @property
    def complete_runs(self) -> pd.DataFrame:
        """The rows of trainees who did every condition (Exp. 1) or all runs (Exp. 2):
        the within-subject tests need them whole."""
        if self.runs.empty:
            return self.runs
        table = self.trainees
        whole = set(table.loc[table.complete, "trainee_key"])
        return self.runs[self.runs.trainee_key.isin(whole)].reset_index(drop=True)
