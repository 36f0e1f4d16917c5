r"""Pictures of the maze task (Sena & Howard, Experiment 1).

(About 700 lines, over the project's ~600: its three pictures, the maze, the feedback
with failure marks and the zoomed target, and the grid status, share the maze's axes,
label placement and caption helpers; split, each module would import the others'
private helpers.)

Notation, as in :mod:`tutor.framework`:

B^
    The objective approximation of the task space: the test points, here a
    20 x 7 grid of start points over the start zone I (|B^| = 140).
R^
    The realisations: the robot's attempt from every start point in B^, its pen
    starting there at rest and tracking the learnt TP-GMM
    (:meth:`tutor.framework.Task.realise`).
b
    The demonstration set, the teacher's demos in the order given (M = |b|).
r
    The realisations actually shown to the teacher: empty (no feedback), all of
    R^ (visual feedback), a fixed batch, a replay or the teacher's own choice.

The main picture is :func:`plot_feedback`, the paper's feedback figure: the
maze, R^ as solid green lines where a realisation meets the task criteria (stays
in X, starts in I, ends in the target beta) and dashed dark red lines where it does
not, each failure marked where it went wrong (× where it hit an obstacle or left the
maze, ○ where it ended outside the target) and its causes counted under the
picture, and the demos in blue, numbered in the order given. The target is drawn to
scale, with a zoomed inset of the target area so that millimetre misses show.
Positions are stored in metres; the axes are labelled in centimetres.
"""

from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Rectangle
from matplotlib.ticker import FuncFormatter, MultipleLocator

from ..tasks.maze import load_layout
from .maze_reasons import main_causes, reason_summary
from .style import (
    DEMO,
    FAIL,
    FAIL_DASH,
    OBSTACLE,
    PASS,
    PASS_DASH,
    START_ZONE,
    TARGET,
    UNDEMONSTRATED,
    new_axes,
)

__all__ = ["draw_maze", "plot_feedback", "plot_grid_status", "realisations_at"]

_CM = FuncFormatter(lambda v, _pos: f"{100 * v:.0f}")


def _cm_axes(ax, x0, x1, y0, y1, step=0.05, pad=0.004):
    """Equal aspect, limits with a small pad, ticks every ``step`` metres labelled in cm."""
    ax.set_xlim(x0 - pad, x1 + pad)
    ax.set_ylim(y0 - pad, y1 + pad)
    ax.set_aspect("equal")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(MultipleLocator(step))
        axis.set_major_formatter(_CM)
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    ax.tick_params(labelsize=8)


def _target_circle(layout, zorder: float) -> Circle:
    """The target beta, to scale (on the maze and in the zoomed inset)."""
    return Circle(
        tuple(layout.target_center),
        layout.target_radius,
        facecolor=TARGET,
        edgecolor="black",
        linewidth=0.6,
        zorder=zorder,
    )


def _short_name(box, default):
    return box.label or box.name or default


def draw_maze(ax=None, layout=None, zone_label=True):
    """Draw the maze: workspace X, start zone I, the two obstacles and the target beta.

    Parameters
    ----------
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure is made when None.
    layout : MazeLayout, optional
        Defaults to the bundled layout (``assets/maze.json``).
    zone_label : bool
        Write "start zone I" inside the start zone. Either way the zone patch
        carries that label, so a later ``ax.legend()`` lists it.

    Returns
    -------
    matplotlib.axes.Axes
        With equal aspect, ticks every 5 cm labelled in cm, and no title.

    Notes
    -----
    The target is drawn to scale (0.5 cm across, a few pixels at screen size), with
    a black edge and the label "target β"; :func:`plot_feedback` adds a zoomed inset.
    """
    if layout is None:
        layout = load_layout()
    ax = new_axes(ax, figsize=(4.0, 5.5))
    ws, zone = layout.workspace, layout.start_zone
    ax.add_patch(
        Rectangle(
            (zone.x0, zone.y0),
            zone.x1 - zone.x0,
            zone.y1 - zone.y0,
            facecolor=START_ZONE,
            edgecolor="none",
            zorder=0,
            label="start zone I",
        )
    )
    if zone_label:
        ax.text(
            zone.x1 - 0.003,
            zone.y1 - 0.003,
            "start zone I",
            ha="right",
            va="top",
            fontsize=7,
            color="#35506b",
            zorder=6,
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.7},
        )
    ax.add_patch(
        Rectangle(
            (ws.x0, ws.y0),
            ws.x1 - ws.x0,
            ws.y1 - ws.y0,
            facecolor="none",
            edgecolor="black",
            linewidth=1.4,
            zorder=4,
        )
    )
    for i, obs in enumerate(layout.obstacles):
        ax.add_patch(
            Rectangle(
                (obs.x0, obs.y0),
                obs.x1 - obs.x0,
                obs.y1 - obs.y0,
                facecolor=OBSTACLE,
                edgecolor="black",
                linewidth=0.8,
                zorder=0.5,
            )
        )
        ax.text(
            *obs.center,
            _short_name(obs, f"obstacle {i + 1}"),
            ha="center",
            va="center",
            fontsize=7,
            color="white",
            zorder=6,
            bbox={"boxstyle": "round,pad=0.2", "fc": OBSTACLE, "ec": "none", "alpha": 0.85},
        )
    tx, ty = layout.target_center
    ax.add_patch(_target_circle(layout, zorder=5))
    ax.annotate(
        "target β",
        (tx, ty),
        xytext=(9, 7),
        textcoords="offset points",
        fontsize=7,
        color=TARGET,
        zorder=6,
        bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.7},
    )
    _cm_axes(ax, ws.x0, ws.x1, ws.y0, ws.y1)
    return ax


def _step_index(session, step):
    """The 0-based index into ``session.history`` that ``step`` names (negative from the end)."""
    n = len(session.history)
    if n == 0:
        return None
    if not -n <= step < n:
        raise IndexError(f"step {step} is out of range for a session with {n} demos")
    return step % n


def realisations_at(session, step=-1):
    """R^ after a given demo: the realisations from every test point.

    Parameters
    ----------
    session : TeachingSession
    step : int
        Index into ``session.history`` (0 = after the first demo, -1 = latest).

    Returns
    -------
    ndarray (n_conditions, T, d) or None
        None when the session has no demo yet.

    Notes
    -----
    """
    i = _step_index(session, step)
    if i is None:
        return None
    return session.realisations_at(i)


def _label_positions(points, min_gap=0.011):
    """Where to put numbers for ``points`` (k, 2): nudged until no two are within ``min_gap``."""
    step = 0.9 * min_gap
    nudges = [(0, 0), (0, -step), (-step, 0), (step, 0), (0, step)]
    nudges += [(dx, dy) for dx in (-step, step) for dy in (-step, step)]
    nudges += [(2 * dx, 2 * dy) for dx, dy in nudges[1:]]
    placed = []
    for p in np.asarray(points, dtype=float):
        for dx, dy in nudges:
            q = p + (dx, dy)
            if all(np.hypot(*(q - o)) >= min_gap for o in placed):
                break
        placed.append(q)
    return np.array(placed).reshape(-1, 2)


def _draw_demos(ax, demos):
    """The demos b in blue, each numbered (in order given) at its start."""
    for demo in demos:
        ax.plot(demo[:, 1], demo[:, 2], color=DEMO, linewidth=1.8, zorder=7, solid_capstyle="round")
    if not demos:
        return
    starts = np.array([d[0, 1:3] for d in demos])
    for k, (x, y) in enumerate(_label_positions(starts), start=1):
        ax.text(
            x,
            y,
            str(k),
            ha="center",
            va="center",
            fontsize=7,
            fontweight="bold",
            color="white",
            zorder=8,
            bbox={"boxstyle": "circle,pad=0.2", "fc": DEMO, "ec": "white", "lw": 0.8},
        )


def plot_feedback(session, ax=None, step=-1, reveal=False):
    """The paper's feedback picture: R^ (or r) over the maze, with the numbered demos.

    Realisations that meet the task criteria are solid green, the others dashed
    dark red, each marked where it went wrong (× hit an obstacle or left the maze,
    ○ ended outside the target) with the causes counted under the picture, and a
    zoomed inset shows the target area (top right); the teacher's demos are blue
    and numbered in the order given (the number sits at each demo's start; numbers
    of demos with (nearly) the same start are nudged apart).

    Parameters
    ----------
    session : TeachingSession
        A session on a :class:`~tutor.tasks.maze.MazeTask`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure is made when None.
    step : int
        Which record to draw: index into ``session.history`` (default -1, the
        latest; 0 is after the first demo). Only the demos given up to then are shown.
    reveal : bool
        False: draw only the realisations in r (``record.shown``), what the
        teacher saw; with r empty (no feedback) only the maze and demos show,
        with the note "no feedback shown". True: draw all of R^ and, when r is
        not all of R^, highlight r (thick, opaque, its start points ringed) over
        the rest (thin, faint).

    Returns
    -------
    matplotlib.axes.Axes
        The legend (outside, right) counts the passing and failing realisations
        drawn, the failure marks and the demos; a line above the maze says what is
        shown, and one below it why the failing ones fail.
    """
    task = session.task
    ax = draw_maze(ax, task.layout, zone_label=False)
    i = _step_index(session, step)
    zone_handle = Patch(facecolor=START_ZONE, edgecolor="none", label="start zone I")
    legend = {
        "loc": "upper left",
        "bbox_to_anchor": (1.02, 1.0),
        "fontsize": 7,
        "frameon": False,
        "borderaxespad": 0.0,
    }
    if i is None:
        _caption(ax, "no demo yet", italic=True)
        ax.legend(handles=[zone_handle], **legend)
        return ax
    record = session.history[i]
    demos = session.demos[: i + 1]
    n = len(task.test_points)
    shown = np.asarray(record.shown, dtype=int)
    passed = np.asarray(record.passed, dtype=bool)
    everything = np.array_equal(np.unique(shown), np.arange(n))
    highlight = reveal and shown.size > 0 and not everything
    drawn = np.arange(n) if reveal else shown
    found = []
    if drawn.size:
        mean = realisations_at(session, i)
        found = main_causes(mean, record.causes, task.layout)
        if highlight:
            rest = np.setdiff1d(np.arange(n), shown)
            _draw_realisations(ax, mean, passed, rest, linewidth=0.5, alpha=0.3, zorder=1)
            _draw_realisations(ax, mean, passed, shown, linewidth=1.8, alpha=1.0, zorder=2)
            ax.plot(
                task.test_points[shown, 0],
                task.test_points[shown, 1],
                "o",
                markersize=4.5,
                markerfacecolor="white",
                markeredgecolor="black",
                markeredgewidth=0.9,
                linestyle="none",
                zorder=6,
            )
        else:
            few = drawn.size <= 20  # a small r (batch, replay) can afford thicker lines
            width, alpha = (1.4, 0.95) if few else (0.8, 0.8)
            _draw_realisations(ax, mean, passed, drawn, linewidth=width, alpha=alpha, zorder=1)
        _draw_failure_marks(ax, found, drawn)
    _draw_demos(ax, demos)
    if drawn.size or demos:
        _target_inset(ax, task.layout, mean if drawn.size else None, passed, drawn, found, demos)

    n_pass = int(passed[drawn].sum())
    handles = []
    if drawn.size:
        handles += [
            Line2D(
                [],
                [],
                color=PASS,
                linewidth=1.2,
                linestyle=PASS_DASH,
                label=f"meets the criteria ({n_pass})",
            ),
            Line2D(
                [],
                [],
                color=FAIL,
                linewidth=1.2,
                linestyle=FAIL_DASH,
                label=f"fails ({drawn.size - n_pass})",
            ),
        ]
        kinds = [found[k].kind for k in drawn]
        crashes = sum(k in ("obstacle", "outside", "start") for k in kinds)
        misses = sum(k in ("miss", "other") for k in kinds)
        if crashes:
            handles.append(
                Line2D(
                    [],
                    [],
                    color=FAIL,
                    marker="x",
                    markersize=5,
                    linestyle="none",
                    label=f"hit an obstacle or left the maze here ({crashes})",
                )
            )
        if misses:
            handles.append(
                Line2D(
                    [],
                    [],
                    color=FAIL,
                    marker="o",
                    markerfacecolor="none",
                    markersize=5,
                    linestyle="none",
                    label=f"ended outside the target ({misses})",
                )
            )
    handles.append(Line2D([], [], color=DEMO, linewidth=1.8, label=f"demos b ({len(demos)})"))
    if highlight:
        handles.append(
            Line2D(
                [],
                [],
                color="0.2",
                linewidth=1.8,
                marker="o",
                markersize=4.5,
                markerfacecolor="white",
                label=f"shown to the teacher, r ({shown.size})",
            )
        )
    handles.append(zone_handle)
    ax.legend(handles=handles, **legend)
    if reveal:
        what = f"{n_pass} of {n} realisations pass"
        if highlight:
            what += f"\nthe teacher saw r = {shown.size}: {_passes(passed[shown].sum())}"
        elif not shown.size:
            what += "\nthe teacher saw none of them"
    elif everything:
        what = f"{n_pass} of {n} realisations pass"
    elif shown.size:
        what = f"shown {shown.size} of {n} realisations, {_passes(n_pass)}"
    else:
        what = "no feedback shown"
    _caption(ax, f"after demo {record.n_demos}: {what}", italic=not drawn.size)
    why = reason_summary(found, drawn) if drawn.size else ""
    if why:
        ax.text(
            0.0,
            -0.09,
            textwrap.fill(f"why they fail: {_unbroken(why)}", 64),
            transform=ax.transAxes,
            ha="left",
            va="top",
            fontsize=7,
            color="0.15",
            gid="failure-reasons",
        )
    return ax


def _unbroken(text: str) -> str:
    """``text`` with its numbers and units held together (no line break in "1–5 mm")."""
    return text.replace(" mm", "\u00a0mm").replace(" cm", "\u00a0cm")


def _passes(k):
    k = int(k)
    return f"{k} {'passes' if k == 1 else 'pass'}"


def _caption(ax, text, italic=False):
    ax.text(
        0.5,
        1.01,
        text,
        transform=ax.transAxes,
        ha="center",
        va="bottom",
        fontsize=8,
        style="italic" if italic else "normal",
        color="0.25",
    )


def _draw_realisations(ax, mean, passed, idx, **style):
    """Passing paths solid green, failing ones dashed dark red on top (they are the news)."""
    idx = np.asarray(idx, dtype=int)
    for mask, colour, dash in ((passed[idx], PASS, PASS_DASH), (~passed[idx], FAIL, FAIL_DASH)):
        sel = idx[mask]
        if sel.size == 0:
            continue
        xs = np.column_stack([mean[sel, :, 0], np.full(sel.size, np.nan)]).ravel()
        ys = np.column_stack([mean[sel, :, 1], np.full(sel.size, np.nan)]).ravel()
        ax.plot(xs, ys, color=colour, linestyle=dash, solid_capstyle="round", **style)


def _draw_failure_marks(ax, found, idx, size=4.5, zorder=6.5):
    """× where a shown realisation hit an obstacle or left the maze, ○ where it ended."""
    crash = [found[k].point for k in idx if found[k].kind in ("obstacle", "outside", "start")]
    miss = [found[k].point for k in idx if found[k].kind in ("miss", "other")]
    if crash:
        xy = np.array(crash)
        ax.plot(
            xy[:, 0],
            xy[:, 1],
            "x",
            color=FAIL,
            markersize=size,
            markeredgewidth=1.2,
            linestyle="none",
            zorder=zorder,
            gid="failure-crash",
        )
    if miss:
        xy = np.array(miss)
        ax.plot(
            xy[:, 0],
            xy[:, 1],
            "o",
            color=FAIL,
            markerfacecolor="none",
            markersize=size * 0.8,
            markeredgewidth=0.9,
            linestyle="none",
            zorder=zorder,
            gid="failure-miss",
        )


#: half the side of the region the target inset shows (metres)
INSET_HALF = 0.008


def _target_inset(ax, layout, mean, passed, idx, found, demos):
    """A zoomed inset (top right) of the target area, rings 1 mm apart beyond its edge."""
    inset = ax.inset_axes([0.62, 0.745, 0.36, 0.245], zorder=9)
    tx, ty = layout.target_center
    inset.set_xlim(tx - INSET_HALF, tx + INSET_HALF)
    inset.set_ylim(ty - INSET_HALF, ty + INSET_HALF)
    inset.set_aspect("equal")
    inset.set_xticks([])
    inset.set_yticks([])
    inset.set_facecolor("white")
    for mm in range(1, 9):
        inset.add_patch(
            Circle(
                (tx, ty),
                layout.target_radius + mm / 1000,
                facecolor="none",
                edgecolor="0.8",
                linewidth=0.5,
                zorder=0,
            )
        )
    inset.add_patch(_target_circle(layout, zorder=1))
    if mean is not None and len(idx):
        _draw_realisations(inset, mean, passed, idx, linewidth=0.9, alpha=0.85, zorder=2)
        ends = mean[np.asarray(idx)[passed[idx]], -1]
        inset.plot(
            ends[:, 0], ends[:, 1], "o", color=PASS, markersize=2.5, linestyle="none", zorder=3
        )
        _draw_failure_marks(inset, found, idx, size=4, zorder=4)
    for demo in demos:
        inset.plot(demo[:, 1], demo[:, 2], color=DEMO, linewidth=1.4, zorder=3)
    zoom = (0.36 * np.ptp(ax.get_xlim())) / (2 * INSET_HALF)
    inset.text(
        0.03,
        0.03,
        f"target ×{zoom:.0f}\nrings 1 mm apart",
        transform=inset.transAxes,
        fontsize=5.5,
        va="bottom",
        color="0.2",
        bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8},
        zorder=5,
    )
    ax.indicate_inset_zoom(inset, edgecolor="0.3", linewidth=0.6)
    return inset


def _group_numbers(points, tol=0.004):
    """Demo numbers grouped by (nearly) equal start: [("1, 5", (x, y)), ...]."""
    groups: list[tuple[list[int], np.ndarray]] = []
    for k, p in enumerate(np.asarray(points, dtype=float), start=1):
        for numbers, q in groups:
            if np.hypot(*(p - q)) <= tol:
                numbers.append(k)
                break
        else:
            groups.append(([k], p))
    return [(", ".join(map(str, numbers)), tuple(q)) for numbers, q in groups]


def plot_grid_status(session, ax=None, step=-1):
    """The start grid B^ over the start zone, each point coloured by its status.

    Statuses (they add up to |B^|):

    - covered (green): the realisation from this start point meets the criteria;
    - demonstrated, still fails (blue): a correct demo starts within half a grid
      cell, but the realisation fails;
    - undemonstrated (lavender): the realisation fails and no demo covers it.

    A blue ring marks every point a correct demo covers; the demos' start points
    are drawn as blue stars (hollow for incorrect demos), numbered.

    Parameters
    ----------
    session : TeachingSession
        A session on a :class:`~tutor.tasks.maze.MazeTask`.
    ax : matplotlib.axes.Axes, optional
    step : int
        Index into ``session.history`` (default -1, the latest).

    Returns
    -------
    matplotlib.axes.Axes
    """
    task = session.task
    layout = task.layout
    ax = new_axes(ax, figsize=(6.0, 3.0))
    zone = layout.start_zone
    ax.add_patch(
        Rectangle(
            (zone.x0, zone.y0),
            zone.x1 - zone.x0,
            zone.y1 - zone.y0,
            facecolor=START_ZONE,
            edgecolor="0.3",
            linewidth=1.0,
            zorder=0,
        )
    )
    grid = task.test_points
    n = len(grid)
    i = _step_index(session, step)
    if i is None:
        ax.scatter(grid[:, 0], grid[:, 1], s=22, c="0.7", zorder=2)
        _cm_axes(ax, zone.x0, zone.x1, zone.y0, zone.y1, step=0.02, pad=0.006)
        ax.set_title("start grid $\\hat{B}$ (no demo yet)", fontsize=9)
        return ax
    record = session.history[i]
    passed = np.asarray(record.passed, dtype=bool)
    demonstrated = np.asarray(record.demonstrated, dtype=bool)
    undemonstrated = np.asarray(record.undemonstrated, dtype=bool)
    demo_fail = ~passed & demonstrated
    size = 30
    handles = []
    for mask, colour, label in (
        (passed, PASS, "covered (passes)"),
        (demo_fail, DEMO, "demonstrated, still fails"),
        (undemonstrated, UNDEMONSTRATED, "undemonstrated"),
    ):
        h = ax.scatter(
            grid[mask, 0],
            grid[mask, 1],
            s=size,
            c=colour,
            edgecolors="white",
            linewidths=0.4,
            zorder=2,
            label=f"{label}: {int(mask.sum())}",
        )
        if mask.any() or colour != DEMO:
            handles.append(h)
    ring = ax.scatter(
        grid[demonstrated, 0],
        grid[demonstrated, 1],
        s=size * 3.2,
        facecolors="none",
        edgecolors=DEMO,
        linewidths=1.3,
        zorder=3,
        label=f"demonstrated (a correct demo covers it): {int(demonstrated.sum())}",
    )
    handles.append(ring)
    history = session.history[: i + 1]
    starts = np.array([d[0, 1:3] for d in session.demos[: i + 1]])
    ok = np.array([r.demo_passed for r in history])
    # incorrect ones larger and below, so a correct demo from the same start stays visible
    for good, label in ((True, "demo start"), (False, "incorrect demo start")):
        sel = ok == good
        if not sel.any():
            continue
        h = ax.scatter(
            starts[sel, 0],
            starts[sel, 1],
            s=110 if good else 170,
            marker="*",
            c=DEMO if good else "white",
            edgecolors=DEMO,
            linewidths=1.0,
            zorder=4.5 if good else 4,
            label=f"{label}: {int(sel.sum())}",
        )
        handles.append(h)
    for label, (x, y) in _group_numbers(starts):
        ax.annotate(
            label,
            (x, y),
            xytext=(0, 8),
            textcoords="offset points",
            ha="center",
            va="bottom",
            fontsize=7,
            fontweight="bold",
            color=DEMO,
            zorder=5,
            bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.75},
        )
    x0, x1 = min(zone.x0, starts[:, 0].min()), max(zone.x1, starts[:, 0].max())
    y0, y1 = min(zone.y0, starts[:, 1].min()), max(zone.y1, starts[:, 1].max())
    _cm_axes(ax, x0, x1, y0, y1, step=0.02, pad=0.006)
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.3),
        ncol=2,
        fontsize=7,
        frameon=False,
        columnspacing=1.2,
        handletextpad=0.3,
    )
    ax.set_title(
        f"start grid $\\hat{{B}}$ after demo {record.n_demos}: {int(passed.sum())} of {n} covered",
        fontsize=9,
    )
    return ax
