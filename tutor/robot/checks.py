"""Validators of the robot's inputs: vectors, rotations, tool paths and hand commands.

Each returns the input as a float array of the right shape or raises
:class:`~tutor.errors.InvalidParameterError` saying what was wrong.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["check_vector", "check_rotation", "check_paths"]


def check_vector(x, n: int, what: str) -> np.ndarray:
    """``x`` as a finite float array of shape (n,), or a named error."""
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{what} must be {n} numbers, got {x!r}") from exc
    if a.shape != (n,):
        raise InvalidParameterError(f"{what} must have shape ({n},), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InvalidParameterError(f"{what} must be finite, got {a}")
    return a


def check_rotation(R) -> np.ndarray:
    """``R`` as a finite 3 x 3 rotation matrix (orthonormal, det +1), or a named error."""
    try:
        a = np.asarray(R, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"rotation must be a 3 x 3 matrix, got {R!r}") from exc
    if a.shape != (3, 3) or not np.all(np.isfinite(a)):
        raise InvalidParameterError(f"rotation must be a finite 3 x 3 matrix, got shape {a.shape}")
    if np.abs(a.T @ a - np.eye(3)).max() > 1e-6 or np.linalg.det(a) < 0:
        raise InvalidParameterError("rotation must be a rotation matrix (orthonormal, det +1)")
    return a


def check_paths(points, gripper=None) -> tuple[np.ndarray, np.ndarray]:
    """Validate tool paths and their hand commands.

    Parameters
    ----------
    points : array_like (..., T, 3)
        Tool positions (m).
    gripper : array_like broadcastable to (..., T), optional
        Hand command per sample, 0 open .. 1 closed (default open).

    Returns
    -------
    points : ndarray (..., T, 3) of float
    gripper : ndarray (..., T) of float

    Raises
    ------
    InvalidParameterError
        Wrong shapes or values that are not numbers.
    """
    try:
        P = np.asarray(points, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError("points must be numbers of shape (..., T, 3)") from exc
    if P.ndim < 2 or P.shape[-1] != 3:
        raise InvalidParameterError(f"points must have shape (..., T, 3), got {P.shape}")
    if gripper is None:
        return P, np.zeros(P.shape[:-1])
    try:
        G = np.broadcast_to(np.asarray(gripper, dtype=float), P.shape[:-1])
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(
            f"gripper must have shape {P.shape[:-1]} like the points, got {np.shape(gripper)}"
        ) from exc
    return P, G
