"""The matplotlib pictures of tutor.views: they draw, and they draw the right things."""

from __future__ import annotations

import ast
import os
import re

os.environ.setdefault("MPLBACKEND", "Agg")

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

import tutor.views.teaching as teaching_module  # noqa: E402
from tutor.framework import TeachingSession  # noqa: E402
from tutor.views import (  # noqa: E402
    draw_maze,
    feedback_figure,
    plot_feedback,
    plot_grid_status,
    plot_progress,
    plot_set_diagram,
    realisations_at,
    set_counts,
)
from tutor.views.style import DEMO, FAIL, PASS  # noqa: E402

STARTS = [(0.02, 0.03), (0.18, 0.03), (0.10, 0.03)]
BATCH = [0, 19, 70, 120, 139]  # corners and centre of the 20 x 7 grid


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _teach(task, feedback="all", **kw):
    rng = np.random.default_rng(0)
    session = TeachingSession(task, feedback=feedback, **kw)
    for start in STARTS:
        session.add_demo(task.layout.reference_path(start, rng, jitter=0.003))
    return session


def _straight_to_target(layout, start=(0.02, 0.03)):
    """An incorrect demo: a straight line from ``start`` to the target, through obstacle 1."""
    demo = layout.reference_path(start) * [1, 1, 1]
    t = demo[:, 0]
    demo[:, 1:] = np.asarray(start) + t[:, None] * (layout.target_center - np.asarray(start))
    return demo


@pytest.fixture(scope="module")
def vf(maze_task):
    return _teach(maze_task)


@pytest.fixture(scope="module")
def nf(maze_task):
    return _teach(maze_task, feedback="none")


@pytest.fixture(scope="module")
def bf(maze_task):
    return _teach(maze_task, feedback="batch", batch=BATCH)


@pytest.fixture(scope="module")
def with_incorrect(maze_task):
    session = _teach(maze_task)
    record = session.add_demo(_straight_to_target(maze_task.layout))
    assert not record.demo_passed and "incorrect" in record.kinds
    return session


def _pixels(fig, ax=None):
    """RGB pixels (H, W, 3) of the rendered figure, cropped to ``ax`` when given."""
    fig.canvas.draw()
    rgb = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)
    if ax is None:
        return rgb
    box = ax.get_window_extent()
    height = rgb.shape[0]
    x0, x1 = int(box.x0) + 2, int(box.x1) - 2
    y0, y1 = height - int(box.y1) + 2, height - int(box.y0) - 2
    return rgb[y0:y1, x0:x1]


def _count(rgb, colour):
    """Pixels of the hue family of ``colour`` (lines are thin, faint and antialiased,
    so exact colours are rare): green for PASS, dark red for FAIL, blue for DEMO."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    masks = {
        PASS: (g - r > 40) & (g - b > 40),
        FAIL: (r - g > 40) & (r - b > 40) & (g < 140),
        DEMO: (b - r > 90) & (b - g > 40),
    }
    return int(masks[colour].sum())


def _realisation_segments(ax, min_width=0.0):
    """Number of realisation paths drawn (NaN-separated) in the pass/fail colours."""
    n = 0
    for line in ax.get_lines():
        if to_rgb(line.get_color()) in (to_rgb(PASS), to_rgb(FAIL)):
            if line.get_linewidth() >= min_width:
                n += int(np.isnan(np.asarray(line.get_xdata(), dtype=float)).sum())
    return n


def _demo_lines(ax):
    return [
        line
        for line in ax.get_lines()
        if to_rgb(line.get_color()) == to_rgb(DEMO) and len(line.get_xdata()) > 2
    ]


def test_draw_maze_axes_in_cm(maze_task):
    ax = draw_maze(layout=maze_task.layout)
    assert isinstance(ax, Axes)
    assert ax.get_aspect() == 1.0
    assert ax.xaxis.get_major_formatter()(0.05, 0) == "5"
    assert ax.get_title() == ""
    ax2 = draw_maze(ax)  # default layout, given axes
    assert ax2 is ax


def test_feedback_shows_green_red_and_blue(vf):
    record = vf.latest
    assert record.passed.any() and not record.passed.all()
    ax = plot_feedback(vf)
    assert isinstance(ax, Axes)
    rgb = _pixels(ax.figure, ax)
    assert _count(rgb, PASS) > 50
    assert _count(rgb, FAIL) > 50
    assert _count(rgb, DEMO) > 50
    assert _realisation_segments(ax) == len(vf.task.test_points)
    assert len(_demo_lines(ax)) == 3
    numbers = {t.get_text() for t in ax.texts}
    assert {"1", "2", "3"} <= numbers


def test_no_feedback_draws_no_realisations(nf):
    ax = plot_feedback(nf)
    rgb = _pixels(ax.figure)
    assert _count(rgb, PASS) == 0
    assert _count(rgb, FAIL) == 0
    assert _count(rgb, DEMO) > 50
    assert _realisation_segments(ax) == 0
    assert any("no feedback shown" in t.get_text() for t in ax.texts)
    # the educator's view reveals R^ even though the teacher saw nothing
    revealed = plot_feedback(nf, reveal=True)
    assert _realisation_segments(revealed) == len(nf.task.test_points)


def test_batch_feedback_and_reveal(bf):
    ax = plot_feedback(bf)
    assert _realisation_segments(ax) == len(BATCH)
    ax = plot_feedback(bf, reveal=True)
    n = len(bf.task.test_points)
    assert _realisation_segments(ax) == n
    assert _realisation_segments(ax, min_width=1.5) == len(BATCH)  # r highlighted


def test_past_step_uses_that_learner(vf):
    task = vf.task
    first = realisations_at(vf, 0)
    np.testing.assert_allclose(first, task.realise(vf._learners[0]))  # the robot's attempts
    assert realisations_at(vf, -1) is vf.realisations
    ax = plot_feedback(vf, step=0)
    assert len(_demo_lines(ax)) == 1
    with pytest.raises(IndexError):
        plot_feedback(vf, step=3)


def test_grid_status_counts_add_up(with_incorrect):
    record = with_incorrect.latest
    ax = plot_grid_status(with_incorrect)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert f"covered (passes): {int(record.passed.sum())}" in labels
    assert f"undemonstrated: {record.n_undemonstrated}" in labels
    assert "incorrect demo start: 1" in labels
    status = [lab for lab in labels if lab.startswith(("covered", "demonstrated,", "undem"))]
    assert sum(int(lab.rsplit(": ", 1)[1]) for lab in status) == len(record.passed)


def test_progress_one_point_per_demo(with_incorrect):
    ax = plot_progress(with_incorrect)
    m = with_incorrect.n_demos
    lines = {line.get_gid(): line for line in ax.get_lines() if line.get_gid()}
    np.testing.assert_array_equal(lines["efficacy"].get_xdata(), np.arange(1, m + 1))
    np.testing.assert_allclose(
        lines["efficacy"].get_ydata(), [r.efficacy for r in with_incorrect.history]
    )
    assert len(lines["efficiency"].get_xdata()) == m
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(lab.startswith("incorrect demo") for lab in labels)
    crosses = [line for line in ax.get_lines() if line.get_marker() == "x"]
    assert crosses and m in np.asarray(crosses[0].get_xdata())


def test_set_diagram_labels_the_counts(with_incorrect):
    c = set_counts(with_incorrect)
    ax = plot_set_diagram(with_incorrect)
    text = "\n".join(t.get_text() for t in ax.texts)
    assert f"R ∩ B: {c['covered']} covered" in text
    assert f"{c['undemonstrated']}" in text and "undemonstrated" in text
    assert f"incorrect demos (b ∖ B): {c['incorrect']}" in text
    assert c["incorrect"] == 1
    assert f"demonstrated (b ∩ B): {c['demonstrated']}" in text
    assert f"{c['n']} start points" in text
    assert c["covered"] + c["failed"] == c["n"]


def test_feedback_figure_and_empty_session(vf, maze_task):
    fig = feedback_figure(vf)
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    empty = TeachingSession(maze_task)
    for draw in (plot_feedback, plot_grid_status, plot_progress, plot_set_diagram):
        assert isinstance(draw(empty), Axes)


def test_teaching_views_are_task_agnostic():
    tree = ast.parse(open(teaching_module.__file__, encoding="utf-8").read())
    names = [node.module or "" for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)] + [
        a.name for node in ast.walk(tree) if isinstance(node, ast.Import) for a in node.names
    ]
    assert not any("tasks" in name for name in names)


# ------------------------------------------------------------ why attempts fail


def _paths_that_fail(layout):
    """Five realisations (5, 200, 2): pass, obstacle 2, leaves the maze, near miss, far miss."""
    good = layout.reference_path((0.05, 0.03))[:, 1:]
    hit2 = good.copy()
    hit2[120:] = [0.15, 0.195]  # parks inside obstacle 2 (x 7–20 cm, y 18–21 cm)
    out = good.copy()
    out[60:] = [0.25, 0.10]  # right of the 20 cm wide maze
    near = good + [0.0, -(layout.target_radius + 0.003)] * np.linspace(0, 1, 200)[:, None]
    far = good + [0.0, -(layout.target_radius + 0.02)] * np.linspace(0, 1, 200)[:, None]
    return np.stack([good, hit2, out, near, far])


def test_classify_reads_the_maze_tasks_own_reasons(maze_task):
    from tutor.framework.task import Reason
    from tutor.views.maze_reasons import classify, main_causes

    paths = _paths_that_fail(maze_task.layout)
    verdict = maze_task.judge(paths)
    assert verdict.passed.tolist() == [True, False, False, False, False]
    kinds = [classify(r).kind for r in verdict.causes]
    assert kinds == ["pass", "obstacle", "outside", "miss", "miss"]
    assert classify(verdict.causes[1], maze_task.layout).obstacle == "obstacle 2"
    assert classify(verdict.causes[1]).obstacle == "obstacle 2"  # numbered without one
    found = main_causes(paths, verdict.causes, maze_task.layout)
    np.testing.assert_allclose(found[1].point, [0.15, 0.195])  # where it went in
    np.testing.assert_allclose(found[2].point, [0.25, 0.10])
    assert found[3].miss == pytest.approx(0.003, abs=1e-6)  # from the target's edge
    assert found[0].point is None and found[0].miss == 0.0
    assert classify((Reason("start"),)).kind == "start"
    assert classify((Reason("start"), Reason("end", distance=0.02))).kind == "start"
    assert classify((Reason("end", distance=0.02), Reason("obstacle", 5, 200))).kind == "obstacle"
    assert classify((Reason("no_grab"),)).kind == "other"


def test_reason_summary_counts_each_cause(maze_task):
    from tutor.views.maze_reasons import main_causes, reason_summary

    paths = _paths_that_fail(maze_task.layout)
    paths = np.concatenate([paths, paths[3:4] + [0.0, -0.001]])  # a second near miss, 4 mm
    found = main_causes(paths, maze_task.judge(paths).causes, maze_task.layout)
    text = reason_summary(found)
    assert text.startswith("2 miss the target by 3–4 mm; ")
    assert "1 hits obstacle 2" in text and "1 leaves the maze" in text
    assert "1 ends 2.0 cm from the target" in text
    assert reason_summary(found, shown=[0]) == ""  # only what is shown is counted
    assert reason_summary(found, shown=[1, 0]) == "1 hits obstacle 2"


def test_feedback_marks_failures_dashed_with_reasons_and_a_target_inset(vf, maze_task):
    ax = plot_feedback(vf)
    fails = [ln for ln in ax.get_lines() if to_rgb(ln.get_color()) == to_rgb(FAIL)]
    passes = [ln for ln in ax.get_lines() if to_rgb(ln.get_color()) == to_rgb(PASS)]
    lines = [ln for ln in fails if ln.get_marker() in ("None", "", None)]
    assert lines and all(ln.get_linestyle() not in ("-", "None") for ln in lines)  # dashed
    assert passes and all(ln.get_linestyle() == "-" for ln in passes)
    why = [t for t in ax.texts if t.get_gid() == "failure-reasons"]
    assert len(why) == 1 and why[0].get_text().startswith("why they fail: ")
    n_fail = int((~vf.latest.passed).sum())
    counted = sum(
        int(n) for n in re.findall(r"(?:: |; )(\d+) ", why[0].get_text().replace("\n", " "))
    )
    assert counted == n_fail
    marks = [ln for ln in ax.get_lines() if (ln.get_gid() or "").startswith("failure-")]
    assert sum(len(ln.get_xdata()) for ln in marks) == n_fail
    # the target is drawn to scale (no oversized ring), and zoomed in an inset
    circles = [p for p in ax.patches if isinstance(p, matplotlib.patches.Circle)]
    assert [c.radius for c in circles] == [maze_task.layout.target_radius]
    assert not any(ln.get_marker() == "o" and ln.get_markersize() > 8 for ln in ax.get_lines())
    (inset,) = ax.child_axes
    assert np.ptp(inset.get_xlim()) <= 0.02
    tx = maze_task.layout.target_center[0]
    assert inset.get_xlim()[0] < tx < inset.get_xlim()[1]


def test_no_feedback_counts_no_reasons(nf):
    ax = plot_feedback(nf)
    assert not [t for t in ax.texts if t.get_gid() == "failure-reasons"]


# ------------------------------------------------------------ the sketchpad's data


def test_sketchpad_layout_is_the_widget_layout(maze_task):
    """The maze geometry has its own trait: a dict in `layout` broke every render (3 page
    errors "Cannot read properties of undefined (reading 'then')" in notebook 02)."""
    import ipywidgets

    from tutor.errors import InvalidParameterError
    from tutor.views.sketchpad import Sketchpad, layout_spec

    spec = layout_spec(maze_task.layout)
    for pad in (Sketchpad(maze=spec), Sketchpad(layout=spec)):
        assert isinstance(pad.layout, ipywidgets.Layout)
        assert pad.maze == spec
        assert pad.get_state()["layout"].startswith("IPY_MODEL_")
    with pytest.raises(InvalidParameterError, match="maze"):
        Sketchpad()
    with pytest.raises(InvalidParameterError, match="once"):
        Sketchpad(maze=spec, layout=spec)


def test_sketchpad_sends_paths_as_bytes_and_counts_reasons(vf, maze_task):
    from tutor.errors import InvalidParameterError
    from tutor.views.sketchpad import BROWSER_SAMPLES, Sketchpad, layout_spec

    pad = Sketchpad(maze=layout_spec(maze_task.layout))
    rec = vf.latest
    pad.show(vf.demos, vf.realisations, rec.passed, rec.shown, causes=rec.causes)
    n = len(maze_task.test_points)
    assert isinstance(pad.real_xy, bytes) and len(pad.real_xy) == n * BROWSER_SAMPLES * 2 * 4
    assert len(pad.realisations) == n and len(pad.demos) == 3
    np.testing.assert_allclose(pad.realisations[7][-1], vf.realisations[7, -1], atol=1e-6)
    np.testing.assert_allclose(pad.demos[0][0], vf.demos[0][0, 1:], atol=1e-6)
    n_fail = int((~rec.passed).sum())
    assert len(pad.marks) == n_fail and {m[2] for m in pad.marks} <= {1, 2, 3, 4}
    assert pad.summary and "target" in pad.summary
    # only what is shown: nothing shown, nothing counted
    pad.show(vf.demos, vf.realisations, rec.passed, [], causes=rec.causes)
    assert pad.marks == [] and pad.summary == ""
    with pytest.raises(InvalidParameterError, match="one per realisation"):
        pad.show(vf.demos, vf.realisations, rec.passed, rec.shown, causes=rec.causes[:3])
