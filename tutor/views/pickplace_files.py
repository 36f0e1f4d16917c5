"""Which plant each demonstration of a loaded pick-and-place file is for.

A demonstration file may say, per demo, the plant it was meant for (its ``conditions``:
the plant's grasp point, x, y, z in metres); otherwise the plant nearest to where the
hand closes counts. A meant condition farther than half a plant spacing from every
plant's grasp point is refused (with a hint when the file looks like centimetres or
millimetres), and so is a file whose demos take more time than the run has left.
:class:`~tutor.framework.controller.RunController` calls :func:`plant_items` when the
pick-and-place tutor loads a file.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidFileError, TutorError

__all__ = ["plant_items", "plant_at"]


def plant_items(run, demos, name: str) -> list:
    """(raw, options) for each demo of a loaded file: its plant's condition and its time.

    Parameters
    ----------
    run : PickPlaceRun
        The run the demos are for (its task, and the time it has left).
    demos : DemoSet
        The file's demos, with ``conditions`` (None where the file gives none).
    name : str
        The file as the trainee knows it (named in errors).

    Raises
    ------
    InvalidFileError
        A demo's meant plant is wrong, or the demos take more time than is left.
    """
    task = run.task
    items = []
    width = task.test_points.shape[1]
    for i, (raw, meant) in enumerate(zip(demos, demos.demo_points, strict=True), start=1):
        try:
            if meant is not None and np.asarray(meant).shape != (width,):
                raise InvalidFileError(
                    f"its condition has {np.asarray(meant).size} number(s); a plant's "
                    f"grasp point has {width} (x, y, z in metres), or write null"
                )
            where = task.test_point_of(task.preprocess(raw)) if meant is None else meant
            plant = plant_at(task, where, meant is not None)
        except TutorError as exc:
            raise InvalidFileError(f"demo {i} of {name}: {exc}") from exc
        items.append((raw, {"point": task.test_points[plant], "seconds": task.duration(raw)}))
    total = sum(o["seconds"] for _, o in items)
    if total > run.remaining:
        raise InvalidFileError(
            f"the {len(items)} demonstration(s) in {name} take {total:.0f} s, but only "
            f"{run.remaining:.0f} s of this run are left: load fewer "
            "demonstrations, or load them into the next run"
        )
    return items


def plant_at(task, where, meant: bool) -> int:
    """The plant whose grasp point is ``where`` (a meant condition must lie within
    half a plant spacing of one, in all three coordinates)."""
    where = np.asarray(where, dtype=float)
    plant = int(task.nearest_test_point(where))
    if meant:
        grasp = task.test_points
        gap = float(np.linalg.norm(where - grasp[plant]))
        pitch = float(task.scene.pitch)
        if gap > pitch / 2:
            hint = ""
            for unit, scale in (("centimetres", 100.0), ("millimetres", 1000.0)):
                if np.linalg.norm(grasp - where / scale, axis=1).min() <= pitch / 2:
                    hint = (
                        f" It looks like {unit}: divide the positions and conditions "
                        f"by {scale:g}."
                    )
                    break
            raise InvalidFileError(
                f"its condition {np.round(where, 3).tolist()} is {100 * gap:.1f} cm from "
                f"the nearest plant's grasp point; a meant plant must be within half a "
                f"plant spacing ({100 * pitch / 2:.1f} cm), in metres.{hint}"
            )
    return plant
