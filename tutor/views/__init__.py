"""Pictures of a teaching session (matplotlib).

- :mod:`.maze`: the maze, the paper's feedback picture (R^ green/red, demos blue
  and numbered) and the start grid B^ by status.
- :mod:`.teaching`: task-agnostic pictures: efficacy/efficiency per demo and the
  set diagram of B^, R^ and b.
- :mod:`.figures`: a 2 x 2 summary figure for the notebooks.
"""

from .figures import feedback_figure
from .maze import draw_maze, plot_feedback, plot_grid_status, realisations_at
from .teaching import plot_progress, plot_set_diagram, set_counts

__all__ = [
    "draw_maze",
    "feedback_figure",
    "plot_feedback",
    "plot_grid_status",
    "plot_progress",
    "plot_set_diagram",
    "realisations_at",
    "set_counts",
]
