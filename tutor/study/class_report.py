"""A class's results beside the paper's and beside a simulated class of the same size.

:func:`analyse_class` runs the paper's statistics on a :class:`~.class_result.ClassResult`
(the same functions as the simulated cohorts, :mod:`tutor.study.stats`):

- Experiment 1: repeated-measures ANOVA of η over NF, VF, VR with Mauchly's sphericity
  check, then paired t-tests (Bonferroni), on the trainees who did all three;
- Experiment 2: mixed ANOVA (condition between, run within), then Welch t-tests of the
  trainees' mean η, on the trainees who did all three runs; the failure-count table.

The paper's tests run on the paper's conditions only. A condition beyond the paper
(any the registry, :data:`tutor.framework.protocol.EXPERIMENTS`, lists as not the
paper's: AF, HF, VA, or one added later) that has counted runs gets its own row of the
per-condition table and its own comparison with the paper's condition it is compared
with (:func:`beyond_table`, :func:`tutor.study.stats.compare_two`), never a place in the
paper's ANOVA.

A class too small for a test (fewer than :data:`MIN_PER_CONDITION` whole trainees in a
condition) gets descriptive numbers and a plain sentence saying why there is no test.

The comparison cohort is drawn from the paper-sized simulated cohorts bundled with the
tutor (:data:`tutor.study.report.BUNDLED`): as many simulated teachers per condition as
the class has whole trainees, chosen at random with a fixed seed, so it shows what a
class of this size may give by chance alone when teachers behave like the simulation.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import SaveError
from ..framework.protocol import EXPERIMENTS
from ..framework.wording import NOT_A_NUMBER, plural, sentence
from . import stats
from .class_result import ClassResult
from .report import check_out_dir, jsonable, load_result, pct, test_lines
from .tables import has_no_number, readable_label, readable_table

__all__ = [
    "MIN_PER_CONDITION",
    "analyse_class",
    "format_class_report",
    "save_class",
    "same_size_cohort",
    "descriptive_table",
    "beyond_table",
    "paper_runs",
]

#: the fewest whole trainees per condition for the paper's tests (below it: description only)
MIN_PER_CONDITION = 3

#: what a dash means in the class's tables (report and dashboard)
BESIDE_LEGEND = (
    f"{NOT_A_NUMBER} = no number yet: no counted run in that condition, or (simulated, same "
    "size) no trainee there has finished every run"
)


def _counts(runs: pd.DataFrame, experiment: int) -> dict[str, int]:
    conditions = EXPERIMENTS[experiment].paper_codes
    if runs.empty:
        return dict.fromkeys(conditions, 0)
    per = runs.groupby("condition", observed=False)["teacher"].nunique()
    return {c: int(per.get(c, 0)) for c in conditions}


def paper_runs(runs: pd.DataFrame, experiment: int) -> pd.DataFrame:
    """The rows of ``runs`` in the paper's conditions, their ``condition`` a categorical
    of the paper's conditions only (what the paper's tests and figures read)."""
    conditions = list(EXPERIMENTS[experiment].paper_codes)
    if "condition" not in runs:
        return runs
    mine = runs[runs.condition.astype(str).isin(conditions)].reset_index(drop=True)
    mine["condition"] = pd.Categorical(
        mine.condition.astype(str), categories=conditions, ordered=True
    )
    return mine


def _taught(runs: pd.DataFrame, experiment: int) -> list[str]:
    """The paper's conditions, then those beyond it that ``runs`` holds, in registry order."""
    spec = EXPERIMENTS[experiment]
    held = set(runs.condition.astype(str)) if "condition" in runs else set()
    return [*spec.paper_codes, *(c for c in spec.extra_codes if c in held)]


def too_small(runs: pd.DataFrame, experiment: int) -> str:
    """Why the paper's tests cannot be run on ``runs`` (whole trainees only), or ""."""
    counts = _counts(runs, experiment)
    short = {c: k for c, k in counts.items() if k < MIN_PER_CONDITION}
    if not short:
        return ""
    have = ", ".join(f"{c} {k}" for c, k in counts.items())
    design = EXPERIMENTS[experiment].design
    return (
        f"the class is too small for the paper's tests: they need at least "
        f"{MIN_PER_CONDITION} trainees per condition who finished every run ({design}), "
        f"and it has {have}. The numbers below describe the class; they test nothing."
    )


def descriptive_table(runs: pd.DataFrame, experiment: int) -> pd.DataFrame:
    """Per condition: trainees, runs, η (median, mean), demos, ε, and the failures.

    A row for each of the paper's conditions, then one for each condition beyond the
    paper that has counted runs."""
    conditions = _taught(runs, experiment)
    if runs.empty:
        return pd.DataFrame(index=conditions, columns=["trainees", "runs"]).fillna(0)
    g = runs.groupby("condition", observed=False)
    table = pd.DataFrame(
        {
            "trainees": g["teacher"].nunique(),
            "runs": g.size(),
            "median eta": g["eta"].median(),
            "mean eta": g["eta"].mean(),
            "mean demos": g["n_demos"].mean(),
            "mean efficacy": g["efficacy"].mean(),
            "errors": g["errors"].sum(),
            "undemonstrated": g["undemonstrated"].sum(),
            "ambiguous": g["ambiguous"].sum(),
        }
    )
    name, column = stats.ANALYSES[experiment].class_column(g)
    table[name] = column
    return table.reindex(conditions)


def same_size_cohort(class_runs: pd.DataFrame, experiment: int, seed: int = 0) -> pd.DataFrame:
    """Runs of simulated teachers, as many per condition as ``class_runs`` has trainees.

    Drawn without replacement from the bundled paper-sized cohort (30 or 36 teachers; at
    most 9 per condition in Experiment 2), with a fixed seed.
    """
    bundled = load_result(experiment).runs
    rng = np.random.default_rng(seed)
    counts = _counts(class_runs, experiment)
    if EXPERIMENTS[experiment].within_subjects:
        pool = np.sort(bundled.teacher.unique())
        k = min(max(counts.values(), default=0), len(pool))
        chosen = rng.choice(pool, size=k, replace=False)
    else:
        chosen = []
        for cond, k in counts.items():
            pool = np.sort(bundled.loc[bundled.condition == cond, "teacher"].unique())
            chosen += list(rng.choice(pool, size=min(k, len(pool)), replace=False))
    return bundled[bundled.teacher.isin(chosen)].reset_index(drop=True)


def beyond_table(runs: pd.DataFrame, experiment: int) -> pd.DataFrame:
    """Each condition beyond the paper that ``runs`` holds, against the paper's condition
    the registry compares it with (:func:`tutor.study.stats.compare_two`).

    Columns: ``compared with``, ``trainees`` and ``<measure>`` of the condition, the same
    of the one it is compared with, ``test``, ``T`` and ``p`` (NaN: too few trainees).
    Empty (no rows) when ``runs`` holds none of them.
    """
    spec = EXPERIMENTS[experiment]
    pick = stats.ANALYSES[experiment].summary
    measure = f"{pick} eta"
    columns = ["compared with", "trainees", measure, "trainees (compared)",
               f"{measure} (compared)", "test", "T", "p"]
    rows = {}
    for code in _taught(runs, experiment)[len(spec.paper_codes):]:
        other = spec.condition(code).compared_with
        mine, theirs = (runs[runs.condition.astype(str) == c] for c in (code, other))
        test = stats.compare_two(runs, code, other, experiment)
        rows[code] = [
            other, mine.teacher.nunique(), getattr(mine.eta, pick)(), theirs.teacher.nunique(),
            getattr(theirs.eta, pick)() if len(theirs) else np.nan, test["test"], test["T"],
            test["p"],
        ]
    return pd.DataFrame.from_dict(rows, orient="index", columns=columns)


def _tests(runs: pd.DataFrame, experiment: int) -> dict:
    """The paper's statistics on whole trainees' runs, or why there are none."""
    why = too_small(runs, experiment)
    if not why and runs["eta"].nunique() < 2:
        why = (
            f"every counted run has the same η ({100 * runs['eta'].iloc[0]:.1f} %): the "
            "tests compare differences and there are none (do the runs all hold the same "
            "demonstrations?)"
        )
    if why:
        return {"tested": False, "why_not": why}
    st = stats.ANALYSES[experiment].tests(runs)
    return {
        "tested": True,
        "why_not": "",
        "stats": st,
        "relative": stats.relative_improvement(st, experiment),
        "conclusions": stats.conclusions(runs, experiment, st),
    }


def analyse_class(result: ClassResult, seed: int = 0) -> dict:
    """Statistics, tables and the comparisons of a class (see the module docstring).

    Returns
    -------
    dict
        ``descriptive`` (all counted runs), ``failures`` (the paper's table, all counted
        runs), ``class`` (tests on whole trainees: ``tested``, ``why_not``, ``stats``,
        ``relative``, ``conclusions``), ``simulated`` (the same for the same-size
        simulated cohort, with its ``runs``), ``beside`` (class, paper and simulated η per
        condition), ``beyond`` (each condition beyond the paper against the one it is
        compared with, on whole trainees: :func:`beyond_table`). The tests, the failure
        table and ``beside`` are on the paper's conditions only.
    """
    exp = result.experiment
    whole = paper_runs(result.complete_runs, exp)  # the paper's tests: its conditions only
    simulated_runs = same_size_cohort(whole, exp, seed)
    paper_part = paper_runs(result.runs, exp)
    out = {
        "descriptive": descriptive_table(result.runs, exp),
        "failures": stats.failure_table(paper_part) if not paper_part.empty else None,
        "class": _tests(whole, exp),
        "simulated": {**_tests(simulated_runs, exp), "runs": simulated_runs},
        "beyond": beyond_table(result.complete_runs, exp),
    }
    conditions = list(EXPERIMENTS[exp].paper_codes)
    how = stats.ANALYSES[exp]
    measure, ref = f"{how.summary} eta", how.paper_eta
    sim = descriptive_table(simulated_runs, exp)
    out["beside"] = pd.DataFrame(
        {
            "trainees": out["descriptive"]["trainees"],
            f"{measure} (class)": out["descriptive"].get(measure),
            f"{measure} (paper)": [ref[c] for c in conditions],
            f"{measure} (simulated, same size)": sim.get(measure),
            "simulated teachers": sim["trainees"],
        },
        index=conditions,
    )
    out["measure"] = measure
    return out


# ---------------------------------------------------------------- the report


def tested_lines(tests: dict, experiment: int, who: str) -> list[str]:
    if not tests["tested"]:
        return [f"{who}: no test — {tests['why_not']}"]
    lines = test_lines(tests["stats"], experiment, who)
    lines.append(
        "  the paper's conclusions: "
        + "; ".join(
            f"{k} {'holds' if v else 'does not hold'}" for k, v in tests["conclusions"].items()
        )
    )
    return lines


def beyond_lines(beyond: pd.DataFrame) -> list[str]:
    """The conditions beyond the paper, each against the one it is compared with, one
    line each (none when the class has no run beyond the paper)."""
    lines = []
    for code, row in beyond.iterrows():
        measure = readable_label(beyond.columns[2])
        other = row["compared with"]
        said = (
            f"{row['test']} = {row['T']:.2f}, p = {row['p']:.3g}"
            if np.isfinite(row["p"])
            else "no test (it needs 2 whole trainees a side, with some spread)"
        )
        lines.append(
            f"Beyond the paper, {code} against {other}: {said}; {measure} "
            f"{pct(row.iloc[2])} ({plural(int(row['trainees']), 'whole trainee')}) against "
            f"{pct(row.iloc[4])} ({plural(int(row['trainees (compared)']), 'whole trainee')})"
        )
    return lines


def format_class_report(result: ClassResult, analysis: dict) -> str:
    """Plain-text report of a class: what was counted, the numbers, the files left out."""
    exp = result.experiment
    trainees = result.trainees
    counted = int((trainees.counted_runs > 0).sum()) if len(trainees) else 0
    whole = int(trainees.complete.sum()) if len(trainees) else 0
    spec = EXPERIMENTS[exp]
    task = spec.title
    lines = [
        f"Experiment {exp} ({task}) of the class in {result.source}",
        f"{plural(len(result.runs), 'run')} counted from {plural(counted, 'trainee')}; "
        f"{plural(whole, 'trainee')} finished every {spec.unit}.",
        "",
    ]
    if result.runs.empty:
        lines.append(
            "No finished run of this experiment was found, so there is nothing to analyse yet."
        )
    else:
        measure = readable_label(analysis["measure"])
        lines.append(f"The class's {measure} beside the paper's and a simulated")
        lines.append("class of the same size (drawn from the bundled simulated cohort):")
        beside = readable_table(analysis["beside"])
        descriptive = readable_table(analysis["descriptive"])
        lines.append(beside.to_string())
        lines.append("")
        lines.append("Per condition (every counted run):")
        lines.append(descriptive.to_string())
        if has_no_number(beside) or has_no_number(descriptive):
            lines.append(f"({BESIDE_LEGEND})")
        lines.append("")
        lines += tested_lines(analysis["class"], exp, "This class")
        lines += tested_lines(analysis["simulated"], exp, "Simulated, same size")
        lines += beyond_lines(analysis["beyond"])
        if stats.ANALYSES[exp].failures and analysis["failures"] is not None:
            fail = analysis["failures"]
            ref = pd.DataFrame(stats.ANALYSES[exp].paper["failures"]).T[fail.columns]
            lines.append("")
            lines.append("Failures over all counted runs: class (paper)")
            lines.append((fail.astype(str) + " (" + ref.astype(str) + ")").to_string())
    lacking = trainees[~trainees.complete] if len(trainees) else trainees
    if len(lacking):
        lines.append("")
        lines.append(f"Trainees with runs still to finish ({len(lacking)}):")
        for _, t in lacking.iterrows():
            lines.append(f"  {t.trainee} ({t.trainee_key}): {t.missing}")
    problems = result.not_counted
    lines.append("")
    if problems:
        lines.append(f"Files not counted ({len(problems)}):")
        for f in problems:
            lines.append(f"  {f.file}: {f.kind} — {f.reason}")
    else:
        lines.append("Every run file of this experiment was counted.")
    lines += [as_sentence(note) for note in result.notes]
    others = result.other_experiment
    if others:
        other = next(n for n in EXPERIMENTS if n != exp)
        lines.append(
            f"{len(others)} files of Experiment {other} were set aside: read them with "
            f"--experiment {other}."
        )
    return "\n".join(lines)


def as_sentence(note: str) -> str:
    """A :attr:`ClassResult.notes` entry as a sentence: capitalised, with its full stop."""
    return sentence(note, capital=True)


def _class_json(result: ClassResult, analysis: dict) -> dict:
    trainees = []
    for _, t in result.trainees.iterrows():
        mine = [f for f in result.files if f.trainee_key == t.trainee_key]
        trainees.append(
            {
                "key": t.trainee_key,
                "name": t.trainee,
                "complete": bool(t.complete),
                "missing": t.missing,
                "runs": [
                    {k: v for k, v in f.to_dict().items() if k not in ("trainee", "trainee_key")}
                    for f in mine
                    if f.kind != "other experiment"
                ],
            }
        )
    tests = {
        who: {k: v for k, v in analysis[who].items() if k != "runs"}
        for who in ("class", "simulated")
    }
    return {
        "experiment": result.experiment,
        "source": result.source,
        "n_runs_counted": len(result.runs),
        "trainees": trainees,
        "skipped": [f.to_dict() for f in result.not_counted],
        "other_experiment": [f.file for f in result.other_experiment],
        "beside": jsonable(analysis["beside"]),
        "descriptive": jsonable(analysis["descriptive"]),
        "failures": None if analysis["failures"] is None else jsonable(analysis["failures"]),
        "beyond": jsonable(analysis["beyond"]),
        **jsonable(tests),
    }


def class_figure(result: ClassResult, analysis: dict):
    """The paper-style figure of the class (the paper's conditions), the simulated
    same-size medians/means marked."""
    from .figures import FIGURES

    draw = FIGURES[result.experiment]
    runs = paper_runs(result.runs, result.experiment)  # beside the paper's: its conditions
    return draw(runs, who="trainees", reference=analysis["simulated"]["runs"])


#: what a spreadsheet reads as the start of a formula (OWASP, CSV injection)
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def spreadsheet_safe(value):
    """``value`` as a CSV cell a spreadsheet will not run: a text starting a formula gets
    a leading ``'``; numbers (negative ones too) stay numbers.

    >>> spreadsheet_safe("=1+1"), spreadsheet_safe("-x"), spreadsheet_safe(-2.5)
    ("'=1+1", "'-x", -2.5)
    """
    if isinstance(value, str) and value.startswith(FORMULA_STARTS):
        return "'" + value
    return value


def write_csv(frame: pd.DataFrame, path) -> None:
    """Write ``frame`` as a CSV an educator may open in a spreadsheet: every text cell
    (and column name) made :func:`spreadsheet_safe`."""
    safe = frame.copy()
    for column in safe.columns:
        if not pd.api.types.is_numeric_dtype(safe[column]):
            safe[column] = safe[column].map(spreadsheet_safe)
    safe.columns = [spreadsheet_safe(str(c)) for c in safe.columns]
    safe.to_csv(path, index=False)


def save_class(result: ClassResult, analysis: dict, out, figures: bool = True) -> dict:
    """Write ``class_runs.csv``, ``class_demos.csv``, ``class_files.csv``, ``class.json``,
    ``class_report.txt`` and (``figures``, with runs) ``class_experiment<N>.png``.

    Returns a dict of the paths written.

    Raises
    ------
    SaveError
        ``out`` cannot be made or written.
    """
    out = check_out_dir(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SaveError(f"cannot make the output folder {out}: {exc.strerror or exc}") from exc
    paths = {
        "runs": out / "class_runs.csv",
        "demos": out / "class_demos.csv",
        "files": out / "class_files.csv",
        "summary": out / "class.json",
        "report": out / "class_report.txt",
    }
    try:
        write_csv(result.runs, paths["runs"])
        write_csv(result.demos, paths["demos"])
        write_csv(pd.DataFrame([f.to_dict() for f in result.files]), paths["files"])
        text = json.dumps(_class_json(result, analysis), indent=2, default=str)
        Path(paths["summary"]).write_text(text, encoding="utf-8")
        paths["report"].write_text(format_class_report(result, analysis) + "\n", "utf-8")
        if figures and not paper_runs(result.runs, result.experiment).empty:
            import matplotlib.pyplot as plt

            fig = class_figure(result, analysis)
            paths["figure"] = out / f"class_experiment{result.experiment}.png"
            fig.savefig(paths["figure"], dpi=110)
            plt.close(fig)
    except OSError as exc:
        raise SaveError(f"cannot write the class results in {out}: {exc.strerror or exc}") from exc
    return paths
