r"""EM for the TP-GMM on sufficient statistics, accelerated by SQUAREM, compiled.

The model (:mod:`tutor.tpgmm.model`) hands EM the standardised local data; see the
package docstring for the features, the covariance prior and why EM never decreases
the objective.

With the quadratic features :math:`\phi(u)` of every frame's local state stacked in
``Phi`` (N, F), one iteration is

.. math::

    \log p(k, u_n) = W_k^\top \phi_n, \qquad
    \gamma_{kn} = \frac{\exp \log p(k, u_n)}{\sum_l \exp \log p(l, u_n)}, \qquad
    S = \gamma\, \Phi,

where :math:`W_k` holds, for each frame, :math:`-\tfrac12 \Sigma_k^{-1}` (its upper
triangle, off-diagonal terms doubled), :math:`\Sigma_k^{-1} \mu_k` and the constant
:math:`\log \pi_k - \tfrac12 \sum_j (\mu_k^\top \Sigma_k^{-1} \mu_k + \log|2\pi\Sigma_k|)`;
the M-step reads weights, means and covariances off :math:`S`.

The iteration is compiled with numba: a fit is 10-60 iterations on a few hundred to a
few thousand samples, where numpy's cost per call (about half of each iteration,
measured on the adaptive study's fits) outweighed the arithmetic. The two products
with ``Phi`` are BLAS calls; the small factorisations (one Cholesky factor per
component and frame, D <= 5) are written out; the passes over (K, N) run along memory
with an exp written in plain arithmetic, so they vectorise. Features that are the same
in every frame (those of time, which no frame transforms) are kept once in ``Phi``,
with their weights summed over the frames: the same model, a sixth fewer columns on
the maze.
"""

from __future__ import annotations

import numpy as np

from ..compiled import compiled
from .linalg import LOG_2PI

__all__ = ["EM", "Infeasible"]


class EM:
    """EM for the TP-GMM on standardised local data U (P, N, D)."""

    def __init__(self, U: np.ndarray, K: int, reg_covar: float):
        P, N, D = U.shape
        self.P, self.N, self.D, self.K = P, N, D, K
        self.iu = np.triu_indices(D)
        self.n_quad = len(self.iu[0])
        U = np.ascontiguousarray(U, dtype=float)
        pairs = (self.iu[0].astype(np.int64), self.iu[1].astype(np.int64))
        col, keep, mult = _feature_columns(U, *pairs)
        # (iu0, iu1, col, mult): every kernel's map from frames' features to Phi's columns
        self._layout = (*pairs, col, mult)
        # Phi (N, F) and its transpose (F, N), along which the E-step's reductions run
        self.Phi, self.PhiT = _features(U, *pairs, keep)
        self.psi = float(reg_covar * N / K)

    def m_step(self, resp: np.ndarray):
        """Parameters from responsibilities ``resp`` (K, N)."""
        return self.params(np.ascontiguousarray(resp, dtype=float) @ self.Phi)

    def params(self, S: np.ndarray):
        """Weights (K,), means (P, K, D), covariances (P, K, D, D) from statistics S (K, F).

        Raises ``Infeasible`` when extrapolated statistics give no valid mixture.
        """
        weights, mean, cov, ok = _params(
            np.ascontiguousarray(S, dtype=float), self.P, self.D, self._layout, self.psi, self.N
        )
        if not ok:
            raise Infeasible
        return weights, mean, cov

    def log_joint(self, params):
        """log pi_k + sum_j log N(u^(j) | mu_k^(j), Sigma_k^(j)) (K, N) and the log prior."""
        W, log_prior, ok = _joint_weights(*_contiguous(params), self._layout, self.psi)
        if not ok:
            raise Infeasible
        return W @ self.PhiT, log_prior

    def warm_responsibilities(self, params, floor: float):
        """Responsibilities (K, N) for a warm start from ``params`` (the previous model).

        Samples the previous model explains (log density at least ``floor``) get its
        posterior. The others, typically those of a new demo from an unseen condition,
        get the posterior of time alone: under the previous model's narrow spatial
        Gaussians the full posterior would hand them to whichever component is least
        improbable, often one from another part of the movement, and EM then stays in
        that poor optimum (measured on a simulated teacher's 19 maze demos added one at
        a time: the warm fit's objective fell 2-8 below a cold fit's and no start point
        passed, where the cold fit passed 98 %).
        """
        log_joint, _ = self.log_joint(params)
        top = log_joint.max(axis=0)
        resp = np.exp(log_joint - top)
        total = resp.sum(axis=0)
        log_density = np.log(total) + top
        resp /= total
        lost = log_density < floor
        if lost.any():
            weights, mean, cov = params
            mu_t, var_t = mean[0, :, 0], cov[0, :, 0, 0]  # time is the same in every frame
            t = self.Phi[lost, self.n_quad]  # the linear feature of time in frame 0 (kept)
            log_h = np.log(np.maximum(weights, 1e-300))[:, None] - 0.5 * (
                np.log(var_t)[:, None] + (t[None, :] - mu_t[:, None]) ** 2 / var_t[:, None]
            )
            h = np.exp(log_h - log_h.max(axis=0))
            resp[:, lost] = h / h.sum(axis=0)
        return resp

    def e_step(self, params):
        """Objective at ``params`` and the sufficient statistics of the next M-step."""
        objective, S, ok = _e_step(
            *_contiguous(params), self.Phi, self.PhiT, self._layout, self.psi
        )
        if not ok:
            raise Infeasible
        return float(objective), S

    def run(self, params, tol: float, max_iter: int):
        """EM accelerated by SQUAREM (Varadhan & Roland 2008) on the sufficient statistics.

        Each cycle takes two EM steps S0 -> S1 -> S2, extrapolates along them and
        keeps the extrapolated point only if its objective beats the plain EM
        step, so the objective never decreases. Stops when one plain EM step
        gains less than ``tol``; ``n_iter`` counts E-steps.

        Returns weights, means, covariances, objective, n_iter and converged.
        """
        weights, mean, cov, objective, n_iter, converged, ok = _run(
            *_contiguous(params),
            self.Phi,
            self.PhiT,
            self._layout,
            self.psi,
            float(tol),
            int(max_iter),
        )
        if not ok:
            raise Infeasible
        return weights, mean, cov, float(objective), int(n_iter), bool(converged)


class Infeasible(Exception):
    """Extrapolated statistics that describe no valid mixture."""


def _contiguous(params):
    return tuple(np.ascontiguousarray(a, dtype=float) for a in params)


# ---------------------------------------------------------------- compiled kernels
# Each returns a flag ``ok`` instead of raising: False where numpy's Cholesky factor
# would fail (a covariance that is not positive definite) or statistics are not finite.


def _feature_columns(U, iu0, iu1):
    """Which of the frames' features Phi keeps, as (col, keep, mult).

    A state dimension whose standardised values are the same in every frame (time,
    which no frame transforms) gives every frame the same features of it; Phi keeps
    them once, from frame 0, so both products with Phi skip the copies (6 of the
    maze's 37 columns). ``col`` (F,) maps each frame's feature to its column of Phi,
    ``keep`` lists the kept features, ``mult`` (F_kept,) counts the features each
    column stands for (SQUAREM's step length weighs the columns by it).
    """
    P, N, D = U.shape
    nq = len(iu0)
    F = P * (nq + D) + 1
    shared = np.array(
        [all(np.array_equal(U[p, :, i], U[0, :, i]) for p in range(1, P)) for i in range(D)]
    )
    source = np.arange(F)
    for p in range(1, P):
        base = p * (nq + D)
        for q in range(nq):
            if shared[iu0[q]] and shared[iu1[q]]:
                source[base + q] = q
        for i in np.flatnonzero(shared):
            source[base + nq + i] = nq + i
    keep = np.flatnonzero(source == np.arange(F))
    rank = np.full(F, -1)
    rank[keep] = np.arange(len(keep))
    col = rank[source]
    mult = np.bincount(col, minlength=len(keep)).astype(float)
    return col.astype(np.int64), keep.astype(np.int64), mult


@compiled
def _features(U, iu0, iu1, keep):
    """Phi (N, F_kept): of each frame's quadratic terms u_i u_j (i <= j), then u, then 1,
    the features ``keep`` lists; and Phi.T."""
    P, N, D = U.shape
    nq = iu0.shape[0]
    F = P * (nq + D) + 1
    PhiT = np.empty((keep.shape[0], N))
    for c in range(keep.shape[0]):
        f = keep[c]
        p, j = f // (nq + D), f % (nq + D)
        if f == F - 1:
            PhiT[c] = 1.0
        elif j < nq:
            a, b = iu0[j], iu1[j]
            for n in range(N):
                PhiT[c, n] = U[p, n, a] * U[p, n, b]
        else:
            for n in range(N):
                PhiT[c, n] = U[p, n, j - nq]
    Phi = np.empty((N, keep.shape[0]))
    for n in range(N):
        for c in range(keep.shape[0]):
            Phi[n, c] = PhiT[c, n]
    return Phi, PhiT


@compiled
def _params(S, P, D, layout, psi, N):
    """M-step: weights (K,), means (P, K, D), covariances (P, K, D, D) and ok."""
    iu0, iu1, col, _ = layout
    K, F = S.shape
    nq = iu0.shape[0]
    weights = np.empty(K)
    mean = np.empty((P, K, D))
    cov = np.empty((P, K, D, D))
    for k in range(K):
        Nk = S[k, col[col.shape[0] - 1]]
        if not Nk >= 0.0:
            return weights, mean, cov, False
        for f in range(F):
            if not np.isfinite(S[k, f]):
                return weights, mean, cov, False
        Nk_safe = max(Nk, 1e-10 * N)
        weights[k] = Nk / N
        for p in range(P):
            base = p * (nq + D)
            for i in range(D):
                mean[p, k, i] = S[k, col[base + nq + i]] / Nk_safe
            for q in range(nq):
                i, j = iu0[q], iu1[q]
                value = S[k, col[base + q]] - Nk * (mean[p, k, i] * mean[p, k, j])
                if i == j:
                    value += psi  # the covariance prior's ridge
                value /= Nk_safe
                cov[p, k, i, j] = value
                cov[p, k, j, i] = value
    return weights, mean, cov, True


@compiled
def _joint_weights(weights, mean, cov, layout, psi):
    """W (K, F) with ``W @ PhiT`` the log joint, the log prior and ok (the weights of
    features Phi keeps once summed, frame by frame)."""
    iu0, iu1, col, mult = layout
    P, K, D = mean.shape
    nq = iu0.shape[0]
    F = col.shape[0]
    W = np.zeros((K, mult.shape[0]))
    L = np.zeros((D, D))
    Linv = np.zeros((D, D))
    prec = np.zeros((D, D))
    trace = 0.0
    for k in range(K):
        const = 0.0
        for p in range(P):
            # Cholesky factor L of the covariance, and log |Sigma| / 2
            half_logdet = 0.0
            for j in range(D):
                s = cov[p, k, j, j]
                for q in range(j):
                    s -= L[j, q] * L[j, q]
                if not s > 0.0:
                    return W, 0.0, False
                L[j, j] = np.sqrt(s)
                half_logdet += np.log(L[j, j])
                for i in range(j + 1, D):
                    s = cov[p, k, i, j]
                    for q in range(j):
                        s -= L[i, q] * L[j, q]
                    L[i, j] = s / L[j, j]
            # the precision L^-T L^-1
            for j in range(D):
                Linv[j, j] = 1.0 / L[j, j]
                for i in range(j + 1, D):
                    s = 0.0
                    for q in range(j, i):
                        s -= L[i, q] * Linv[q, j]
                    Linv[i, j] = s / L[i, i]
            for i in range(D):
                for j in range(i, D):
                    s = 0.0
                    for q in range(j, D):
                        s += Linv[q, i] * Linv[q, j]
                    prec[i, j] = s
                    prec[j, i] = s
            base = p * (nq + D)
            for q in range(nq):
                i, j = iu0[q], iu1[q]
                W[k, col[base + q]] += -0.5 * prec[i, i] if i == j else -prec[i, j]
            quad = 0.0
            for i in range(D):
                s = 0.0
                for j in range(D):
                    s += prec[i, j] * mean[p, k, j]
                W[k, col[base + nq + i]] += s
                quad += s * mean[p, k, i]
                trace += prec[i, i]
            const += quad + 2.0 * half_logdet
        W[k, col[F - 1]] = -0.5 * const - 0.5 * P * D * LOG_2PI + np.log(max(weights[k], 1e-300))
    return W, -0.5 * psi * trace, True


@compiled
def _e_step(weights, mean, cov, Phi, PhiT, layout, psi):
    """Objective (penalised mean log-likelihood), statistics S (K, F) and ok."""
    W, log_prior, ok = _joint_weights(weights, mean, cov, layout, psi)
    if not ok:
        return np.nan, W, False
    resp = W @ PhiT  # (K, N) log joint, made responsibilities in place
    top = _column_max(resp)
    total = _exp_gaps(resp, top)
    N = resp.shape[1]
    total_log = 0.0
    for n in range(N):
        total_log += np.log(total[n]) + top[n]
    _divide_columns(resp, total)
    return (total_log + log_prior) / N, resp @ Phi, True


# The E-step's passes over (K, N) run row by row, along memory, each in a kernel of its
# own: so compiled, their loops vectorise (inlined into _e_step they took twice as long).


@compiled
def _column_max(a):
    """The largest entry of each column of ``a`` (K, N), taken in row order."""
    top = a[0].copy()
    for k in range(1, a.shape[0]):
        for n in range(a.shape[1]):
            top[n] = max(top[n], a[k, n])
    return top


@compiled
def _exp_gaps(resp, top):
    """resp <- exp(max(resp - top, -100)) in place; returns its column sums."""
    total = np.zeros(resp.shape[1])
    for k in range(resp.shape[0]):
        for n in range(resp.shape[1]):
            # exp(-100) ~ 4e-44 is already nothing next to the top term (1); clipping
            # keeps exp and the next product away from subnormal numbers (10x slower),
            # and keeps _exp's table index in range (a NaN gap is clipped too)
            gap = resp[k, n] - top[n]
            value = _exp(gap if gap > -100.0 else -100.0)
            resp[k, n] = value
            total[n] += value
    return total


@compiled
def _divide_columns(a, d):
    """a[:, n] *= 1 / d[n] in place (a product by the reciprocal: 44 000 divisions took
    a seventh of an iteration)."""
    inv = 1.0 / d
    for k in range(a.shape[0]):
        for n in range(a.shape[1]):
            a[k, n] *= inv[n]


# exp on [-100, 0] (the E-step's clipped gaps): x = k ln 2 + r with |r| <= ln 2 / 2
# (Cody and Waite's two-part ln 2, fdlibm's constants, so k ln 2 is exact), exp(r) by
# its Taylor series to r^13 / 13! (remainder below 1e-17) and 2^k from a table. Within
# one unit in the last place of the exact value (10 % of values one off, checked
# against 50-digit decimal arithmetic in tests/test_tpgmm.py); written in plain
# arithmetic so that the E-step's loop vectorises: three times faster than calling
# libm's exp per term, and the same bits wherever IEEE arithmetic is.
_LN2_HI = 6.93147180369123816490e-01
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00
_EXP_MIN = -150  # 2^k for k = -150 .. 0, all normal numbers
_POW2 = np.ldexp(1.0, np.arange(_EXP_MIN, 1))


@compiled(inline=True)
def _exp(x):
    """exp(x) for x in [-100, 0]."""
    kf = np.floor(x * _INV_LN2 + 0.5)
    r = (x - kf * _LN2_HI) - kf * _LN2_LO
    p = 1.0 / 6227020800.0
    p = p * r + 1.0 / 479001600.0
    p = p * r + 1.0 / 39916800.0
    p = p * r + 1.0 / 3628800.0
    p = p * r + 1.0 / 362880.0
    p = p * r + 1.0 / 40320.0
    p = p * r + 1.0 / 5040.0
    p = p * r + 1.0 / 720.0
    p = p * r + 1.0 / 120.0
    p = p * r + 1.0 / 24.0
    p = p * r + 1.0 / 6.0
    p = p * r + 0.5
    p = p * r + 1.0
    p = p * r + 1.0
    return p * _POW2[int(kf) - _EXP_MIN]


@compiled
def _run(weights, mean, cov, Phi, PhiT, layout, psi, tol, max_iter):
    """SQUAREM-accelerated EM (see :meth:`EM.run`); returns the best parameters,
    objective, n_iter, converged and ok (False: a plain EM step was infeasible)."""
    P, K, D = mean.shape
    N = Phi.shape[0]
    mult = layout[3]
    obj0, S1, ok = _e_step(weights, mean, cov, Phi, PhiT, layout, psi)
    if not ok:
        return weights, mean, cov, obj0, 1, False, False
    S0 = S1
    have_S0 = False
    n_iter, converged = 1, False
    best_w, best_m, best_c, best_obj = weights, mean, cov, obj0
    while n_iter < max_iter:
        w1, m1, c1, ok = _params(S1, P, D, layout, psi, N)
        if not ok:
            return best_w, best_m, best_c, best_obj, n_iter, False, False
        obj1, S2, ok = _e_step(w1, m1, c1, Phi, PhiT, layout, psi)
        if not ok:
            return best_w, best_m, best_c, best_obj, n_iter, False, False
        n_iter += 1
        best_w, best_m, best_c, best_obj = w1, m1, c1, obj1
        if obj1 - obj0 < tol:
            converged = True
            break
        if not have_S0 or n_iter >= max_iter:
            S0, obj0, S1 = S1, obj1, S2
            have_S0 = True
            continue
        r = S1 - S0
        v = S2 - 2.0 * S1 + S0
        # the norms over every frame's statistics: a column Phi keeps once counts for all
        alpha = -np.sqrt((mult * r * r).sum() / max((mult * v * v).sum(), 1e-300))
        if alpha < -1.0:
            wx, mx, cx, ok = _params(S0 - 2.0 * alpha * r + alpha * alpha * v, P, D, layout, psi, N)
            if ok:
                obj_x, S_x, ok = _e_step(wx, mx, cx, Phi, PhiT, layout, psi)
                if ok:
                    n_iter += 1
                    if obj_x >= obj1:
                        best_w, best_m, best_c, best_obj = wx, mx, cx, obj_x
                        obj0, S1 = obj_x, S_x
                        have_S0 = False
                        continue
        S0, obj0, S1 = S1, obj1, S2
        have_S0 = True
    return best_w, best_m, best_c, best_obj, n_iter, converged, True
