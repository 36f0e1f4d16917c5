"""Package data: the files bundled inside :mod:`tutor` (``tutor/assets``).

Everything the tutor reads at run time ships inside the package and is found with
:mod:`importlib.resources`, so a non-editable install (a wheel, a hub image, Binder)
finds it wherever ``site-packages`` is; nothing depends on the repository's layout.

``asset("maze.json")`` gives a filesystem path (the package is installed as files; a
zipped install is not supported, since NumPy and Pinocchio need real paths).
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

__all__ = ["asset", "assets_dir"]


def assets_dir() -> Path:
    """The folder of bundled assets."""
    return Path(str(files("tutor") / "assets"))


def asset(*parts: str) -> Path:
    """The path of one bundled asset, e.g. ``asset("demos", "maze_good.json")``."""
    return assets_dir().joinpath(*parts)
