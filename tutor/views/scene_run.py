"""What a teaching run shows in the 3-D view: its trails and the one trajectory animated.

:func:`run_picture` reads a :class:`~tutor.framework.run.TeachingRun` (a pick-and-place
run) and says what :meth:`tutor.views.scene3d.Scene3D.update` draws after each step,
which draws nothing else of the run:

- the demonstrations as blue trails, and the robot's attempts the trainee may see (the
  run's visibility decides, as for the tray) as green (success) or dark red (failure)
  trails;
- one animation: the robot's latest shown attempt (the plant just tested, the trainee's
  own plant, the first failing one of the batch), or the latest demonstration when the
  robot showed nothing (NF); none before the first demonstration.

The plants' colours are the tutor's (the status it passes to ``update``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .style import DEMO, FAIL, PASS

__all__ = ["RunPicture", "run_picture", "pick_plant", "tests_after"]


@dataclass(frozen=True)
class RunPicture:
    """What :func:`run_picture` says to draw.

    Attributes
    ----------
    trails : dict of str to (list of ndarray (T, 4), str)
        Each trail group ("demos", "passed", "failed", in the order they are drawn): its
        paths and their colour.
    animation : (ndarray (T, 4), str, str) or None
        The path to animate, its caption and its trail's colour; None: no animation.
    """

    trails: dict
    animation: tuple | None


def run_picture(run) -> RunPicture:
    """The trails and the animation that show ``run`` now (see the module docstring)."""
    session, task = run.session, run.task
    demos = [d[:, -4:] for d in session.demos]
    trails = {"demos": (demos, DEMO)}
    rec = session.latest
    shown = np.zeros(0, int)
    if rec is not None:  # what the trainee may see: the run decides, as for the tray
        vis = run.visibility()
        shown = np.arange(len(task.test_points)) if vis.everything else vis.shown
    R = session.realisations if rec is not None else None
    ok = [p for p in shown if rec.passed[p]] if rec is not None else []
    bad = [p for p in shown if not rec.passed[p]] if rec is not None else []
    if R is not None:
        trails["passed"] = ([R[p][:, -4:] for p in ok], PASS)
        trails["failed"] = ([R[p][:, -4:] for p in bad], FAIL)
    else:
        trails["passed"] = ([], PASS)
        trails["failed"] = ([], FAIL)
    animation = None
    plant = pick_plant(run, shown)
    if plant is not None:
        passed = bool(rec.passed[plant])
        reason = rec.reasons[plant]
        label = f"The robot's attempt at {task.plant_name(plant)}: " + (
            "success." if passed else f"fails ({reason})."
        )
        animation = (R[plant][:, -4:], label, PASS if passed else FAIL)
    elif demos:
        plant = task.nearest_test_point(session.demo_points[-1])
        label = f"Your demonstration {len(demos)} ({task.plant_name(plant)})."
        animation = (demos[-1], label, DEMO)
    return RunPicture(trails, animation)


def pick_plant(run, shown):
    """The plant whose attempt is animated, of those ``shown`` (k,); None: none of them.

    The plant the trainee's latest test tried, else the trainee's own plant (the one of
    the latest demonstration) if its attempt is shown, else the first failing one, else
    the first shown.
    """
    rec = run.session.latest
    if rec is None or len(shown) == 0:
        return None
    tests = tests_after(run, rec.n_demos)
    if tests and tests[-1].plants:
        return int(tests[-1].plants[-1])
    own = run.task.nearest_test_point(run.session.demo_points[-1])
    if own in set(int(p) for p in rec.shown):
        return int(own)
    failing = [int(p) for p in shown if not rec.passed[p]]
    return failing[0] if failing else int(shown[0])


def tests_after(run, n_demos: int | None = None) -> list:
    """The robot's tests the trainee asked for in ``run``'s current attempt, after
    ``n_demos`` demos (all of them when None): :class:`~tutor.framework.record.Test`
    records, read from the typed run record."""
    tests = run.attempt.tests
    return list(tests) if n_demos is None else [t for t in tests if t.after_demo == n_demos]
