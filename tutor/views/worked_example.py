"""The short instruction each condition begins with: a few words and one worked example.

Sena & Howard began every condition with a short instruction for it. Here each one is
two or three plain sentences and a strip of three frames drawn from a bundled example
teacher: what a demonstration looks like, what the trainee is then shown under *this*
condition, and what comes next. The frames are drawn once per kernel (matplotlib,
about a second) and kept.

- :func:`instruction_text` the words, per experiment and condition;
- :func:`example_png` the three frames as one PNG image;
- :func:`instruction_widget` both, as a widget shown above the condition's tutor;
- :func:`controls_step` Experiment 2's "Try the controls" step: who moves the arm (the
  hand, :mod:`tutor.views.hand`), its keys (:func:`tutor.views.hand.controls_html`) and,
  before the first run and in a practice run, a few minutes to try them (the paper's
  5-minute familiarisation).
"""

from __future__ import annotations

import base64
import functools
import html
import io

import numpy as np

from ..errors import InvalidParameterError
from ..framework import Trainee, protocol
from .hand import HAND_TASKS, HANDS, check_hand, controls_html
from .style import AMBIGUOUS, DEMO, FAIL, PASS, PROSE, UNKNOWN, prose

__all__ = [
    "instruction_text",
    "example_png",
    "instruction_widget",
    "controls_step",
    "TRY_THE_CONTROLS",
    "PRACTICE_CONTROLS",
]

#: the heading of Experiment 2's step that teaches the controls
TRY_THE_CONTROLS = "Try the controls"
#: what a practice run adds to it
PRACTICE_CONTROLS = (
    "In this practice run nothing counts: give whole demonstrations too, until the "
    "controls feel easy."
)

#: the plants the pick-and-place example demonstrates, and the ones SF asks to test
_EXAMPLE_PLANTS = (44, 0)
_SF_TESTS = (99, 9)


def instruction_text(experiment: int, condition: str) -> str:
    """The instruction of ``condition`` in ``experiment`` (1 maze, 2 pick-and-place)."""
    words = protocol.experiment(experiment).condition(condition).instruction
    if not words:
        raise InvalidParameterError(
            f"condition {condition!r} of experiment {experiment} has no instruction: give "
            "its Condition an instruction= in tutor/framework/protocol.py"
        )
    return words


@functools.cache
def example_png(experiment: int, condition: str) -> bytes:
    """Three frames of the worked example of ``condition``, as PNG bytes (kept per kernel)."""
    instruction_text(experiment, condition)  # refuses unknown conditions
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(9.0, 3.6), layout="constrained")
    try:
        EXAMPLE_FRAMES[protocol.experiment(experiment).task](axes, condition)
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=80)
    finally:
        plt.close(fig)
    return buffer.getvalue()


def controls_step(hand, practice: bool = False, first: bool = True):
    """Experiment 2's "Try the controls" step for ``hand`` (a hand's code), as a widget
    (CSS class ``lfd-try-controls``): the hand's words and keys, and, in the first run
    (``first``) or a practice run, its :attr:`~tutor.views.hand.Hand.try_it` sentences.

    Raises
    ------
    InvalidParameterError
        ``hand`` is not one of :data:`tutor.views.hand.HANDS`.
    """
    import ipywidgets as w

    chosen = HANDS[check_hand(hand)]
    words = [chosen.try_it] if first or practice else []
    if practice:
        words.append(PRACTICE_CONTROLS)
    said = "".join(f"<p style='{PROSE}'>{html.escape(x)}</p>" for x in words)
    box = w.HTML(f"<b>{html.escape(TRY_THE_CONTROLS)}</b>{said}{controls_html(chosen)}")
    box.add_class("lfd-try-controls")
    return box


def instruction_widget(
    experiment: int, condition: str, practice: bool = False, hand=None, first: bool = True
):
    """The instruction and the worked example as one widget (CSS class ``lfd-instruction``).

    ``hand`` (a hand's code, or None for none) adds, in a task taught with a hand
    (:data:`~tutor.views.hand.HAND_TASKS`: pick-and-place), the
    :func:`controls_step` under the example (``first``: the trainee's first run).
    """
    import ipywidgets as w

    words = instruction_text(experiment, condition)
    if practice:
        words += " This is a practice run: you see everything, and it is not counted."
    heading = w.HTML(
        prose(f"<b>Condition {html.escape(condition)}: how it works</b><br>{html.escape(words)}")
    )
    # an <img> with alt text (an Image widget has none: axe's image-alt rule)
    png = base64.b64encode(example_png(experiment, condition)).decode("ascii")
    alt = html.escape(f"Worked example in three pictures: {words}")
    frames = w.HTML(f'<img src="data:image/png;base64,{png}" alt="{alt}" style="max-width:720px">')
    parts = [heading, frames]
    if hand is not None and protocol.experiment(experiment).task in HAND_TASKS:
        parts.append(controls_step(hand, practice, first))
    box = w.VBox(parts)
    box.add_class("lfd-instruction")
    return box


# ------------------------------------------------------------------------ the maze


def _maze_frames(axes, condition: str) -> None:
    from ..demofiles import bundled_demos
    from ..tasks.maze import MazeTask
    from ..tasks.maze_run import MazeRun
    from .maze import draw_maze, realisations_at

    task = MazeTask()
    spec = MazeRun.protocol().condition(condition)
    # VR: a teacher whose third demo starts inside the rules' circle; else the good one
    demos = bundled_demos("maze_undemonstrated" if spec.rules else "maze_good")[:4]
    run = MazeRun.new(condition, task, trainee=Trainee.from_name("worked example"))
    advice = []
    for demo in demos:
        run.add_demo(demo)
        advice.append(run.advice() if spec.rules else None)
    session = run.session

    def frame(ax, n_demos, realised, title):
        draw_maze(ax, task.layout, zone_label=False)
        step = n_demos - 1
        if realised:
            paths = realisations_at(session, step)
            passed = np.asarray(session.history[step].passed, dtype=bool)
            for path, ok in zip(paths, passed, strict=True):
                ax.plot(path[:, 0], path[:, 1], color=PASS if ok else FAIL, lw=0.6, alpha=0.7)
        for k, demo in enumerate(demos[:n_demos]):
            points = task.preprocess(demo)
            ax.plot(points[:, 1], points[:, 2], color=DEMO, lw=2.2)
            ax.annotate(
                str(k + 1),
                points[0, 1:],
                color=DEMO,
                fontsize=9,
                weight="bold",
                xytext=(3, -10),
                textcoords="offset points",
            )
        ax.set_title(title, fontsize=9)
        for hide in (ax.set_xticks, ax.set_yticks):
            hide([])
        ax.set_xlabel("")
        ax.set_ylabel("")

    frame(axes[0], 1, False, "1. You draw a demonstration")
    if spec.policy.silent:
        frame(axes[1], 3, False, "2. You see only your own paths")
        frame(axes[2], 3, True, "3. After Finish: what it learned")
    elif not spec.rules:
        frame(axes[1], 3, True, "2. Robot's tries: green ok, dark red fail")
        frame(axes[2], 4, True, "3. Demo 4 where they failed")
    else:
        import matplotlib.patches as mpatches

        frame(axes[1], 2, True, "2. The circle: start inside it")
        rule = advice[1]
        if rule is not None and rule.center is not None:
            axes[1].add_patch(
                mpatches.Circle(
                    rule.center, rule.radius, fill=False, ls="--", lw=2, color=AMBIGUOUS, zorder=5
                )
            )
        frame(axes[2], 3, True, "3. Demo 3 from the circle")


# ------------------------------------------------------------------------ pick and place


def _pickplace_frames(axes, condition: str) -> None:
    from ..tasks.pickplace import PickPlaceTask
    from ..tasks.pickplace_protocol import PickPlaceRun

    task = PickPlaceTask()
    spec = PickPlaceRun.protocol().condition(condition)
    run = PickPlaceRun.new(condition, task, trainee=Trainee.from_name("worked example"))
    rng = np.random.default_rng(1)
    first, second = _EXAMPLE_PLANTS
    run.demonstrate(first, rng=rng)
    shown_after_first = _status(run, reveal=False)
    hinted = run.hint().plant if spec.hinted else None
    if hinted is not None:  # the example follows the hint
        second = hinted
    if spec.policy.teacher_picks:
        run.test(list(_SF_TESTS))
        shown_after_first = _status(run, reveal=False)
    run.demonstrate(second, rng=rng)
    revealed = _status(run, reveal=True)

    demo_only = np.full(len(task.test_points), "unknown", dtype=object)
    demo_only[first] = "demo"
    _tray(axes[0], task, demo_only, f"1. You demonstrate {task.plant_name(first)}")
    caption = (spec.example or "2. What the robot shows you").format(
        plant=task.plant_name(second)
    )
    _tray(axes[1], task, shown_after_first, caption, hinted)
    if spec.policy.silent:
        _tray(axes[2], task, revealed, "3. After the run: every plant")
    else:
        _tray(axes[2], task, _status(run, reveal=False), "3. After the next demo")


def _status(run, reveal: bool) -> np.ndarray:
    from .pickplace_app import tray_status

    return tray_status(run, reveal=reveal)


def _tray(ax, task, status, title: str, hinted: int | None = None) -> None:
    """The tray as the map draws it (as the 3-D view's camera sees it): row 1, nearest
    the robot, at the top; column 1 on the left; status by colour and glyph; the
    ``hinted`` plant (HF) marked ★."""
    colours = {"pass": PASS, "fail": FAIL, "demo": DEMO, "unknown": UNKNOWN}
    glyphs = {"pass": "✓", "fail": "✗", "demo": "●", "unknown": ""}
    rows, cols = task.scene.rows, task.scene.cols
    for i, s in enumerate(status):
        r, c = divmod(i, cols)
        ax.add_patch(_square(c, rows - 1 - r, colours[s]))
        if glyphs[s]:
            ax.text(c, rows - 1 - r, glyphs[s], ha="center", va="center", fontsize=5, color="white")
    if hinted is not None:
        r, c = divmod(int(hinted), cols)
        ax.text(c, rows - 1 - r, "★", ha="center", va="center", fontsize=9, color="black")
    ax.set_xlim(-0.6, cols - 0.4)
    ax.set_ylim(-0.6, rows + 0.6)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.text((cols - 1) / 2, rows + 0.3, "robot side", ha="center", va="center", fontsize=8)
    ax.set_title(title, fontsize=9)


def _square(x, y, colour):
    import matplotlib.patches as mpatches

    return mpatches.Rectangle((x - 0.42, y - 0.42), 0.84, 0.84, color=colour, lw=0)


#: task name -> the three frames of its worked example
EXAMPLE_FRAMES = {"maze": _maze_frames, "pickplace": _pickplace_frames}
