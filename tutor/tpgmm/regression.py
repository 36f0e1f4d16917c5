"""Gaussian mixture regression over time in each frame, and the product over frames."""

from __future__ import annotations

import numpy as np

from .frames import FrameBatch
from .linalg import LOG_2PI, inv_small, logsumexp, sym

__all__ = ["gmr", "product_of_frames"]


def gmr(weights, means, covs, t):
    """GMR over time in every frame: means (P, T, d), covariances (P, T, d, d)."""
    mu_t = means[0, :, 0]  # (K,) time is identical in every frame
    var_t = covs[0, :, 0, 0]
    log_h = (
        np.log(np.maximum(weights, 1e-300))
        - 0.5 * (np.log(var_t) + LOG_2PI)
        - 0.5 * (t[:, None] - mu_t) ** 2 / var_t
    )  # (T, K)
    h = np.exp(log_h - logsumexp(log_h, axis=1)[:, None])
    slope = covs[:, :, 1:, 0] / covs[:, :, :1, 0]  # (P, K, d)
    cond_cov = covs[:, :, 1:, 1:] - slope[..., :, None] * covs[:, :, None, 0, 1:]  # (P, K, d, d)
    m_k = means[:, None, :, 1:] + slope[:, None] * (
        t[None, :, None, None] - mu_t[None, None, :, None]
    )
    mean = np.einsum("tk,ptkd->ptd", h, m_k)
    second = np.einsum("tk,pkij->ptij", h, cond_cov) + np.einsum("tk,ptki,ptkj->ptij", h, m_k, m_k)
    cov = second - mean[..., :, None] * mean[..., None, :]
    return mean, sym(cov)


def product_of_frames(batch: FrameBatch, L: np.ndarray, Lm: np.ndarray):
    """Product over frames of the world Gaussians, for B conditions at T times.

    ``L`` (P, T, d, d) and ``Lm`` (P, T, d) are the local GMR precisions and
    precision-weighted means. With ``W = A^-1`` the world precision of frame j is
    ``W^T L W`` and its precision-weighted mean ``W^T (L m) + W^T L (W b)``.

    When every condition has the same rotations (each frame's ``A`` is the same across
    the batch, as in both tasks, whose frames are axis aligned), the product's
    precision is one per time step, shared by all B conditions, and the mean is an
    affine map of the frame origins: it is computed so, with one inversion per time
    step instead of B (equal to the general computation to rounding), and the
    covariance returned is a read-only view of that one (B, T, d, d) whose first
    stride is 0.
    """
    W = batch.A_inv  # (B, P, d, d)
    B, P, d, _ = W.shape
    if B > 1 and np.array_equal(W, np.broadcast_to(W[:1], W.shape)):
        return _shared_rotation_product(W[0], batch.b, L, Lm)
    T = L.shape[1]
    L_flat = L.transpose(0, 2, 3, 1).reshape(P * d * d, T)  # rows (p, j, k)
    Lm_flat = Lm.transpose(0, 2, 1).reshape(P * d, T)  # rows (p, j)
    # precision: Lambda[b, i, l] = sum_{p, j, k} W[b,p,j,i] W[b,p,k,l] L[p, j, k]
    Q = np.einsum("bpji,bpkl->bilpjk", W, W).reshape(B * d * d, P * d * d)
    prec = (Q @ L_flat).reshape(B, d, d, T).transpose(0, 3, 1, 2)
    # precision-weighted mean: sum_p W^T Lm + W^T L c, c = W b
    c = np.einsum("bpkl,bpl->bpk", W, batch.b)
    R1 = W.transpose(0, 3, 1, 2).reshape(B * d, P * d)  # (b, i), (p, j)
    R2 = np.einsum("bpji,bpk->bipjk", W, c).reshape(B * d, P * d * d)
    eta = (R1 @ Lm_flat + R2 @ L_flat).reshape(B, d, T).transpose(0, 2, 1)
    cov = sym(inv_small(prec))
    mean = np.einsum("btij,btj->bti", cov, eta)
    return mean, cov


def _shared_rotation_product(W: np.ndarray, b: np.ndarray, L: np.ndarray, Lm: np.ndarray):
    """:func:`product_of_frames` when ``W`` (P, d, d) is shared by the B origins ``b``."""
    Wt = np.swapaxes(W, -1, -2)[:, None]  # (P, 1, d, d)
    world = Wt @ L @ W[:, None]  # each frame's precision in the world, (P, T, d, d)
    cov = sym(inv_small(world.sum(axis=0)))  # (T, d, d)
    base = (cov @ (Wt @ Lm[..., None]).sum(axis=0))[..., 0]  # (T, d)
    gain = cov @ world  # how each frame's origin moves the mean, (P, T, d, d)
    P, T, d, _ = gain.shape
    B = b.shape[0]
    shift = gain.transpose(1, 2, 0, 3).reshape(T * d, P * d) @ b.reshape(B, P * d).T
    mean = base[None] + shift.reshape(T, d, B).transpose(2, 0, 1)
    return mean, np.broadcast_to(cov, (B, T, d, d))  # one covariance, seen B times
