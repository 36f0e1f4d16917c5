"""Task frames: the affine maps (A, b) under which a demonstration was given.

A local point ``x`` is ``A @ x + b`` in the world; time is never transformed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidFrameError
from .checks import check_real_array

__all__ = ["Frame", "FrameBatch", "check_frame_row", "check_frame_matrix"]

#: largest condition number of A: beyond it A^-1 loses most digits
MAX_CONDITION = 1e12
#: range of A's singular values (its scales). The model squares local coordinates and
#: reproduction multiplies A^-1 twice with a precision (fourth powers of the scale);
#: 1e-60 .. 1e60 keeps those within about 1e-240 .. 1e240, clear of overflow and underflow.
MIN_SCALE, MAX_SCALE = 1e-60, 1e60


def check_frame_matrix(A, name: str = "frame matrix A") -> tuple[np.ndarray, np.ndarray]:
    """Validate a frame's matrix and return it with its inverse, both float (d, d).

    Raises
    ------
    InvalidFrameError
        Text or complex entries, not square, NaN/inf, singular (condition number above
        ``MAX_CONDITION``), or a scale (singular value) outside ``MIN_SCALE .. MAX_SCALE``,
        which would make ``A^-1`` or the model's squares of it overflow.
    """
    A = check_real_array(A, name, InvalidFrameError, "a square (d, d) matrix")
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] < 1:
        raise InvalidFrameError(f"{name} must be square with shape (d, d), got shape {A.shape}")
    if not np.all(np.isfinite(A)):
        raise InvalidFrameError(f"{name} must be finite (no NaN or inf)")
    scales = np.linalg.svd(A, compute_uv=False)  # descending
    smallest, largest = float(scales[-1]), float(scales[0])
    cond = largest / smallest if smallest > 0 else np.inf
    if not np.isfinite(cond) or cond > MAX_CONDITION:
        raise InvalidFrameError(
            f"{name} is singular (condition number {cond:.3g}): its columns must "
            "be independent directions, e.g. a rotation matrix times a non-zero scale"
        )
    if smallest < MIN_SCALE or largest > MAX_SCALE:
        raise InvalidFrameError(
            f"{name} scales lengths by {smallest:.3g} .. {largest:.3g}, outside the "
            f"{MIN_SCALE:g} .. {MAX_SCALE:g} the learner can invert and square without "
            "overflow; give the frame in units where its scale is near 1 (e.g. metres)"
        )
    return A, np.linalg.inv(A)


class Frame:
    """A task frame: an invertible affine map from local to world coordinates.

    Parameters
    ----------
    A : array-like, shape (d, d)
        Invertible matrix (rotation, possibly scaled or reflected).
    b : array-like, shape (d,)
        Origin of the frame in world coordinates.

    A local point ``x`` is ``A @ x + b`` in the world. Time is never transformed.
    """

    __slots__ = ("A", "b", "A_inv")

    def __init__(self, A, b):
        A, A_inv = check_frame_matrix(A)
        b = check_real_array(b, "frame offset b", InvalidFrameError, f"{A.shape[0]} numbers")
        if b.shape != (A.shape[0],):
            raise InvalidFrameError(
                f"frame offset b must have shape ({A.shape[0]},) to match A {A.shape}, "
                f"got shape {b.shape}"
            )
        if not np.all(np.isfinite(b)):
            raise InvalidFrameError("frame offset b must be finite (no NaN or inf)")
        self.A = A
        self.b = b
        self.A_inv = A_inv
        for arr in (self.A, self.b, self.A_inv):
            arr.setflags(write=False)

    @property
    def dim(self) -> int:
        """Spatial dimension d."""
        return self.b.shape[0]

    @classmethod
    def identity(cls, dim: int) -> Frame:
        """The world frame in ``dim`` dimensions."""
        return cls(np.eye(dim), np.zeros(dim))

    @classmethod
    def from_pose(cls, position, rotation=None, scale: float = 1.0) -> Frame:
        """Frame at ``position`` (d,) with orientation ``rotation`` (d, d), default identity."""
        position = np.asarray(position, dtype=float)
        rotation = np.eye(position.shape[-1]) if rotation is None else np.asarray(rotation, float)
        return cls(scale * rotation, position)

    @classmethod
    def from_angle(cls, position, angle: float = 0.0, scale: float = 1.0) -> Frame:
        """Planar frame at ``position`` (2,) rotated by ``angle`` radians."""
        c, s = np.cos(angle), np.sin(angle)
        return cls.from_pose(position, np.array([[c, -s], [s, c]]), scale)

    def to_local(self, x):
        """Map world points ``x`` (..., d) into this frame."""
        return (np.asarray(x, dtype=float) - self.b) @ self.A_inv.T

    def to_world(self, x):
        """Map local points ``x`` (..., d) into the world."""
        return np.asarray(x, dtype=float) @ self.A.T + self.b

    def transformed(self, G, g) -> Frame:
        """This frame after the world is moved by ``x -> G @ x + g``."""
        G = np.asarray(G, dtype=float)
        return Frame(G @ self.A, G @ self.b + np.asarray(g, dtype=float))

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"A": self.A.tolist(), "b": self.b.tolist()}

    @classmethod
    def from_dict(cls, data: dict) -> Frame:
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(data["A"], data["b"])
        except (KeyError, TypeError) as exc:
            raise InvalidFrameError(f"a frame needs keys 'A' and 'b', got {data!r}") from exc

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, Frame)
            and np.array_equal(self.A, other.A)
            and np.array_equal(self.b, other.b)
        )

    __hash__ = None

    def __repr__(self) -> str:
        return f"Frame(A={self.A.tolist()}, b={self.b.tolist()})"


@dataclass(frozen=True)
class FrameBatch:
    """Frames of B task conditions stacked as arrays, for vectorised reproduction.

    Attributes
    ----------
    A, A_inv : ndarray, shape (B, P, d, d)
    b : ndarray, shape (B, P, d)
    """

    A: np.ndarray
    A_inv: np.ndarray
    b: np.ndarray

    @classmethod
    def from_frames(cls, frames_batch) -> FrameBatch:
        """Stack a sequence of B sequences of P :class:`Frame` objects."""
        if isinstance(frames_batch, FrameBatch):
            return frames_batch
        rows = [check_frame_row(row, f"frames_batch[{i}]") for i, row in enumerate(frames_batch)]
        if not rows:
            raise InvalidFrameError("frames_batch is empty: give at least one set of frames")
        n_frames = {len(r) for r in rows}
        dims = {f.dim for r in rows for f in r}
        if len(n_frames) != 1 or len(dims) != 1:
            raise InvalidFrameError(
                "every task condition needs the same number of frames of the same dimension; "
                f"got frame counts {sorted(n_frames)} and dimensions {sorted(dims)}"
            )
        A = np.array([[f.A for f in r] for r in rows])
        A_inv = np.array([[f.A_inv for f in r] for r in rows])
        b = np.array([[f.b for f in r] for r in rows])
        return cls(A, A_inv, b)

    def __len__(self) -> int:
        return self.b.shape[0]

    @property
    def n_frames(self) -> int:
        return self.b.shape[1]

    @property
    def dim(self) -> int:
        return self.b.shape[2]

    def __getitem__(self, index) -> FrameBatch:
        index = np.atleast_1d(np.arange(len(self))[index])
        return FrameBatch(self.A[index], self.A_inv[index], self.b[index])


def check_frame_row(row, name: str) -> list[Frame]:
    if isinstance(row, Frame):
        raise InvalidFrameError(
            f"{name} is a single Frame; give a sequence of frames (one per task parameter)"
        )
    try:
        row = list(row)
    except TypeError as exc:
        raise InvalidFrameError(f"{name} must be a sequence of Frame objects") from exc
    if not row:
        raise InvalidFrameError(f"{name} is empty: a task condition needs at least one frame")
    for j, f in enumerate(row):
        if not isinstance(f, Frame):
            raise InvalidFrameError(
                f"{name}[{j}] is a {type(f).__name__}, not a Frame; build it with Frame(A, b)"
            )
    return row
