r"""Task-parameterised Gaussian mixture model with regression over time (TP-GMM/GMR).

This is the learning function :math:`\lambda` of Sena & Howard ("Quantifying
Teaching Behaviour in Robot Learning from Demonstration", section "Learning and
Teaching Framework"): it maps the demonstration set :math:`b_m` to a policy
:math:`\pi = \lambda(b_m)`. Running that policy under a new task condition
(:meth:`TPGMM.reproduce`) is the realisation function :math:`\Lambda`. The model
follows Calinon (2016), "A tutorial on task-parameterized movement learning and
retrieval", Intelligent Service Robotics 9(1).

Notation
--------
d
    Spatial dimension (2 for the maze; 3 or more for an arm with a gripper column).
D = 1 + d
    State dimension; a state is :math:`\xi = (t, x)` with time first.
P
    Number of task frames. Frame :math:`j` is an affine map :math:`(A_j, b_j)`:
    a local point :math:`x^{(j)}` is :math:`A_j x^{(j)} + b_j` in the world, so
    :math:`x^{(j)} = A_j^{-1}(x - b_j)`. Time is never transformed.
K
    Number of Gaussian components; component :math:`k` has a prior
    :math:`\pi_k` and, in every frame :math:`j`, a mean :math:`\mu_k^{(j)}` and
    covariance :math:`\Sigma_k^{(j)}` over the local state.
M, T_m, N
    Number of demonstrations, samples in demonstration m, total samples.

The likelihood of a sample is
:math:`\sum_k \pi_k \prod_j \mathcal N(\xi^{(j)} | \mu_k^{(j)}, \Sigma_k^{(j)})`.

Reproduction regresses over time *in each frame first* (Gaussian mixture
regression gives a local Gaussian :math:`\mathcal N(m^{(j)}(t), S^{(j)}(t))`),
maps each to the world with the new frames (mean :math:`A m + b`, covariance
:math:`A S A^\top`) and then takes the product of the P Gaussians at every time
step (PbDlib's ``demo_TPGMR01``). Taking the product of the components first
lets components slide along time and misses start points when demos are few.

Implementation notes
--------------------
* Each frame's local data are standardised (per dimension) before EM, so that
  ``reg_covar`` is a variance *relative to the data's spread*, in any units.
* EM works on sufficient statistics: with quadratic features
  :math:`\phi(u) = (u_i u_j)_{i \le j} \Vert u \Vert 1` of the standardised
  local states, the E-step is one matrix product ``Phi @ W`` and the M-step is
  one matrix product ``gamma.T @ Phi``; all in log space.
* Covariances get a fixed improper inverse-Wishart prior
  :math:`p(\Sigma) \propto \exp(-\tfrac12 \operatorname{tr}(\psi \Sigma^{-1}))`,
  so the M-step is :math:`\Sigma_k = (S_k + \psi I) / N_k` and EM provably never
  decreases the penalised log-likelihood it reports in ``lower_bound_``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import (
    DemoFrameMismatchError,
    InvalidDemoError,
    InvalidFrameError,
    InvalidParameterError,
    NotFittedError,
    TooFewSamplesError,
)

__all__ = [
    "Frame",
    "FrameBatch",
    "TPGMM",
    "check_demo",
    "check_times",
]

_LOG_2PI = np.log(2.0 * np.pi)
_MAX_CONDITION = 1e12


# --- frames


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
        A = np.array(A, dtype=float)
        b = np.array(b, dtype=float)
        if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] < 1:
            raise InvalidFrameError(
                f"frame matrix A must be square with shape (d, d), got shape {A.shape}"
            )
        if b.shape != (A.shape[0],):
            raise InvalidFrameError(
                f"frame offset b must have shape ({A.shape[0]},) to match A {A.shape}, "
                f"got shape {b.shape}"
            )
        if not (np.all(np.isfinite(A)) and np.all(np.isfinite(b))):
            raise InvalidFrameError("frame A and b must be finite (no NaN or inf)")
        cond = np.linalg.cond(A)
        if not np.isfinite(cond) or cond > _MAX_CONDITION:
            raise InvalidFrameError(
                f"frame matrix A is singular (condition number {cond:.3g}): its columns must "
                "be independent directions, e.g. a rotation matrix times a non-zero scale"
            )
        self.A = A
        self.b = b
        self.A_inv = np.linalg.inv(A)
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
        rows = [_check_frame_row(row, f"frames_batch[{i}]") for i, row in enumerate(frames_batch)]
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


def _check_frame_row(row, name: str) -> list[Frame]:
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


# --- validators


def check_demo(demo, name: str = "demo", n_columns: int | None = None) -> np.ndarray:
    """Validate one demonstration and return it as a float array (T, 1 + d).

    Parameters
    ----------
    demo : array-like, shape (T, 1 + d)
        Column 0 is time, the rest world coordinates.
    name : str
        How to call the demo in error messages.
    n_columns : int, optional
        Required number of columns ``1 + d``.

    Raises
    ------
    InvalidDemoError
        Wrong shape, fewer than 2 samples, NaN/inf, or time not strictly increasing.
    """
    try:
        arr = np.array(demo, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidDemoError(
            f"{name} is not a numeric table; give an array of shape (T, 1 + d) "
            "with time in column 0"
        ) from exc
    if arr.ndim != 2:
        raise InvalidDemoError(
            f"{name} must be a 2-D array (T samples, 1 + d columns: time then position), "
            f"got shape {arr.shape}"
        )
    if n_columns is not None and arr.shape[1] != n_columns:
        raise InvalidDemoError(
            f"{name} has {arr.shape[1]} columns but {n_columns} are needed "
            f"(time and {n_columns - 1} coordinates); check the column order and drop extras"
        )
    if arr.shape[1] < 2:
        raise InvalidDemoError(
            f"{name} has {arr.shape[1]} column(s); it needs time plus at least one coordinate"
        )
    if arr.shape[0] < 2:
        raise InvalidDemoError(
            f"{name} has {arr.shape[0]} sample(s); a demonstration needs at least 2 "
            "(record a longer movement)"
        )
    bad = ~np.isfinite(arr).all(axis=1)
    if bad.any():
        rows = np.flatnonzero(bad)
        raise InvalidDemoError(
            f"{name} has NaN or inf in {rows.size} sample(s) (rows {_list_rows(rows)}); "
            "remove or interpolate those samples"
        )
    steps = np.diff(arr[:, 0])
    if np.any(steps <= 0):
        row = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise InvalidDemoError(
            f"time in {name} is not strictly increasing (row {row}: {arr[row - 1, 0]:g} then "
            f"{arr[row, 0]:g}); sort the samples by time and drop repeated time stamps"
        )
    return arr


def check_times(times, name: str = "times") -> np.ndarray:
    """Validate query times and return them as a float array (T,)."""
    try:
        t = np.array(times, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{name} must be a 1-D array of numbers") from exc
    if t.ndim != 1 or t.size < 1:
        raise InvalidParameterError(f"{name} must be a non-empty 1-D array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise InvalidParameterError(f"{name} contains NaN or inf")
    return t


def _list_rows(rows: np.ndarray, limit: int = 5) -> str:
    shown = ", ".join(str(int(r)) for r in rows[:limit])
    return shown + (", ..." if rows.size > limit else "")


# --- small linear algebra


def _inv(M: np.ndarray) -> np.ndarray:
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


def _sym(M: np.ndarray) -> np.ndarray:
    return 0.5 * (M + np.swapaxes(M, -1, -2))


# --- the model


class TPGMM:
    """Task-parameterised GMM with Gaussian mixture regression over time.

    Parameters
    ----------
    n_components : int, default 3
        Number of Gaussian components K.
    reg_covar : float, default 1e-3
        Regularisation, as a variance relative to each frame's data spread
        (1e-3 is a standard deviation of about 3 % of the spread). It is the
        strength of the covariance prior for a component that holds an average
        share N/K of the samples.
    tol : float, default 1e-5
        EM stops when the penalised mean log-likelihood per sample improves by
        less than ``tol`` in one iteration.
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
        reg_covar: float = 1e-3,
        tol: float = 1e-5,
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
        loc, scale = _standardisation(data.local)
        U = (data.local - loc[:, None, :]) / scale[:, None, :]
        em = _EM(U, K, self.reg_covar)

        if self.warm_start and self._is_compatible(data):
            gamma_params = self._standardised_params(loc, scale)
        else:
            gamma_params = em.m_step(self._initial_responsibilities(data, U))

        weights, means, covs, lb, n_iter, converged = em.run(gamma_params, self.tol, self.max_iter)
        self.weights_ = weights
        self.means_ = loc[:, None, :] + means * scale[:, None, :]
        self.covariances_ = covs * scale[:, None, :, None] * scale[:, None, None, :]
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
        return float(np.mean(_logsumexp(log_resp, axis=1)))

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
        return mean[0], cov[0]

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
        return _product_of_frames(batch, L, Lm)

    def regress_local(self, times):
        """Gaussian mixture regression over time in each frame (local coordinates).

        Returns
        -------
        mean : ndarray (P, T, d)
        cov : ndarray (P, T, d, d)
        """
        self._check_fitted()
        return _gmr(self.weights_, self.means_, self.covariances_, check_times(times))

    # ---------------------------------------------------------------- internals

    def _check_params(self):
        K = self.n_components
        if not isinstance(K, (int, np.integer)) or K < 1:
            raise InvalidParameterError(f"n_components must be a positive integer, got {K!r}")
        if not (np.isfinite(self.reg_covar) and self.reg_covar > 0):
            raise InvalidParameterError(
                f"reg_covar must be a positive number, got {self.reg_covar!r}"
            )
        if not (np.isfinite(self.tol) and self.tol >= 0):
            raise InvalidParameterError(f"tol must be >= 0, got {self.tol!r}")
        if not isinstance(self.max_iter, (int, np.integer)) or self.max_iter < 1:
            raise InvalidParameterError(
                f"max_iter must be a positive integer, got {self.max_iter!r}"
            )
        if self.init_params not in ("time", "random"):
            raise InvalidParameterError(
                f"init_params must be 'time' or 'random', got {self.init_params!r}"
            )

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
        return np.log(self.weights_) - 0.5 * (maha + logdet + P * D * _LOG_2PI)

    def _local_gmr(self, t):
        key = t.tobytes()
        cached = self._gmr_cache.get(key)
        if cached is None:
            mean, cov = _gmr(self.weights_, self.means_, self.covariances_, t)
            L = _sym(_inv(cov))
            Lm = np.einsum("ptij,ptj->pti", L, mean)
            cached = (L, Lm)
            if len(self._gmr_cache) > 16:
                self._gmr_cache.clear()
            self._gmr_cache[key] = cached
        return cached


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
    rows = [_check_frame_row(row, f"frames[{m}]") for m, row in enumerate(frames)]
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


# --- EM on sufficient statistics


class _EM:
    """EM for the TP-GMM on standardised local data U (P, N, D)."""

    def __init__(self, U: np.ndarray, K: int, reg_covar: float):
        P, N, D = U.shape
        self.P, self.N, self.D, self.K = P, N, D, K
        self.iu = np.triu_indices(D)
        self.n_quad = len(self.iu[0])
        quad = U[:, :, self.iu[0]] * U[:, :, self.iu[1]]  # (P, N, Dq)
        feats = np.concatenate([quad, U], axis=2)  # (P, N, Dq + D)
        self.Phi = np.concatenate(
            [feats.transpose(1, 0, 2).reshape(N, -1), np.ones((N, 1))], axis=1
        )  # (N, F)
        self.PhiT = np.ascontiguousarray(self.Phi.T)  # (F, N): E-step reductions run along N
        self.psi = reg_covar * N / K
        self.quad_factor = np.where(self.iu[0] == self.iu[1], -0.5, -1.0)

    def m_step(self, resp: np.ndarray):
        """Parameters from responsibilities ``resp`` (K, N)."""
        return self.params(resp @ self.Phi)

    def params(self, S: np.ndarray):
        """Weights (K,), means (P, K, D), covariances (P, K, D, D) from statistics S (K, F).

        Raises ``_Infeasible`` when extrapolated statistics give no valid mixture.
        """
        P, D, K = self.P, self.D, self.K
        Nk = S[:, -1]
        if np.any(Nk < 0) or not np.all(np.isfinite(S)):
            raise _Infeasible
        feats = S[:, :-1].reshape(K, P, self.n_quad + D)
        Nk_safe = np.maximum(Nk, 1e-10 * self.N)
        mean = feats[..., self.n_quad :] / Nk_safe[:, None, None]  # (K, P, D)
        second = np.empty((K, P, D, D))
        second[..., self.iu[0], self.iu[1]] = feats[..., : self.n_quad]
        second[..., self.iu[1], self.iu[0]] = feats[..., : self.n_quad]
        scatter = second - Nk[:, None, None, None] * mean[..., :, None] * mean[..., None, :]
        cov = (scatter + self.psi * np.eye(D)) / Nk_safe[:, None, None, None]
        return Nk / self.N, mean.transpose(1, 0, 2), _sym(cov).transpose(1, 0, 2, 3)

    def e_step(self, params):
        """Objective at ``params`` and the sufficient statistics of the next M-step."""
        weights, mean, cov = params
        try:
            chol = np.linalg.cholesky(cov)
        except np.linalg.LinAlgError:
            raise _Infeasible from None
        prec = _sym(np.linalg.inv(cov))  # (P, K, D, D)
        logdet = 2.0 * np.log(np.diagonal(chol, axis1=-2, axis2=-1)).sum(-1)  # (P, K)
        lin = np.einsum("pkij,pkj->pki", prec, mean)
        quad = prec[..., self.iu[0], self.iu[1]] * self.quad_factor
        const = -0.5 * (np.einsum("pki,pki->pk", lin, mean) + logdet + self.D * _LOG_2PI)
        W = np.concatenate([quad, lin], axis=2).transpose(1, 0, 2).reshape(self.K, -1)
        const_k = const.sum(0) + np.log(np.maximum(weights, 1e-300))
        W = np.hstack([W, const_k[:, None]])  # W @ PhiT = log pi_k + sum_j log N_j
        log_prior = -0.5 * self.psi * np.trace(prec, axis1=-2, axis2=-1).sum()

        resp = W @ self.PhiT  # (K, N) log joint, turned into responsibilities in place
        top = resp.max(axis=0)
        np.subtract(resp, top, out=resp)
        # exp(-100) ~ 4e-44 is already nothing next to the top term (1); clipping keeps
        # exp and the next product away from subnormal numbers, which are 10x slower
        np.maximum(resp, -100.0, out=resp)
        np.exp(resp, out=resp)
        total = resp.sum(axis=0)
        objective = (np.log(total).sum() + top.sum() + log_prior) / self.N
        np.divide(resp, total, out=resp)
        return float(objective), resp @ self.Phi

    def run(self, params, tol: float, max_iter: int):
        """EM accelerated by SQUAREM (Varadhan & Roland 2008) on the sufficient statistics.

        Each cycle takes two EM steps S0 -> S1 -> S2, extrapolates along them and
        keeps the extrapolated point only if its objective beats the plain EM
        step, so the objective never decreases. Stops when one plain EM step
        gains less than ``tol``; ``n_iter`` counts E-steps.
        """
        obj0, S1 = self.e_step(params)
        S0 = None
        n_iter, converged = 1, False
        best = (params, obj0)
        while n_iter < max_iter:
            params1 = self.params(S1)
            obj1, S2 = self.e_step(params1)
            n_iter += 1
            best = (params1, obj1)
            if obj1 - obj0 < tol:
                converged = True
                break
            if S0 is None or n_iter >= max_iter:
                S0, obj0, S1 = S1, obj1, S2
                continue
            r = S1 - S0
            v = S2 - 2.0 * S1 + S0
            alpha = -np.sqrt((r * r).sum() / max((v * v).sum(), 1e-300))
            if alpha < -1.0:
                try:
                    params_x = self.params(S0 - 2.0 * alpha * r + alpha * alpha * v)
                    obj_x, S_x = self.e_step(params_x)
                    n_iter += 1
                    if obj_x >= obj1:
                        best = (params_x, obj_x)
                        S0, obj0, S1 = None, obj_x, S_x
                        continue
                except _Infeasible:
                    pass
            S0, obj0, S1 = S1, obj1, S2
        (weights, mean, cov), objective = best
        return weights, mean, cov, objective, n_iter, converged


class _Infeasible(Exception):
    """Extrapolated statistics that describe no valid mixture."""


def _logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    m = a.max(axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    return np.log(np.exp(a - m).sum(axis=axis)) + np.squeeze(m, axis=axis)


# --- regression and product


def _gmr(weights, means, covs, t):
    """GMR over time in every frame: means (P, T, d), covariances (P, T, d, d)."""
    mu_t = means[0, :, 0]  # (K,) time is identical in every frame
    var_t = covs[0, :, 0, 0]
    log_h = (
        np.log(np.maximum(weights, 1e-300))
        - 0.5 * (np.log(var_t) + _LOG_2PI)
        - 0.5 * (t[:, None] - mu_t) ** 2 / var_t
    )  # (T, K)
    h = np.exp(log_h - _logsumexp(log_h, axis=1)[:, None])
    slope = covs[:, :, 1:, 0] / covs[:, :, :1, 0]  # (P, K, d)
    cond_cov = covs[:, :, 1:, 1:] - slope[..., :, None] * covs[:, :, None, 0, 1:]  # (P, K, d, d)
    m_k = means[:, None, :, 1:] + slope[:, None] * (
        t[None, :, None, None] - mu_t[None, None, :, None]
    )
    mean = np.einsum("tk,ptkd->ptd", h, m_k)
    second = np.einsum("tk,pkij->ptij", h, cond_cov) + np.einsum("tk,ptki,ptkj->ptij", h, m_k, m_k)
    cov = second - mean[..., :, None] * mean[..., None, :]
    return mean, _sym(cov)


def _product_of_frames(batch: FrameBatch, L: np.ndarray, Lm: np.ndarray):
    """Product over frames of the world Gaussians, for B conditions at T times.

    ``L`` (P, T, d, d) and ``Lm`` (P, T, d) are the local GMR precisions and
    precision-weighted means. With ``W = A^-1`` the world precision of frame j is
    ``W^T L W`` and its precision-weighted mean ``W^T (L m) + W^T L (W b)``.
    """
    W = batch.A_inv  # (B, P, d, d)
    B, P, d, _ = W.shape
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
    cov = _sym(_inv(prec))
    mean = np.einsum("btij,btj->bti", cov, eta)
    return mean, cov
