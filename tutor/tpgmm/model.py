"""The TP-GMM learner itself: fit (EM), score, and reproduce under new frames."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import (
    DemoFrameMismatchError,
    InvalidDemoError,
    NotFittedError,
    TooFewSamplesError,
)
from .checks import (
    check_choice,
    check_count,
    check_demo,
    check_flag,
    check_number,
    check_seed,
    check_times,
)
from .em import EM, Infeasible
from .frames import FrameBatch, check_frame_row
from .linalg import LOG_2PI, inv_small, logsumexp, sym
from .regression import gmr, product_of_frames

__all__ = ["TPGMM"]


class TPGMM:
    """Task-parameterised GMM with Gaussian mixture regression over time.

    Parameters
    ----------
    n_components : int, default 3
        Number of Gaussian components K.
    reg_covar : float, default 3e-5
        Regularisation, as a variance relative to each frame's data spread
        (3e-5 is a standard deviation of about 0.5 % of the spread). It is the
        strength of the covariance prior for a component that holds an average
        share N/K of the samples.

        The spread is that of the whole movement in the frame, while what matters
        most is the spread at the frame's own end of the movement, which is far
        smaller. On maze-like data (start-frame spread 5.5 x 9.3 cm) the former
        default 1e-3 added 1.9-2.8 mm of standard deviation to the start frame at
        t = 0 (the demos themselves: about 0.5 mm), so the three world-fixed frames
        pulled every reproduction off its start point: 3-6 mm worst start error at
        M = 8-12 demos and 1.3 mm at the target, against 0.3 mm for a plain TP-GMR
        (``tests/test_learner_parity.py``). EM to tol 1e-9 changed nothing (the
        same errors), and with reg_covar 1e-6 the learner matched the plain TP-GMR
        to 0.1 mm, so neither early stopping nor the initialisation was the cause.
        3e-5 keeps parity (about 0.6 mm) while keeping the warm refits short and
        two-demo generalisation as before (smaller values cost both).
    tol : float, default 1e-3
        EM stops when the penalised mean log-likelihood per sample improves by
        less than ``tol`` in one iteration (scikit-learn's ``GaussianMixture``
        convention and default). On maze-shaped data (``benchmarks/bench_tpgmm.py``'s
        demo sets) 1e-5 took 51 / 68 iterations at M = 5 / 20 for the same medians of
        worst start and end errors within 0.1 mm at M = 20 (0.6 / 0.5 mm); 1e-3 takes
        28 / 13 and is what brings a cold fit at M = 20 under 15 ms. Parity with a plain
        TP-GMR run to 1e-9 is tested at M = 3, 5, 8 and 12.
    max_iter : int, default 1000
        Maximum number of EM iterations.
    warm_start : bool, default False
        If True, :meth:`fit` starts EM from the previous solution (adding one demo
        then refits in a few iterations).
    init_params : {"time", "random"}, default "time"
        "time": equal time bins shared by all frames; "random": random
        responsibilities drawn with ``random_state``.
    random_state : int, numpy Generator or None
        Seed for ``init_params="random"``.

    Attributes
    ----------
    weights_ : ndarray (K,)
    means_ : ndarray (P, K, 1 + d)
        In each frame's local coordinates, time first.
    covariances_ : ndarray (P, K, 1 + d, 1 + d)
    converged_ : bool
    n_iter_ : int
    lower_bound_ : float
        Mean log-likelihood per training sample, penalised by the covariance
        prior's log density (divided by N): the quantity EM never decreases.
    n_frames_, n_features_ : int
        P and d seen in :meth:`fit`.
    """

    def __init__(
        self,
        n_components: int = 3,
        reg_covar: float = 3e-5,
        tol: float = 3e-4,
        max_iter: int = 1000,
        warm_start: bool = False,
        init_params: str = "time",
        random_state=None,
    ):
        self.n_components = n_components
        self.reg_covar = reg_covar
        self.tol = tol
        self.max_iter = max_iter
        self.warm_start = warm_start
        self.init_params = init_params
        self.random_state = random_state
        self._check_params()

    # ---------------------------------------------------------------- public API

    def fit(self, demos, frames) -> TPGMM:
        """Fit the model to demonstrations given under their task frames.

        Parameters
        ----------
        demos : sequence of M arrays (T_m, 1 + d)
            Column 0 time, the rest world coordinates; lengths may differ.
        frames : sequence of M sequences of P :class:`Frame`
            The task parameters each demonstration was given under.

        Returns
        -------
        self
        """
        self._check_params()
        data = _prepare(demos, frames)
        K = self.n_components
        n_samples = data.local.shape[1]
        if n_samples < K:
            raise TooFewSamplesError(
                f"{K} components need at least {K} samples but the demos hold {n_samples}; "
                "give more or longer demos, or lower n_components"
            )
        with np.errstate(over="ignore", invalid="ignore"):
            loc, scale = _standardisation(data.local)
        if not (np.all(np.isfinite(scale)) and np.all(np.isfinite(loc))):
            raise _too_large()
        U = (data.local - loc[:, None, :]) / scale[:, None, :]
        em = EM(U, K, self.reg_covar)

        try:
            if self.warm_start and self._is_compatible(data):
                # a sample is explained if its log density is within two nats per
                # dimension of the previous fit's mean (both in the new standardised
                # units); one nat flagged ordinary new demos too and doubled the warm
                # refit's iterations
                P, D = scale.shape
                floor = self.lower_bound_ + float(np.log(scale).sum()) - 2 * P * D
                previous = self._standardised_params(loc, scale)
                resp = em.warm_responsibilities(previous, floor)
            else:
                resp = self._initial_responsibilities(data, U)
            weights, means, covs, lb, n_iter, converged = em.run(
                em.m_step(resp), self.tol, self.max_iter
            )
        except Infeasible:  # no valid mixture from the start: only overflowing data does it
            raise _too_large() from None
        with np.errstate(over="ignore", invalid="ignore"):
            covariances = covs * scale[:, None, :, None] * scale[:, None, None, :]
        if not np.all(np.isfinite(covariances)):
            raise _too_large()
        self.weights_ = weights
        self.means_ = loc[:, None, :] + means * scale[:, None, :]
        self.covariances_ = covariances
        self.lower_bound_ = lb - float(np.log(scale).sum())
        self.n_iter_ = n_iter
        self.converged_ = converged
        self.n_frames_ = data.local.shape[0]
        self.n_features_ = data.local.shape[2] - 1
        self._gmr_cache = {}
        return self

    def score(self, demos, frames) -> float:
        """Mean log-likelihood per sample of ``demos`` under ``frames`` (no prior term)."""
        self._check_fitted()
        data = _prepare(demos, frames, self.n_features_, self.n_frames_)
        log_resp = self._log_joint(data.local)
        return float(np.mean(logsumexp(log_resp, axis=1)))

    def reproduce(self, frames, times):
        """Reproduce the task under one new set of P frames.

        Parameters
        ----------
        frames : sequence of P :class:`Frame`
        times : array-like (T,)

        Returns
        -------
        mean : ndarray (T, d)
        cov : ndarray (T, d, d)
        """
        mean, cov = self.reproduce_batch([frames], times)
        return mean[0], np.array(cov[0])

    def reproduce_batch(self, frames_batch, times):
        """Reproduce the task under B task conditions at once.

        Parameters
        ----------
        frames_batch : sequence of B sequences of P :class:`Frame`, or :class:`FrameBatch`
        times : array-like (T,)

        Returns
        -------
        mean : ndarray (B, T, d)
        cov : ndarray (B, T, d, d)
            Read-only when every task condition has the same frame rotations: then it
            is one covariance per time step shared by all B (a view; copy to write).
        """
        self._check_fitted()
        batch = FrameBatch.from_frames(frames_batch)
        if batch.n_frames != self.n_frames_ or batch.dim != self.n_features_:
            raise DemoFrameMismatchError(
                f"the model was fitted with {self.n_frames_} frames in {self.n_features_}-D but "
                f"reproduction got {batch.n_frames} frames in {batch.dim}-D; give frames of the "
                "same kind and order as in fit"
            )
        t = check_times(times)
        L, Lm = self._local_gmr(t)
        return product_of_frames(batch, L, Lm)

    def regress_local(self, times):
        """Gaussian mixture regression over time in each frame (local coordinates).

        Returns
        -------
        mean : ndarray (P, T, d)
        cov : ndarray (P, T, d, d)
        """
        self._check_fitted()
        return gmr(self.weights_, self.means_, self.covariances_, check_times(times))

    # ---------------------------------------------------------------- internals

    def _check_params(self):
        """Validate the settings (each by its ``check_*``); raise InvalidParameterError."""
        check_count(self.n_components, "n_components")
        check_number(self.reg_covar, "reg_covar", strict=True)
        check_number(self.tol, "tol")
        check_count(self.max_iter, "max_iter")
        check_flag(self.warm_start, "warm_start")
        check_choice(self.init_params, "init_params", ("time", "random"))
        check_seed(self.random_state)

    def _check_fitted(self):
        if not hasattr(self, "weights_"):
            raise NotFittedError(
                "this TPGMM is not fitted yet: call fit(demos, frames) before reproducing"
            )

    def _is_compatible(self, data) -> bool:
        return (
            hasattr(self, "weights_")
            and self.weights_.shape[0] == self.n_components
            and self.means_.shape[0] == data.local.shape[0]
            and self.means_.shape[2] == data.local.shape[2]
        )

    def _standardised_params(self, loc, scale):
        means = (self.means_ - loc[:, None, :]) / scale[:, None, :]
        covs = self.covariances_ / (scale[:, None, :, None] * scale[:, None, None, :])
        return self.weights_.copy(), means, covs

    def _initial_responsibilities(self, data, U):
        N, K = U.shape[1], self.n_components
        if self.init_params == "random":
            rng = np.random.default_rng(self.random_state)
            return rng.dirichlet(np.ones(K), size=N).T
        t = data.time
        edges = np.linspace(t.min(), t.max(), K + 1)
        labels = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, K - 1)
        if np.bincount(labels, minlength=K).min() == 0:  # uneven sampling: equal-count bins
            labels = np.minimum(np.argsort(np.argsort(t, kind="stable")) * K // N, K - 1)
        resp = np.zeros((K, N))
        resp[labels, np.arange(N)] = 1.0
        return resp

    def _log_joint(self, local):
        """log pi_k + sum_j log N(xi^(j) | mu_k^(j), Sigma_k^(j)), shape (N, K)."""
        diff = local[:, None, :, :] - self.means_[:, :, None, :]  # (P, K, N, D)
        chol = np.linalg.cholesky(self.covariances_)
        sol = np.linalg.solve(chol[:, :, None], diff[..., None])[..., 0]
        maha = np.einsum("pknd,pknd->nk", sol, sol)
        logdet = 2.0 * np.log(np.diagonal(chol, axis1=-2, axis2=-1)).sum(axis=(-1, 0))
        D, P = local.shape[2], local.shape[0]
        return np.log(self.weights_) - 0.5 * (maha + logdet + P * D * LOG_2PI)

    def _local_gmr(self, t):
        key = t.tobytes()
        cached = self._gmr_cache.get(key)
        if cached is None:
            mean, cov = gmr(self.weights_, self.means_, self.covariances_, t)
            L = sym(inv_small(cov))
            Lm = np.einsum("ptij,ptj->pti", L, mean)
            cached = (L, Lm)
            if len(self._gmr_cache) > 16:
                self._gmr_cache.clear()
            self._gmr_cache[key] = cached
        return cached


def _too_large() -> InvalidDemoError:
    return InvalidDemoError(
        "the demonstrations' coordinates are too large to fit a model to (their squares "
        "overflow double precision, beyond about 1e150); give them in units where they "
        "are moderate numbers, e.g. metres or centimetres"
    )


# --- data preparation


@dataclass
class _Data:
    local: np.ndarray  # (P, N, D) states in every frame, time first
    time: np.ndarray  # (N,)


def _prepare(demos, frames, dim: int | None = None, n_frames: int | None = None) -> _Data:
    """Validate demos and frames and project every sample into every frame."""
    if isinstance(demos, np.ndarray) and demos.ndim == 2:
        raise InvalidDemoError(
            "demos must be a sequence of demonstrations; wrap a single demo in a list: [demo]"
        )
    try:
        demos = list(demos)
        frames = list(frames)
    except TypeError as exc:
        raise InvalidDemoError(
            "demos and frames must both be sequences (one entry per demo)"
        ) from exc
    if not demos:
        raise InvalidDemoError("no demonstrations given; give at least one")
    if len(demos) != len(frames):
        raise DemoFrameMismatchError(
            f"got {len(demos)} demos but {len(frames)} sets of frames; every demo needs "
            "exactly one set of task frames (the conditions it was given under)"
        )
    rows = [check_frame_row(row, f"frames[{m}]") for m, row in enumerate(frames)]
    P = len(rows[0]) if n_frames is None else n_frames
    d = rows[0][0].dim if dim is None else dim
    for m, row in enumerate(rows):
        if len(row) != P or any(f.dim != d for f in row):
            raise DemoFrameMismatchError(
                f"frames[{m}] has {len(row)} frames of dimension {[f.dim for f in row]} but "
                f"{P} frames of dimension {d} are expected; every demo needs the same frames"
            )
    arrays = [check_demo(x, f"demo {m}", n_columns=1 + d) for m, x in enumerate(demos)]
    lengths = np.array([a.shape[0] for a in arrays])
    stacked = np.concatenate(arrays)
    group = np.repeat(np.arange(len(arrays)), lengths)
    A_inv = np.array([[f.A_inv for f in row] for row in rows])  # (M, P, d, d)
    b = np.array([[f.b for f in row] for row in rows])  # (M, P, d)
    x = stacked[:, 1:]
    local_x = np.einsum("npij,npj->pni", A_inv[group], x[:, None, :] - b[group])  # (P, N, d)
    time = stacked[:, 0]
    local = np.concatenate([np.broadcast_to(time, (P, time.size))[..., None], local_x], axis=2)
    return _Data(local=local, time=time)


def _standardisation(local: np.ndarray):
    """Per-frame, per-dimension location and scale (P, D); degenerate dims fall back."""
    loc = local.mean(axis=1)
    scale = local.std(axis=1)
    P, D = scale.shape
    for j in range(P):
        ok = scale[j] > 1e-9 * max(1.0, float(np.abs(loc[j]).max()))
        fallback = float(np.exp(np.log(scale[j][ok]).mean())) if ok.any() else 1.0
        scale[j][~ok] = fallback
    return loc, scale
