"""Combined figures for the notebooks: several views of one session side by side."""

from __future__ import annotations

import matplotlib.pyplot as plt

from .maze import plot_feedback, plot_grid_status
from .teaching import plot_progress, plot_set_diagram

__all__ = ["feedback_figure"]


def feedback_figure(session, reveal=True, step=-1):
    """One 2 x 2 figure (about 11 x 9 in) summarising a maze teaching session.

    Top left: the feedback picture (:func:`~tutor.views.maze.plot_feedback`);
    top right: the start grid B^ by status (:func:`~tutor.views.maze.plot_grid_status`);
    bottom left: efficacy and efficiency per demo
    (:func:`~tutor.views.teaching.plot_progress`); bottom right: the set diagram
    (:func:`~tutor.views.teaching.plot_set_diagram`).

    Parameters
    ----------
    session : TeachingSession
        A session on a :class:`~tutor.tasks.maze.MazeTask`.
    reveal : bool
        Passed to :func:`plot_feedback`: True shows all of R^ with r highlighted
        (the educator's view), False only what the teacher was shown.
    step : int
        Which record to draw in the feedback, grid and set pictures (default the latest).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = plt.subplots(2, 2, figsize=(11, 9), layout="constrained")
    plot_feedback(session, ax=axes[0, 0], step=step, reveal=reveal)
    plot_grid_status(session, ax=axes[0, 1], step=step)
    plot_progress(session, ax=axes[1, 0])
    plot_set_diagram(session, ax=axes[1, 1], step=step)
    return fig
