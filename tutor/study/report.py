"""Tables beside the paper's, files on disk, and robustness over seeds."""

from __future__ import annotations

import itertools
import json
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from .. import paper
from ..engine import Engine
from ..errors import InvalidFileError, InvalidParameterError, SaveError
from ..fileio import check_path_length
from ..framework import protocol
from ..framework.protocol import EXPERIMENTS
from ..framework.wording import percent
from ..resources import asset
from . import replication, stats
from .cohort import CohortResult, StudySettings, check_request, run_experiment
from .limits import MAX_SEEDS
from .tables import readable_table

__all__ = [
    "check_out_dir",
    "analyse",
    "format_report",
    "replication_table",
    "save_result",
    "robustness",
    "robustness_summary",
    "check_seeds",
    "load_result",
    "load_robustness",
    "BUNDLED",
]

#: the paper-sized cohorts bundled with the tutor, as ``lfd-tutor reproduce`` and
#: ``lfd-tutor robustness`` wrote them (seed 0; seeds 0-9): notebook 04 reads them
#: instead of simulating for a minute
BUNDLED = asset("cohorts")
#: bytes kept free below an output folder for the names of the files written in it
OUT_ROOM = 100


def check_out_dir(out) -> Path:
    """Check that the folder ``out`` can be made (if missing) and written, before any work.

    Nothing is created: the nearest existing folder on the way to ``out`` must be a
    folder, and a scratch file made in it and deleted at once shows it is writable.

    Returns
    -------
    Path
        ``out`` as a path.

    Raises
    ------
    InvalidParameterError
        ``out`` is not a path, or too long for the file system with room for the files
        written in it (:func:`tutor.fileio.check_path_length`).
    SaveError
        ``out`` (or a folder on the way to it) is a file, or the folder is read-only or
        otherwise cannot be written.
    """
    out = check_path_length(out, "the output folder (--out)", room=OUT_ROOM)
    nearest = out
    while not nearest.exists() and nearest != nearest.parent:
        if nearest.is_symlink():  # a dangling link cannot become a folder
            break
        nearest = nearest.parent
    if not nearest.is_dir():
        what = (
            "exists and is not a folder"
            if nearest == out
            else f"goes through the file {nearest}, which is a file, not a folder"
        )
        raise SaveError(
            f"the output folder {out} {what}; give --out another folder (new or existing)"
        )
    try:
        with tempfile.TemporaryFile(dir=nearest):
            pass
    except OSError as exc:
        raise SaveError(
            f"cannot write in {nearest} ({exc.strerror or exc}), so the results for {out} "
            "could not be saved; give --out a folder you can write to"
        ) from exc
    return out


def analyse(result: CohortResult) -> dict:
    """Statistics, tables, relative improvements and the paper's conclusions for a cohort."""
    runs, exp = result.runs, result.experiment
    how = stats.ANALYSES[exp]
    st = how.tests(runs)
    out = {
        "stats": st,
        "summary": stats.summary_table(runs, exp, st),
        "relative": stats.relative_improvement(st, exp),
        "conclusions": stats.conclusions(runs, exp, st),
    }
    if how.failures:
        out["failures"] = stats.failure_table(runs)
    out["replication"] = replication_table(runs, exp)
    return out


def replication_table(runs: pd.DataFrame, experiment: int, n_boot: int = 2000,
                      seed: int = 0) -> pd.DataFrame:
    """Replication rates of the experiment's conclusions (see :mod:`.replication`).

    Columns: ``this cohort`` (teachers resampled as simulated), ``paper's levels`` (each
    condition rescaled to the paper's median eta, or its totals and mean eta, first) and
    ``8 of 10 seeds`` (the chance that a conclusion with the paper-matched rate holds in
    at least 8 of 10 cohorts).
    """
    own = replication.replication_rates(runs, experiment, n_boot, seed)
    matched = replication.replication_rates(runs, experiment, n_boot, seed, match_paper=True)
    chance = matched.map(lambda r: replication.chance_of_at_least(8, 10, r))
    return pd.DataFrame({"this cohort": own, "paper's levels": matched, "8 of 10 seeds": chance})


def pct(x) -> str:
    """A share as a percentage with one decimal, as every η is written
    (:func:`tutor.framework.wording.percent`; "n/a" when there is none)."""
    return "n/a" if x is None or not np.isfinite(x) else percent(x)


def _anova_lines1(st: dict, named) -> list[str]:
    a, pa = st["anova"], paper.EXPERIMENT_1["anova"]
    sph = "holds" if a["sphericity_ok"] else "violated: Greenhouse-Geisser p used"
    lines = [
        named(
            f"repeated-measures ANOVA F({a['ddof1']},{a['ddof2']}) = {a['F']:.3f}, "
            f"p = {a['p_used']:.3g}   (paper: F({pa['ddof1']},{pa['ddof2']}) = {pa['F']}, "
            f"p = {pa['p']})"
        ),
        f"  Mauchly's sphericity: W = {a['sphericity_W']:.3f}, p = "
        f"{a['sphericity_p']:.3g} ({sph})",
    ]
    for _, r in st["pairwise"].iterrows():
        pp = paper.EXPERIMENT_1["pairwise_p"].get((r.A, r.B), float("nan"))
        lines.append(
            f"  {r.A}-{r.B}: paired t = {r['T']:.2f}, Bonferroni p = {r.p_bonf:.3g}   "
            f"(paper p = {pp})"
        )
    return lines


def _anova_lines2(st: dict, named) -> list[str]:
    a, pa = st["anova"], paper.EXPERIMENT_2["mixed_anova"]
    lines = []
    for key in ("condition", "run", "interaction"):
        r, ref = a[key], pa[key]
        ref_text = (
            f"F({ref['ddof1']},{ref['ddof2']}) = {ref['F']}, p = {ref['p']}"
            if isinstance(ref, dict)
            else ref
        )
        lines.append(
            named(
                f"mixed ANOVA, {key}: F({r['ddof1']},{r['ddof2']}) = {r['F']:.3f}, "
                f"p = {r['p']:.3g}   (paper: {ref_text})"
            )
        )
    if "sphericity_p" in a:
        ref = paper.EXPERIMENT_2["sphericity"]
        lines.append(
            f"  Mauchly's sphericity (runs): p = {a['sphericity_p']:.3g} (paper p = {ref['p']})"
        )
    for _, r in st["pairwise"].iterrows():
        lines.append(f"  {r.A}-{r.B}: Welch t = {r['T']:.2f}, Bonferroni p = {r.p_bonf:.3g}")
    return lines


#: experiment number -> the lines of the paper's tests
_ANOVA_LINES = {1: _anova_lines1, 2: _anova_lines2}


def test_lines(st: dict, experiment: int, lead: str = "") -> list[str]:
    """The paper's tests on ``st`` (:func:`tutor.study.stats.experiment_1` or ``_2``)
    beside the paper's values, one line each; ``lead`` names whose they are."""
    def named(text: str) -> str:  # "Who: repeated-measures ..." or "Repeated-measures ..."
        return f"{lead}: {text}" if lead else text[0].upper() + text[1:]

    return _ANOVA_LINES[experiment](st, named)


def _report_lines1(result: CohortResult, analysis: dict, n: int) -> list[str]:
    lines = []
    rel, prel = analysis["relative"], paper.EXPERIMENT_1["relative"]
    lines.append(
        "Relative improvement of median eta: "
        + ", ".join(f"{k} {pct(rel[k])} (paper {pct(prel[k])})" for k in rel)
        + "; the paper rounds to 'about 180 %'"
    )
    nf = protocol.experiment(1).without_feedback
    good = int(result.runs.reached_target[result.runs.condition == nf].sum())
    well, of = paper.EXPERIMENT_1["did_well_without_feedback"], paper.EXPERIMENT_1["n"]
    lines.append(f"{nf} teachers reaching 90 %: {good} of {n} (paper: {well} of {of} did well)")
    return lines


def _report_lines2(result: CohortResult, analysis: dict, n: int) -> list[str]:
    lines = []
    rel, prel = analysis["relative"], paper.EXPERIMENT_2["relative"]
    lines.append(
        "BF relative to the mean of NF, RF, SF: "
        + ", ".join(f"{k} {pct(rel[k])} (paper {pct(prel[k])})" for k in rel)
    )
    lines.append("")
    fail = analysis["failures"].copy()
    ref = pd.DataFrame(paper.EXPERIMENT_2["failures"]).T[fail.columns]
    both = fail.astype(str) + " (" + ref.astype(str) + ")"
    lines.append("Failures over all teachers and runs: simulation (paper)")
    lines.append(both.to_string())
    return lines


#: experiment -> (how many teachers a new study draws, the level the paper gives)
_REPLICATION_WORDS = {
    1: ("30 teachers, each keeping their three conditions", "median eta"),
    2: ("9 teachers per condition, each keeping their three runs", "totals and mean eta"),
}


def _replication_lines(experiment: int, table: pd.DataFrame) -> list[str]:
    drawn, level = _REPLICATION_WORDS[experiment]
    return [
        f"How often each conclusion comes out again in a new study of the paper's size "
        f"({drawn}, drawn from this cohort; 'paper's levels': each condition rescaled to "
        f"the paper's {level} first):",
        table.to_string(float_format=lambda v: f"{v:.2f}", na_rep="n/a"),
    ]


#: experiment number -> its own lines of the plain-text report
_REPORT_LINES = {1: _report_lines1, 2: _report_lines2}


def format_report(result: CohortResult, analysis: dict) -> str:
    """Plain-text report: every table beside the paper's numbers."""
    exp, st = result.experiment, analysis["stats"]
    n = result.runs.teacher.nunique()
    lines = [f"Experiment {exp}: {n} simulated teachers, seed {result.seed}", ""]
    lines.append(readable_table(analysis["summary"]).to_string())
    lines.append("")
    lines += test_lines(st, exp)
    lines += _REPORT_LINES[exp](result, analysis, n)
    lines.append("")
    lines += _replication_lines(exp, analysis["replication"])
    lines.append("")
    lines.append("The paper's conclusions on this cohort:")
    for k, v in analysis["conclusions"].items():
        lines.append(f"  {k}: {'holds' if v else 'DOES NOT HOLD'}")
    return "\n".join(lines)


def jsonable(value):
    if isinstance(value, pd.DataFrame):
        return json.loads(value.to_json(orient="index"))
    if isinstance(value, dict):
        return {
            "-".join(k) if isinstance(k, tuple) else str(k): jsonable(v) for k, v in value.items()
        }
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def save_result(result: CohortResult, analysis: dict, out, figures: bool = True) -> dict:
    """Write ``runs.csv``, ``demos.csv``, ``summary.json``, ``report.txt`` and the figure.

    Returns a dict of the paths written.

    Raises
    ------
    SaveError
        ``out`` cannot be made or written (see :func:`check_out_dir`).
    """
    out = check_out_dir(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SaveError(f"cannot make the output folder {out}: {exc.strerror or exc}") from exc
    stem = f"experiment{result.experiment}"
    paths = {
        "runs": out / f"{stem}_runs.csv",
        "demos": out / f"{stem}_demos.csv",
        "summary": out / f"{stem}_summary.json",
        "report": out / f"{stem}_report.txt",
    }
    result.runs.to_csv(paths["runs"], index=False)
    result.demos.to_csv(paths["demos"], index=False)
    summary = {
        "experiment": result.experiment,
        "seed": result.seed,
        "n_teachers": int(result.runs.teacher.nunique()),
        "settings": result.settings.__dict__,
        "paper": jsonable(stats.ANALYSES[result.experiment].paper),
        **jsonable({k: v for k, v in analysis.items()}),
    }
    paths["summary"].write_text(json.dumps(summary, indent=2, default=str))
    paths["report"].write_text(format_report(result, analysis) + "\n")
    if figures:
        import matplotlib.pyplot as plt

        from .figures import FIGURES

        fig = FIGURES[result.experiment](result.runs)
        paths["figure"] = out / f"{stem}.png"
        fig.savefig(paths["figure"], dpi=110)
        plt.close(fig)
    return paths


def robustness(
    experiment: int, seeds, n=None, workers=None, progress=True, scheduler=None
) -> pd.DataFrame:
    """Rerun a cohort for each seed; one row per seed: the conclusions and key numbers.

    Raises
    ------
    InvalidParameterError
        Before any work: no seeds, more than :data:`~tutor.study.limits.MAX_SEEDS`, or a
        seed, ``experiment`` or ``n`` that :func:`~tutor.study.cohort.check_request`
        refuses.
    """
    seeds = check_seeds(seeds)
    for seed in seeds:
        check_request(experiment, n, seed)
    rows = []
    with Engine(workers, scheduler) as engine:  # one pool or cluster for every seed
        for seed in seeds:
            rows.append(_robustness_row(
                run_experiment(experiment, seed=seed, n=n, progress=progress, engine=engine)
            ))
    return pd.DataFrame(rows)


def _robustness_row(result: CohortResult) -> dict:
    """One seed's row of :func:`robustness`: its conclusions and key numbers."""
    experiment, seed = result.experiment, result.seed
    a = analyse(result)
    row = {"seed": seed, **a["conclusions"]}
    row["all hold"] = all(a["conclusions"].values())
    row.update({f"relative {k}": v for k, v in a["relative"].items()})
    how = stats.ANALYSES[experiment]
    row.update({f"eta {c}": v for c, v in a["stats"][how.key].items()})
    if how.failures:
        fail = a["failures"]
        for kind in fail.index:
            row.update({f"{kind} {c}": int(fail.loc[kind, c]) for c in fail.columns})
    matched = a["replication"]["paper's levels"]
    row.update({f"paper-matched rate: {k}": v for k, v in matched.items()})
    return row


def check_seeds(seeds) -> list[int]:
    """``seeds`` as a list: at least one, at most :data:`~tutor.study.limits.MAX_SEEDS`.

    Raises
    ------
    InvalidParameterError
        Not a collection of seeds, none, or more than ``MAX_SEEDS`` (counted without
        reading past the limit, so ``range(10**9)`` is refused at once).
    """
    if isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__iter__"):
        raise InvalidParameterError(f"seeds must be a list or range of seeds, got {seeds!r}")
    taken = list(itertools.islice(seeds, MAX_SEEDS + 1))
    if not taken:
        raise InvalidParameterError("seeds is empty: give at least one seed, e.g. range(10)")
    if len(taken) > MAX_SEEDS:
        raise InvalidParameterError(
            f"at most {MAX_SEEDS} seeds can be run (each is a whole cohort), got more: give "
            "fewer seeds, e.g. --seeds 10"
        )
    return taken


def robustness_summary(table: pd.DataFrame) -> str:
    """Text under a :func:`robustness` table: seeds where each conclusion holds, and
    the mean paper-matched replication rates with the chance of holding in at least 8
    of 10 seeds."""
    held = {c: int(table[c].sum()) for c in table.columns if table[c].dtype == bool}
    lines = [f"seeds where each conclusion holds (of {len(table)}):"]
    lines += [f"  {k}: {v}" for k, v in held.items()]
    rates = [c for c in table.columns if c.startswith("paper-matched rate: ")]
    if rates:
        lines += [
            "",
            "If each condition's level were the paper's (teachers' relative spread as",
            "simulated), how often a new study of the paper's size would find each",
            "conclusion, mean over seeds, and the chance that it then holds in at least",
            "8 of 10 seeds:",
        ]
    for c in rates:
        known = table[c].dropna()
        name = c.split(": ", 1)[1]
        if known.empty:
            lines.append(f"  {name}: n/a (the simulation has 0 where the paper has more)")
            continue
        rate = float(known.mean())
        chance = replication.chance_of_at_least(8, 10, rate)
        where = "" if len(known) == len(table) else f", from {len(known)} seeds"
        lines.append(f"  {name}: {rate:.2f} (8 of 10: {chance:.2f}{where})")
    return "\n".join(lines)


def _check_experiment(experiment) -> int:
    if experiment not in EXPERIMENTS or isinstance(experiment, bool):
        raise InvalidParameterError(
            f"experiment must be 1 (maze) or 2 (pick-and-place), got {experiment!r}"
        )
    return int(experiment)


def _read_csv(path: Path, what: str) -> pd.DataFrame:
    if not path.is_file():
        raise InvalidFileError(
            f"{path} is missing: write it with `lfd-tutor {what} --out {path.parent}`"
        )
    try:
        return pd.read_csv(path)
    except (ValueError, OSError, UnicodeDecodeError) as exc:
        raise InvalidFileError(
            f"{path} cannot be read as the CSV file `lfd-tutor {what}` writes ({exc}); "
            "write it again with that command"
        ) from exc


def load_result(experiment: int, folder=None) -> CohortResult:
    """A cohort saved by :func:`save_result` (``lfd-tutor reproduce --out folder``).

    Parameters
    ----------
    experiment : {1, 2}
    folder : path, optional
        Where ``experiment<N>_runs.csv``, ``_demos.csv`` and ``_summary.json`` are;
        default the paper-sized cohorts bundled with the tutor (:data:`BUNDLED`).

    Raises
    ------
    InvalidFileError
        A file is missing or is not what the command writes.
    """
    experiment = _check_experiment(experiment)
    folder = BUNDLED if folder is None else Path(folder)
    stem = f"experiment{experiment}"
    command = f"reproduce --experiment {experiment}"
    runs = _read_csv(folder / f"{stem}_runs.csv", command)
    demos = _read_csv(folder / f"{stem}_demos.csv", command)
    summary_path = folder / f"{stem}_summary.json"
    try:
        summary = json.loads(summary_path.read_text(encoding="utf-8"))
        seed, settings = int(summary["seed"]), StudySettings(**summary["settings"])
        if summary["experiment"] != experiment:
            raise ValueError(f"it holds experiment {summary['experiment']!r}")
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InvalidFileError(
            f"{summary_path} is not the summary `lfd-tutor {command}` writes ({exc}); "
            "write it again with that command"
        ) from exc
    order = list(EXPERIMENTS[experiment].paper_codes)
    for frame in (runs, demos):
        if "condition" not in frame or not frame["condition"].isin(order).all():
            raise InvalidFileError(
                f"the files of experiment {experiment} in {folder} hold conditions other "
                f"than {', '.join(order)}: write them again with `lfd-tutor {command}`"
            )
        frame["condition"] = pd.Categorical(frame["condition"], categories=order, ordered=True)
    return CohortResult(experiment, seed, runs, demos, settings)


def load_robustness(experiment: int, folder=None) -> pd.DataFrame:
    """A robustness table saved by ``lfd-tutor robustness --out folder`` (default: bundled)."""
    experiment = _check_experiment(experiment)
    folder = BUNDLED if folder is None else Path(folder)
    return _read_csv(
        folder / f"experiment{experiment}_robustness.csv",
        f"robustness --experiment {experiment} --seeds 10",
    )


def seeds_report(table: pd.DataFrame, experiment: int) -> str:
    """The levels of a robustness table beside the paper's: means over the seeds.

    Experiment 1: the median eta per condition (mean over seeds) and the relative
    improvements (range and median over seeds). Experiment 2: the mean eta per condition,
    BF's relative improvement, and the failure counts averaged over the seeds. Then
    :func:`robustness_summary` (the seeds where each conclusion holds).
    """
    experiment = _check_experiment(experiment)
    conds = EXPERIMENTS[experiment].paper_codes
    first, last = int(table["seed"].min()), int(table["seed"].max())
    how = stats.ANALYSES[experiment]
    kind, ref = how.summary, how.paper_eta
    lines = [f"Over seeds {first}-{last} ({len(table)} cohorts of the paper's size):", ""]
    lines.append(f"{kind} eta per condition, mean over the seeds (paper):")
    lines += [f"  {c}: {pct(table[f'eta {c}'].mean())} ({pct(ref[c])})" for c in conds]
    relative = [c for c in table.columns if c.startswith("relative ")]
    lines.append("relative improvement over the seeds, range (median):")
    for c in relative:
        values = table[c].dropna()
        lines.append(
            f"  {c[len('relative ') :]}: {pct(values.min())}-{pct(values.max())} "
            f"({pct(values.median())})"
        )
    if how.failures:
        lines.append("failures over all teachers and runs, mean over the seeds (paper):")
        for failure, counts in how.paper["failures"].items():
            cells = [f"{c} {table[f'{failure} {c}'].mean():.0f} ({counts[c]})" for c in conds]
            lines.append(f"  {failure}: " + ", ".join(cells))
    lines += ["", robustness_summary(table)]
    return "\n".join(lines)
