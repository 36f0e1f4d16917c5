"""A class folder taught by simulated teachers, laid out as a real class's.

:func:`write_simulated_class` lets an educator try ``lfd-tutor class`` and the class
dashboard (notebook 05) before the workshop, and gives the tests and benchmarks a class
to read: the simulated cohort's teachers (:func:`tutor.study.cohort.teach_runs`, the same
seeds) teach, and each finished run is saved as the tutor saves a trainee's, one
folder per trainee (named by :func:`tutor.runtime.trainee_key`) holding ``NF.json`` ...
(Experiment 1) or ``pickplace_BF_run1.json`` ... (Experiment 2).

A class is rarely tidy: ``unfinished=k`` leaves the last run of k trainees stopped after
two demonstrations (the trainee never pressed Finish), and ``damaged=k`` spoils the last
file of k others the ways files get spoiled (cut off while copying, replaced by another
kind of file, a demonstration emptied by hand), so an educator can see how ``lfd-tutor
class`` and the dashboard report them before meeting them in a real class.

Examples
--------
>>> write_simulated_class("demo_class/", experiment=1, n=6)   # doctest: +SKIP
"""

from __future__ import annotations

import json
import os
from dataclasses import replace
from pathlib import Path

from ..engine import Engine
from ..errors import InvalidParameterError, SaveError
from ..fileio import write_json
from ..framework.protocol import run_file_name
from ..framework.record import Trainee
from .cohort import StudySettings, check_conditions, check_request, teach_runs

__all__ = ["write_simulated_class", "trainee_name", "DAMAGES"]


def _cut_off(path: Path) -> None:
    """The first half of the file: a copy that was interrupted."""
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _not_a_record(path: Path) -> None:
    """A demonstration file saved where the run was (valid JSON, another format)."""
    path.write_text(json.dumps({"format": "lfd-tutor-demos", "demos": [[[0.0, 0.0]]]}))


def _emptied_demo(path: Path) -> None:
    """The first demonstration's samples deleted by hand: a record that cannot be replayed."""
    data = json.loads(path.read_text())
    data["attempts"][-1]["demos"][0]["samples"] = [data["attempts"][-1]["demos"][0]["samples"][0]]
    path.write_text(json.dumps(data))


#: the ways :func:`write_simulated_class` spoils files, used in turn
DAMAGES = {"cut off": _cut_off, "not a run record": _not_a_record, "emptied": _emptied_demo}


def _stopped_early(data: dict, keep: int = 2) -> dict:
    """The record as it was after ``keep`` demos, before the trainee pressed Finish."""
    attempt = dict(data["attempts"][-1])
    attempt["demos"] = attempt["demos"][:keep]
    attempt.update(finished=False, stopped="", tests=[], undone=[], other_seconds=0.0)
    events = []
    for event in data["events"]:
        if event["kind"] == "finish" or (event["kind"] == "add" and event["n_demos"] > keep):
            break
        events.append(event)
    return {**data, "attempts": [*data["attempts"][:-1], attempt], "events": events}


def trainee_name(i: int) -> str:
    """The display name of simulated trainee ``i`` (0-based): ``"Trainee 01"`` ..."""
    return f"Trainee {i + 1:02d}"


def _teacher_records(item):
    experiment, teacher, seed, n, conditions = item
    trainee = Trainee.from_name(trainee_name(teacher))
    records = []
    settings = StudySettings()
    taught = teach_runs(experiment, teacher, seed, n, settings=settings, conditions=conditions)
    for _, number, run in taught:
        records.append(replace(run.record, trainee=trainee, run=number).to_dict())
    return trainee, records


def write_simulated_class(
    folder,
    experiment: int,
    n: int | None = None,
    seed: int = 0,
    workers: int | None = None,
    unfinished: int = 0,
    damaged: int = 0,
    conditions=None,
) -> dict[str, list[Path]]:
    """Write every run of ``n`` simulated trainees under ``folder``.

    Parameters
    ----------
    folder : path
        The class folder (made if missing).
    experiment : {1, 2}
    n : int, optional
        Trainees (default the paper's: 30, 36; Experiment 2 needs a multiple of 4).
    seed : int
    workers : int, optional
        Processes (default: the machine's cores).
    unfinished, damaged : int
        How many trainees' last run is left unfinished, or spoiled (see the module);
        different trainees, counted from the last.
    conditions : sequence of str, optional
        The conditions taught (default the paper's), any the experiment's registry entry
        lists (:func:`tutor.study.cohort.check_conditions`): Experiment 2's teachers are
        split evenly over them, as in a simulated cohort.

    Returns
    -------
    dict
        ``"written"``: every file, trainee by trainee; ``"unfinished"`` and ``"damaged"``:
        the files left unfinished or spoiled.

    Raises
    ------
    InvalidParameterError
        A bad experiment, ``n`` or seed (see :func:`tutor.study.cohort.check_request`).
    SaveError
        A file cannot be written.
    """
    experiment, n, seed = check_request(experiment, n, seed, conditions)
    conditions = check_conditions(experiment, conditions)
    for name, value in (("unfinished", unfinished), ("damaged", damaged)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise InvalidParameterError(f"{name} must be a whole number >= 0, got {value!r}")
    if unfinished + damaged > n:
        raise InvalidParameterError(
            f"unfinished + damaged ({unfinished} + {damaged}) is more than the {n} trainees"
        )
    folder = Path(folder)
    items = [(experiment, i, seed, n, conditions) for i in range(n)]
    workers = min(os.cpu_count() or 1, n) if workers is None else workers
    with Engine(workers) as engine:
        taught = engine.map(_teacher_records, items)
    out = {"written": [], "unfinished": [], "damaged": []}
    spoil = list(DAMAGES.values())
    for i, (trainee, records) in enumerate(taught):
        home = folder / trainee.key
        try:
            home.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SaveError(f"cannot make the folder {home}: {exc.strerror or exc}") from exc
        from_last = n - 1 - i  # damaged: the last trainees; unfinished: the ones before
        for j, data in enumerate(records):
            last = j == len(records) - 1
            if last and damaged <= from_last < damaged + unfinished:
                data = _stopped_early(data)
            name = run_file_name(experiment, data["condition"], data["run"], data["practice"])
            path = write_json(home / name, data)
            out["written"].append(path)
            if last and from_last < damaged:
                spoil[from_last % len(spoil)](path)
                out["damaged"].append(path)
            elif last and from_last < damaged + unfinished:
                out["unfinished"].append(path)
    return out
