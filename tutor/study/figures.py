"""Figures of the simulated cohorts, laid out like the paper's (matplotlib).

Each function takes the ``runs`` frame of a :class:`~tutor.study.cohort.CohortResult`
(nothing else), draws the simulation and marks the paper's numbers beside it, and, when
given the optimal teacher's reference (:func:`tutor.tasks.optimal_reference.optimal_reference`),
the best possible η and the fewest demonstrations as dashed lines.

η and ε axes read in % (as every η the tutor writes, :func:`tutor.framework.wording.percent`).
Each condition has one colour (:data:`CONDITION_COLOURS`), whatever conditions a figure
holds, so notebook 04's cohorts and a class on the dashboard colour NF, RF, BF, SF alike.
:func:`eta_caption` says in words what the η panel draws, from the same marks the panel
is drawn with, so a caption never names a mark or a kind of plot the figure lacks.
"""

from __future__ import annotations

import textwrap

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.ticker import PercentFormatter

from .. import paper
from ..framework.wording import percent

__all__ = [
    "experiment1_figure",
    "experiment2_figure",
    "calibration_figure",
    "FIGURES",
    "eta_caption",
    "wrap_label",
    "CONDITION_COLOURS",
    "PLOT_KINDS",
    "PAPER_MARK",
    "PAPER_RUN3_MARK",
    "REFERENCE_MARK",
    "OPTIMAL_LINE",
    "MARK_WORDS",
]

#: one colour per condition, in every figure of the study (Set2 for the paper's
#: Experiment 2 conditions, in the paper's order; then the other conditions)
CONDITION_COLOURS = {
    "NF": "#66c2a5",
    "RF": "#fc8d62",
    "BF": "#8da0cb",
    "SF": "#e78ac3",
    "AF": "#a6d854",
    "HF": "#ffd92f",
    "VF": "#e5c494",
    "VR": "#b3b3b3",
    "VA": "#1b9e77",
}

#: what each experiment's η panel is: box plots (Experiment 1) or bars (Experiment 2)
PLOT_KINDS = {1: "box", 2: "bar"}

PAPER_MARK = {"marker": "D", "color": "#d62728", "s": 40, "zorder": 5}
#: Experiment 2: the paper's third-run η
PAPER_RUN3_MARK = {**PAPER_MARK, "marker": "x"}
BOX = {"patch_artist": True, "widths": 0.55, "medianprops": {"color": "#d62728", "lw": 2}}


def _conditions(runs: pd.DataFrame) -> list[str]:
    cond = runs["condition"]
    if hasattr(cond, "cat"):
        return [c for c in cond.cat.categories if (cond == c).any()]
    return list(dict.fromkeys(cond))


def _boxes(ax, runs, column, conds, colour="#9ecae1"):
    data = [runs.loc[runs.condition == c, column].to_numpy(float) for c in conds]
    parts = ax.boxplot(data, tick_labels=conds, **BOX)
    for patch in parts["boxes"]:
        patch.set_facecolor(colour)
    rng = np.random.default_rng(0)  # fixed jitter: the figure is the same every time
    for i, d in enumerate(data, start=1):
        ax.scatter(i + rng.uniform(-0.12, 0.12, len(d)), d, s=9, color="#08519c", alpha=0.6)


def _legend_below(ax, ncol: int = 2, drop: float = 0.1) -> None:
    """The panel's legend under its tick labels (``drop`` axes heights below the axis),
    where it covers no bar, box or mark."""
    ax.legend(
        loc="upper center", bbox_to_anchor=(0.5, -drop), ncol=ncol, fontsize=8, frameon=False
    )


#: how a reference cohort's numbers are marked (e.g. a simulated class of the same size)
REFERENCE_MARK = {"marker": "^", "color": "#636363", "s": 40, "zorder": 5}
#: how the optimal teacher's numbers are drawn (a line across the conditions)
OPTIMAL_LINE = {"color": "#2ca02c", "linestyle": "--", "linewidth": 1.5, "zorder": 4}

#: the words for the marks (marker, colour), as a caption names them
MARK_WORDS = {"D": "diamonds", "x": "crosses", "^": "triangles"}
COLOUR_WORDS = {"#d62728": "red", "#636363": "grey"}


def _mark_words(mark: dict) -> str:
    return f"{COLOUR_WORDS[mark['color']]} {MARK_WORDS[mark['marker']]}"


def eta_caption(experiment: int, who: str = "simulated teachers", reference=None) -> str:
    """The η panel of :func:`experiment1_figure` or :func:`experiment2_figure` in words.

    Built from the panel's own kind (:data:`PLOT_KINDS`) and marks (:data:`PAPER_MARK`,
    :data:`PAPER_RUN3_MARK`, :data:`REFERENCE_MARK`); the reference's mark is named only
    when ``reference`` (the same frame the figure is given) has runs, as it is drawn only
    then. E.g. ``eta_caption(2, "trainees")``: "bars: the trainees' mean η in each run
    and, darkest, over the runs; red diamonds: the paper's mean; red crosses: the
    paper's run 3".
    """
    if PLOT_KINDS[experiment] == "box":
        parts = [
            f"boxes: η of every run of the {who}, a dot each",
            f"{_mark_words(PAPER_MARK)}: the paper's median",
        ]
        statistic = "median"
    else:
        whose = f"{who}'" if who.endswith("s") else f"{who}'s"
        parts = [
            f"bars: the {whose} mean η in each run and, darkest, over the runs",
            f"{_mark_words(PAPER_MARK)}: the paper's mean",
            f"{_mark_words(PAPER_RUN3_MARK)}: the paper's run 3",
        ]
        statistic = "mean"
    if reference is not None and len(reference):
        n = reference.teacher.nunique()
        parts.append(
            f"{_mark_words(REFERENCE_MARK)}: the {statistic} of a simulated class of the same "
            f"size, {n} simulated teachers"
        )
    return "; ".join(parts)


def wrap_label(text: str, width: int) -> str:
    """``text`` on lines of at most ``width`` characters, broken between words only (a
    word longer than ``width`` keeps its own line whole)."""
    return "\n".join(
        textwrap.wrap(text, width, break_long_words=False, break_on_hyphens=False)
    )


def _optimal_eta(ax, optimal, scale: float = 1.0) -> None:
    """The optimal teacher's eta as a dashed line on an eta axis (nothing without one)."""
    if optimal is None or optimal.best_eta is None:
        return
    ax.axhline(
        scale * optimal.best_eta,
        label=f"optimal teacher: η = {percent(optimal.best_eta)} ({optimal.n_demos} demos)",
        **OPTIMAL_LINE,
    )


def _optimal_demos(ax, optimal) -> None:
    """The fewest demos the robot needs, as a dashed line on a demos axis."""
    if optimal is None or optimal.n_demos is None:
        return
    ax.axhline(
        optimal.n_demos,
        label=f"fewest needed for {optimal.coverage:.0%}: {optimal.n_demos}",
        **OPTIMAL_LINE,
    )
    _legend_below(ax, 1)


def experiment1_figure(
    runs: pd.DataFrame,
    who: str = "simulated teachers",
    reference: pd.DataFrame | None = None,
    optimal=None,
):
    """Experiment 1: eta per condition (box plots, paper's medians marked), demos, efficacy.

    ``who`` names the teachers in the title; ``reference`` (another ``runs`` frame, e.g. a
    simulated cohort of the class's size) has its medians marked beside the paper's;
    ``optimal`` (an :class:`~tutor.tasks.optimal_reference.OptimalReference`) draws the
    best possible η and the fewest demos needed as dashed lines.

    Returns
    -------
    matplotlib.figure.Figure
    """
    conds = _conditions(runs)
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), layout="constrained")
    ax = axes[0]
    _boxes(ax, runs, "eta", conds)
    med = paper.EXPERIMENT_1["median_eta"]
    ax.scatter(
        range(1, len(conds) + 1), [med[c] for c in conds], label="paper's median", **PAPER_MARK
    )
    if reference is not None and len(reference):
        ref = reference.groupby("condition", observed=True)["eta"].median()
        ax.scatter(
            np.arange(1, len(conds) + 1) + 0.3,
            [ref.get(c, np.nan) for c in conds],
            label=f"simulated median ({reference.teacher.nunique()} teachers)",
            **REFERENCE_MARK,
        )
    _optimal_eta(ax, optimal)
    ax.set_ylabel("teaching efficiency η (at 90 % coverage)")
    ax.yaxis.set_major_formatter(PercentFormatter(1.0))
    ax.set_title(f"η per condition ({runs.teacher.nunique()} {who})")
    _legend_below(ax)
    _boxes(axes[1], runs, "n_demos", conds, "#c7e9c0")
    _optimal_demos(axes[1], optimal)
    axes[1].set_ylabel("demonstrations given")
    axes[1].set_title("(a) demonstrations per condition")
    _boxes(axes[2], runs, "efficacy", conds, "#fdd0a2")
    axes[2].set_ylabel("efficacy ε after the last demo")
    axes[2].set_ylim(-0.03, 1.05)
    axes[2].yaxis.set_major_formatter(PercentFormatter(1.0))
    axes[2].set_title("(b) efficacy per condition")
    return fig


def experiment2_figure(
    runs: pd.DataFrame,
    who: str = "simulated teachers",
    reference: pd.DataFrame | None = None,
    optimal=None,
):
    """Experiment 2: mean eta per run and overall per condition, the paper's beside it.

    ``who``, ``reference`` and ``optimal`` as in :func:`experiment1_figure` (the
    reference's mean η is marked; the optimal teacher's η is a dashed line).

    Returns
    -------
    matplotlib.figure.Figure
    """
    conds = _conditions(runs)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4), layout="constrained")
    ax = axes[0]
    by_run = runs.pivot_table(
        index="condition", columns="run", values="eta", aggfunc="mean", observed=True
    )
    n_runs = by_run.shape[1]
    width = 0.8 / (n_runs + 1)
    x = np.arange(len(conds))
    shades = plt.cm.Blues(np.linspace(0.35, 0.75, n_runs))
    for j, run in enumerate(by_run.columns):
        ax.bar(
            x + (j - n_runs / 2) * width,
            by_run.loc[conds, run],
            width,
            color=shades[j],
            label=f"run {run}",
        )
    overall = runs.groupby("condition", observed=True)["eta"].mean()
    ax.bar(x + (n_runs / 2) * width, overall.loc[conds], width, color="#08306b", label="mean")
    pm = paper.EXPERIMENT_2["mean_eta"]
    p3 = paper.EXPERIMENT_2["third_run_eta"]
    ax.scatter(x + (n_runs / 2) * width, [pm[c] for c in conds], label="paper: mean", **PAPER_MARK)
    ax.scatter(
        x + (n_runs / 2 - 1) * width,
        [p3[c] for c in conds],
        label="paper: run 3",
        **PAPER_RUN3_MARK,
    )
    if reference is not None and len(reference):
        ref = reference.groupby("condition", observed=True)["eta"].mean()
        ax.scatter(
            x + (n_runs / 2) * width,
            [ref.get(c, np.nan) for c in conds],
            label=f"simulated: mean ({reference.teacher.nunique()} teachers)",
            **REFERENCE_MARK,
        )
    _optimal_eta(ax, optimal)
    ax.set_xticks(x, conds)
    ax.set_ylabel("mean teaching efficiency η")
    ax.yaxis.set_major_formatter(PercentFormatter(1.0))
    ax.set_title(f"η̄ per run and overall ({runs.teacher.nunique()} {who})")
    _legend_below(ax, 4)
    ax = axes[1]
    sums = runs.groupby("condition", observed=True)[["errors", "undemonstrated", "ambiguous"]]
    sums = sums.sum().loc[conds]
    fail = paper.EXPERIMENT_2["failures"]
    kinds = ["errors", "undemonstrated", "ambiguous"]
    share_sim = sums / sums.sum(axis=0).replace(0, np.nan)
    share_paper = pd.DataFrame({k: fail[k] for k in kinds}).loc[conds]
    share_paper = share_paper / share_paper.sum(axis=0)
    xk = np.arange(len(kinds))
    w = 0.8 / len(conds)
    for i, c in enumerate(conds):
        ax.bar(
            xk + (i - (len(conds) - 1) / 2) * w,
            share_sim.loc[c, kinds].fillna(0),
            w,
            color=CONDITION_COLOURS.get(c, "#999999"),
            label=c,
        )
        ax.scatter(
            xk + (i - (len(conds) - 1) / 2) * w,
            share_paper.loc[c, kinds],
            s=22,
            color="k",
            marker="_",
            linewidths=2,
            zorder=5,
        )
    names = ["demonstration errors", "undemonstrated states", "ambiguous demos"]
    ax.set_xticks(xk, [wrap_label(name, 14) for name in names])
    ax.set_ylabel("share of all failures of that kind")
    ax.yaxis.set_major_formatter(PercentFormatter(1.0))
    ax.set_title(f"Failures by condition (bars: {who}, black: paper)")
    _legend_below(ax, len(conds), drop=0.16)  # two-line tick labels
    return fig


#: experiment number -> its figure of eta per condition
FIGURES = {1: experiment1_figure, 2: experiment2_figure}


def calibration_figure(table: pd.DataFrame):
    """The calibration's predictive checks: one row per statistic.

    ``table`` is :func:`tutor.study.calibration.report`'s. Each row draws 90 %
    predictive intervals as distances from the paper's value, in the statistic's own
    scale (the one the fit measured distance in: a quarter of the paper's value for an
    η, a few counts for a failure count), so every statistic fits one axis; the paper's
    value is the line at 0, and the row's label gives it in its own units. The thick bar
    and dot are the bundled point's interval and median (fresh seeds), the thin line
    the posterior's; fitted statistics are blue, held-out ones orange, and a cross marks
    a statistic whose bundled-point interval misses the paper's value.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .calibration import STATISTICS

    rows = table.reset_index(drop=True)
    point = "point_median" in rows and rows.point_median.notna().any()
    main = "point_" if point else ""
    fig, ax = plt.subplots(figsize=(9, 0.32 * len(rows) + 1.6), layout="constrained")
    colours = {True: "#3182bd", False: "#e6550d"}
    y = np.arange(len(rows))[::-1]
    for k, r in enumerate(rows.to_dict(orient="records")):
        scale = STATISTICS[r["statistic"]].scale
        c = colours[bool(r["fitted"])]
        if point:  # the posterior's interval, thin
            lo, hi = ((r[v] - r["paper"]) / scale for v in ("low", "high"))
            ax.plot([lo, hi], [y[k], y[k]], color=c, lw=1)
        lo, mid, hi = ((r[main + v] - r["paper"]) / scale for v in ("low", "median", "high"))
        ax.plot([lo, hi], [y[k], y[k]], color=c, lw=4, solid_capstyle="butt")
        ax.plot(mid, y[k], "o", color=c, ms=5)
        if not r[main + "inside"]:
            ax.plot(max(min(mid, 9.5), -9.5), y[k], "x", color="black", ms=7)
    shown = [f"{r.statistic} (paper {r.paper:.3g})" for r in rows.itertuples()]
    ax.set_yticks(y, shown, fontsize=8)
    ax.axvline(0, color="black", lw=1)
    ax.axvspan(-1, 1, color="#dddddd", zorder=0)
    ax.set_xlim(-10, 10)
    ax.set_xlabel("predicted minus the paper's value, in the statistic's scale "
                  "(grey: within one scale)")
    who = "bundled point" if point else "posterior"
    ax.plot([], [], color=colours[True], lw=4, label=f"fitted: {who}'s 90 % interval")
    ax.plot([], [], color=colours[False], lw=4, label=f"held out: {who}'s 90 % interval")
    if point:
        ax.plot([], [], color="grey", lw=1, label="the posterior's 90 % interval")
    ax.plot([], [], "x", color="black", label="paper's value outside the interval")
    inside = rows[~rows.fitted.astype(bool)][main + "inside"].astype(bool)
    ax.set_title(f"Calibration check ({who}):\nthe paper's value inside the interval for "
                 f"{int(inside.sum())} of {len(inside)} held-out statistics")
    _legend_below(ax, 2, drop=0.12)
    return fig
