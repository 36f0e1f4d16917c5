"""Why each maze attempt fails, in a form a picture can draw and a sentence can count.

The maze task's criteria (:meth:`tutor.tasks.maze.MazeTask.judge`) give every failing
realisation its causes as data (:class:`tutor.framework.task.Reason`: an obstacle hit at
sample 97 of 200, an end 5.1 cm from the target). :func:`classify` picks the main cause
(the first thing that went wrong along the path), :func:`main_causes` adds where on the
path it happened, and :func:`reason_summary` counts the causes, e.g. "93 miss the
target by 1–4 mm; 12 hit obstacle 2". No words are read back.

A miss is measured from the target's edge (how far the attempt would have had to go
on to reach the target), not from its centre.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["KINDS", "MainCause", "classify", "main_causes", "reason_summary"]

#: the causes, in the order a summary lists equal counts; "pass" is no failure
KINDS = ("pass", "obstacle", "outside", "start", "miss", "other")

#: a miss up to this far from the target's edge is "near" (counted in millimetres)
NEAR_MISS = 0.005

@dataclass(frozen=True)
class MainCause:
    """The main cause of one realisation's failure.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    sample : int or None
        0-based index of the first sample inside an obstacle or outside the workspace
        (kinds "obstacle" and "outside"), else None.
    obstacle : str
        Short name of the obstacle hit ("obstacle 2"), else "".
    point : tuple of float or None
        Where it went wrong (metres): the first bad sample, the start (kind "start")
        or the end (kind "miss"); set by :func:`main_causes`.
    miss : float
        How far the end is from the target's edge (metres), for every realisation.
    """

    kind: str
    sample: int | None = None
    obstacle: str = ""
    point: tuple[float, float] | None = None
    miss: float = 0.0


def classify(causes, layout=None) -> MainCause:
    """The main cause among one realisation's causes (a tuple of
    :class:`~tutor.framework.task.Reason`; empty means it passes).

    ``layout`` (a :class:`~tutor.tasks.maze.MazeLayout`) gives an obstacle hit its short
    label ("obstacle 2"); without one it is numbered.

    A path that hits an obstacle or leaves the workspace is counted by that, even when
    it also ends away from the target: the end follows from the crash.
    """
    if not causes:
        return MainCause("pass")
    by_kind = {r.kind: r for r in causes}
    if "obstacle" in by_kind:
        r = by_kind["obstacle"]
        i = r.obstacle
        if i is None:
            label = "an obstacle"
        else:
            label = layout.obstacles[i].label if layout is not None else f"obstacle {i + 1}"
        return MainCause("obstacle", r.sample, label)
    if "outside" in by_kind:
        return MainCause("outside", by_kind["outside"].sample)
    if "start" in by_kind:
        return MainCause("start")
    if "end" in by_kind:
        return MainCause("miss")
    return MainCause("other")


def main_causes(paths, causes, layout) -> list[MainCause]:
    """Each realisation's :class:`MainCause`, with the point where it went wrong.

    Parameters
    ----------
    paths : ndarray (n, T, 2)
        The realisations R^ (metres), at the resolution they were judged.
    causes : sequence of tuple of Reason, length n
        The task's causes (``Verdict.causes``, ``DemoStep.causes``; empty for a
        realisation that passes).
    layout : MazeLayout
        For the target (the miss is measured from its edge).
    """
    paths = np.asarray(paths, dtype=float)
    out = []
    ends = paths[:, -1] if len(paths) else np.zeros((0, 2))
    miss = np.linalg.norm(ends - layout.target_center, axis=1) - layout.target_radius
    for i, found in enumerate(causes):
        f = classify(found, layout)
        if f.kind in ("obstacle", "outside"):
            point = paths[i, min(f.sample, paths.shape[1] - 1)]
        elif f.kind == "start":
            point = paths[i, 0]
        elif f.kind in ("miss", "other"):
            point = paths[i, -1]
        else:
            point = None
        out.append(
            MainCause(
                f.kind,
                f.sample,
                f.obstacle,
                None if point is None else (float(point[0]), float(point[1])),
                float(max(miss[i], 0.0)),
            )
        )
    return out


def _span(values, unit: float, name: str) -> str:
    lo, hi = float(np.min(values)) / unit, float(np.max(values)) / unit
    if name == "mm":
        lo, hi = max(1, round(lo)), max(1, round(hi))
        return f"{lo} mm" if lo == hi else f"{lo}–{hi} mm"
    return f"{lo:.1f} cm" if round(lo, 1) == round(hi, 1) else f"{lo:.1f}–{hi:.1f} cm"


def reason_summary(found, shown=None) -> str:
    """Count the causes among the shown realisations, largest first.

    Parameters
    ----------
    found : sequence of MainCause
        From :func:`main_causes`.
    shown : sequence of int, optional
        Indices of the realisations to count (default all).

    Returns
    -------
    str
        E.g. "93 miss the target by 1–4 mm; 12 hit obstacle 2; 2 end 1.2–3.4 cm from
        the target" (a far miss is measured from the target's edge too), or "" when
        none of them fails.
    """
    idx = range(len(found)) if shown is None else [int(i) for i in shown]
    groups: dict[tuple, list[MainCause]] = {}
    for i in idx:
        f = found[i]
        if f.kind == "pass":
            continue
        if f.kind == "miss":
            key = ("miss", "near" if f.miss <= NEAR_MISS else "far")
        else:
            key = (f.kind, f.obstacle)
        groups.setdefault(key, []).append(f)
    parts = []
    for key, items in groups.items():
        n = len(items)
        kind, detail = key
        if kind == "miss" and detail == "near":
            text = f"miss the target by {_span([f.miss for f in items], 0.001, 'mm')}"
        elif kind == "miss":
            text = f"end {_span([f.miss for f in items], 0.01, 'cm')} from the target"
        elif kind == "obstacle":
            text = f"hit{'s' if n == 1 else ''} {detail}"
        elif kind == "outside":
            text = f"leave{'s' if n == 1 else ''} the maze"
        elif kind == "start":
            text = f"start{'s' if n == 1 else ''} outside the start zone"
        else:
            text = f"fail{'s' if n == 1 else ''} for another reason"
        if n == 1 and kind == "miss":
            text = text.replace("miss ", "misses ", 1).replace("end ", "ends ", 1)
        parts.append((-n, KINDS.index(kind), f"{n} {text}"))
    return "; ".join(p[2] for p in sorted(parts))
