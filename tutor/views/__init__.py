"""Pictures of a teaching session (matplotlib).

- :mod:`.maze`: the maze, the paper's feedback picture (R^ green/red, demos blue
  and numbered) and the start grid B^ by status.
- :mod:`.teaching`: task-agnostic pictures: efficacy/efficiency per demo and the
  set diagram of B^, R^ and b.
- :mod:`.figures`: a 2 x 2 summary figure for the notebooks.
- :mod:`.scene3d`: the pick-and-place scene in 3-D (Meshcat), live or as a static page;
  :mod:`.meshcat_server` runs its loopback-only server. Imported on first use.
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
    "Scene3D",
]


def __getattr__(name):
    # Scene3D pulls in meshcat and Pinocchio: import it only when asked for.
    if name == "Scene3D":
        from .scene3d import Scene3D

        return Scene3D
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
