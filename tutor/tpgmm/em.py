"""EM for the TP-GMM on sufficient statistics, accelerated by SQUAREM.

The model (:mod:`tutor.tpgmm.model`) hands EM the standardised local data; see the
package docstring for the features, the covariance prior and why EM never decreases
the objective.
"""

from __future__ import annotations

import numpy as np

from .linalg import LOG_2PI

__all__ = ["EM", "Infeasible"]


class EM:
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
        # the quadratic features' weights from a precision, flattened (D * D, Dq): the
        # mean of its two triangles, -1/2 on the diagonal and -1 off it (the features
        # hold each off-diagonal product once), so no symmetrising is needed
        self.from_precision = np.zeros((D * D, self.n_quad))
        # the second moments from their upper triangle, (Dq, D * D)
        self.to_moments = np.zeros((self.n_quad, D * D))
        for q, (i, j) in enumerate(zip(*self.iu, strict=True)):
            self.from_precision[[i * D + j, j * D + i], q] = -0.5  # once on the diagonal
            self.to_moments[q, i * D + j] = self.to_moments[q, j * D + i] = 1.0
        self.ridge = self.psi * np.eye(D)

    def m_step(self, resp: np.ndarray):
        """Parameters from responsibilities ``resp`` (K, N)."""
        return self.params(resp @ self.Phi)

    def params(self, S: np.ndarray):
        """Weights (K,), means (P, K, D), covariances (P, K, D, D) from statistics S (K, F).

        Raises ``Infeasible`` when extrapolated statistics give no valid mixture.
        """
        P, D, K = self.P, self.D, self.K
        Nk = S[:, -1]
        if not (Nk.min() >= 0 and np.isfinite(S).all()):
            raise Infeasible
        feats = S[:, :-1].reshape(K, P, self.n_quad + D)
        Nk_safe = np.maximum(Nk, 1e-10 * self.N)[:, None, None]
        mean = feats[..., self.n_quad :] / Nk_safe  # (K, P, D)
        second = (feats[..., : self.n_quad] @ self.to_moments).reshape(K, P, D, D)
        scatter = second - Nk[:, None, None, None] * (mean[..., :, None] * mean[..., None, :])
        cov = (scatter + self.ridge) / Nk_safe[..., None]
        return Nk / self.N, mean.transpose(1, 0, 2), cov.transpose(1, 0, 2, 3)

    def log_joint(self, params):
        """log pi_k + sum_j log N(u^(j) | mu_k^(j), Sigma_k^(j)) (K, N) and the log prior."""
        weights, mean, cov = params
        P, K, D = mean.shape
        try:
            chol = np.linalg.cholesky(cov)
        except np.linalg.LinAlgError:
            raise Infeasible from None
        prec = np.linalg.inv(cov)  # (P, K, D, D)
        logdet = 2.0 * np.log(np.diagonal(chol, axis1=-2, axis2=-1)).sum(-1)  # (P, K)
        lin = np.einsum("pkij,pkj->pki", prec, mean)  # (P, K, D)
        W = np.empty((K, P * (self.n_quad + D) + 1))
        blocks = W[:, :-1].reshape(K, P, self.n_quad + D)
        blocks[..., : self.n_quad] = (prec.reshape(P, K, D * D) @ self.from_precision).transpose(
            1, 0, 2
        )
        blocks[..., self.n_quad :] = lin.transpose(1, 0, 2)
        const = -0.5 * ((lin * mean).sum(-1) + logdet).sum(0) - 0.5 * P * D * LOG_2PI
        W[:, -1] = const + np.log(np.maximum(weights, 1e-300))  # W @ PhiT = log joint
        log_prior = -0.5 * self.psi * np.einsum("pkii->", prec)
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
            t = self.Phi[lost, self.n_quad]  # the linear feature of time in frame 0
            log_h = np.log(np.maximum(weights, 1e-300))[:, None] - 0.5 * (
                np.log(var_t)[:, None] + (t[None, :] - mu_t[:, None]) ** 2 / var_t[:, None]
            )
            h = np.exp(log_h - log_h.max(axis=0))
            resp[:, lost] = h / h.sum(axis=0)
        return resp

    def e_step(self, params):
        """Objective at ``params`` and the sufficient statistics of the next M-step."""
        resp, log_prior = self.log_joint(params)  # (K, N) log joint, made responsibilities
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
                except Infeasible:
                    pass
            S0, obj0, S1 = S1, obj1, S2
        (weights, mean, cov), objective = best
        return weights, mean, cov, objective, n_iter, converged


class Infeasible(Exception):
    """Extrapolated statistics that describe no valid mixture."""
