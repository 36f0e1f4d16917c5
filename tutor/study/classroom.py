"""A class's own runs read back: every trainee's saved run records, checked and scored.

The tutor saves each teaching run as a run record (:mod:`tutor.framework.record`) in
the trainee's folder. :func:`read_class` reads a whole class: a folder tree (one
subfolder per trainee, at any depth, as a hub's class folder or the collected
``sessions/`` folders give it) or a zip of one; a zip inside it is read as one
trainee's hand-in, their folder (:mod:`.class_files` finds the files, with the caps of
:mod:`tutor.limits`, and reads zips in memory). Each file is checked in turn, and a
file that cannot be used is listed with the reason, never counted silently and never
allowed to stop the others:

- it cannot be read (not JSON, not UTF-8, too large, truncated, a link out of the
  class folder, a zip entry refused ...);
- it is not a run record (another format, a newer version, a field out of range);
- its demonstrations cannot be replayed by this tutor's learner (or are more than a run
  can have, :data:`~tutor.limits.MAX_DEMOS_PER_RUN`);
- it is a practice run, or its current attempt is not finished;
- it repeats a run another file already holds (the finished, latest one is counted).

Files of the other experiment are set aside (``other_experiment``), not reported as
problems; hidden files (``.NF.lock``, temporary files) and files that are neither
``.json`` nor ``.zip`` are not looked at. A class of more than
:data:`~tutor.limits.MAX_CLASS_FILES` run files is refused as a whole (LimitError).

Every counted run is replayed through the same learner and scored by the same
function as the simulated cohorts (:func:`tutor.study.cohort.rows_of`), so the class's
rows have the cohort's columns (``teacher`` is the trainee's number in the class, and
``trainee``, ``trainee_key`` and ``file`` say whose run it is).

Examples
--------
>>> result = read_class("class_folder/", experiment=1)      # doctest: +SKIP
>>> result.runs.groupby("condition").eta.median()           # doctest: +SKIP
"""

from __future__ import annotations

import os
import sys
import zipfile
from collections import Counter
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path, PurePosixPath

import pandas as pd

from ..errors import InvalidFileError, InvalidParameterError, LimitError, TutorError
from ..framework.assignment import ClassPlan, load_plan
from ..framework.protocol import EXPERIMENTS
from ..framework.record import RunRecord
from ..framework.wording import plural, sentence
from ..runtime import headless
from ..workers import one_blas_thread, process_pool
from .class_files import ZIP_AGAIN, close_zips, hidden, list_class, read_run_file
from .cohort import StudySettings, _task, rows_of

__all__ = [
    "ClassResult",
    "FileOutcome",
    "RUN_CLASSES",
    "read_class",
    "PROBLEMS",
]

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


def _run_class(experiment: int):
    if experiment == 1:
        from ..tasks.maze_run import MazeRun

        return MazeRun
    from ..tasks.pickplace_protocol import PickPlaceRun

    return PickPlaceRun


#: experiment -> a function giving its TeachingRun subclass (imported on first use)
RUN_CLASSES = {1: lambda: _run_class(1), 2: lambda: _run_class(2)}


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
            assigned = self.roster.get(key, ("", ""))[1] if self.experiment == 2 else ""
            taught = {f.condition for f in counted}
            if not theirs:
                missing = "no run file yet"
            elif assigned and taught and taught != {assigned}:
                missing = (
                    f"taught {', '.join(sorted(taught))}, but the class plan assigns {assigned}"
                )
            elif self.experiment == 1:
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


# ---------------------------------------------------------------- finding the files


#: the reason given for a folder of the class that this account cannot read
CANNOT_READ = (
    "you cannot read this trainee folder (no permission): its runs are not counted. Read "
    "the class as root, or from an account in the educators' group (the hub kit's "
    "lfd-educators)"
)


def _unreadable_folders(root: Path) -> list[FileOutcome]:
    """One "unreadable" outcome (file ``<folder>/``) per folder under ``root`` that this
    account may not list: :func:`.class_files.list_class`'s walk passes over them in
    silence."""
    blocked = []

    def note(error: OSError) -> None:
        if isinstance(error, PermissionError):
            label = Path(error.filename).relative_to(root).as_posix()
            blocked.append(FileOutcome(f"{label}/", "unreadable", CANNOT_READ))

    for _, dirnames, _ in os.walk(root, onerror=note):
        dirnames[:] = [d for d in dirnames if not hidden([d])]
    return sorted(blocked, key=lambda outcome: outcome.file)


@dataclass(frozen=True)
class _Meta:
    """What deciding between copies of one run needs of a record (cheap to send back)."""

    key: tuple
    finished: bool
    latest: str
    label: str
    name: str
    run_id: str | None = None


def _read(item):
    """Worker: read, check and (when it may count) replay one file, in one pass.

    ``item`` is (class folder or zip, RunFile, label, experiment, settings); gives
    (FileOutcome, _Meta or None, the replay's (kind, reason, run row, demo rows) or None).
    """
    source, run_file, label, experiment, settings = item
    read = partial(read_run_file, Path(source), run_file)
    outcome, record = _check(label, read, experiment, ZIP_AGAIN if run_file.members else "")
    if record is None:
        return outcome, None, None
    meta = _Meta(
        (record.trainee.key, record.condition, record.run),
        record.finished,
        _latest(record),
        record.label,
        record.trainee.name,
        record.run_id,
    )
    return outcome, meta, _replay((label, record, experiment, settings))[1:]


# ---------------------------------------------------------------- one file


def _summary(record: RunRecord) -> dict:
    return {
        "trainee": record.trainee.name,
        "trainee_key": record.trainee.key,
        "condition": record.condition,
        "run": record.run,
        "n_demos": record.current.n_demos,
        "finished": record.finished,
        "practice": record.practice,
    }


ASK_AGAIN = "Ask the trainee for the run file again (from their folder in the class folder)."


def _check(label: str, read, experiment: int, again: str = ""):
    """(FileOutcome, record or None): every check short of replaying the demos (``again``
    says what to do about a file that cannot be used; default :data:`ASK_AGAIN`)."""
    again = again or ASK_AGAIN
    try:
        data = read()
    except TutorError as exc:
        return FileOutcome(label, "unreadable", f"{sentence(exc)} {again}"), None
    try:
        record = RunRecord.from_dict(data)
    except TutorError as exc:
        return FileOutcome(label, "not a run record", f"{sentence(exc)} {again}"), None
    info = _summary(record)
    if record.experiment != experiment:
        reason = f"an Experiment {record.experiment} run: read it with --experiment "
        return FileOutcome(label, "other experiment", reason + str(record.experiment), **info), None
    spec = EXPERIMENTS[experiment]
    if record.condition not in spec.paper_codes or record.task != spec.task:
        return (
            FileOutcome(
                label,
                "not a run record",
                f"its task {record.task!r} and condition {record.condition!r} are not "
                f"Experiment {experiment}'s ({spec.task}: {', '.join(spec.paper_codes)})",
                **info,
            ),
            None,
        )
    if record.practice:
        return (
            FileOutcome(label, "practice", "a practice run: practice is never counted", **info),
            None,
        )
    return FileOutcome(label, "counted", "", **info), record


def _replay(item):
    """Worker: replay one record; gives (label, kind, reason, run row, demo rows)."""
    label, record, experiment, settings = item
    spec = EXPERIMENTS[experiment]
    try:
        run = RUN_CLASSES[experiment]().from_record(_task(spec.task, settings), record)
    except LimitError as exc:  # too many demos to replay: said before any is
        return label, "cannot be replayed", f"{sentence(exc)} {ASK_AGAIN}", None, []
    except TutorError as exc:
        reason = (
            f"{sentence(exc)} The tutor's learner cannot use it (was it edited by hand?). "
            + ASK_AGAIN
        )
        return label, "cannot be replayed", reason, None, []
    if not run.finished:
        reason = (
            f"not finished ({run.n_demos} demonstrations so far): the trainee has not "
            "pressed Finish, so it is not counted yet"
        )
        return label, "unfinished", reason, None, []
    if not run.n_demos:
        reason = (
            "finished with no demonstration: its η (final ε / demonstrations) is not "
            "defined, so it is not counted; ask the trainee to teach the run again"
        )
        return label, "no demonstrations", reason, None, []
    base = {"condition": record.condition, "run": record.run}
    row, demo_rows = rows_of(run, base, settings)
    return label, "counted", "", row, demo_rows


def _latest(record: RunRecord) -> str:
    return record.events[-1].at if record.events else record.created


# ---------------------------------------------------------------- a class


def read_class(
    source,
    experiment: int,
    workers: int | None = None,
    settings: StudySettings | None = None,
    plan=None,
    meanwhile=None,
    cache: dict | None = None,
    progress=None,
) -> ClassResult:
    """Read and score every run record of a class (see the module docstring).

    Parameters
    ----------
    source : path
        The class folder (one subfolder per trainee) or a ``.zip`` of it.
    experiment : {1, 2}
    workers : int, optional
        Processes that replay the runs (default: the machine's cores); 1 works here.
    settings : StudySettings, optional
        The analysis settings (default: the simulated cohorts' own).
    plan : path or ClassPlan, optional
        The class plan (:mod:`tutor.framework.assignment`): its trainees without a file
        are listed as missing, and in Experiment 2 a trainee who taught another
        condition than the plan's is not counted as whole. Default: ``plan.csv`` or
        ``plan.json`` in the class folder when there is one.
    meanwhile : callable, optional
        Called here while the workers replay the runs (the command line imports the
        statistics then, which would otherwise wait for them).
    cache : dict, optional
        Kept by the caller between reads of the same class folder (the dashboard's
        Refresh): a file whose size and modification time are unchanged is neither read
        nor replayed again (a trainee's zip: while the zip is unchanged). Ignored for a
        class zip.
    progress : bool or callable, optional
        A tqdm progress bar on stderr over the files read (default: when stderr is a
        terminal and ``TUTOR_HEADLESS`` is not set), or ``progress(done, total)`` called
        after each file.

    Returns
    -------
    ClassResult

    Raises
    ------
    InvalidParameterError
        ``experiment`` is not 1 or 2, or ``workers`` is not a whole number >= 1.
    InvalidFileError
        ``source`` is neither a folder nor a readable zip file (InvalidPlanError: the
        plan cannot be read).
    LimitError
        The class holds more than :data:`~tutor.limits.MAX_CLASS_FILES` run files, or the
        class zip goes over a zip cap (:mod:`.class_files`).
    """
    if isinstance(experiment, bool) or experiment not in EXPERIMENTS:
        raise InvalidParameterError(
            f"experiment must be 1 (maze) or 2 (pick-and-place), got {experiment!r}"
        )
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise InvalidParameterError(f"workers must be a whole number >= 1, got {workers!r}")
    step = _progress(progress)
    settings = StudySettings() if settings is None else settings
    path = Path(source)
    if not path.is_dir() and not (path.is_file() and zipfile.is_zipfile(path)):
        if path.exists():
            raise InvalidFileError(
                f"{path} is neither a folder nor a zip file: give the class folder (one "
                "subfolder per trainee) or a zip of it"
            )
        raise InvalidFileError(
            f"there is no folder or zip file at {path}: give the class folder (on a hub, "
            "the folder the kit keeps every trainee's runs in, e.g. /srv/lfd-class)"
        )
    listing = list_class(path)
    run_files = {f.label: f for f in listing.files if PurePosixPath(f.label).name not in PLAN_NAMES}
    labels = list(run_files)
    workers = min(os.cpu_count() or 1, max(1, len(labels))) if workers is None else workers
    roster = _roster(path, plan, experiment)
    context = (str(path.resolve()), experiment, settings)  # a cache is for one class
    memo = _Memo(None if path.is_file() else cache, run_files, context)
    try:
        with _Pool(workers) as pool:
            fresh = memo.todo(labels, "file")
            items = [(str(path), run_files[lab], lab, experiment, settings) for lab in fresh]
            done = pool.map(_read, items, meanwhile, step(len(items)))
            outcomes = memo.merge(labels, "file", dict(zip(fresh, done, strict=True)))
    finally:
        close_zips()
    refused = [(FileOutcome(lab, "unreadable", why), None, None) for lab, why in listing.refused]
    outcomes = sorted(outcomes + refused, key=lambda o: o[0].file)
    if path.is_dir():
        outcomes += [(outcome, None, None) for outcome in _unreadable_folders(path)]
    result = _score(path, experiment, outcomes, settings)
    result.roster = roster
    return result


def _progress(progress):
    """``progress`` checked; gives a function of the number of files that makes the
    progress callback (None for none): a tqdm bar on stderr, or the caller's own."""
    if not (progress is None or isinstance(progress, bool) or callable(progress)):
        raise InvalidParameterError(
            f"progress must be True, False, None or a function of (done, total), got {progress!r}"
        )

    def make(total: int):
        if total < 1 or progress is False:
            return None
        if callable(progress):
            return lambda done: progress(done, total)
        if progress is None and (headless() or not sys.stderr.isatty()):
            return None
        from tqdm import tqdm

        tqdm.monitor_interval = 0  # no monitor thread in a process that forks workers
        return _Bar(tqdm(total=total, desc="Reading the class", unit="file", file=sys.stderr))

    return make


class _Bar:
    """A tqdm bar as a function of the files done so far (closed at the last one)."""

    def __init__(self, bar):
        self.bar = bar

    def __call__(self, done: int) -> None:
        self.bar.update(done - self.bar.n)
        if done >= self.bar.total:
            self.bar.close()


class _Memo:
    """What :func:`read_class` learnt about each file, kept while the file is unchanged."""

    def __init__(self, cache, run_files: dict, context):
        self.cache, self.stamps = cache, {}
        if cache is None:
            return
        if cache.get("context") != context:  # another experiment or settings: start over
            cache.clear()
            cache["context"] = context
        for label, run_file in run_files.items():
            try:  # a run file in a trainee's zip changes with the zip
                info = os.stat(run_file.path)
                self.stamps[label] = (info.st_mtime_ns, info.st_size, info.st_ino)
            except OSError:
                self.stamps[label] = None

    def _known(self, label: str, step: str):
        if self.cache is None or self.stamps.get(label) is None:
            return None
        hit = self.cache.get((step, label))
        return hit[1] if hit is not None and hit[0] == self.stamps[label] else None

    def todo(self, labels, step: str) -> list:
        return [lab for lab in labels if self._known(lab, step) is None]

    def merge(self, labels, step: str, new: dict) -> list:
        if self.cache is not None:
            for label, value in new.items():
                self.cache[(step, label)] = (self.stamps.get(label), value)
        return [new[lab] if lab in new else self._known(lab, step) for lab in labels]


#: the class plan's file names in a class folder (read as the plan, not as runs)
PLAN_NAMES = ("plan.csv", "plan.json")


def _roster(path: Path, plan, experiment: int) -> dict:
    if plan is None and path.is_dir():
        plan = next((path / n for n in PLAN_NAMES if (path / n).is_file()), None)
    if plan is None:
        return {}
    if not isinstance(plan, ClassPlan):
        # the plan assigns Experiment 2's conditions; for Experiment 1 it is a roster
        plan = load_plan(plan, EXPERIMENTS[2].paper_codes, 2)
    return {key: (plan.names[key], plan.table[key][0]) for key in plan.table}


class _Pool:
    """``map`` over worker processes (or here, for one worker), results in order."""

    def __init__(self, workers: int):
        self.workers, self._pool = workers, None

    def __enter__(self):
        if self.workers > 1:
            self._pool = process_pool(self.workers)
        else:
            one_blas_thread()
        return self

    def map(self, fn, items, meanwhile=None, step=None) -> list:
        """``fn`` of each item; ``meanwhile()`` runs here while the workers work, and
        ``step(n)`` after each of the n first results."""
        if self._pool is None or len(items) < 2:
            results = []
            for item in items:
                results.append(fn(item))
                if step is not None:
                    step(len(results))
            if meanwhile is not None:
                meanwhile()
            return results
        chunk = max(1, len(items) // (4 * self.workers))
        pending = self._pool.map(fn, items, chunksize=chunk)  # submitted at once
        if meanwhile is not None:
            meanwhile()
        results = []
        for result in pending:
            results.append(result)
            if step is not None:
                step(len(results))
        return results

    def __exit__(self, *exc):
        if self._pool is not None:
            self._pool.shutdown()


def _folder(label: str) -> str:
    return PurePosixPath(label).parent.as_posix()


def _best(members):
    """The copy to count: the finished one, then the one changed last, then the shorter
    name (NF.json before the NF-2.json the tutor saves beside it)."""
    return max(members, key=lambda m: (m[1].finished, m[1].latest, -len(m[0].file)))


def _duplicates(outcomes) -> tuple[dict[str, tuple[str, str]], set[str]]:
    """(label -> (the label counted instead, why), trainee keys whose name clashes).

    Files are copies of one run only when they share a run id (old records without one:
    when they share trainee, condition and run number, as before ids). Two runs with
    different ids under one name in different folders are two trainees: a name clash.
    In one folder, the run changed last is counted (the trainee began the run again)."""
    groups: dict[tuple, list] = {}
    for outcome, meta, _ in outcomes:
        if meta is not None and outcome.counted:
            groups.setdefault(meta.key, []).append((outcome, meta))
    beaten, clashes = {}, set()

    def keep_one(same: list, why: str):
        best = _best(same)
        beaten.update({o.file: (best[0].file, why) for o, _ in same if o is not best[0]})
        return best

    for key, members in groups.items():
        copies: dict = {}
        for m in members:
            copies.setdefault(m[1].run_id, []).append(m)
        kept = [
            keep_one(same, "holds the same run" + (" (the same run id)" if run_id else ""))
            for run_id, same in copies.items()
        ]
        by_folder: dict = {}
        for m in kept:
            by_folder.setdefault(_folder(m[0].file), []).append(m)
        if len(by_folder) > 1:
            clashes.add(key[0])
        for same in by_folder.values():
            keep_one(same, "is a later run of the same condition in the same folder")
    return beaten, clashes


def _apart(outcome: FileOutcome, clashes: set[str]) -> FileOutcome:
    """A file of a clashing name, keyed by name and folder (a trainee of its own)."""
    if outcome.trainee_key not in clashes:
        return outcome
    folder = _folder(outcome.file)
    return replace(
        outcome,
        trainee_key=f"{outcome.trainee_key}@{folder}",
        trainee=f"{outcome.trainee} ({folder})",
        reason=outcome.reason
        or f"name clash: other trainees typed the name {outcome.trainee!r} too; "
        f"told apart by their folder ({folder})",
    )


def _score(path: Path, experiment: int, outcomes, settings) -> ClassResult:
    beaten, clashes = _duplicates(outcomes)
    files, rows, demo_rows = [], [], []
    old_runs = sum(1 for o, meta, _ in outcomes if meta is not None and meta.run_id is None)
    for outcome, meta, replayed in outcomes:
        if outcome.file in beaten:
            instead, why = beaten[outcome.file]
            outcome = replace(
                outcome,
                kind="duplicate",
                reason=f"{instead} {why} ({meta.label} of {meta.name}); that file is counted",
            )
        outcome = _apart(outcome, clashes)
        if outcome.counted:
            kind, reason, row, extra = replayed
            if kind != "counted":
                outcome = replace(outcome, kind=kind, reason=reason)
            else:
                who = {"trainee": outcome.trainee, "trainee_key": outcome.trainee_key}
                rows.append({"teacher": 0, **who, "file": outcome.file, **row})
                demo_rows += [{"teacher": 0, **who, **d} for d in extra]
        files.append(outcome)
    order = list(EXPERIMENTS[experiment].paper_codes)
    runs, demos = pd.DataFrame(rows), pd.DataFrame(demo_rows)
    for frame in (runs, demos):
        if frame.empty:
            frame["condition"] = pd.Categorical([], categories=order, ordered=True)
        else:
            frame["condition"] = pd.Categorical(frame["condition"], categories=order, ordered=True)
    if not runs.empty:  # the trainees' numbers in the class, in key order
        number = {key: i for i, key in enumerate(sorted(set(runs.trainee_key)))}
        runs["teacher"] = runs.trainee_key.map(number)
        demos["teacher"] = demos.trainee_key.map(number)
        runs = runs.sort_values(["teacher", "run", "condition"], kind="stable")
        runs = runs.reset_index(drop=True)
    return ClassResult(experiment, str(path), runs, demos, files, settings, old_runs=old_runs)
