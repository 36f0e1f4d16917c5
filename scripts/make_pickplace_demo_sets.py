"""Regenerate the bundled pick-and-place demonstration sets in tutor/assets/demos/.

Each demo is a kinesthetic-style recording made by :meth:`PickPlaceTask.demonstrate`
(the simulated teacher of :mod:`tutor.tasks.kinesthetic`;
20 Hz; t in s, the gripper position x, y, z in m, the hand g: 0 open, 1 closed), as a
person guiding the Panda by hand would record it. ``tests/test_pickplace_app.py``
loads them.

Run:  .venv/bin/python scripts/make_pickplace_demo_sets.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tutor.demofiles import save_demos
from tutor.tasks.pickplace import PickPlaceTask

OUT = Path(__file__).resolve().parents[1] / "tutor" / "assets" / "demos"
COLUMNS = ("t", "x", "y", "z", "g")

#: name: (description, [(row, col, mistake), ...]); rows and columns count from 0
SETS = {
    "corners": (
        "Five good demonstrations: the four corner plants and the centre one (the paper's "
        "generalisation sampling set). The robot then picks almost every plant.",
        [(0, 0, None), (9, 9, None), (0, 9, None), (9, 0, None), (4, 4, None)],
    ),
    "wrong_plant": (
        "Three demonstrations; in the second the teacher guided the hand to the plant next "
        "to the chosen corner one: an incorrect demonstration.",
        [(0, 0, None), (9, 9, "wrong_plant"), (0, 9, None)],
    ),
}


def main() -> None:
    task = PickPlaceTask()
    cols = task.scene.cols
    OUT.mkdir(parents=True, exist_ok=True)
    for name, (description, plants) in SETS.items():
        rng = np.random.default_rng(sum(map(ord, name)))
        chosen = [r * cols + c for r, c, _ in plants]
        demos = [
            task.demonstrate(p, rng, mistake=m) for p, (_, _, m) in zip(chosen, plants, strict=True)
        ]
        path = save_demos(
            OUT / f"pickplace_{name}.json",
            demos,
            task="pickplace",
            columns=COLUMNS,
            description=description,
            points=task.test_points[chosen],  # the plant the teacher meant
        )
        print(f"wrote {path} ({len(demos)} demos)")


if __name__ == "__main__":
    main()
