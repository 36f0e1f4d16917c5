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

A run may be in any condition the experiment's registry entry lists
(:data:`tutor.framework.protocol.EXPERIMENTS`): the paper's and those beyond it (the
``condition`` column orders them so). Files of the other experiment are set aside
(``other_experiment``), not reported as problems; hidden files (``.NF.lock``, temporary
files) and files that are neither ``.json`` nor ``.zip`` are not looked at. A class of more than
:data:`~tutor.limits.MAX_CLASS_FILES` run files is refused as a whole (LimitError).

Every counted run is replayed through the same learner and scored by the same
function as the simulated cohorts (:func:`tutor.study.cohort.rows_of`), so the class's
rows have the cohort's columns (``teacher`` is the trainee's number in the class, and
``trainee``, ``trainee_key`` and ``file`` say whose run it is).

What a read gives is in :mod:`.class_result`; the worker pool, progress and refresh
cache in :mod:`.class_workers`; which copy of a run is counted in :mod:`.class_copies`.

Examples
--------
>>> result = read_class("class_folder/", experiment=1)      # doctest: +SKIP
>>> result.runs.groupby("condition").eta.median()           # doctest: +SKIP
"""

from __future__ import annotations

import os
import zipfile
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path, PurePosixPath

import pandas as pd

from ..engine import Engine
from ..errors import InvalidFileError, InvalidParameterError, LimitError, TutorError
from ..framework.assignment import ClassPlan, load_plan
from ..framework.protocol import EXPERIMENTS
from ..framework.record import RunRecord
from ..framework.wording import sentence
from ..tasks import run_class
from .class_copies import duplicate_runs, runs_apart
from .class_files import ZIP_AGAIN, close_zips, hidden, list_class, read_run_file
from .class_result import PROBLEMS, ClassResult, FileOutcome
from .class_workers import ReadMemo, progress_bar
from .cohort import StudySettings, cohort_task, rows_of

__all__ = [
    "ClassResult",
    "FileOutcome",
    "read_class",
    "PROBLEMS",
]


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
    if record.condition not in spec.codes or record.task != spec.task:
        beyond = f"; beyond the paper: {', '.join(spec.extra_codes)}" if spec.extra_codes else ""
        return (
            FileOutcome(
                label,
                "not a run record",
                f"its task {record.task!r} and condition {record.condition!r} are not "
                f"Experiment {experiment}'s ({spec.task}: {', '.join(spec.paper_codes)}{beyond})",
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
        run = run_class(spec.task).from_record(cohort_task(spec.task, settings), record)
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
    scheduler: str | None = None,
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
    scheduler : str, optional
        Replay on a Dask cluster (``"auto"`` or ``"tcp://HOST:PORT"``, see
        :class:`tutor.engine.Engine`) instead of local processes.

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
    step = progress_bar(progress)
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
    memo = ReadMemo(None if path.is_file() else cache, run_files, context)
    try:
        with Engine(workers, scheduler) as engine:
            fresh = memo.todo(labels, "file")
            items = [(str(path), run_files[lab], lab, experiment, settings) for lab in fresh]
            done = engine.map(_read, items, step=step(len(items)), meanwhile=meanwhile)
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


def _score(path: Path, experiment: int, outcomes, settings) -> ClassResult:
    beaten, clashes = duplicate_runs(outcomes)
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
        outcome = runs_apart(outcome, clashes)
        if outcome.counted:
            kind, reason, row, extra = replayed
            if kind != "counted":
                outcome = replace(outcome, kind=kind, reason=reason)
            else:
                who = {"trainee": outcome.trainee, "trainee_key": outcome.trainee_key}
                rows.append({"teacher": 0, **who, "file": outcome.file, **row})
                demo_rows += [{"teacher": 0, **who, **d} for d in extra]
        files.append(outcome)
    order = list(EXPERIMENTS[experiment].codes)  # the paper's first, then those beyond
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
