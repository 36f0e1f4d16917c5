r"""Recordings of the trainee's own hand guiding the arm: their check, and a scripted hand.

In notebook 03 the trainee drags a handle on the gripper (:mod:`tutor.robot.follow`);
the page records :math:`(t, x, y, z, g)` from the first move to Enter and sends it to
the kernel once. :func:`check_recording` decides whether such a recording can be a
demonstration at all (before the task's own preprocessing and criteria judge how good
it is), and :func:`steady_hand` makes one the way a person drives the handle, for
tests, benchmarks and the worked example.

A recording is (T, 5): t (s, increasing), x, y, z (m, robot base frame: the handle's
position) and g (0 open .. 1 closed).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..errors import InvalidParameterError, InvalidRecordingError
from ..limits import MAX_RECORDING_SAMPLES, MAX_RECORDING_SECONDS
from ..robot.follow import REACH_CENTER, REACH_RADIUS, guide_limits
from .kinesthetic import check_plant, hand_tremor
from .pickplace import GRAB_LEVEL, load_scene

__all__ = [
    "check_recording",
    "steady_hand",
    "MAX_RECORDING_SECONDS",
    "MAX_RECORDING_SAMPLES",
    "MAX_JUMP",
    "REACH_SLACK",
]

#: Largest move of the hand between two consecutive samples (m): more is a gap or junk.
MAX_JUMP = 0.25
#: How far past the reach sphere, or below the lowest handle position, a sample may lie
#: (m) before it counts as out of reach (rounding in the page, the hand's tremor).
REACH_SLACK = 0.01

_HOW = "guide the arm again"


@lru_cache(maxsize=1)
def _default_scene():
    return load_scene()


def _fail(what: str, fix: str = _HOW):
    raise InvalidRecordingError(
        f"The recording cannot be a demonstration: {what}. {fix[0].upper()}{fix[1:]}."
    )


def check_recording(raw, scene=None) -> np.ndarray:
    """The recording ``raw`` as a float array (T, 5), or a named error saying what is wrong.

    Parameters
    ----------
    raw : array_like (T, 5)
        t (s), x, y, z (m), g (0 open .. 1 closed).
    scene : PickPlaceScene, optional
        Where the table is (default: the bundled scene).

    Returns
    -------
    ndarray (T, 5)
        A new float array.

    Raises
    ------
    InvalidRecordingError
        Not a table of 5 numbers a row; NaN or infinity; fewer than 2 samples; time not
        increasing; longer than :data:`MAX_RECORDING_SECONDS` or more than
        :data:`MAX_RECORDING_SAMPLES` samples; g outside [0, 1]; a jump of more than
        :data:`MAX_JUMP` between samples; a sample out of the arm's reach or below the
        table; a hand that never closes, or never opens again after closing.
    """
    scene = _default_scene() if scene is None else scene
    try:
        n = len(raw)
    except TypeError:
        n = None
    if n is not None and n > MAX_RECORDING_SAMPLES:
        _too_many(n)
    try:
        a = np.array(raw, dtype=float)
    except (TypeError, ValueError, OverflowError):
        _fail(
            "it must be a table of numbers with 5 columns (t, x, y, z, g), and some entries "
            "are not numbers or the rows differ in length"
        )
    if a.ndim != 2 or a.shape[1] != 5:
        _fail(f"it must be a table with 5 columns (t, x, y, z, g), got shape {a.shape}")
    T = len(a)
    if T > MAX_RECORDING_SAMPLES:
        _too_many(T)
    if T < 2:
        _fail(
            f"it holds {T} sample{'' if T == 1 else 's'}, and a demonstration needs the hand "
            "moving from the start to the bin",
            "drag the handle from the start to the plant and on to the bin, then press Enter",
        )
    finite = np.isfinite(a).all(axis=1)
    if not finite.all():
        k = int(np.argmin(finite))
        _fail(f"sample {k + 1} of {T} is not a number (NaN or infinity)")
    t = a[:, 0]
    dt = np.diff(t)
    if (dt <= 0).any():
        k = int(np.argmax(dt <= 0)) + 1
        _fail(
            f"time does not increase at sample {k + 1} of {T} (t = {t[k]:.3f} s after "
            f"{t[k - 1]:.3f} s)"
        )
    seconds = float(t[-1] - t[0])
    if seconds > MAX_RECORDING_SECONDS:
        _fail(
            f"it lasts {seconds / 60:.1f} minutes, longer than the {MAX_RECORDING_SECONDS:.0f} s "
            "a demonstration may take",
            "press Escape to cancel a guide that runs on, and guide the arm in one go",
        )
    g = a[:, 4]
    off = (g < 0) | (g > 1)
    if off.any():
        k = int(np.argmax(off))
        _fail(
            f"the hand value (last column) of sample {k + 1} is {g[k]:.3g}; it must be "
            "from 0 (open) to 1 (closed)"
        )
    xyz = a[:, 1:4]
    steps = np.linalg.norm(np.diff(xyz, axis=0), axis=1)
    if (steps > MAX_JUMP).any():
        k = int(np.argmax(steps > MAX_JUMP))
        _fail(
            f"the hand jumps {100 * steps[k]:.0f} cm between samples {k + 1} and {k + 2} "
            f"(a hand moves at most {100 * MAX_JUMP:.0f} cm between samples): the recording "
            "has a gap or a wrong sample"
        )
    _check_reach(xyz, scene)
    closed = g >= GRAB_LEVEL
    if not closed.any():
        _fail(
            "the hand never closes",
            "close the hand at the plant (the grip key or button), carry it to the bin and "
            "open it there",
        )
    k = int(np.argmax(closed))
    if closed[k:].all():
        _fail(
            f"the hand closes at sample {k + 1} and never opens again",
            "open the hand over the bin before pressing Enter",
        )
    return a


def _too_many(n: int):
    _fail(
        f"it holds {n} samples, more than the {MAX_RECORDING_SAMPLES} a recording may have",
        "guide the arm in one go (a demonstration takes well under a minute)",
    )


def _check_reach(xyz: np.ndarray, scene) -> None:
    """Refuse a sample out of the arm's reach or below the lowest handle position."""
    d = np.linalg.norm(xyz - REACH_CENTER, axis=1)
    far = d > REACH_RADIUS + REACH_SLACK
    floor = guide_limits(scene)["z"][0]
    low = xyz[:, 2] < floor - REACH_SLACK
    if far.any():
        k = int(np.argmax(far))
        x, y, z = xyz[k]
        _fail(
            f"sample {k + 1} ({x:.2f}, {y:.2f}, {z:.2f}) m is out of the arm's reach: "
            f"{100 * d[k]:.0f} cm from its shoulder, and it reaches {100 * REACH_RADIUS:.0f} cm"
        )
    if low.any():
        k = int(np.argmax(low))
        _fail(
            f"sample {k + 1} is at height {100 * xyz[k, 2]:.1f} cm, below the table top "
            f"(the hand stays at least {100 * floor:.1f} cm above it)"
        )


# --------------------------------------------------------------------------- the scripted hand

#: A move to a target of width W at distance D takes a + b log2(2 D / W + 1) seconds
#: (Fitts' law); a and b are drawn once per person (s, s per bit). Long moves come out at
#: 0.15 to 0.3 m/s, the precise ones slower.
FITTS_A, FITTS_B = (0.2, 0.4), (0.18, 0.3)
#: Target widths (m): the plant (precise), the release point, the rest (hover points).
WIDTH_PLANT, WIDTH_RELEASE, WIDTH_LOOSE = 0.005, 0.02, 0.03
#: The pause between two moves (s): letting go of the mouse, looking, taking it again.
STOP_SECONDS = (0.15, 0.45)
#: The grip key is pressed this soon after the hand arrives (s) ...
PRESS_SECONDS = (0.05, 0.15)
#: ... and the hand stays this long after the press (s).
GRIP_SECONDS = (0.4, 0.8)
#: Where a person lets go of the handle: SD off the intended point (m), horizontal,
#: vertical; loosely placed hover points: :data:`LOOSE_SD`.
AIM_SD, LOOSE_SD = (0.004, 0.003), (0.01, 0.01)
#: A move overshoots by this fraction of its length, then is corrected back (the moves
#: onto the plant and the release point are slowed down instead).
OVERSHOOT = (0.0, 0.04)
#: The hand is brought down to this height above the grasp point, then across to above
#: the plant (moving across at the start height would leave the arm's reach) (m).
HOVER = 0.1
#: The carrying height above the release point (m).
CARRY_ABOVE_RELEASE = 0.05


def steady_hand(task, plant, rng=None, rate_hz: float = 40.0) -> np.ndarray:
    """A scripted person's own-hand recording to ``plant``, made as a person drives the handle.

    The handle is dragged in the horizontal plane or moved up and down (one or the other,
    as the view offers), each move with a bell-shaped (minimum-jerk) speed at a personal
    hand speed (:data:`HAND_SPEED`), a small overshoot corrected back, and a pause before
    the next: down from the start, across to above the plant, down, slowly onto the plant,
    the grip key (the hand closes), up to the carrying height, across to above the bin,
    down to the release point, the grip key again (the hand opens), and Enter. Where the
    person lets go of the handle is a few mm off the intended point (:data:`AIM_SD`), and
    a little tremor rides on the path (the
    simulated kinesthetic hand's, :mod:`tutor.tasks.kinesthetic`).

    Parameters
    ----------
    task : PickPlaceTask
        Where the start pose, the plants and the bin are.
    plant : int
        The plant meant (0 .. rows * cols - 1).
    rng : numpy Generator or seed, optional
    rate_hz : float
        Samples per second the page records.

    Returns
    -------
    ndarray (T, 5)
        t (s from the first move), x, y, z (m), g (0 open, 1 closed): a recording that
        :func:`check_recording` accepts.
    """
    scene = task.scene
    plant = check_plant(scene, plant)
    try:
        rate = float(rate_hz)
        ok = np.isfinite(rate) and 1.0 <= rate <= 1000.0
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InvalidParameterError(f"rate_hz must be a number from 1 to 1000, got {rate_hz!r}")
    rng = np.random.default_rng(rng)
    fitts = (rng.uniform(*FITTS_A), rng.uniform(*FITTS_B))

    def aim(point, sd=AIM_SD):
        h, v = sd
        return np.asarray(point, float) + rng.normal(0, [h, h, v])

    start = np.asarray(task.start, float)
    grasp = aim(scene.plant_positions[plant])
    release = aim(scene.release_point)
    carry_z = scene.release_point[2] + CARRY_ABOVE_RELEASE
    moves = [  # (target, its width, then: None / "close" / "open")
        (aim([start[0], start[1], grasp[2] + HOVER], LOOSE_SD), WIDTH_LOOSE, None),
        (aim(grasp + [0, 0, HOVER]), WIDTH_LOOSE, None),
        (grasp, WIDTH_PLANT, "close"),
        (aim([grasp[0], grasp[1], carry_z], LOOSE_SD), WIDTH_LOOSE, None),
        (aim([release[0], release[1], carry_z]), WIDTH_LOOSE, None),
        (release, WIDTH_RELEASE, "open"),
    ]
    knots, grip_at = _timeline(start, moves, fitts, rng)
    t = np.arange(0.0, knots[-1][0] + 0.5 / rate, 1.0 / rate)
    xyz = _sample(knots, t)
    xyz += hand_tremor(len(t), rng)
    g = ((t >= grip_at["close"]) & (t < grip_at["open"])).astype(float)
    floor = guide_limits(scene)["z"][0]
    xyz[:, 2] = np.maximum(xyz[:, 2], floor)  # the handle never goes below the table top
    return np.column_stack([t, xyz, g])


def _timeline(start, moves, fitts, rng):
    """Knots (t, position) of the handle's path, and when the grip key is pressed."""
    a, b = fitts
    knots = [(0.0, start)]
    t, here, grip_at = 0.0, start, {}
    for target, width, then in moves:
        length = float(np.linalg.norm(target - here))
        t += (a + b * np.log2(2 * length / width + 1)) * rng.uniform(0.9, 1.1)
        if then is None:  # overshoot, and the correction back
            knots.append((t, target + (target - here) * rng.uniform(*OVERSHOOT)))
            t += rng.uniform(0.15, 0.3)
        knots.append((t, target))
        if then is not None:
            t += rng.uniform(*PRESS_SECONDS)
            grip_at[then] = t
            t += rng.uniform(*GRIP_SECONDS)
        else:
            t += rng.uniform(*STOP_SECONDS)
        knots.append((t, target))  # resting until the next move
        here = target
    return knots, grip_at


def _sample(knots, t: np.ndarray) -> np.ndarray:
    """Positions at times ``t``: minimum-jerk from knot to knot (still where two are equal)."""
    times = np.array([k[0] for k in knots])
    points = np.array([k[1] for k in knots])
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    span = times[i + 1] - times[i]
    tau = np.clip((t - times[i]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    return points[i] + s[:, None] * (points[i + 1] - points[i])
