"""One animated trajectory as a small Meshcat ``set_animation`` command.

meshcat-python's :class:`meshcat.animation.Animation` writes one ``{time, value}`` map
per key per track and converts each rotation matrix on its own: for the Panda's links
over 200 samples that is ~240 kB of msgpack and ~0.4 s of Python, and the browser then
decodes ~45 000 small objects. The viewer (three.js r129) also accepts a track as two
flat arrays, ``times`` and ``values``, which msgpack carries as Float32Array, so this
module packs the same animation directly:

- keys at :data:`KEYS_PER_SECOND` (the viewer interpolates between them: positions
  linearly, rotations by slerp), always including the last sample;
- only the nodes that move (the robot's base link never does);
- a step track (discrete interpolation) for what switches, e.g. the hand marker's
  open and closed balls, with one key per switch;
- quaternions of all the rotation matrices at once (numpy).

The command is the one meshcat's viewer handles (``type`` "set_animation", ``path``
"", ``animations`` [{path, clip}], ``options``), so the recorder, the live server and
the static page treat it like any other.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError

__all__ = [
    "KEYS_PER_SECOND",
    "Track",
    "continuous",
    "key_samples",
    "moving",
    "pack_animation",
    "quaternions",
    "step_track",
    "transform_tracks",
]

#: Animation keys per second of the played trajectory. A person's guided motion is
#: smooth (minimum jerk through a few via points), so 5 keys a second interpolated
#: by the viewer look like the 20 samples a second of the trajectory itself.
KEYS_PER_SECOND = 5.0
_FLOAT32 = 0x17  # msgpack extension code meshcat's viewer decodes as a Float32Array
_DISCRETE = 2300  # THREE.InterpolateDiscrete
_LINEAR = 2301  # THREE.InterpolateLinear


def key_samples(n_samples: int, seconds: float, keys_per_second: float = KEYS_PER_SECOND):
    """Indices (k,) of the samples kept as keys: evenly spread, first and last included."""
    if n_samples < 2:
        raise InvalidParameterError("an animation needs at least 2 samples")
    n_keys = int(np.clip(round(seconds * keys_per_second) + 1, 2, n_samples))
    return np.unique(np.round(np.linspace(0, n_samples - 1, n_keys)).astype(int))


def quaternions(R) -> np.ndarray:
    """Unit quaternions (..., 4) as three.js orders them (x, y, z, w) of rotations (..., 3, 3).

    Shepperd's method: each rotation uses the largest of the four candidate
    denominators, so no division is ill-conditioned.
    """
    R = np.asarray(R, dtype=float)
    m00, m11, m22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    trace = m00 + m11 + m22
    cand = np.stack([trace, m00, m11, m22], axis=-1)
    which = np.argmax(cand, axis=-1)
    q = np.empty(R.shape[:-2] + (4,))
    # w largest
    s = np.sqrt(np.maximum(1.0 + trace, 1e-12)) * 2
    qw = np.stack(
        [
            (R[..., 2, 1] - R[..., 1, 2]) / s,
            (R[..., 0, 2] - R[..., 2, 0]) / s,
            (R[..., 1, 0] - R[..., 0, 1]) / s,
            0.25 * s,
        ],
        axis=-1,
    )
    # x, y, z largest
    sx = np.sqrt(np.maximum(1.0 + m00 - m11 - m22, 1e-12)) * 2
    qx = np.stack(
        [
            0.25 * sx,
            (R[..., 0, 1] + R[..., 1, 0]) / sx,
            (R[..., 0, 2] + R[..., 2, 0]) / sx,
            (R[..., 2, 1] - R[..., 1, 2]) / sx,
        ],
        axis=-1,
    )
    sy = np.sqrt(np.maximum(1.0 + m11 - m00 - m22, 1e-12)) * 2
    qy = np.stack(
        [
            (R[..., 0, 1] + R[..., 1, 0]) / sy,
            0.25 * sy,
            (R[..., 1, 2] + R[..., 2, 1]) / sy,
            (R[..., 0, 2] - R[..., 2, 0]) / sy,
        ],
        axis=-1,
    )
    sz = np.sqrt(np.maximum(1.0 + m22 - m00 - m11, 1e-12)) * 2
    qz = np.stack(
        [
            (R[..., 0, 2] + R[..., 2, 0]) / sz,
            (R[..., 1, 2] + R[..., 2, 1]) / sz,
            0.25 * sz,
            (R[..., 1, 0] - R[..., 0, 1]) / sz,
        ],
        axis=-1,
    )
    for k, cand_q in enumerate((qw, qx, qy, qz)):
        pick = which == k
        q[pick] = cand_q[pick]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def continuous(q) -> np.ndarray:
    """Quaternions (k, 4) with signs chosen so that each is in the hemisphere of the one
    before (q and -q are one rotation): the viewer's slerp then takes the short way."""
    q = np.asarray(q, dtype=float)
    dots = np.sum(q[1:] * q[:-1], axis=-1)
    sign = np.cumprod(np.r_[1.0, np.where(dots < 0, -1.0, 1.0)])
    return q * sign[:, None]


class Track:
    """One property of one node over time: ``name`` (".position", ".quaternion",
    ".scale"), three.js ``kind`` ("vector3", "quaternion"), key ``times`` (s) and
    ``values`` (k, n), ``step`` for discrete interpolation."""

    __slots__ = ("name", "kind", "times", "values", "step")

    def __init__(self, name: str, kind: str, times, values, step: bool = False):
        self.name, self.kind, self.step = name, kind, bool(step)
        self.times = np.asarray(times, dtype=np.float32).ravel()
        self.values = np.asarray(values, dtype=np.float32).reshape(len(self.times), -1)

    def lower(self) -> dict:
        import umsgpack

        return {
            "name": self.name,
            "type": self.kind,
            "times": umsgpack.Ext(_FLOAT32, self.times.tobytes()),
            "values": umsgpack.Ext(_FLOAT32, np.ascontiguousarray(self.values).tobytes()),
            "interpolation": _DISCRETE if self.step else _LINEAR,
        }


def transform_tracks(times, placements) -> list[Track]:
    """Position and rotation tracks (k keys) of homogeneous ``placements`` (k, 4, 4)."""
    M = np.asarray(placements, dtype=float)
    return [
        Track(".position", "vector3", times, M[:, :3, 3]),
        Track(".quaternion", "quaternion", times, continuous(quaternions(M[:, :3, :3]))),
    ]


def step_track(name: str, kind: str, times, values) -> Track:
    """A discrete track keeping only the keys where ``values`` (k, n) change."""
    V = np.asarray(values, dtype=float).reshape(len(times), -1)
    keep = np.r_[True, np.any(V[1:] != V[:-1], axis=1)]
    return Track(name, kind, np.asarray(times)[keep], V[keep], step=True)


def moving(placements, tol: float = 1e-7) -> np.ndarray:
    """Which nodes (G,) of ``placements`` (k, G, 4, 4) move at all over the keys."""
    P = np.asarray(placements, dtype=float)
    return np.any(np.abs(P - P[:1]) > tol, axis=(0, 2, 3))


def pack_animation(clips: dict, play: bool = True, repetitions: int = 1) -> bytes:
    """The packed ``set_animation`` command of ``clips`` {node path: [Track, ...]}.

    Paths are full Meshcat paths ("/meshcat/robot/visuals/panda_link1_0"). Times are in
    seconds (the clip's fps is 1).
    """
    import umsgpack

    animations = [
        {
            "path": path,
            "clip": {"fps": 1.0, "name": "default", "tracks": [t.lower() for t in tracks]},
        }
        for path, tracks in clips.items()
        if tracks
    ]
    command = {
        "type": "set_animation",
        "animations": animations,
        "options": {"play": bool(play), "repetitions": int(repetitions)},
        "path": "",
    }
    return umsgpack.packb(command)
