"""Benchmark one teaching step: ``TeachingSession.add_demo`` at demo M, on both tasks.

Maze (Experiment 1): preprocess the recording, warm refit of the TP-GMM (K = 11,
4 frames), 140 realisations (R^), the task criteria on all of them, the failure flags.

Pick-and-place (Experiment 2): the same step with a refit from scratch (K = 9,
3 frames, state (t, x, y, z, g)), and separately the judgement of all 100 plants after
a demo: 100 reproductions plus criteria (i) (feasibility map, with the hand state),
(ii) and (iii) with the delta rule (target <= 100 ms).

The trainee's whole step on the maze (what a finished stroke costs in the tutor): the
same ``add_demo`` through the run (:class:`~tutor.tasks.maze_run.MazeRun`, which also
extends the typed run record), then the autosave of the record (JSON, temp file, fsync,
rename, fsync of the folder).

Each figure is the median over several random demo sets and repeats (the session is
copied before each timed step, so every repeat adds the same M-th demo).

Run:  .venv/bin/python benchmarks/bench_session.py [--repeats 9] [--sets 5]
"""

from __future__ import annotations

import argparse
import copy
import tempfile
import time
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

from tutor.framework import TeachingSession
from tutor.tasks.maze import MazeTask
from tutor.tasks.maze_run import MazeRun
from tutor.tasks.pickplace import PickPlaceTask
from tutor.workers import one_blas_thread

DEFAULT_OUT = RESULTS / "bench_session.json"


def run(repeats: int = 9, n_sets: int = 5, steps=(5, 10, 20)) -> dict:
    task = MazeTask()
    out = {}
    for m in steps:
        times = []
        for s in range(n_sets):
            rng = np.random.default_rng(10_000 + 100 * m + s)
            starts = task.layout.sample_starts(m, rng)
            demos = [task.layout.reference_path(p, rng, jitter=0.004) for p in starts]
            session = TeachingSession(task)
            for d in demos[:-1]:
                session.add_demo(d)
            for _ in range(repeats):
                trial = copy.deepcopy(session)
                t0 = time.perf_counter()
                trial.add_demo(demos[-1])
                times.append(time.perf_counter() - t0)
        out[m] = {
            "add_demo_ms": 1e3 * float(np.median(times)),
            "add_demo_ms_p90": 1e3 * float(np.percentile(times, 90)),
        }
    return out


def run_recorded(repeats: int = 9, n_sets: int = 5, steps=(5, 10, 20)) -> dict:
    """The trainee's step: ``MazeRun.add_demo`` (session + record), then the autosave."""
    task = MazeTask()
    out = {}
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "VF.json"
        for m in steps:
            add_times, save_times = [], []
            for s in range(n_sets):
                rng = np.random.default_rng(10_000 + 100 * m + s)
                starts = task.layout.sample_starts(m, rng)
                demos = [task.layout.reference_path(p, rng, jitter=0.004) for p in starts]
                run_ = MazeRun.new("VF", task)
                for d in demos[:-1]:
                    run_.add_demo(d)
                for _ in range(repeats):
                    trial = copy.deepcopy(run_)
                    t0 = time.perf_counter()
                    trial.add_demo(demos[-1])
                    t1 = time.perf_counter()
                    trial.save(path)
                    add_times.append(t1 - t0)
                    save_times.append(time.perf_counter() - t1)
            out[m] = {
                "run_add_demo_ms": 1e3 * float(np.median(add_times)),
                "autosave_ms": 1e3 * float(np.median(save_times)),
                "autosave_kb": path.stat().st_size / 1e3,
            }
    return out


def run_pickplace(repeats: int = 9, n_sets: int = 3, steps=(5, 10, 20)) -> dict:
    task = PickPlaceTask()
    conditions = task.test_points
    out = {}
    for m in steps:
        step_times, judge_times = [], []
        for s in range(n_sets):
            rng = np.random.default_rng(20_000 + 100 * m + s)
            plants = rng.choice(len(conditions), size=m, replace=False)
            raws = [task.demonstrate(int(p), rng) for p in plants]
            session = TeachingSession(task)
            for p, raw in zip(plants[:-1], raws[:-1], strict=True):
                session.add_demo(raw, point=conditions[p])
            for _ in range(repeats):
                trial = copy.deepcopy(session)
                t0 = time.perf_counter()
                trial.add_demo(raws[-1], point=conditions[plants[-1]])
                step_times.append(time.perf_counter() - t0)
            learner = trial.learner
            demos = trial.demos
            conds = np.array(trial.demo_points)

            def judge_all(learner=learner, demos=demos, conds=conds):
                context = task.criteria_context(demos, conds)
                attempts = task.realise(learner, conditions)  # tracked from the start pose
                return task.judge(attempts, conditions, context)

            judge_all()
            for _ in range(repeats):
                t0 = time.perf_counter()
                judge_all()
                judge_times.append(time.perf_counter() - t0)
        out[m] = {
            "add_demo_ms": 1e3 * float(np.median(step_times)),
            "add_demo_ms_p90": 1e3 * float(np.percentile(step_times, 90)),
            "judge_100_plants_ms": 1e3 * float(np.median(judge_times)),
        }
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--sets", type=int, default=5)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    one_blas_thread()  # as the tutor's apps and workers run the learner
    maze = run(args.repeats, args.sets)
    print(
        f"TeachingSession.add_demo on the maze: medians over {args.sets} demo sets "
        f"x {args.repeats} runs"
    )
    print(f"{'demo M':>7} {'median ms':>10} {'90th pct ms':>12}")
    for m, r in maze.items():
        print(f"{m:>7} {r['add_demo_ms']:10.1f} {r['add_demo_ms_p90']:12.1f}")
    recorded = run_recorded(args.repeats, args.sets)
    print("\nThe trainee's step on the maze: MazeRun.add_demo (session + run record), then")
    print("the autosave of the record (atomic, fsynced), medians")
    print(f"{'demo M':>7} {'add_demo ms':>12} {'autosave ms':>12} {'file kB':>8}")
    for m, r in recorded.items():
        print(
            f"{m:>7} {r['run_add_demo_ms']:12.1f} {r['autosave_ms']:12.1f} "
            f"{r['autosave_kb']:8.0f}"
        )
    pick = run_pickplace(args.repeats, max(1, min(args.sets, 3)))
    print("\nPick-and-place: add_demo (refit from scratch + 100 plants judged) and the")
    print("judgement of all 100 plants alone (tracked attempts + criteria (i)-(iii)), medians")
    print(f"{'demo M':>7} {'add_demo ms':>12} {'90th pct ms':>12} {'judge 100 ms':>13}")
    for m, r in pick.items():
        print(
            f"{m:>7} {r['add_demo_ms']:12.1f} {r['add_demo_ms_p90']:12.1f} "
            f"{r['judge_100_plants_ms']:13.1f}"
        )
    results = {"maze": maze, "maze_recorded": recorded, "pickplace": pick}
    save(results, args.out)


if __name__ == "__main__":
    main()
