"""Environment obstacles as axis-aligned boxes in the robot base frame.

A box is ``(name, center (3,), size (3,))`` in metres, ``size`` the full edge
lengths. The tasks pass their geometry in as such boxes, so the robot never imports
:mod:`tutor.tasks`: :func:`scene_obstacles` reads a pick-and-place scene by duck
typing and :func:`open_box` builds a bin from five boxes.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from .checks import check_vector

__all__ = ["check_boxes", "open_box", "scene_obstacles", "box_shape"]

Box = tuple[str, tuple[float, ...], tuple[float, ...]]


def check_boxes(obstacles) -> tuple[Box, ...]:
    """Validated, hashable obstacle boxes ``((name, center, size), ...)``."""
    if obstacles is None:
        return ()
    out, names = [], set()
    try:
        items = list(obstacles)
    except TypeError as exc:
        raise InvalidParameterError(
            "obstacles must be a sequence of (name, center (3,), size (3,)) boxes"
        ) from exc
    for item in items:
        try:
            name, center, size = item
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(
                f"an obstacle must be (name, center (3,), size (3,)), got {item!r}"
            ) from exc
        if not isinstance(name, str) or not name:
            raise InvalidParameterError(f"an obstacle's name must be a non-empty string: {name!r}")
        if name in names:
            raise InvalidParameterError(f"two obstacles are called {name!r}; names must differ")
        names.add(name)
        c = check_vector(center, 3, f"the centre of obstacle {name!r}")
        s = check_vector(size, 3, f"the size of obstacle {name!r}")
        if np.any(s <= 0):
            raise InvalidParameterError(f"obstacle {name!r} needs positive edge lengths, got {s}")
        out.append((name, tuple(map(float, c)), tuple(map(float, s))))
    return tuple(out)


def open_box(name: str, center, size, wall: float) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """An open-topped box (a bin) as five obstacle boxes: a floor and four walls.

    Parameters
    ----------
    name : str
        Prefix of the parts' names (``name``, ``name wall -x``, ...). The floor takes
        the plain name.
    center, size : array_like (3,)
        The bin's outer bounding box (m).
    wall : float
        Wall and floor thickness (m).

    Returns
    -------
    list of (name, center (3,), size (3,))
    """
    c = check_vector(center, 3, f"the centre of {name!r}")
    s = check_vector(size, 3, f"the size of {name!r}")
    if not (0 < wall < min(s) / 2):
        raise InvalidParameterError(f"wall thickness of {name!r} must be in (0, {min(s) / 2})")
    lo, hi = c - s / 2, c + s / 2
    parts = [(name, np.r_[c[:2], lo[2] + wall / 2], np.r_[s[:2], wall])]
    for axis, label in ((0, "x"), (1, "y")):
        for sign in (-1, 1):
            wc = c.copy()
            wc[axis] = (lo if sign < 0 else hi)[axis] - sign * wall / 2
            ws = s.copy()
            ws[axis] = wall
            parts.append((f"{name} wall {'-' if sign < 0 else '+'}{label}", wc, ws))
    return parts


def scene_obstacles(scene) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The boxes of a pick-and-place scene: table, tray and the bin (floor + 4 walls).

    Parameters
    ----------
    scene : object
        Anything with ``table_center``, ``table_size``, ``tray_center``, ``tray_size``,
        ``bin_center``, ``bin_size`` (3,) and ``bin_wall`` (m), such as
        :class:`tutor.tasks.pickplace.PickPlaceScene` (duck-typed: this module does not
        import the tasks).

    Returns
    -------
    list of (name, center (3,), size (3,))
    """
    try:
        return [
            ("table", np.asarray(scene.table_center, float), np.asarray(scene.table_size, float)),
            ("tray", np.asarray(scene.tray_center, float), np.asarray(scene.tray_size, float)),
            *open_box("bin", scene.bin_center, scene.bin_size, float(scene.bin_wall)),
        ]
    except AttributeError as exc:
        raise InvalidParameterError(f"not a pick-and-place scene: {exc}") from exc


def box_shape(size):
    """A coal (or, before pin 3.4, hpp-fcl) box of full edge lengths ``size`` (3,)."""
    try:
        import coal

        return coal.Box(*size)
    except ImportError:  # pin < 3.4 ships hpp-fcl instead of coal
        import hppfcl

        return hppfcl.Box(*size)
