"""How steady is the learner on a maze of given blocks? (a check before bundling a maze)

Prints :func:`tutor.study.steadiness.steadiness` for each maze: per guided teacher, the
demos needed to first reach 90 % coverage and the deepest fall of efficacy below the
best reached so far, and whether the maze counts as steady (the calibration keeps away
from mazes that do not).

Run:  .venv/bin/python scripts/maze_fragility.py --blocks 0.13,0.10,0.03,0.05 --blocks ...
"""

from __future__ import annotations

import argparse

from tutor.study.steadiness import MAX_FALL, steadiness_of_blocks


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--blocks", action="append", required=True,
                        help="reach,low,height,gap in metres (repeat for several mazes)")
    args = parser.parse_args(argv)
    for text in args.blocks:
        found = steadiness_of_blocks(tuple(float(v) for v in text.split(",")))
        print(f"blocks {text}: demos to 90 % {list(found.needed)}; deepest fall "
              f"{[round(f, 2) for f in found.falls]}, median {found.median_fall:.0%} "
              f"({'steady' if found.steady else 'unsteady'}: at most {MAX_FALL:.0%})")


if __name__ == "__main__":
    main()
