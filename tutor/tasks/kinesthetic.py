"""A simulated kinesthetic teacher: a person guiding the arm by hand to pick one plant.

The pick-and-place task (:mod:`tutor.tasks.pickplace`) judges demonstrations; this
module makes them, the way a trainee in the paper's Experiment 2 recorded them by
moving the Sawyer's wrist and pressing its button:

- the hand is guided through via points (above the plant, the grasp, a lift, above
  the bin, the release), with minimum-jerk motion between them and one smooth reach
  and one smooth transport;
- the via points and the timing vary from person to person (a few mm; a pace of 0.85
  to 1.2 times the average);
- a little hand tremor (about 1 mm, smoothed) rides on the path;
- the button is pressed (hand closed) at the grasp and released over the bin, each
  with a short pause;
- on request the teacher makes one of two mistakes (:data:`MISTAKES`).

A recording is (T, 5): t (s), x, y, z (m, robot base frame) and g (0 open, 1 closed),
sampled at ``rate_hz``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import InvalidParameterError
from .paths import minimum_jerk_through

if TYPE_CHECKING:  # the task imports this module; no cycle at run time
    from .pickplace import PickPlaceScene

__all__ = ["demonstrate", "MISTAKES"]

#: What the simulated teacher can get wrong: guide the arm to a neighbouring plant,
#: or close the hand 2-3 cm off the plant.
MISTAKES = ("wrong_plant", "sloppy_grab")

#: Seconds of the reach (start to grasp) and of the transport (grasp to release) at an
#: average pace, and of the pause at each button press.
REACH_SECONDS, CARRY_SECONDS, PAUSE_SECONDS = 4.5, 5.5, 0.6
#: Standard deviation of where a person puts a via point (m), and of the tremor (m).
PLACEMENT_SD, TREMOR_SD = 0.005, 0.001


def demonstrate(
    scene: PickPlaceScene,
    start,
    plant: int,
    rng=None,
    mistake: str | None = None,
    rate_hz: float = 20.0,
) -> np.ndarray:
    """A kinesthetic-style demonstration to ``plant`` as a person would give it.

    Parameters
    ----------
    scene : PickPlaceScene
        Where the plants and the bin are.
    start : array_like (3,)
        The tool position at the start configuration (m), where the hand begins.
    plant : int
        Index of the plant the teacher chose (0 .. rows * cols - 1).
    rng : numpy Generator or seed, optional
    mistake : {None, "wrong_plant", "sloppy_grab"}
        "wrong_plant": the teacher guides the arm to a neighbouring plant;
        "sloppy_grab": the hand closes 2-3 cm off the plant.
    rate_hz : float
        Samples per second of the recording.

    Returns
    -------
    ndarray (T, 5)
        t (s), x, y, z (m), g (0 open, 1 closed).

    Raises
    ------
    InvalidParameterError
        An unknown plant, mistake or a rate that is not a positive number.
    """
    target = check_plant(scene, plant)
    if mistake is not None and mistake not in MISTAKES:
        raise InvalidParameterError(
            f"unknown mistake {mistake!r}; use None, 'wrong_plant' or 'sloppy_grab'"
        )
    try:
        rate_ok = float(rate_hz) > 0 and np.isfinite(float(rate_hz))
    except (TypeError, ValueError):
        rate_ok = False
    if not rate_ok:
        raise InvalidParameterError(f"rate_hz must be a positive number, got {rate_hz!r}")
    rng = np.random.default_rng(rng)
    if mistake == "wrong_plant":
        target = _neighbour(scene, target, rng)
    grasp = _grasp_point(scene, target, rng, sloppy=mistake == "sloppy_grab")
    release = scene.release_point + rng.normal(0, PLACEMENT_SD, 3)  # where the hand opens
    reach, carry = _via_points(np.asarray(start, dtype=float), grasp, release, rng)
    t, path, g = _guide(reach, carry, float(rate_hz), rng)
    return np.column_stack([t, path + hand_tremor(len(path), rng), g])


def check_plant(scene: PickPlaceScene, plant) -> int:
    """``plant`` as a plant index of ``scene``, or a named error."""
    n = scene.rows * scene.cols
    if isinstance(plant, bool) or not isinstance(plant, int | np.integer) or not 0 <= plant < n:
        raise InvalidParameterError(f"plant must be an index from 0 to {n - 1}, got {plant!r}")
    return int(plant)


def _neighbour(scene: PickPlaceScene, plant: int, rng) -> int:
    """A plant next to ``plant`` on the tray (left, right, in front or behind), at random."""
    r, c = divmod(plant, scene.cols)
    moves = [
        (dr, dc)
        for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0))
        if 0 <= r + dr < scene.rows and 0 <= c + dc < scene.cols
    ]
    dr, dc = moves[rng.integers(len(moves))]
    return scene.plant_index(r + dr, c + dc)


def _grasp_point(scene: PickPlaceScene, plant: int, rng, sloppy: bool) -> np.ndarray:
    """Where the hand closes: on the plant within a few mm, or 2-3 cm off when sloppy."""
    grasp = scene.plant_positions[plant] + rng.normal(0, PLACEMENT_SD, 3)
    if sloppy:
        angle = rng.uniform(0, 2 * np.pi)
        grasp = grasp + rng.uniform(0.02, 0.03) * np.array([np.cos(angle), np.sin(angle), 0])
    return grasp


def _via_points(start, grasp, release, rng) -> tuple[list, list]:
    """The reach (start, above the plant, grasp) and the transport (grasp, lift, above
    the bin, release), each intermediate point placed by hand (a few mm off)."""
    reach = [start, grasp + [0, 0, 0.10] + rng.normal(0, PLACEMENT_SD, 3), grasp]
    carry = [
        grasp,
        grasp + [0, 0, 0.15] + rng.normal(0, PLACEMENT_SD, 3),
        release + [0, 0, 0.06] + rng.normal(0, PLACEMENT_SD, 3),
        release,
    ]
    return reach, carry


def _guide(reach, carry, rate_hz: float, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move through the via points at one personal pace, pausing at each button press.

    Returns
    -------
    t : ndarray (T,)
        Seconds from the start.
    path : ndarray (T, 3)
        Tool positions (m).
    g : ndarray (T,)
        The hand: open while reaching, closed from the grasp to the release.
    """
    pace = rng.uniform(0.85, 1.2)
    times, points_out, hands, t0 = [], [], [], 0.0
    for points, seconds, hand in ((reach, REACH_SECONDS, 0.0), (carry, CARRY_SECONDS, 1.0)):
        dur = seconds * pace * rng.uniform(0.95, 1.05)
        n = max(int(dur * rate_hz), 2)
        times.append(t0 + np.arange(n) / rate_hz * dur / (n / rate_hz))
        points_out.append(minimum_jerk_through(points, n + 1)[:-1])
        hands.append(np.full(n, hand))
        t0 += dur
        pause = PAUSE_SECONDS * pace * rng.uniform(0.9, 1.1)  # press (or release) the button
        m = max(int(pause * rate_hz), 1)
        times.append(t0 + np.arange(m) / rate_hz)
        points_out.append(np.tile(points[-1], (m, 1)))
        hands.append(np.full(m, 1.0 - hand))
        t0 += m / rate_hz
    return np.concatenate(times), np.concatenate(points_out), np.concatenate(hands)


def hand_tremor(n: int, rng) -> np.ndarray:
    """Hand tremor (n, 3) (m): white noise smoothed over 7 samples."""
    noise = rng.normal(scale=TREMOR_SD, size=(n, 3))
    kernel = np.hanning(7) / np.hanning(7).sum()
    return np.column_stack([np.convolve(noise[:, j], kernel, mode="same") for j in range(3)])
