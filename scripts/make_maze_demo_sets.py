"""Regenerate the bundled maze demonstration sets in tutor/assets/demos/.

Each demo is a scripted stroke through the maze's gaps (MazeLayout.reference_path),
recorded as a person's mouse stroke would be: 80 Hz samples over 2-3.5 s, with a
little smoothed hand tremor that fades out at both ends. The sets illustrate the
paper's teaching failures; tests/test_demo_sets.py checks that each one raises
the failure it is named after.

Run:  .venv/bin/python scripts/make_maze_demo_sets.py
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from tutor.demofiles import save_demos
from tutor.tasks.maze import load_layout

OUT = Path(__file__).resolve().parents[1] / "tutor" / "assets" / "demos"
RATE_HZ = 80.0


def recording(layout, start, rng, guide_shift=None, end_shift=(0.0, 0.0)):
    """A stroke from ``start`` as an 80 Hz recording (t in s, x and y in m)."""
    duration = rng.uniform(2.0, 3.5)
    n = int(duration * RATE_HZ) + 1
    guides = layout.guide_points.copy()
    if guide_shift is not None:
        guides = guides + np.asarray(guide_shift)
    scripted = dataclasses.replace(layout, guide_points=guides)
    path = scripted.reference_path(start, rng, jitter=0.003, n_samples=n)
    s = path[:, 0]
    tremor = rng.normal(scale=0.0015, size=(n, 2))
    kernel = np.hanning(9) / np.hanning(9).sum()
    tremor = np.column_stack([np.convolve(tremor[:, i], kernel, mode="same") for i in range(2)])
    xy = path[:, 1:] + tremor * np.sin(np.pi * s)[:, None] + np.outer(s**3, end_shift)
    return np.column_stack([s * duration, xy])


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


def main() -> None:
    layout = load_layout()
    OUT.mkdir(parents=True, exist_ok=True)
    for name, (description, starts, special) in SETS.items():
        rng = np.random.default_rng(sum(map(ord, name)))
        demos = [recording(layout, s, rng, **special.get(i, {})) for i, s in enumerate(starts)]
        path = save_demos(OUT / f"maze_{name}.json", demos, task="maze", description=description)
        print(f"wrote {path} ({len(demos)} demos)")


if __name__ == "__main__":
    main()
