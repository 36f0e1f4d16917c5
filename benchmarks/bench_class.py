"""Benchmark ``lfd-tutor class`` on a workshop-sized class.

The class: 30 simulated trainees of Experiment 1 (NF, VF, VR each: 90 run files), of
which 2 left a run unfinished and 3 files are spoiled (cut off, not a run record, a
demonstration emptied), written once with :func:`write_simulated_class`. Optionally
also Experiment 2 with 36 trainees x 3 runs.

One repeat is the whole command as an educator runs it, in a fresh process:
``python -m tutor class CLASS --experiment 1 --out OUT`` (imports, reading and checking
every file, replaying each run through the learner on all cores, the statistics of the
class and of a simulated class of its size, CSV/JSON/report and the figure). Prints the
median wall time; the target (issue 13) is <= 5 s for Experiment 1.

Run:  .venv/bin/python benchmarks/bench_class.py [--repeats 5] [--experiment2]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

from tutor.study.simulated_class import write_simulated_class

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = RESULTS / "bench_class.json"
TARGET_S = 5.0


def one(folder: Path, experiment: int, out: Path) -> float:
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)}
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "tutor", "class", str(folder), "--experiment", str(experiment),
         "--out", str(out)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    seconds = time.perf_counter() - t0
    if proc.returncode != 0 or "Files not counted (5)" not in proc.stdout:
        raise SystemExit(f"lfd-tutor class failed or did not list 5 files:\n{proc.stdout}\n"
                         f"{proc.stderr}")
    return seconds


def run(repeats: int, experiment2: bool) -> dict:
    result = {"repeats": repeats, "cores": os.cpu_count(), "target_s": TARGET_S}
    with tempfile.TemporaryDirectory() as tmp:
        plans = [(1, 30)] + ([(2, 36)] if experiment2 else [])
        for experiment, n in plans:
            folder = Path(tmp) / f"class{experiment}"
            write_simulated_class(folder, experiment, n, seed=1, unfinished=2, damaged=3)
            times = [one(folder, experiment, Path(tmp) / "out") for _ in range(repeats)]
            files = sum(1 for _ in folder.rglob("*.json"))
            result[f"experiment{experiment}"] = {
                "trainees": n,
                "files": files,
                "median_s": float(np.median(times)),
                "all_s": times,
            }
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--experiment2", action="store_true", help="also 36 x 3 of Exp. 2")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args()
    result = run(args.repeats, args.experiment2)
    for key in ("experiment1", "experiment2"):
        if key in result:
            r = result[key]
            print(f"lfd-tutor class, {key}: {r['trainees']} trainees, {r['files']} files: "
                  f"median {r['median_s']:.2f} s over {args.repeats} runs "
                  f"(target for experiment 1: <= {TARGET_S:.0f} s)")
    save(result, args.out)
    print(f"written: {args.out}")


if __name__ == "__main__":
    main()
