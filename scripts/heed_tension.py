"""Why one population cannot give both Experiment 1's VF and Experiment 2's BF levels.

The calibration fits ``heed`` (the chance that a teacher shown failures aims the next
demo at them rather than following their own plan) to Experiment 1, whose VF people
were inefficient. This script reruns both experiments' cohorts with the bundled
population and with every teacher heeding (``heed`` = 1, nothing else changed), on the
same seeds, and prints each condition's level (Experiment 1: median eta, the paper's
statistic; Experiment 2: mean eta) and demos kept per run, averaged over the seeds,
beside the paper's. NF is the control: it is shown nothing, so heed cannot move it.

It also counts the seeds in which each of Experiment 2's conclusions holds under each
heed. Heed moves only Experiment 2 there, so "every teacher heeds" is also what a heed
kept per task (pick-and-place teachers always heeding, maze teachers as calibrated)
would give Experiment 2: BF's level comes near the paper's, but BF then no longer leaves
the most undemonstrated states.

Run:  .venv/bin/python scripts/heed_tension.py [--seeds 10] [--workers N]
"""

from __future__ import annotations

import argparse
import dataclasses

import pandas as pd

from tutor import paper
from tutor.__main__ import _whole_number
from tutor.engine import Engine
from tutor.study.cohort import run_experiment
from tutor.study.stats import conclusions
from tutor.teachers.traits import DEFAULT_POPULATION

#: (label, heed_low, heed_high): the bundled range, and every teacher heeding
HEEDS = (
    (f"bundled {DEFAULT_POPULATION.heed_low:g}-{DEFAULT_POPULATION.heed_high:g}",
     DEFAULT_POPULATION.heed_low, DEFAULT_POPULATION.heed_high),
    ("every teacher heeds (1)", 1.0, 1.0),
)


def levels(seeds: int, workers=None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Both experiments under each heed, on the same seeds.

    Returns
    -------
    levels : DataFrame
        One row per heed, experiment, seed and condition: eta level and demos kept.
    held : DataFrame
        One row per heed and Experiment 2 seed: each of its conclusions (bool) and
        ``all hold``.
    """
    rows, held = [], []
    with Engine(workers) as engine:
        for label, low, high in HEEDS:
            population = dataclasses.replace(DEFAULT_POPULATION, heed_low=low, heed_high=high)
            for experiment in (1, 2):
                for seed in range(seeds):
                    runs = run_experiment(experiment, seed=seed, progress=False,
                                          engine=engine, population=population).runs
                    if experiment == 2:
                        found = conclusions(runs, 2)
                        held.append({"heed": label, "seed": seed, **found,
                                     "all hold": all(found.values())})
                    by = runs.groupby("condition")
                    eta = by.eta.median() if experiment == 1 else by.eta.mean()
                    demos = by.n_demos.mean()
                    for condition, value in eta.items():
                        rows.append({"heed": label, "experiment": experiment, "seed": seed,
                                     "condition": condition, "eta": value,
                                     "demos": demos[condition]})
    return pd.DataFrame(rows), pd.DataFrame(held)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=_whole_number(1, 1000, " seeds"), default=10)
    parser.add_argument("--workers", type=_whole_number(1), default=None)
    args = parser.parse_args(argv)
    report(*levels(args.seeds, args.workers))


def report(table: pd.DataFrame, held: pd.DataFrame) -> None:
    """Print each condition's level under each heed (means over the seeds of ``table``,
    as :func:`levels` makes it) beside the paper's, then how many of ``held``'s seeds
    each Experiment 2 conclusion holds in."""
    mean = table.groupby(["experiment", "condition", "heed"])[["eta", "demos"]].mean()
    papers = {1: paper.PAPER_MEDIAN_ETA, 2: paper.PAPER_MEAN_ETA}
    for (experiment, condition), part in mean.groupby(level=[0, 1]):
        cells = ", ".join(f"{heed}: {100 * r.eta:.1f} % ({r.demos:.1f} demos)"
                          for (_, _, heed), r in part.iterrows())
        level = 100 * papers[experiment][condition]
        print(f"Experiment {experiment} {condition} (paper {level:.1f} %): {cells}")
    counts = held.groupby("heed", sort=False).sum(numeric_only=True).drop(columns="seed")
    n = held.groupby("heed", sort=False).size()
    print("Experiment 2, seeds where each conclusion holds:")
    for name in counts.columns:
        cells = ", ".join(f"{heed}: {int(counts.loc[heed, name])} of {n[heed]}"
                          for heed in counts.index)
        print(f"  {name}: {cells}")


if __name__ == "__main__":
    main()
