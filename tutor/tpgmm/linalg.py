"""Small linear algebra shared by EM, regression and the model."""

from __future__ import annotations

import numpy as np

__all__ = ["LOG_2PI", "inv_small", "sym", "logsumexp"]

LOG_2PI = float(np.log(2.0 * np.pi))


def inv_small(M: np.ndarray) -> np.ndarray:
    """Inverse of a stack of small matrices (..., n, n); closed form for n <= 2."""
    n = M.shape[-1]
    if n == 1:
        return 1.0 / M
    if n == 2:
        a, b, c, d = M[..., 0, 0], M[..., 0, 1], M[..., 1, 0], M[..., 1, 1]
        det = a * d - b * c
        out = np.empty_like(M)
        out[..., 0, 0] = d / det
        out[..., 0, 1] = -b / det
        out[..., 1, 0] = -c / det
        out[..., 1, 1] = a / det
        return out
    return np.linalg.inv(M)


def sym(M: np.ndarray) -> np.ndarray:
    return 0.5 * (M + np.swapaxes(M, -1, -2))


def logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    m = a.max(axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    return np.log(np.exp(a - m).sum(axis=axis)) + np.squeeze(m, axis=axis)
