r"""Each frame's own view of a reproduction, mapped into the world, and how much they disagree.

Reproduction (:meth:`TPGMM.reproduce_batch`) regresses over time in every frame
:math:`j` (a local Gaussian :math:`\mathcal N(m_j(t), S_j(t))`), maps each into the
world with the condition's frames,

.. math::

    \xi_j(t) = A_j m_j(t) + b_j, \qquad \Sigma_j(t) = A_j S_j(t) A_j^\top,

and takes their product, whose mean is :math:`\mu(t)`. Where the frames agree the
product is a compromise nobody objects to; where they disagree (a condition unlike the
demonstrated ones, so that the frame of the target and the fixed frames pull apart) at
least one frame's prediction is far, in its own covariance, from the product. The
*frame disagreement* of a condition measures that:

.. math::

    D = \frac{1}{T} \sum_{t=1}^{T} \sum_{j=1}^{P}
        (\xi_j(t) - \mu(t))^\top \Sigma_j(t)^{-1} (\xi_j(t) - \mu(t)).

It is computed in each frame's local coordinates, where it is the same number
(:math:`\Sigma_j^{-1} = A_j^{-\top} S_j^{-1} A_j^{-1}`):
:math:`(m_j - A_j^{-1}(\mu - b_j))^\top S_j^{-1} (m_j - A_j^{-1}(\mu - b_j))`.
:math:`D = 0` for a single frame, and for frames that coincide.
"""

from __future__ import annotations

import numpy as np

from ..errors import DemoFrameMismatchError, InvalidParameterError
from .frames import FrameBatch
from .linalg import inv_small, sym

__all__ = ["frame_views", "frame_disagreement"]


def frame_views(model, frames_batch, times):
    r"""Every frame's regression mapped into the world, for B conditions.

    Parameters
    ----------
    model : TPGMM
        A fitted model.
    frames_batch : sequence of B sequences of P :class:`Frame`, or :class:`FrameBatch`
    times : array-like (T,)

    Returns
    -------
    means : ndarray (B, P, T, d)
        :math:`\xi_j(t) = A_j m_j(t) + b_j`.
    covs : ndarray (B, P, T, d, d)
        :math:`\Sigma_j(t) = A_j S_j(t) A_j^\top`.
    """
    batch = _batch(model, frames_batch)
    m, S = model.regress_local(times)
    A = batch.A  # (B, P, d, d)
    means = np.einsum("bpij,ptj->bpti", A, m) + batch.b[:, :, None, :]
    covs = np.einsum("bpij,ptjk,bplk->bptil", A, S, A)
    return means, sym(covs)


def frame_disagreement(model, frames_batch, times, product_mean=None) -> np.ndarray:
    r""":math:`D` (see the module docstring) of each of B conditions, shape (B,).

    Parameters
    ----------
    model : TPGMM
        A fitted model.
    frames_batch : sequence of B sequences of P :class:`Frame`, or :class:`FrameBatch`
    times : array-like (T,)
    product_mean : ndarray (B, T, d), optional
        :math:`\mu`, the product-of-frames mean of ``model.reproduce_batch(frames_batch,
        times)``, when the caller has it already (it is recomputed otherwise).
    """
    batch = _batch(model, frames_batch)
    if product_mean is None:
        product_mean, _ = model.reproduce_batch(batch, times)
    mu = np.asarray(product_mean, dtype=float)
    m, S = model.regress_local(times)
    B, P, d = len(batch), batch.n_frames, batch.dim
    T = m.shape[1]
    if mu.shape != (B, T, d):
        raise InvalidParameterError(
            f"product_mean must have shape ({B}, {T}, {d}) (conditions, times, dimensions), "
            f"got {mu.shape}; pass the mean of model.reproduce_batch(frames_batch, times)"
        )
    precision = sym(inv_small(S)).reshape(P * T, d, d)
    # mu in every frame's local coordinates, A^-1 (mu - b): (B, P, T, d)
    local_mu = (mu[:, None] - batch.b[:, :, None, :]) @ np.swapaxes(batch.A_inv, -1, -2)
    gap = (m[None] - local_mu).transpose(1, 2, 0, 3).reshape(P * T, B, d)
    maha = ((gap @ precision) * gap).sum(axis=-1)  # (P T, B): one stacked matmul
    return maha.reshape(P, T, B).sum(axis=0).mean(axis=0)


def _batch(model, frames_batch) -> FrameBatch:
    batch = FrameBatch.from_frames(frames_batch)
    model._check_fitted()
    if batch.n_frames != model.n_frames_ or batch.dim != model.n_features_:
        raise DemoFrameMismatchError(
            f"the model was fitted with {model.n_frames_} frames in {model.n_features_}-D but "
            f"got {batch.n_frames} frames in {batch.dim}-D; give frames of the same kind and "
            "order as in fit"
        )
    return batch
