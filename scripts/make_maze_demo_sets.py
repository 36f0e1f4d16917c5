"""Regenerate the bundled maze demonstration sets in tutor/assets/demos/.

Each demo is a scripted stroke through the maze's gaps (MazeLayout.reference_path),
recorded as a person's mouse stroke would be: 80 Hz samples over 2-3.5 s, with a
little smoothed hand tremor that fades out at both ends. The sets illustrate the
paper's teaching failures; tests/test_demo_sets.py checks that each one raises
the failure it is named after. ``--novice`` also writes a typical simulated teacher's
NF run (the median eta of 60), a set of the kind a novice gives.

Run:  .venv/bin/python scripts/make_maze_demo_sets.py
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from tutor.demofiles import save_demos
from tutor.framework.wording import percent
from tutor.tasks.maze import load_layout
from tutor.teachers.maze import MazeTeacher
from tutor.teachers.traits import DEFAULT_POPULATION

OUT = Path(__file__).resolve().parents[1] / "tutor" / "assets" / "demos"
RATE_HZ = 80.0


def recording(layout, start, rng, guide_shift=None, end_shift=(0.0, 0.0)):
    """A stroke from ``start`` as an 80 Hz recording (t in s, x and y in m)."""
    duration = rng.uniform(2.0, 3.5)
    guides = layout.guide_points if guide_shift is None else (
        layout.guide_points + np.asarray(guide_shift)
    )
    return layout.hand_stroke(start, rng, duration, jitter=0.003, tremor=0.0015,
                              guides=guides, end_shift=end_shift, rate_hz=RATE_HZ)


SETS = {
    "good": (
        "A good teacher: starts spread over the start zone (and over its height), each "
        "where the robot still failed; reaches 90 % coverage within 8 demos.",
        # efficacy 3 %, 32 %, 98 %, 99 %, 100 %; the later two where it still failed
        [(0.03, 0.03), (0.17, 0.045), (0.10, 0.01), (0.195, 0.005), (0.195, 0.055)],
        {},
    ),
    "ambiguous": (
        "An ambiguous teacher: after three demos spread out, the next three start within a "
        "few millimetres of the third and add almost nothing.",
        # efficacy 3 %, 32 %, 99 %, then no change: demos 4, 5 and 6 are flagged
        [(0.03, 0.03), (0.17, 0.045), (0.10, 0.01), (0.102, 0.013), (0.097, 0.008), (0.101, 0.007)],
        {},
    ),
    "undemonstrated": (
        "A teacher who leaves undemonstrated states: every demo starts in the left part "
        "of the start zone, so the right part is never taught.",
        [(0.02, 0.02), (0.06, 0.045), (0.035, 0.01)],
        {},
    ),
    "incorrect": (
        "A teacher who makes an incorrect demo: demo 3 cuts the corner of the left-hand "
        "obstacle; the others are good.",
        [
            (0.03, 0.03),
            (0.17, 0.03),
            (0.10, 0.03),
            (0.06, 0.052),
            (0.14, 0.008),
            (0.015, 0.008),
            (0.185, 0.052),
            (0.10, 0.055),
        ],
        {2: {"guide_shift": [[-0.05, 0.03], [0, 0], [0, 0], [0, 0]]}},
    ),
}


#: how many simulated novices the typical one is chosen from
NOVICES = 60


class _Recorded(MazeTeacher):
    """A simulated teacher that keeps each stroke it draws (the demos, as recorded)."""

    def stroke(self, start, rng, slip=False):
        drawn = super().stroke(start, rng, slip)
        self.strokes.append(drawn)
        return drawn


def novice_set():
    """The demos of a typical simulated novice without feedback (NF).

    ``NOVICES`` teachers drawn from the bundled (calibrated) population each teach the
    maze under NF; the one whose eta (Experiment 1's rule) is the median of theirs is
    kept, so the set scores as a typical novice does, not as the optimum."""
    etas, runs = [], []
    for k in range(NOVICES):
        rng = np.random.default_rng([k, 4])
        teacher = _Recorded(DEFAULT_POPULATION.sample(rng))
        teacher.strokes = []
        run = teacher.teach("NF", rng)
        etas.append(run.score().efficiency)
        runs.append((run, teacher.strokes))
    median = float(np.median(etas))
    k = int(np.argmin(np.abs(np.asarray(etas) - median)))
    run, strokes = runs[k]
    description = (
        f"A typical novice without feedback: the simulated NF teacher (of {NOVICES} drawn "
        f"from the bundled population) whose eta is the median of theirs, "
        f"{percent(etas[k])} with {run.n_demos} demos; they chose their starts by their own "
        "plan and stopped when their prior said the robot had had enough."
    )
    return strokes, description


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--novice", action="store_true",
        help="also write maze_novice.json, a typical simulated NF teacher's demos (not "
        "bundled yet: the hand-set population's novices score near the optimum, 25 %% "
        "against the paper's 7.6 %%; it is meant for the calibrated population)",
    )
    args = parser.parse_args(argv)
    layout = load_layout()
    OUT.mkdir(parents=True, exist_ok=True)
    for name, (description, starts, special) in SETS.items():
        rng = np.random.default_rng(sum(map(ord, name)))
        demos = [recording(layout, s, rng, **special.get(i, {})) for i, s in enumerate(starts)]
        path = save_demos(OUT / f"maze_{name}.json", demos, task="maze", description=description)
        print(f"wrote {path} ({len(demos)} demos)")
    if args.novice:
        demos, description = novice_set()
        path = save_demos(OUT / "maze_novice.json", demos, task="maze",
                          description=description)
        print(f"wrote {path} ({len(demos)} demos): {description}")


if __name__ == "__main__":
    main()
