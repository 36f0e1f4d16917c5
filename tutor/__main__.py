"""Command line of the tutor: ``python -m tutor reproduce ...``.

reproduce   simulate one of the paper's experiments with simulated teachers and write
            CSV/JSON results, a text report beside the paper's numbers and the figure.
robustness  rerun an experiment over several seeds and report how often the paper's
            conclusions hold.
adaptive    beyond the paper: adaptive test sets (and the next-demo hint) against BF with
            simulated teachers, common random numbers, claims with CIs over seeds.
class       read a class's saved runs (a folder with one subfolder or one zip per
            trainee, or a zip of it), list every file not counted and why, and run the
            paper's statistics on the class beside the paper's numbers and a simulated
            class of its size.
calibrate   fit the simulated teachers' population and the maze's blocks to the paper
            by ABC-SMC, check them on the results held out, and write the report.
warm        compile the learner's and the tasks' kernels once (numba caches them), so a
            trainee's first demo does not wait for them (scripts/lab.sh, the hub kit).

Examples::

    python -m tutor reproduce --experiment 1 --seed 0 --out results/
    python -m tutor reproduce --experiment 2 --seed 0 --out results/ --n 12
    python -m tutor robustness --experiment 1 --seeds 10 --out results/
    python -m tutor adaptive --seeds 10 --out results_adaptive/
    python -m tutor class /srv/lfd-class --experiment 1 --out class_results/
    python -m tutor calibrate --out calibration/
    python -m tutor warm
"""

from __future__ import annotations

import argparse
import os
import sys

from .framework.protocol import EXPERIMENTS
from .study.limits import MAX_SEED, MAX_SEEDS, MAX_TEACHERS

# one BLAS thread per process (set before numpy loads); the cohort uses processes instead
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")


def _whole_number(minimum: int, maximum: int | None = None, unit: str = ""):
    """An argparse type: a whole number >= ``minimum`` (and <= ``maximum``), with a message
    saying so."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"must be a whole number >= {minimum}, got {text!r}"
            ) from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(
                f"must be at most {maximum}{unit}, got {value}: give a smaller number"
            )
        return value

    parse.__name__ = f"whole number >= {minimum}"
    return parse


def _scheduler(text: str) -> str:
    """An argparse type: a Dask scheduler, "auto" or tcp://HOST:PORT."""
    from .engine import check_scheduler
    from .errors import InvalidParameterError

    try:
        return check_scheduler(text)
    except InvalidParameterError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


SCHEDULER_HELP = (
    "run on a Dask cluster instead of local processes: 'auto' (a local one) or a "
    "scheduler's address tcp://HOST:PORT (the same numbers either way)"
)


class _OneLineParser(argparse.ArgumentParser):
    """An argument parser whose refusal is one line (exit code 2), like the tutor's own.

    argparse prints the whole usage before the error; a script reading stderr, or a
    person scanning it, then has to find the one line that says what was wrong.
    """

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


#: the --experiment choices' help, from the registry: "1 (maze) or 2 (pickplace)"
EXPERIMENT_HELP = " or ".join(f"{e.number} ({e.title})" for e in EXPERIMENTS.values())
#: the paper's cohort sizes, as --n's help gives them
PAPER_SIZES = ", ".join(str(e.n_teachers) for e in EXPERIMENTS.values())


def _parser() -> argparse.ArgumentParser:
    parser = _OneLineParser(prog="lfd-tutor", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    def common(p):
        p.add_argument(
            "--experiment",
            type=int,
            required=True,
            choices=tuple(EXPERIMENTS),
            help=EXPERIMENT_HELP,
        )
        p.add_argument(
            "--n",
            type=_whole_number(1, MAX_TEACHERS, " teachers"),
            default=None,
            help=f"teachers (default the paper's: {PAPER_SIZES}; at most {MAX_TEACHERS})",
        )
        p.add_argument("--out", default="results", help="folder for the files (default results/)")
        p.add_argument(
            "--workers", type=_whole_number(1), default=None, help="processes (default: all cores)"
        )
        p.add_argument("--no-progress", action="store_true", help="no progress bar")
        p.add_argument("--scheduler", type=_scheduler, default=None, help=SCHEDULER_HELP)

    rep = sub.add_parser("reproduce", help="simulate one experiment and compare with the paper")
    common(rep)
    rep.add_argument(
        "--seed", type=_whole_number(0, MAX_SEED), default=0,
        help=f"random seed, 0 to {MAX_SEED} (default 0)",
    )
    rep.add_argument("--no-figures", action="store_true", help="skip the PNG figure")
    rob = sub.add_parser("robustness", help="rerun an experiment over seeds 0 .. S-1")
    common(rob)
    rob.add_argument(
        "--seeds", type=_whole_number(1, MAX_SEEDS, " seeds"), default=10,
        help=f"how many seeds (default 10, at most {MAX_SEEDS})",
    )
    ada = sub.add_parser(
        "adaptive", help="adaptive feedback (and the next-demo hint) against BF, over seeds"
    )
    ada.add_argument(
        "--seeds", type=_whole_number(2, MAX_SEEDS, " seeds"), default=10,
        help="seeds 0 .. S-1 of the main study (default 10, at least 2 for a CI over seeds, "
        f"at most {MAX_SEEDS})",
    )
    ada.add_argument("--out", default="results", help="folder for the files (default results/)")
    ada.add_argument(
        "--n", type=_whole_number(1, MAX_TEACHERS, " teachers"), default=None,
        help="teachers per seed and policy (default 36; 36-60)",
    )
    ada.add_argument(
        "--variant-seeds", type=_whole_number(0, MAX_SEEDS, " seeds"), default=None,
        help="seeds per teacher-model variant for the robustness check (default 3; 0: none; "
        f"at most {MAX_SEEDS})",
    )
    ada.add_argument(
        "--hf-teachers", type=_whole_number(2, MAX_TEACHERS, " teachers"), default=None,
        help="teach only the first N teachers of each seed in the HF arms, whose runs "
        "cost about 7 times the others' (default: all)",
    )
    ada.add_argument(
        "--workers", type=_whole_number(1), default=None, help="processes (default: all cores)"
    )
    ada.add_argument("--scheduler", type=_scheduler, default=None, help=SCHEDULER_HELP)
    ada.add_argument(
        "--quick", action="store_true",
        help="a reduced test run (4 teachers x 1 run x 2 seeds), not a result",
    )
    ada.add_argument("--no-progress", action="store_true", help="no progress bar")
    ada.add_argument("--no-figures", action="store_true", help="skip the PNG figure")
    cal = sub.add_parser(
        "calibrate",
        help="fit the simulated teachers and the maze to the paper (ABC-SMC) and check them",
    )
    cal.add_argument("--out", default="calibration", help="folder for the files")
    cal.add_argument(
        "--population-size", type=_whole_number(2, 10_000, " particles"), default=None,
        help="particles per ABC-SMC generation (default 60)",
    )
    cal.add_argument(
        "--generations", type=_whole_number(1, 100, " generations"), default=None,
        help="ABC-SMC generations (default 3)",
    )
    cal.add_argument(
        "--draws", type=_whole_number(2, 10_000, " draws"), default=None,
        help="posterior draws of the predictive check (default 20)",
    )
    cal.add_argument(
        "--max-simulations", type=_whole_number(2, 100_000, " studies"), default=None,
        help="start no further generation after this many simulated studies (default 720)",
    )
    cal.add_argument(
        "--from-history", action="store_true",
        help="finish a stopped run from the history in --out (its last whole generation; "
        "give the budget and seed it was started with)",
    )
    cal.add_argument(
        "--recheck", action="store_true",
        help="run only the predictive checks and the report again for the calibration in "
        "--out (its posterior and bundled point kept; give the seed it was run with; "
        "--draws sets how many posterior draws they take)",
    )
    cal.add_argument(
        "--seed", type=_whole_number(0, MAX_SEED), default=0, help="random seed (default 0)"
    )
    cal.add_argument(
        "--workers", type=_whole_number(1), default=None, help="processes (default: all cores)"
    )
    cal.add_argument("--scheduler", type=_scheduler, default=None, help=SCHEDULER_HELP)
    cal.add_argument(
        "--quick", action="store_true",
        help="a reduced test run (6 particles x 2 generations, small cohorts), not a result",
    )
    cls = sub.add_parser(
        "class", help="the paper's statistics on a class's own saved runs"
    )
    cls.add_argument(
        "class_folder",
        help="the class folder (one subfolder or one .zip per trainee) or a .zip of it",
    )
    cls.add_argument(
        "--experiment",
        type=int,
        required=True,
        choices=tuple(EXPERIMENTS),
        help=EXPERIMENT_HELP,
    )
    cls.add_argument("--out", default=None, help="folder for CSV, JSON, report and figure")
    cls.add_argument(
        "--plan",
        default=None,
        help="the class plan (CSV/JSON; default plan.csv or plan.json in the class folder): "
        "its trainees without runs are listed as missing",
    )
    cls.add_argument(
        "--workers", type=_whole_number(1), default=None, help="processes (default: all cores)"
    )
    cls.add_argument("--scheduler", type=_scheduler, default=None, help=SCHEDULER_HELP)
    cls.add_argument("--no-figures", action="store_true", help="skip the PNG figure")
    cls.add_argument("--no-progress", action="store_true", help="no progress bar")
    sub.add_parser(
        "warm",
        help="compile the kernels once (about 8 s; a second or so when already cached), "
        "into NUMBA_CACHE_DIR if set",
    )
    return parser


def class_command(args) -> None:
    """``lfd-tutor class``: read, analyse, print the report and (``--out``) save."""
    from .errors import InvalidFileError
    from .fileio import check_path_length
    from .study.classroom import read_class
    from .study.report import check_out_dir

    check_path_length(args.class_folder, "the class folder", InvalidFileError)
    if args.plan is not None:
        check_path_length(args.plan, "--plan", InvalidFileError)
    if args.out is not None:
        check_out_dir(args.out)

    def load_the_rest():  # statistics and figures take a second to import: do it while
        import matplotlib.pyplot  # noqa: F401
        import pingouin  # noqa: F401  # the workers replay the runs

        from .study import class_report  # noqa: F401

    result = read_class(
        args.class_folder, args.experiment, workers=args.workers, plan=args.plan,
        scheduler=args.scheduler,
        meanwhile=load_the_rest, progress=False if args.no_progress else None,
    )
    from .study.class_report import analyse_class, format_class_report, save_class

    analysis = analyse_class(result)
    print(format_class_report(result, analysis))
    if args.out is not None:
        paths = save_class(result, analysis, args.out, figures=not args.no_figures)
        print("\nwritten: " + ", ".join(str(p) for p in paths.values()))


def adaptive_plan(args):
    """The checked :class:`~tutor.study.adaptive_plan.StudyPlan` of ``lfd-tutor adaptive``."""
    import dataclasses

    from .errors import InvalidParameterError
    from .study.adaptive_plan import QUICK, StudyPlan, check_plan

    if args.quick:
        if args.n is not None:
            raise InvalidParameterError(
                "--quick fixes the size (4 teachers x 1 run x 2 seeds); drop --n or --quick"
            )
        plan = QUICK
    else:
        plan = StudyPlan(seeds=args.seeds)
        if args.n is not None:
            plan = dataclasses.replace(plan, n=args.n)
    if args.variant_seeds is not None:
        plan = dataclasses.replace(plan, variant_seeds=args.variant_seeds)
    if args.hf_teachers is not None:
        plan = dataclasses.replace(plan, hf_teachers=args.hf_teachers)
    return check_plan(plan)


def adaptive_command(args) -> None:
    """``lfd-tutor adaptive``: check everything, simulate, print the report and save."""
    from .study.report import check_out_dir

    plan = adaptive_plan(args)
    check_out_dir(args.out)  # before any work: nothing is made yet
    from .study.adaptive import run_study
    from .study.adaptive_report import analyse_study, format_study_report, save_raw, save_study

    out = check_out_dir(args.out)
    partial = out / "adaptive_partial.jsonl"  # an interrupted study resumes from it
    result = run_study(
        plan, workers=args.workers, progress=not args.no_progress, checkpoint=partial,
        scheduler=args.scheduler,
    )
    save_raw(result, out)  # the simulation is kept even if the analysis fails
    analysis = analyse_study(result)
    print(format_study_report(result, analysis))
    paths = save_study(result, analysis, out, figures=not args.no_figures)
    partial.unlink(missing_ok=True)
    print("\nwritten: " + ", ".join(str(p) for p in paths.values()))


def calibrate_command(args) -> None:
    """``lfd-tutor calibrate``: ABC-SMC, the predictive check, the report and the files."""
    import dataclasses

    from .errors import InvalidParameterError
    from .study import calibration
    from .study.report import check_out_dir

    budget = calibration.QUICK_BUDGET if args.quick else calibration.FULL_BUDGET
    chosen = {
        k: v for k, v in (("population_size", args.population_size),
                          ("generations", args.generations), ("draws", args.draws),
                          ("max_simulations", args.max_simulations))
        if v is not None
    }
    budget = dataclasses.replace(budget, **chosen)
    out = check_out_dir(args.out)  # before any work
    if args.recheck:
        if args.from_history or set(chosen) - {"draws"} or args.quick:
            raise InvalidParameterError(
                "--recheck reruns the checks of the calibration in --out with its own "
                "budget (--draws aside): drop --from-history, --quick, --population-size, "
                "--generations and --max-simulations"
            )
        found, table, paths = calibration.recheck(
            out, seed=args.seed, workers=args.workers, scheduler=args.scheduler,
            draws=args.draws,
        )
        print(calibration.format_report(found, table))
        print("\nwritten: " + ", ".join(str(p) for p in paths.values()))
        return
    if args.from_history:
        found = calibration.from_history(
            out, budget, seed=args.seed, where="a stopped run, finished from its history"
        )
    else:
        found = calibration.calibrate(
            budget, seed=args.seed, workers=args.workers, scheduler=args.scheduler, folder=out
        )
    found = calibration.refine(
        found, seed=args.seed + 2, workers=args.workers, scheduler=args.scheduler,
        candidates=2 if args.quick else 6, seeds=2 if args.quick else 3,
    )
    predicted, at_point = (
        calibration.predictive(found, seed=args.seed + 1, workers=args.workers,
                               scheduler=args.scheduler, at_point=point)
        for point in (False, True)
    )
    table = calibration.report(found, predicted, point_predicted=at_point)
    print(calibration.format_report(found, table))
    paths = calibration.save(found, predicted, table, out, point_predicted=at_point)
    print("\nwritten: " + ", ".join(str(p) for p in paths.values()))


def warm_command(args) -> None:
    """Compile every kernel a trainee's demo calls: two demos on each task."""
    import time

    import numpy as np

    from .framework import TeachingSession
    from .tasks.maze import MazeTask
    from .tasks.pickplace import PickPlaceTask
    from .workers import one_blas_thread

    t0 = time.perf_counter()
    one_blas_thread()
    rng = np.random.default_rng(0)
    maze = MazeTask()
    session = TeachingSession(maze)
    for start in maze.test_points[:2]:
        session.add_demo(maze.layout.reference_path(start, rng), point=start)
    tray = PickPlaceTask()
    session = TeachingSession(tray)
    for plant in (0, 50):
        session.add_demo(tray.demonstrate(plant, rng), point=tray.test_points[plant])
    print(f"lfd-tutor: compiled kernels ready ({time.perf_counter() - t0:.1f} s)")


COMMANDS = {
    "class": class_command,
    "adaptive": adaptive_command,
    "calibrate": calibrate_command,
    "warm": warm_command,
}


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.command in COMMANDS:
        from .errors import TutorError

        try:
            COMMANDS[args.command](args)
        except TutorError as exc:
            print(f"error ({type(exc).__name__}): {exc}", file=sys.stderr)
            return 2
        return 0
    from .errors import SaveError, TutorError
    from .study.cohort import check_request
    from .study.report import (
        analyse,
        check_out_dir,
        format_report,
        robustness,
        robustness_summary,
        save_result,
    )

    try:
        # every argument is checked before the (long) simulation starts
        check_request(args.experiment, args.n, args.seed if args.command == "reproduce" else 0)
        check_out_dir(args.out)
        if args.command == "reproduce":
            from .study.cohort import run_experiment

            result = run_experiment(
                args.experiment,
                seed=args.seed,
                n=args.n,
                workers=args.workers,
                progress=not args.no_progress,
                scheduler=args.scheduler,
            )
            analysis = analyse(result)
            print(format_report(result, analysis))
            paths = save_result(result, analysis, args.out, figures=not args.no_figures)
            print("\nwritten: " + ", ".join(str(p) for p in paths.values()))
        else:
            table = robustness(
                args.experiment,
                range(args.seeds),
                n=args.n,
                workers=args.workers,
                progress=not args.no_progress,
                scheduler=args.scheduler,
            )
            print(table.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
            print("\n" + robustness_summary(table))
            path = os.path.join(args.out, f"experiment{args.experiment}_robustness.csv")
            try:
                os.makedirs(args.out, exist_ok=True)
                table.to_csv(path, index=False)
            except OSError as exc:
                raise SaveError(f"cannot write {path}: {exc.strerror or exc}") from exc
            print(f"\nwritten: {path}")
    except TutorError as exc:
        print(f"error ({type(exc).__name__}): {exc}", file=sys.stderr)
        return 2
    return 0


def run() -> None:
    """Entry point of the ``lfd-tutor`` console script (the same as ``python -m tutor``)."""
    sys.exit(main())


if __name__ == "__main__":
    run()
