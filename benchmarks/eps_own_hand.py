"""eps after 5 own-hand demos (a scripted steady hand) vs the guided hand's range, NF.

For the plants 11, 18, 45, 81 and 88, each seed teaches one NF run with the guided hand
(kinesthetic, :meth:`PickPlaceTask.demonstrate`) and one with own-hand recordings
(:func:`tutor.tasks.recording.steady_hand`, ``given="own"``). Prints both eps lists,
the guided range and whether the own-hand median is within it, the share of own-hand
seeds inside that range, and a two-sided Mann-Whitney test of the two samples.

Why not "every own-hand seed inside the guided range": if both hands gave eps from one
and the same distribution, the lowest of 2n draws would fall in the own-hand half with
probability 1/2, so that reading fails half the time for two equally good hands. The
benchmark reports what can be judged: the own-hand median inside the guided range, and
no detectable difference between the two samples.

Run:  .venv/bin/python benchmarks/eps_own_hand.py [--seeds 8] [--out PATH]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from results_file import RESULTS, save
from scipy.stats import mannwhitneyu

from tutor.errors import TutorError
from tutor.study.report import check_seeds
from tutor.tasks.pickplace import PickPlaceTask
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.tasks.recording import steady_hand

PLANTS = (11, 18, 45, 81, 88)
DEFAULT_OUT = RESULTS / "eps_own_hand.json"


def eps_after(task, hand: str, seed: int, plants=PLANTS) -> float:
    """eps after one demo to each of ``plants`` in an NF run, by ``hand`` ("own"/"guided")."""
    run = PickPlaceRun("NF", task)
    rng = np.random.default_rng(seed)
    for p in plants:
        if hand == "own":
            record = run.demonstrate(p, raw=steady_hand(task, p, rng=rng), given="own")
        else:
            record = run.demonstrate(p, rng=rng)
    return float(record.efficacy)


def run(seeds: int = 8) -> dict:
    task = PickPlaceTask()
    guided = [eps_after(task, "guided", s) for s in range(seeds)]
    own = [eps_after(task, "own", s) for s in range(seeds)]
    lo, hi = min(guided), max(guided)
    test = mannwhitneyu(own, guided, alternative="two-sided")
    return {
        "plants": list(PLANTS),
        "seeds": seeds,
        "guided": guided,
        "own": own,
        "guided_range": [lo, hi],
        "own_median": float(np.median(own)),
        "own_median_within": bool(lo <= np.median(own) <= hi),
        "own_within": [bool(lo <= e <= hi) for e in own],
        "guided_median": float(np.median(guided)),
        "mann_whitney_u": float(test.statistic),
        "mann_whitney_p": float(test.pvalue),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    try:
        seeds = len(check_seeds(range(args.seeds)))
    except TutorError as err:
        parser.error(f"--seeds: {err}")
    r = run(seeds)
    print(f"NF, plants {r['plants']}, {r['seeds']} seeds")
    print("  guided hand eps:", " ".join(f"{e:.2f}" for e in r["guided"]))
    print("  own hand eps:   ", " ".join(f"{e:.2f}" for e in r["own"]))
    lo, hi = r["guided_range"]
    print(
        f"  guided range [{lo:.2f}, {hi:.2f}]; own-hand median {r['own_median']:.2f}: "
        f"{'within' if r['own_median_within'] else 'OUTSIDE'} the range; "
        f"{sum(r['own_within'])} of {r['seeds']} own-hand runs within"
    )
    print(
        f"  medians: own {r['own_median']:.3f}, guided {r['guided_median']:.3f}; "
        f"Mann-Whitney U = {r['mann_whitney_u']:.0f}, two-sided p = {r['mann_whitney_p']:.3f}"
    )
    save(r, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
