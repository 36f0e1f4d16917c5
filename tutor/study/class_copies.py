"""Copies of one run, and trainees who share a name: which file of a class is counted.

A trainee's run may be saved twice (the tutor's ``NF-2.json`` beside ``NF.json``, a copy
handed in again, a run begun again in the same folder); two trainees in different
folders may type the same name. :func:`duplicate_runs` finds which file of each run is
counted and which names clash; :func:`runs_apart` keys a clashing trainee by their folder.
They are :mod:`.classroom`'s own helpers.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import PurePosixPath

from .class_result import FileOutcome


def _folder(label: str) -> str:
    return PurePosixPath(label).parent.as_posix()


def _best(members):
    """The copy to count: the finished one, then the one changed last, then the shorter
    name (NF.json before the NF-2.json the tutor saves beside it)."""
    return max(members, key=lambda m: (m[1].finished, m[1].latest, -len(m[0].file)))


def duplicate_runs(outcomes) -> tuple[dict[str, tuple[str, str]], set[str]]:
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


def runs_apart(outcome: FileOutcome, clashes: set[str]) -> FileOutcome:
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
