r"""Task-agnostic pictures of a teaching session (Sena & Howard, "Evaluating Teaching").

Notation, as in :mod:`tutor.framework`:

B^
    The objective approximation of the task space B: the finite set of test
    test points (|B^| of them).
R^
    The realisations: what the learnt model does from every test point in B^.
    R^ ∩ B^ are the covered test points (the realisation meets the task criteria).
b
    The demonstration set; M = |b|. Demos that fail the criteria themselves lie
    outside B (b \ B, incorrect demonstrations).
r
    The realisations shown to the teacher (depends on the feedback condition).

Measures: efficacy eps = |R^ ∩ B^| / |B^|, efficiency eta = eps / M.

This module only uses what every :class:`~tutor.framework.Task` provides, so it
works for any task; maze pictures live in :mod:`tutor.views.maze`.
"""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Ellipse
from matplotlib.ticker import MaxNLocator, PercentFormatter
from scipy.ndimage import distance_transform_edt

from ..framework import AMBIGUOUS, INCORRECT
from ..framework.wording import percent
from .style import AMBIGUOUS as AMBIGUOUS_COLOUR
from .style import DEMO, FAIL, PASS, new_axes
from .style import INCORRECT as INCORRECT_COLOUR

__all__ = ["plot_progress", "plot_set_diagram", "set_counts"]

EFFICACY_COLOUR = "#1b6e57"
EFFICIENCY_COLOUR = "#7570b3"


def plot_progress(session, ax=None, target=0.9):
    """Efficacy eps and efficiency eta after each demo, with the flagged demos marked.

    Parameters
    ----------
    session : TeachingSession
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure is made when None.
    target : float
        The coverage to reach (the paper's 90 %), drawn as a dashed line; the
        demo that first reaches it is marked.

    Returns
    -------
    matplotlib.axes.Axes
        x is the demo number (integer ticks), y the percentage. The efficacy
        line has gid ``"efficacy"`` and the efficiency line gid ``"efficiency"``.
        Demos with an incorrect warning get a wine cross, ambiguous ones a
        yellow diamond with a dark edge (on the efficacy line).
    """
    ax = new_axes(ax, figsize=(5.0, 3.5))
    history = session.history
    m = np.arange(1, len(history) + 1)
    eps = np.array([r.efficacy for r in history], dtype=float)
    eta = np.array([r.efficiency for r in history], dtype=float)
    ax.axhline(target, color="0.45", linestyle="--", linewidth=1.0, zorder=1)
    ax.text(
        0.01,
        target,
        f"{target:.0%} target",
        transform=ax.get_yaxis_transform(),
        ha="left",
        va="bottom",
        fontsize=7,
        color="0.35",
    )
    ax.plot(
        m,
        eps,
        "-o",
        color=EFFICACY_COLOUR,
        markersize=4.5,
        linewidth=1.6,
        label="efficacy ε (share of test points covered)",
        gid="efficacy",
        zorder=3,
    )
    ax.plot(
        m,
        eta,
        "-s",
        color=EFFICIENCY_COLOUR,
        markersize=4,
        linewidth=1.3,
        label="efficiency η = ε / M",
        gid="efficiency",
        zorder=3,
    )
    for kind, marker, colour, size, label in (
        (INCORRECT, "x", INCORRECT_COLOUR, 10, "incorrect demo"),
        (AMBIGUOUS, "D", AMBIGUOUS_COLOUR, 8, "ambiguous demo"),
    ):
        sel = np.array([kind in r.kinds for r in history], dtype=bool)
        if sel.any():
            ax.plot(
                m[sel],
                eps[sel],
                linestyle="none",
                marker=marker,
                markersize=size,
                markeredgewidth=2.2 if marker == "x" else 1.2,
                # the yellow diamond is filled and edged dark so it shows on white
                markerfacecolor=colour,
                markeredgecolor="#222222" if marker == "D" else colour,
                label=f"{label} ({int(sel.sum())})",
                zorder=4,
            )
    if len(history):
        score = session.score(rule="target", target=target)  # where target is first reached
        if score.reached:
            left = score.n_demos <= (len(history) + 1) / 2
            ax.axvline(score.n_demos, color="0.6", linestyle=":", linewidth=1.0, zorder=0)
            ax.text(
                score.n_demos,
                1.0,
                f"{target:.0%} first reached at demo {score.n_demos} "
                f"(η = {percent(score.efficiency)})",
                transform=ax.get_xaxis_transform(),
                ha="left" if left else "right",
                va="bottom",
                fontsize=7,
                color="0.3",
            )
    ax.set_xlim(0.5, max(len(history), 1) + 0.5)
    ax.set_ylim(0.0, 1.05)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.yaxis.set_major_formatter(PercentFormatter(1.0))
    ax.set_xlabel("demo number M")
    ax.set_ylabel("percent")
    ax.grid(True, axis="y", color="0.9", linewidth=0.8)
    ax.set_axisbelow(True)
    ax.tick_params(labelsize=8)
    ax.legend(
        loc="upper center",
        bbox_to_anchor=(0.5, -0.16),
        ncol=2,
        fontsize=7,
        frameon=False,
        columnspacing=1.2,
    )
    return ax


def set_counts(session, step=-1) -> dict:
    """The counts the set diagram shows, after a given demo.

    Parameters
    ----------
    session : TeachingSession
    step : int
        Index into ``session.history`` (default -1, the latest).

    Returns
    -------
    dict
        ``n`` = |B^|, ``covered`` = |R^ ∩ B^|, ``generalised`` (covered and not
        demonstrated), ``failed`` = |R^ \\ B| (realisations that fail),
        ``demonstrated`` (test points a correct demo covers), ``undemonstrated``,
        ``demos`` = M, ``incorrect`` = |b \\ B| (demos failing the criteria).
    """
    history = session.history
    if not history:
        raise IndexError("the session has no demo yet")
    i = step % len(history) if -len(history) <= step < len(history) else None
    if i is None:
        raise IndexError(f"step {step} is out of range for a session with {len(history)} demos")
    rec = history[i]
    passed = np.asarray(rec.passed, dtype=bool)
    demonstrated = np.asarray(rec.demonstrated, dtype=bool)
    return {
        "n": int(passed.size),
        "covered": int(passed.sum()),
        "generalised": int((passed & ~demonstrated).sum()),
        "failed": int((~passed).sum()),
        "demonstrated": int(demonstrated.sum()),
        "undemonstrated": int(np.asarray(rec.undemonstrated, dtype=bool).sum()),
        "demos": rec.n_demos,
        "incorrect": int(sum(not r.demo_passed for r in history[: i + 1])),
        "step": i,
    }


_B_CENTRE = np.array([6.8, 3.75])
_B_HALF = np.array([2.95, 2.3])  # semi-axes of B^ (and of R^, drawn congruent)
_R_DIRECTION = np.array([-0.85, 0.53])  # R^ sits up and to the left of B^
_b_HALF = np.array([0.95, 0.55])
_XLIM, _YLIM = (0.0, 12.0), (0.0, 9.4)


def _overlap_fraction(s):
    """Area shared by two unit discs whose centres are ``s`` apart, over the area of one."""
    s = min(max(s, 0.0), 2.0)
    return (2 * np.arccos(s / 2) - (s / 2) * np.sqrt(4 - s * s)) / np.pi


def _separation(fraction):
    """The scaled distance s in [0, 2] at which two congruent ellipses share ``fraction``."""
    lo, hi = 0.0, 2.0
    for _ in range(50):
        mid = (lo + hi) / 2
        if _overlap_fraction(mid) > fraction:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def _diagram_geometry(c):
    """Centres of R^ and b for the counts ``c``: areas follow the counts roughly.

    R^ is congruent with B^ and slides over it so that the shared area is the
    covered share (kept between 10 % and 92 % when not exactly 0 or 1, so that
    every region that has members stays visible). b straddles the edge of B^
    when there are incorrect demos, and lies inside B^ otherwise.
    """
    share = c["covered"] / c["n"]
    if c["covered"] == 0:
        s = 2.0
    elif c["covered"] == c["n"]:
        s = 0.0
    else:
        s = _separation(min(max(share, 0.10), 0.92))
    u = _R_DIRECTION / np.linalg.norm(_R_DIRECTION)
    unit = 1.0 / np.sqrt(((u / _B_HALF) ** 2).sum())  # distance to B's edge along u
    r_centre = _B_CENTRE + s * unit * u
    # b sits on B's edge, a little clockwise of the direction of R (towards the top)
    angle = np.deg2rad(108.0)
    edge = _B_CENTRE + _B_HALF * np.array([np.cos(angle), np.sin(angle)])
    normal = np.array([np.cos(angle) / _B_HALF[0], np.sin(angle) / _B_HALF[1]])
    normal /= np.linalg.norm(normal)
    if c["incorrect"] == 0:
        b_centre = edge - normal * (_b_HALF[1] + 0.15)
    elif c["incorrect"] == c["demos"]:
        b_centre = edge + normal * (_b_HALF[1] + 0.15)
    else:
        b_centre = edge
    return r_centre, b_centre


def _region_poles(r_centre, b_centre):
    """The deepest point of each region of the diagram (for its label), or None if empty."""
    xs = np.arange(*_XLIM, 0.04)
    ys = np.arange(*_YLIM, 0.04)
    X, Y = np.meshgrid(xs, ys)

    def inside(centre, half):
        return ((X - centre[0]) / half[0]) ** 2 + ((Y - centre[1]) / half[1]) ** 2 <= 1

    in_B, in_R, in_b = (
        inside(_B_CENTRE, _B_HALF),
        inside(r_centre, _B_HALF),
        inside(b_centre, _b_HALF),
    )
    regions = {
        "covered": in_R & in_B & ~in_b,
        "failed": in_R & ~in_B & ~in_b,
        "undemonstrated": in_B & ~in_R & ~in_b,
        "demonstrated": in_b & in_B,
        "incorrect": in_b & ~in_B,
    }
    poles = {}
    for name, mask in regions.items():
        if mask.sum() < 20:
            poles[name] = None
            continue
        depth = distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
        k = np.unravel_index(np.argmax(depth), depth.shape)
        # prefer the region's centroid when it lies well inside (labels look centred)
        cy, cx = (int(round(v)) for v in np.argwhere(mask).mean(axis=0))
        if depth[cy, cx] >= 0.6 * depth[k]:
            k = (cy, cx)
        poles[name] = (float(X[k]), float(Y[k]), float(depth[k]) * 0.04)
    return poles


def plot_set_diagram(session, ax=None, step=-1):
    """The information-history-space diagram of the paper, with this session's counts.

    A large ellipse is B^ (every test point); R^ (the realisations) is an
    ellipse of the same size that overlaps it by the covered share, so the
    picture changes as teaching goes on. Regions, as in the paper's figure:
    R ∩ B (covered, striped; most of it by generalisation), B^ \\ (R^ ∪ b)
    (undemonstrated, cross-hatched), R^ \\ B (realisations that fail), and the
    demo set b, whose part inside B holds the test points the correct demos
    cover and whose part outside B (shaded grey) the incorrect demos. Every
    region is labelled with its name and count in plain words; a region with
    no members is not drawn, but its label still says 0.

    Parameters
    ----------
    session : TeachingSession
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure (5 x 4 in) is made when None.
    step : int
        Index into ``session.history`` (default -1, the latest).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = new_axes(ax, figsize=(5.0, 4.0))
    ax.set_xlim(*_XLIM)
    ax.set_ylim(*_YLIM)
    ax.set_aspect("equal")
    ax.axis("off")
    if not session.history:
        ax.text(6, 4.7, "no demo yet", ha="center", va="center", fontsize=9, color="0.4")
        return ax
    c = set_counts(session, step)
    noun = getattr(session.task, "point_noun_plural", "test points")
    r_centre, b_centre = _diagram_geometry(c)
    size = {"width": 2 * _B_HALF[0], "height": 2 * _B_HALF[1]}
    B = {"xy": tuple(_B_CENTRE), **size}
    R = {"xy": tuple(r_centre), **size}
    b = {"xy": tuple(b_centre), "width": 2 * _b_HALF[0], "height": 2 * _b_HALF[1]}

    # R \ B: draw R first, B covers its inside part
    ax.add_patch(Ellipse(**R, facecolor="#f6d5bf", edgecolor="none", zorder=1))
    # B^ \ (R u b): undemonstrated, cross-hatched
    ax.add_patch(Ellipse(**B, facecolor="#fdf1e7", edgecolor="none", zorder=2))
    ax.add_patch(
        Ellipse(
            **B, facecolor="none", edgecolor=FAIL, hatch="xx", linewidth=0, alpha=0.45, zorder=2
        )
    )
    clip_B = Ellipse(**B, facecolor="none", edgecolor="none")
    ax.add_patch(clip_B)
    # R n B: covered, striped
    for patch in (
        Ellipse(**R, facecolor="#dff1ea", edgecolor="none", zorder=3),
        Ellipse(**R, facecolor="none", edgecolor=PASS, hatch="///", linewidth=0, zorder=3),
    ):
        ax.add_patch(patch)
        patch.set_clip_path(clip_B)
    # b: grey where outside B (incorrect demos), blue inside
    ax.add_patch(Ellipse(**b, facecolor="#b3b3b3", edgecolor="none", zorder=4))
    b_in = Ellipse(**b, facecolor="#c5d3ec", edgecolor="none", zorder=4)
    ax.add_patch(b_in)
    b_in.set_clip_path(clip_B)
    # outlines
    ax.add_patch(Ellipse(**B, facecolor="none", edgecolor="black", linewidth=1.6, zorder=6))
    ax.add_patch(Ellipse(**R, facecolor="none", edgecolor=PASS, linewidth=1.4, zorder=6))
    ax.add_patch(Ellipse(**b, facecolor="none", edgecolor=DEMO, linewidth=1.6, zorder=6))

    poles = _region_poles(r_centre, b_centre)
    box = {"boxstyle": "round,pad=0.25", "fc": "white", "ec": "none", "alpha": 0.85}
    text = {"fontsize": 8, "zorder": 8, "bbox": box}
    arrow = {"arrowstyle": "-", "color": "0.3", "linewidth": 0.8, "shrinkA": 0, "shrinkB": 0}

    def label(name, words, colour, outside, roomy=1.2, inside=None, **kw):
        """Inside its region when the region is roomy, else outside with a leader line."""
        pole = poles[name]
        if pole is not None and pole[2] >= roomy:
            inside = words if inside is None else inside
            ax.text(pole[0], pole[1], inside, ha="center", va="center", color=colour, **text)
            return
        xytext, ha = outside
        if pole is None:
            ax.text(*xytext, words, ha=ha, va="center", color=colour, **text, **kw)
        else:
            ax.annotate(
                words,
                pole[:2],
                xytext=xytext,
                ha=ha,
                va="center",
                color=colour,
                arrowprops=arrow,
                **text,
                **kw,
            )

    bottom = _B_CENTRE[1] - _B_HALF[1] - 0.2
    ax.text(
        _B_CENTRE[0],
        bottom,
        f"B̂: {c['n']} {noun} (test set)",
        ha="center",
        va="top",
        fontweight="bold",
        **text,
    )
    label(
        "covered",
        f"R ∩ B: {c['covered']} covered\n({c['generalised']} by generalisation)",
        "#0f5e47",
        ((0.1, 0.45), "left"),
    )
    label(
        "undemonstrated",
        f"undemonstrated: {c['undemonstrated']}",
        "#9a3b00",
        ((11.9, 0.45), "right"),
        roomy=0.8,
        inside=f"undemonstrated:\n{c['undemonstrated']}",
    )
    label(
        "failed",
        f"R ∖ B: {c['failed']} realisations fail",
        "#9a3b00",
        ((0.1, 9.1), "left"),
        roomy=99,
    )
    label(
        "demonstrated",
        f"demonstrated (b ∩ B): {c['demonstrated']}",
        DEMO,
        ((11.9, 8.3), "right"),
        roomy=99,
    )
    label(
        "incorrect",
        f"incorrect demos (b ∖ B): {c['incorrect']}",
        "0.25",
        ((11.9, 9.1), "right"),
        roomy=99,
    )
    ax.text(
        b_centre[0] + _b_HALF[0] + 0.1,
        b_centre[1] + 0.3,
        f"b: {c['demos']} demo{'s' if c['demos'] != 1 else ''}",
        ha="left",
        va="bottom",
        color=DEMO,
        fontweight="bold",
        **text,
    )
    return ax
