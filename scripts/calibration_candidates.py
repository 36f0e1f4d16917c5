"""Would the candidates the steadiness check turned away have reproduced the paper?

The calibration's ``refine`` step takes the six particles of the last generation closest
to the paper and bundles the best one whose maze, rounded to the millimetre, the
learner is steady on (:mod:`tutor.study.steadiness`). The closest candidates all had
unsteady mazes, so a reader may ask whether that check, our own, is what keeps the model
from the paper. This script answers it: it runs each candidate, steady or not, as a
bundled population and maze would be run (Experiment 1's 30 teachers, Experiment 2's 36,
the paper's sizes) on fresh seeds, and counts the seeds in which the paper's conclusions
hold, beside each candidate's levels.

Run:  .venv/bin/python scripts/calibration_candidates.py [--seeds 8] [--first-seed 100]
      [--calibration tutor/assets/calibration] [--workers N]
"""

from __future__ import annotations

import argparse

import pandas as pd

from tutor.__main__ import _whole_number
from tutor.engine import Engine
from tutor.errors import InvalidFileError, TutorError
from tutor.study import calibration
from tutor.study.cohort import run_experiment
from tutor.study.stats import ANALYSES, conclusions


def candidates_table(folder, seeds: int, first_seed: int, workers=None,
                     sizes=(None, None)) -> pd.DataFrame:
    """One row per candidate and seed: each conclusion (bool), ``all hold`` per
    experiment and each condition's level (Experiment 1 median eta, 2 mean eta).

    ``sizes`` are the two experiments' teacher counts (default the paper's, 30 and 36).
    """
    found, _, _ = calibration.load(folder)
    if found.refined is None:
        raise InvalidFileError(
            f"{folder or 'the bundled calibration'} has no calibration_refined.csv: finish "
            "the calibration (lfd-tutor calibrate --from-history) so that refine runs"
        )
    rows = []
    with Engine(workers) as engine:
        for i, candidate in found.refined.iterrows():
            theta = {name: candidate[name] for name in calibration.PARAMETERS}
            population, settings = calibration.apply(theta)
            for seed in range(first_seed, first_seed + seeds):
                row = {"candidate": i, "steady": bool(candidate["steady_as_bundled"]),
                       "bundled": bool(candidate["chosen"]), "seed": seed}
                for experiment in (1, 2):
                    runs = run_experiment(experiment, seed=seed, n=sizes[experiment - 1],
                                          population=population,
                                          settings=settings, progress=False,
                                          engine=engine).runs
                    held = conclusions(runs, experiment)
                    row.update({f"E{experiment} {k}": v for k, v in held.items()})
                    row[f"E{experiment} all hold"] = all(held.values())
                    by = runs.groupby("condition", observed=True).eta
                    level = by.agg(ANALYSES[experiment].summary)  # the paper's summary
                    row.update({f"E{experiment} eta {c}": v for c, v in level.items()})
                rows.append(row)
    return pd.DataFrame(rows)


def report(table: pd.DataFrame) -> None:
    keys = ["candidate", "steady", "bundled"]
    held = [c for c in table.columns if table[c].dtype == bool and c not in keys]
    levels = [c for c in table.columns if " eta " in c]
    counts = table.groupby(keys)[held].sum().astype(int)
    seeds = table.groupby(keys).size().iloc[0]
    pd.set_option("display.width", 200)
    print(f"seeds (of {seeds}) in which each conclusion holds, per candidate:")
    print(counts.T.to_string())
    print()
    print("levels, mean over the seeds (Experiment 1 median eta, Experiment 2 mean eta):")
    print((table.groupby(keys)[levels].mean() * 100).round(1).T.to_string())


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=_whole_number(1, 1000, " seeds"), default=8)
    parser.add_argument("--first-seed", type=_whole_number(0), default=100)
    parser.add_argument("--calibration", default=None,
                        help="a folder `lfd-tutor calibrate --out` wrote (default: bundled)")
    parser.add_argument("--workers", type=_whole_number(1), default=None)
    args = parser.parse_args(argv)
    try:
        table = candidates_table(args.calibration, args.seeds, args.first_seed, args.workers)
    except TutorError as exc:
        parser.exit(2, f"{parser.prog}: {exc}\n")
    report(table)


if __name__ == "__main__":
    main()
