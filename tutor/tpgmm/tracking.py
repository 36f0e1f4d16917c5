r"""A robot that follows the TP-GMR from where it is: linear quadratic tracking.

The TP-GMR (:meth:`tutor.tpgmm.TPGMM.reproduce_batch`) gives at every time step a
Gaussian :math:`\mathcal N(\mu_t, \Sigma_t)` over the position. Its mean is a
regression, not a movement: it need not start where the robot is. The standard way to
run a TP-GMM on a robot (Calinon 2016, "A tutorial on task-parameterized movement
learning and retrieval", section 4; PbDlib's ``demo_TPGMR_LQR``) is a controller that
tracks that Gaussian from the robot's actual state, with the precision
:math:`\Sigma_t^{-1}` as the tracking weight: tight where the demonstrations agree,
loose where they do not ("minimal intervention").

The plant is a double integrator per coordinate (the maze's pen; the arm's tool
point), sampled at the TP-GMR's time steps :math:`\Delta t` (Euler, as in the
tutorial):

.. math::

    x_{t+1} = A x_t + B u_t, \quad
    x = \begin{pmatrix} p \\ v \end{pmatrix}, \quad
    A = \begin{pmatrix} I & \Delta t\, I \\ 0 & I \end{pmatrix}, \quad
    B = \begin{pmatrix} 0 \\ \Delta t\, I \end{pmatrix},

and the controller minimises, from the start state :math:`x_0` (the test point at
rest),

.. math::

    \sum_{t=0}^{T-1} (p_t - \mu_t)^\top Q_t (p_t - \mu_t) + \sum_{t=0}^{T-2} u_t^\top R\, u_t,
    \quad Q_t = \Sigma_t^{-1}, \quad R = r I.

Two equivalent solutions:

- **feedback** (:func:`tracking_gains`): the finite-horizon Riccati recursion gives
  :math:`u_t = -K_t x_t + k_t`, what a robot runs to reject disturbances;
- **batch** (:func:`track`): without disturbances the closed loop follows the open-loop
  optimum, the tutorial's batch solution. With this plant
  :math:`u_t = (p_{t+2} - 2 p_{t+1} + p_t) / \Delta t^2`, so with :math:`p_0` and
  :math:`p_1 = p_0 + \Delta t\, v_0` fixed the problem is least squares in the
  positions,

  .. math::

      \min_{p_2 \dots p_{T-1}} \sum_{t=2}^{T-1} (p_t - \mu_t)^\top Q_t (p_t - \mu_t)
      + \frac{r}{\Delta t^4} \sum_{t=0}^{T-3} \lVert p_{t+2} - 2 p_{t+1} + p_t \rVert^2

  (:math:`u_{T-2}` moves nothing within the horizon, so it is 0), whose normal
  equations are block pentadiagonal: one banded Cholesky solve
  (:func:`scipy.linalg.solveh_banded`) for all test points that share their
  precisions, as they do under frames that only translate.

``tests/test_tracking.py`` checks that both give the same path. The path starts
exactly at :math:`x_0`, whatever the regression's first mean.

Examples
--------
>>> import numpy as np
>>> T = 50
>>> mean = np.linspace([0.0, 0.0], [1.0, 1.0], T)[None]          # (1, T, 2)
>>> precision = np.broadcast_to(1e4 * np.eye(2), (1, T, 2, 2))
>>> path = track(mean, precision, start=np.array([[0.1, 0.0]]), dt=1 / (T - 1))
>>> bool(np.allclose(path[0, 0], [0.1, 0.0])), bool(np.allclose(path[0, -1], [1, 1], atol=0.02))
(True, True)
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.linalg import solveh_banded

from ..errors import InvalidParameterError
from .checks import check_number

__all__ = [
    "DEFAULT_CONTROL_COST",
    "check_control_cost",
    "track",
    "tracking_gains",
    "tracking_precision",
]

#: r of R = r I when a task does not give its own (the tasks' choices, and how they were
#: measured, are in their asset files)
DEFAULT_CONTROL_COST = 1e-8


def _plant(d: int, dt: float):
    eye, zero = np.eye(d), np.zeros((d, d))
    A = np.block([[eye, dt * eye], [zero, eye]])
    B = np.vstack([zero, dt * eye])
    return A, B


def check_control_cost(value, name: str = "control_cost") -> float:
    """r of R = r I as a finite positive float, or a named error saying so."""
    return check_number(value, name, strict=True)


def _check(mean, precision, start, dt, control_cost):
    mean = np.asarray(mean, dtype=float)
    precision = np.asarray(precision, dtype=float)
    start = np.asarray(start, dtype=float)
    if mean.ndim != 3:
        raise InvalidParameterError(f"mean must have shape (B, T, d), got {mean.shape}")
    n, T, d = mean.shape
    if precision.shape not in ((n, T, d, d), (1, T, d, d)):
        raise InvalidParameterError(
            f"precision must have shape {(n, T, d, d)} or {(1, T, d, d)}, got {precision.shape}"
        )
    if start.shape not in ((n, d), (n, 2 * d)):
        raise InvalidParameterError(
            f"start must have shape {(n, d)} (positions at rest) or {(n, 2 * d)} "
            f"(positions and velocities), got {start.shape}"
        )
    if not (np.isfinite(mean).all() and np.isfinite(precision).all() and np.isfinite(start).all()):
        raise InvalidParameterError("mean, precision and start must be finite")
    if not (np.isfinite(dt) and dt > 0):
        raise InvalidParameterError(f"dt must be a positive number of seconds, got {dt!r}")
    control_cost = check_control_cost(control_cost)
    if T < 2:
        raise InvalidParameterError(f"a path to track needs at least 2 time steps, got {T}")
    return mean, _shared(precision), start, float(dt), float(control_cost)


def _shared(precision: np.ndarray) -> np.ndarray:
    """``precision`` as (m, T, d, d), m = 1 when every test point has exactly the same:
    a broadcast view (what :meth:`~tutor.tpgmm.TPGMM.reproduce_batch` returns when the
    conditions share their frames' rotations, at no cost to test) or equal arrays."""
    if len(precision) > 1 and (precision.strides[0] == 0 or (precision == precision[:1]).all()):
        return precision[:1]
    return precision


def tracking_precision(cov) -> np.ndarray:
    """The tracking weights for covariances (B, T, d, d): their inverses, (m, T, d, d).

    m = 1 when every test point has the same covariances. Under frames that only
    translate (the maze's and the arm's) the product of the frames' Gaussians has the
    same covariance for every test point (only the means move), so it is inverted once.
    """
    cov = np.asarray(cov, dtype=float)  # keeps a broadcast view's zero stride
    if cov.ndim != 4 or cov.shape[-1] != cov.shape[-2]:
        raise InvalidParameterError(f"cov must have shape (B, T, d, d), got {cov.shape}")
    return np.linalg.inv(_shared(cov))


# ---------------------------------------------------------------- feedback (Riccati)


def tracking_gains(mean, precision, dt: float, control_cost: float = DEFAULT_CONTROL_COST):
    """The time-varying feedback of the tracking controller (see the module docstring).

    Parameters
    ----------
    mean : ndarray (B, T, d)
        The TP-GMR means :math:`\\mu_t` of B test points.
    precision : ndarray (B, T, d, d), or (1, T, d, d) shared by every test point
        Their precisions :math:`\\Sigma_t^{-1}` (the tracking weights).
    dt : float
        The time step.
    control_cost : float
        r of R = r I.

    Returns
    -------
    K : ndarray (B, T - 1, d, 2d)
        Feedback gains.
    k : ndarray (B, T - 1, d)
        Feedforward terms: :math:`u_t = -K_t x_t + k_t`.
    """
    mean, precision, _, dt, r = _check(
        mean, precision, np.zeros(np.shape(mean)[::2]), dt, control_cost
    )
    n, T, d = mean.shape
    m = len(precision)
    A, B = _plant(d, dt)
    R = r * np.eye(d)
    # cost-to-go at step t: 1/2 x^T V x - s^T x (+ const); only positions are weighted
    V = np.zeros((m, 2 * d, 2 * d))
    V[:, :d, :d] = precision[:, -1]
    weighted = (
        np.einsum("mtij,btj->bti", precision, mean)
        if m == 1
        else np.einsum("btij,btj->bti", precision, mean)
    )  # Q_t mu_t, (B, T, d)
    s = np.zeros((n, 2 * d))
    s[:, :d] = weighted[:, -1]
    K = np.empty((m, T - 1, d, 2 * d))
    k = np.empty((n, T - 1, d))
    for t in range(T - 2, -1, -1):
        S = R + B.T @ V @ B  # (m, d, d)
        L = np.linalg.solve(S, np.broadcast_to(B.T, (m, d, 2 * d)))  # S^-1 B^T
        K[:, t] = L @ V @ A
        k[:, t] = (L @ s[..., None])[..., 0]
        closed = A - B @ K[:, t]  # (m, 2d, 2d)
        V = A.T @ V @ closed
        V[:, :d, :d] += precision[:, t]
        V = 0.5 * (V + np.swapaxes(V, 1, 2))
        s = (np.swapaxes(closed, 1, 2) @ s[..., None])[..., 0]
        s[:, :d] += weighted[:, t]
    return np.broadcast_to(K, (n, *K.shape[1:])), k


# ---------------------------------------------------------------- batch (banded)


@lru_cache(maxsize=8)
def _second_differences(T: int) -> np.ndarray:
    """D^T D for the second differences of T samples, (T, T); read only."""
    D = np.zeros((T - 2, T))
    rows = np.arange(T - 2)
    D[rows, rows], D[rows, rows + 1], D[rows, rows + 2] = 1.0, -2.0, 1.0
    DtD = D.T @ D
    DtD.setflags(write=False)
    return DtD


def _banded_normal_matrix(precision: np.ndarray, c: float) -> np.ndarray:
    """The normal equations' matrix for p_2 .. p_{T-1} in upper banded form (2d + 1, N).

    Unknowns are ordered time-major (index (t - 2) d + i), so a precision block sits
    within d - 1 of the diagonal and the smoothness term couples t with t + 1 and t + 2
    at offsets d and 2d.
    """
    T, d, _ = precision.shape
    free = T - 2
    u = 2 * d
    ab = np.zeros((u + 1, free * d))
    cols = np.arange(free) * d
    for i in range(d):
        for j in range(i, d):
            ab[u - (j - i), cols + j] += precision[2:, i, j]
    DtD = _second_differences(T)[2:, 2:]
    for step in range(3):
        band = c * np.diagonal(DtD, step)  # (free - step,)
        for i in range(d):
            ab[u - step * d, cols[step:] + i] += band
    return ab


def track(
    mean,
    precision,
    start,
    dt: float,
    control_cost: float = DEFAULT_CONTROL_COST,
    return_velocity: bool = False,
):
    """The executed path: the robot starts at ``start`` and tracks the TP-GMR.

    Parameters
    ----------
    mean : ndarray (B, T, d)
    precision : ndarray (B, T, d, d), or (1, T, d, d) shared by every test point
        (:func:`tracking_precision` gives it from the TP-GMR's covariances)
    start : ndarray (B, d) or (B, 2d)
        Each test point's start position (at rest), or position and velocity.
    dt : float
    control_cost : float
    return_velocity : bool
        Also return the velocities.

    Returns
    -------
    path : ndarray (B, T, d)
        Positions at every time step; ``path[:, 0]`` is the start.
    velocity : ndarray (B, T, d)
        Only with ``return_velocity``.
    """
    mean, precision, start, dt, r = _check(mean, precision, start, dt, control_cost)
    n, T, d = mean.shape
    velocity0 = start[:, d:] if start.shape[1] == 2 * d else np.zeros((n, d))
    path = np.empty((n, T, d))
    path[:, 0] = start[:, :d]
    path[:, 1] = start[:, :d] + dt * velocity0
    if T > 2:
        c = r / dt**4
        # right-hand side: Q_t mu_t, less the smoothness term's pull from p_0 and p_1
        if len(precision) == 1:  # (B, T - 2, d); einsum is far faster than a stacked @
            rhs = np.einsum("tij,btj->bti", precision[0, 2:], mean[:, 2:])
        else:
            rhs = np.einsum("btij,btj->bti", precision[:, 2:], mean[:, 2:])
        # second differences tie p_0 and p_1 only to p_2 and p_3
        tie = _second_differences(T)[2:4, :2]
        for row in range(min(2, T - 2)):
            rhs[:, row] -= c * (tie[row, 0] * path[:, 0] + tie[row, 1] * path[:, 1])
        if len(precision) == 1:  # one factorisation for every test point
            ab = _banded_normal_matrix(precision[0], c)
            free = solveh_banded(ab, rhs.reshape(n, -1).T, check_finite=False)
            path[:, 2:] = free.T.reshape(n, T - 2, d)
        else:
            for b in range(n):
                ab = _banded_normal_matrix(precision[b], c)
                path[b, 2:] = solveh_banded(ab, rhs[b].ravel(), check_finite=False).reshape(
                    T - 2, d
                )
    if not return_velocity:
        return path
    velocity = np.empty_like(path)
    velocity[:, :-1] = np.diff(path, axis=1) / dt
    velocity[:, -1] = velocity[:, -2]  # u_{T-2} = 0
    return path, velocity
