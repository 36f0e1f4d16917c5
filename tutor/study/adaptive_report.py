r"""The adaptive-feedback study's analysis, report, figure and files.

:func:`analyse_study` gathers the statistics of :mod:`tutor.study.adaptive_stats` for a
:class:`~tutor.study.adaptive.StudyResult`; :func:`format_study_report` states every
claim with its CI over the seeds as measured (and, for a policy that does not beat BF,
why: demos per run, robot time, undemonstrated plants, why runs stopped);
:func:`study_figure` draws the three panels; :func:`save_study` writes them all:

=========================== ==========================================================
``adaptive_runs.csv``       one row per variant, seed, teacher, policy and run
``adaptive_curves.csv``     eps and the clock after every demo (and demo taken back)
``adaptive_plan.json``      the plan as run (:func:`load_study` reads the three back)
``adaptive_summary.json``   the plan, every table and the headline numbers
``adaptive_report.txt``     the report
``adaptive_figure.png``     (a) eps against seconds used, (b) delta-eps against k,
                            (c) undemonstrated plants per run
=========================== ==========================================================
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd

from .. import paper
from ..errors import SaveError
from . import adaptive_stats as st
from .adaptive import StudyResult
from .adaptive_plan import BASELINE, POLICIES, is_secondary
from .report import check_out_dir, pct

__all__ = [
    "PLAN_FORMAT",
    "load_study",
    "save_raw",
    "analyse_study",
    "format_study_report",
    "study_figure",
    "save_study",
    "paper_bf_undemonstrated_per_run",
    "optimal_curve",
]


#: the ``format`` of ``adaptive_plan.json``
PLAN_FORMAT = "lfd-tutor-adaptive-study"


def paper_bf_undemonstrated_per_run() -> float:
    """The paper's BF undemonstrated states per run: its total over the 9 BF teachers x
    3 runs (827) divided by those 27 runs."""
    n_runs = paper.PICKPLACE_N_TEACHERS // len(paper.PICKPLACE_CONDITIONS) * paper.PICKPLACE_N_RUNS
    return paper.EXPERIMENT_2["failures"]["undemonstrated"]["BF"] / n_runs


def optimal_curve(runs: pd.DataFrame):
    """The optimal teacher's greedy eps after each demo, placed on the clock at the
    simulated teachers' own pace with no robot attempts (it needs none): each demo costs
    the mean set-up time plus the mean demo duration of the study's runs.

    Returns ``(seconds, eps, pace)`` (arrays starting at (0, 0); ``pace`` the seconds per
    demo), or None without a bundled reference.
    """
    from ..tasks.optimal_reference import optimal_reference

    ref = optimal_reference("pickplace")
    if ref is None or not ref.greedy:
        return None
    pace = float(runs["trait_setup_seconds"].mean() + runs["demo_seconds"].mean())
    eps = np.r_[0.0, np.asarray(ref.greedy, dtype=float)]
    return np.arange(len(eps)) * pace, eps, pace


def analyse_study(result: StudyResult) -> dict:
    """Every table of the report (see :mod:`tutor.study.adaptive_stats`)."""
    plan, main = result.plan, result.main
    order = list(plan.policies)
    deltas, per_seed = {}, {}
    for column in st.DELTA_MEASURES:
        seeds, overall = st.delta_table(main, column, plan.n_boot, 0, order)
        deltas[column], per_seed[column] = overall, seeds
    # the selection itself, at the same k: each selector against random picks of as many
    selection = {}
    for control in [p for p in order if POLICIES[p].selector == "random"]:
        k = POLICIES[control].k
        same = [p for p in order if POLICIES[p].k == k and p != control
                and not POLICIES[p].reference]
        if same:
            selection[control] = st.delta_table(
                main, "efficacy", plan.n_boot, 0, same, baseline=control
            )[1]
    curves = result.curves[result.curves.variant == "default"]
    from ..tasks.optimal_reference import optimal_reference

    ref = optimal_reference("pickplace")
    return {
        "policies": st.policy_table(main, order),
        "deltas": deltas,
        "per_seed": per_seed,
        "selection": selection,
        "why_stopped": st.why_stopped(main, order),
        "replication": st.replication_table(result.runs, plan.n, plan.n_boot, 0),
        "curves": st.mean_curves(curves),
        "optimal": None if ref is None else {
            "n_demos": ref.n_demos, "best_eta": ref.best_eta, "greedy": list(ref.greedy),
            "best_pair": ref.best_pair,
        },
        "paper_bf_undemonstrated_per_run": paper_bf_undemonstrated_per_run(),
    }


def _plain(value):
    """``value`` with frames, numpy scalars, tuples and NaN made JSON-ready (NaN -> None)."""
    if isinstance(value, pd.DataFrame):
        return _plain(json.loads(value.to_json(orient="index")))
    if isinstance(value, pd.Series):
        return _plain(value.to_dict())
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def _pts(x) -> str:
    return "n/a" if not np.isfinite(x) else f"{100 * x:+.1f}"


def _ci(row, low="low", high="high", fmt=_pts) -> str:
    return f"[{fmt(row[low])}, {fmt(row[high])}]"


def _num(x, digits=1) -> str:
    return "n/a" if not np.isfinite(x) else f"{x:.{digits}f}"


def _policy_lines(table: pd.DataFrame) -> list[str]:
    head = (
        f"{'policy':<7} {'eps at 900 s [95 % CI]':>26} {'reached 0.9':>12} {'ends >=0.9':>11} "
        f"{'undem./run':>10} {'demos':>6} {'redone':>6} {'eta':>7} {'eta@0.9':>8} "
        f"{'robot s':>8} {'clock s':>8}"
    )
    lines = [head, "-" * len(head)]
    for name, r in table.iterrows():
        eps = f"{pct(r.efficacy)} [{pct(r.efficacy_low)}, {pct(r.efficacy_high)}]"
        lines.append(
            f"{name:<7} {eps:>26} {pct(r.reached_target):>12} {pct(r.final_reached):>11} "
            f"{_num(r.undemonstrated):>10} {_num(r.n_demos, 2):>6} {_num(r.retries, 2):>6} "
            f"{pct(r.eta):>7} {pct(r.eta_target):>8} {_num(r.robot_seconds, 0):>8} "
            f"{_num(r.seconds, 0):>8}"
        )
    return lines


def _claim(name: str, analysis: dict, seeds: int) -> str:
    d = analysis["deltas"]["efficacy"].loc[name]
    pol = analysis["policies"]
    base, me = pol.loc[BASELINE], pol.loc[name]
    ref = " (an oracle, for reference only)" if POLICIES[name].reference else ""
    text = (
        f"{name}{ref}: delta-eps vs BF = {_pts(d['mean'])} points, 95 % CI {_ci(d)} "
        f"across {int(d.seeds)} seeds (pooled bootstrap {_ci(d, 'pooled_low', 'pooled_high')}); "
        f"its per-seed CI over teachers is above 0 in {int(d.seeds_above)} of {int(d.seeds)} "
        f"seeds and below 0 in {int(d.seeds_below)}."
    )
    if d["low"] > 0:
        return text + f" {name} beats BF."
    verdict = "does worse than BF" if d["high"] < 0 else "does not beat BF (the CI holds 0)"
    time_share = analysis["why_stopped"].get("time", pd.Series(dtype=float))
    why = (
        f" {name} {verdict}. Why, per run ({name} vs BF): {_num(me.n_demos, 2)} vs "
        f"{_num(base.n_demos, 2)} demos kept, {_num(me.retries, 2)} vs "
        f"{_num(base.retries, 2)} redone, {_num(me.robot_seconds, 0)} vs "
        f"{_num(base.robot_seconds, 0)} robot seconds, {_num(me.undemonstrated)} vs "
        f"{_num(base.undemonstrated)} undemonstrated plants, "
        f"{pct(time_share.get(name, np.nan))} vs {pct(time_share.get(BASELINE, np.nan))} "
        "of runs ended by the clock."
    )
    return text + why


def format_study_report(result: StudyResult, analysis: dict) -> str:
    """The study's text report: every claim with its CI over the seeds, as measured."""
    plan = result.plan
    seeds = plan.seeds
    lines = [
        "Adaptive feedback (beyond the paper): choosing r automatically, Experiment 2",
        f"{plan.n} simulated teachers x {plan.runs} runs x {seeds} seeds per policy, common "
        "random numbers (same traits and run generators in every policy), 15-minute clock, "
        "25 s per realisation" + (" [QUICK: a reduced test run, not a result]" if plan.quick
                                 else ""),
        f"simulation wall time {result.seconds:.0f} s"
        + (f" (and {result.resumed} jobs resumed from a checkpoint)" if result.resumed else ""),
    ]
    if result.missing:
        lines.append(
            f"NOT RUN: {', '.join(result.missing)} (this tutor has no HF condition or no "
            "compliance trait yet: the next-demo hint's arms are missing from this study)"
        )
    hinted = [p for p in plan.policies if POLICIES[p].hinted]
    if hinted and plan.hf_teachers is not None and plan.hf_teachers < plan.n:
        lines.append(
            f"{', '.join(hinted)}: teachers 0-{plan.hf_teachers - 1} of each seed only (the "
            "hint's lookahead makes an HF run about 4 times as long); their deltas are "
            "paired with BF on those teachers, their per-policy rows are means over them"
        )
    few = [p for p in plan.policies if is_secondary(p)]
    if few and plan.secondary_seeds is not None and plan.secondary_seeds < seeds:
        lines.append(
            f"{', '.join(few)}: seeds 0-{plan.secondary_seeds - 1} only (the machine's time; "
            f"the other arms have all {seeds}); their CIs are across those seeds"
        )
    lines += ["", "Per policy (means over all runs; eps CI: t across the seeds' means)", ""]
    lines += _policy_lines(analysis["policies"])
    lines += ["", "Paired delta vs BF (same teacher, seed and run; a teacher's runs averaged)", ""]
    head = (
        f"{'policy':<7} {'measure':<15} {'mean':>8} {'95 % CI (seeds)':>20} "
        f"{'seeds CI>0':>11} {'CI<0':>5}"
    )
    lines += [head, "-" * len(head)]
    for column in st.DELTA_MEASURES:
        table = analysis["deltas"][column]
        points = column in ("efficacy", "reached_target")
        fmt = _pts if points else (lambda v: _num(v, 2))
        for name, d in table.iterrows():
            lines.append(
                f"{name:<7} {column:<15} {fmt(d['mean']):>8} {_ci(d, fmt=fmt):>20} "
                f"{int(d.seeds_above):>5} / {int(d.seeds)} {int(d.seeds_below):>5}"
            )
    lines += ["", "(efficacy and reached_target in percentage points)", ""]
    lines += ["Claims (delta-eps at 900 s against BF)", ""]
    for name in analysis["deltas"]["efficacy"].index:
        lines.append("- " + _claim(name, analysis, seeds))
    for control, table in analysis["selection"].items():
        k = POLICIES[control].k
        lines += ["", f"The choice itself at k = {k}: delta-eps against {control} (as many plants "
                  "shown, chosen at random; same teachers)", ""]
        for name, d in table.iterrows():
            lines.append(
                f"* {name} vs {control}: {_pts(d['mean'])} points, 95 % CI {_ci(d)} across "
                f"{int(d.seeds)} seeds; CI above 0 in {int(d.seeds_above)}, below 0 in "
                f"{int(d.seeds_below)} of the seeds"
            )
    lines += ["", "Per-seed delta-eps vs BF (points; bootstrap CI over teachers)", ""]
    per = analysis["per_seed"]["efficacy"]
    for name, group in per.groupby("policy", sort=False):
        cells = ", ".join(f"{_pts(r['mean'])} {_ci(r)}" for _, r in group.iterrows())
        lines.append(f"{name:<7} {cells}")
    lines += ["", "How runs ended (share of runs)", ""]
    lines.append(analysis["why_stopped"].to_string(float_format=lambda v: f"{100 * v:.0f} %"))
    paper_bf = analysis["paper_bf_undemonstrated_per_run"]
    lines += [
        "",
        f"Undemonstrated plants per run: the paper's BF {paper_bf:.1f}"
        " (827 over 9 teachers x 3 runs); simulated BF "
        f"{_num(analysis['policies'].loc[BASELINE].undemonstrated)}.",
    ]
    rep = analysis["replication"]
    if len(rep):
        lines += [
            "",
            "Robustness over teacher-model variants: replication rates of 'the policy beats "
            "BF' (delta-eps CI above 0)",
            "seed_rate: share of seeds whose bootstrap CI is above 0; boot_rate: share of "
            f"resampled cohorts of {plan.n} teachers whose 95 % CI is above 0",
            "",
            rep.to_string(index=False, float_format=lambda v: f"{v:.3f}"),
        ]
    opt = analysis["optimal"]
    if opt is not None:
        lines += [
            "",
            f"The optimal teacher (greedy machine teacher, bundled reference): eps = 1 with "
            f"{opt['n_demos']} demos, best eta {pct(opt['best_eta'])}; no pair of demos "
            f"reaches 0.9 (best pair {pct(opt['best_pair'])}).",
        ]
    lines += [
        "",
        "Caveats: these are simulated teachers (the traits of tutor.teachers.traits, never "
        "tuned per policy);",
        "part of BF's deficit is a confound: BF re-shows the corner just demonstrated, which "
        "a one-demo model fails,",
        "so its teachers redo that demo; the oracle (ORC) knows where the robot fails, which "
        "no real robot does without trying.",
    ]
    if result.missing:
        lines.append(
            "HF (the next-demo hint) was not part of this run: the results say nothing about it."
        )
    return "\n".join(lines)


#: the colours of the policies in the figure
COLOURS = {
    "BF": "#d62728", "KC5": "#1f77b4", "KC2": "#6baed6", "DIS2": "#17becf",
    "DIS5": "#9edae5", "RAND2": "#7f7f7f", "RAND5": "#c7c7c7", "ORC2": "#9467bd",
    "HF0.5": "#ff7f0e", "HF1": "#8c564b",
}


def study_figure(result: StudyResult, analysis: dict):
    """The three panels: (a) mean eps against seconds used per policy, with the optimal
    teacher's line; (b) delta-eps at 900 s against k per selector (CI across seeds);
    (c) undemonstrated plants per run per policy, the paper's BF value marked.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib import patheffects

    from .figures import OPTIMAL_LINE

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), layout="constrained")
    ax = axes[0]
    curves = analysis["curves"]
    for name in curves.columns:
        ax.plot(curves.index, curves[name], color=COLOURS.get(name), label=name, lw=1.6)
    line = optimal_curve(result.main)
    if line is not None:
        t, eps, pace = line
        ax.step(t, eps, where="post", label=f"optimal teacher ({pace:.0f} s a demo, no robot)",
                **OPTIMAL_LINE)
    ax.set_xlim(0, 900)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("seconds used of the 15-minute run")
    ax.set_ylabel("efficacy ε (mean over runs)")
    ax.set_title("(a) ε against the clock")
    # below the panel, where it hides no curve
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=3)

    ax = axes[1]
    deltas = analysis["deltas"]["efficacy"]
    by_selector: dict[str, list] = {}
    for name, d in deltas.iterrows():
        p = POLICIES[name]
        if p.selector is not None:
            by_selector.setdefault(p.selector, []).append((p.k, d))
    from ..framework.selectors import SELECTORS

    for i, (selector, points) in enumerate(sorted(by_selector.items())):
        points.sort(key=lambda kd: kd[0])
        k = np.array([kd[0] for kd in points], dtype=float) + (i - 1.5) * 0.06
        mean = np.array([kd[1]["mean"] for kd in points], dtype=float)
        err = np.array([[kd[1]["mean"] - kd[1]["low"], kd[1]["high"] - kd[1]["mean"]]
                        for kd in points], dtype=float).T
        short = SELECTORS[selector].short
        ref = " (oracle)" if selector == "failures" else ""
        ax.errorbar(k, 100 * mean, yerr=100 * np.nan_to_num(err), marker="o", capsize=3,
                    label=f"{short}{ref}", color=COLOURS.get(f"{short}2"))
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("k (plants shown after each demo)")
    ax.set_ylabel("Δε vs BF at 900 s (points, 95 % CI over seeds)")
    ax.set_title("(b) Δε against k, per selector")
    ax.set_xticks(sorted({POLICIES[n].k for n in deltas.index if POLICIES[n].k}))
    ax.legend(fontsize=8)

    ax = axes[2]
    table = analysis["policies"]
    names = list(table.index)
    x = np.arange(len(names))
    mean = table["undemonstrated"].to_numpy(float)
    err = np.vstack([mean - table["undemonstrated_low"].to_numpy(float),
                     table["undemonstrated_high"].to_numpy(float) - mean])
    ax.bar(x, mean, color=[COLOURS.get(n, "#999") for n in names], yerr=np.nan_to_num(err),
           capsize=3)
    # across BF's own bar, in black with a white edge: BF's bar is the paper mark's red
    at = names.index(BASELINE)
    ax.hlines(analysis["paper_bf_undemonstrated_per_run"], at - 0.45, at + 0.45, colors="k",
              linestyles="--", lw=2.2, zorder=3, label="paper's BF (827 / 27 runs)",
              path_effects=[patheffects.withStroke(linewidth=4, foreground="white")])
    ax.set_xticks(x, names)
    ax.set_ylabel("undemonstrated plants per run (of 100)")
    ax.set_title("(c) undemonstrated plants per run")
    ax.legend(fontsize=8)
    fig.suptitle(
        f"Adaptive r vs BF: {result.plan.n} simulated teachers x {result.plan.runs} runs x "
        f"{result.plan.seeds} seeds" + (" (quick test run)" if result.plan.quick else "")
    )
    return fig


def save_raw(result: StudyResult, out) -> dict:
    """Write the simulation itself (``adaptive_runs.csv``, ``adaptive_curves.csv`` and
    ``adaptive_plan.json``), before any analysis; :func:`load_study` reads them back.

    Raises
    ------
    SaveError
        ``out`` cannot be made or written.
    """
    out = check_out_dir(out)
    paths = {
        "runs": out / "adaptive_runs.csv",
        "curves": out / "adaptive_curves.csv",
        "plan": out / "adaptive_plan.json",
    }
    plan = {
        "format": PLAN_FORMAT,
        "plan": result.plan.to_dict(),
        "missing": list(result.missing),
        "simulation_seconds": result.seconds,
        "resumed": result.resumed,
    }
    try:
        out.mkdir(parents=True, exist_ok=True)
        result.runs.to_csv(paths["runs"], index=False)
        result.curves.to_csv(paths["curves"], index=False)
        paths["plan"].write_text(json.dumps(_plain(plan), indent=2))
    except OSError as exc:
        raise SaveError(f"cannot write the study's files in {out}: {exc.strerror or exc}") from exc
    return paths


def load_study(folder) -> StudyResult:
    """A study written by :func:`save_raw` (or ``lfd-tutor adaptive --out folder``).

    Raises
    ------
    InvalidFileError
        A file is missing or is not the study's.
    """
    import dataclasses
    from pathlib import Path

    from ..errors import InvalidFileError
    from ..fileio import read_json
    from .adaptive_plan import StudyPlan

    folder = Path(folder)
    data = read_json(folder / "adaptive_plan.json", "adaptive study's plan")
    if not isinstance(data, dict) or data.get("format") != PLAN_FORMAT:
        raise InvalidFileError(
            f"{folder / 'adaptive_plan.json'} is not an adaptive study's plan ({PLAN_FORMAT}); "
            "write one with lfd-tutor adaptive --out FOLDER"
        )
    try:
        fields = {f.name for f in dataclasses.fields(StudyPlan)}
        raw = {k: tuple(v) if isinstance(v, list) else v for k, v in data["plan"].items()}
        plan = StudyPlan(**{k: v for k, v in raw.items() if k in fields})
        frames = [pd.read_csv(folder / name) for name in ("adaptive_runs.csv",
                                                           "adaptive_curves.csv")]
    except (KeyError, TypeError, OSError, ValueError) as exc:
        raise InvalidFileError(f"the adaptive study in {folder} cannot be read: {exc}") from exc
    return StudyResult(
        plan, frames[0], frames[1], tuple(data.get("missing", ())),
        float(data.get("simulation_seconds", 0.0)), resumed=int(data.get("resumed", 0)),
    )


def save_study(result: StudyResult, analysis: dict, out, figures: bool = True) -> dict:
    """Write the study's files (the module docstring) into ``out``; returns their paths.

    Raises
    ------
    SaveError
        ``out`` cannot be made or written.
    """
    paths = save_raw(result, out)
    out = paths["runs"].parent
    paths.update(summary=out / "adaptive_summary.json", report=out / "adaptive_report.txt")
    report = format_study_report(result, analysis)
    headline = {
        name: {
            "efficacy": row.efficacy,
            "reached_0.9": row.reached_target,
            "undemonstrated_per_run": row.undemonstrated,
            "demos_per_run": row.n_demos,
            "delta_efficacy": None if name == BASELINE
            else _plain(analysis["deltas"]["efficacy"].loc[name].to_dict()),
        }
        for name, row in analysis["policies"].iterrows()
    }
    summary = {
        "plan": result.plan.to_dict(),
        "missing": list(result.missing),
        "simulation_seconds": result.seconds,
        "headline": headline,
        "policies": analysis["policies"],
        "deltas": analysis["deltas"],
        "selection": analysis["selection"],
        "per_seed": {k: v.to_dict(orient="records") for k, v in analysis["per_seed"].items()},
        "why_stopped": analysis["why_stopped"],
        "replication": analysis["replication"].to_dict(orient="records"),
        "optimal": analysis["optimal"],
        "paper_bf_undemonstrated_per_run": analysis["paper_bf_undemonstrated_per_run"],
    }
    try:
        paths["summary"].write_text(json.dumps(_plain(summary), indent=2, default=str))
        paths["report"].write_text(report + "\n")
        if figures:
            import matplotlib.pyplot as plt

            fig = study_figure(result, analysis)
            paths["figure"] = out / "adaptive_figure.png"
            fig.savefig(paths["figure"], dpi=110)
            plt.close(fig)
    except OSError as exc:
        raise SaveError(f"cannot write the study's files in {out}: {exc.strerror or exc}") from exc
    return paths
