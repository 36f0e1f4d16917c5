r"""A robot that follows the TP-GMR from where it is: linear quadratic tracking.

The TP-GMR (:meth:`tutor.tpgmm.TPGMM.reproduce_batch`) gives at every time step a
Gaussian :math:`\mathcal N(\mu_t, \Sigma_t)` over the position. Its mean is a
regression, not a movement: it need not start where the robot is. The standard way to
run a TP-GMM on a robot (Calinon 2016, section 4; PbDlib's ``demo_TPGMR_LQR``) is a
controller that tracks that Gaussian from the robot's actual state, with the
precision :math:`\Sigma_t^{-1}` as the tracking weight: tight where the demonstrations
agree, loose where they do not ("minimal intervention").

The plant is a double integrator per coordinate (the maze's pen; the arm's tool
point), sampled at the TP-GMR's time steps :math:`\Delta t`:

.. math::

    x_{t+1} = A x_t + B u_t, \quad
    x = \begin{pmatrix} p \\ v \end{pmatrix}, \quad
    A = \begin{pmatrix} I & \Delta t\, I \\ 0 & I \end{pmatrix}, \quad
    B = \begin{pmatrix} \tfrac12 \Delta t^2 I \\ \Delta t\, I \end{pmatrix},

and the controller minimises, from the start state :math:`x_0` (the test point at
rest),

.. math::

    \sum_{t=0}^{T-1} (p_t - \mu_t)^\top Q_t (p_t - \mu_t) + \sum_{t=0}^{T-2} u_t^\top R\, u_t,
    \quad Q_t = \Sigma_t^{-1}, \quad R = r I.

The finite-horizon Riccati recursion gives the feedback :math:`u_t = -K_t x_t + k_t`
(:func:`tracking_gains`), batched over test points; :func:`track` runs it forward.
The path starts exactly at :math:`x_0`, whatever the regression's first mean.

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

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["DEFAULT_CONTROL_COST", "track", "tracking_gains", "tracking_precision"]

#: r of R = r I, relative to the precisions (the model's units): small enough that the
#: robot follows the demos where they agree, large enough that it does not jump
DEFAULT_CONTROL_COST = 1e-8


def _plant(d: int, dt: float):
    eye, zero = np.eye(d), np.zeros((d, d))
    A = np.block([[eye, dt * eye], [zero, eye]])
    B = np.vstack([0.5 * dt * dt * eye, dt * eye])
    return A, B


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
    if not (np.isfinite(control_cost) and control_cost > 0):
        raise InvalidParameterError(f"control_cost must be positive, got {control_cost!r}")
    if T < 2:
        raise InvalidParameterError(f"a path to track needs at least 2 time steps, got {T}")
    return mean, precision, start, float(dt), float(control_cost)


def tracking_precision(cov) -> np.ndarray:
    """The tracking weights for covariances (B, T, d, d): their inverses, (m, T, d, d).

    m = 1 when every test point has the same covariances. Under frames that only
    translate (the maze's and the arm's) the product of the frames' Gaussians has the
    same covariance for every test point (only the means move), so it is inverted once
    and the Riccati recursion, which sees only the precisions, runs once.
    """
    cov = np.asarray(cov, dtype=float)
    if cov.ndim != 4 or cov.shape[-1] != cov.shape[-2]:
        raise InvalidParameterError(f"cov must have shape (B, T, d, d), got {cov.shape}")
    if len(cov) > 1 and np.allclose(cov, cov[:1], rtol=1e-10, atol=0.0):
        cov = cov[:1]
    return np.linalg.inv(cov)


def _shared(precision: np.ndarray) -> np.ndarray:
    """``precision`` as (m, T, d, d), m = 1 when all test points share it."""
    if len(precision) > 1 and np.allclose(precision, precision[:1], rtol=1e-10, atol=0.0):
        return precision[:1]
    return precision


def _riccati(precision: np.ndarray, dt: float, r: float):
    """The backward pass that needs only the precisions (m, T, d, d).

    Returns the feedback gains K (m, T - 1, d, 2d), the maps L = S^-1 B^T (m, T - 1, d, 2d)
    that turn the next step's linear cost term into the feedforward, and the closed-loop
    matrices A - B K (m, T - 1, 2d, 2d).
    """
    m, T, d, _ = precision.shape
    A, B = _plant(d, dt)
    R = r * np.eye(d)
    if m == 1:  # one controller for every test point: plain 2-D products are faster
        return tuple(a[None] for a in _riccati_one(precision[0], A, B, R))
    V = np.zeros((m, 2 * d, 2 * d))
    V[:, :d, :d] = precision[:, -1]
    K = np.empty((m, T - 1, d, 2 * d))
    L = np.empty((m, T - 1, d, 2 * d))
    closed = np.empty((m, T - 1, 2 * d, 2 * d))
    for t in range(T - 2, -1, -1):
        VB = V @ B  # (m, 2d, d)
        S = R + B.T @ VB  # (m, d, d)
        L[:, t] = np.linalg.solve(S, np.broadcast_to(B.T, (m, d, 2 * d)))
        K[:, t] = L[:, t] @ V @ A
        closed[:, t] = A - B @ K[:, t]
        V = A.T @ V @ closed[:, t]
        V[:, :d, :d] += precision[:, t]
        V = 0.5 * (V + np.swapaxes(V, 1, 2))
    return K, L, closed


def _riccati_one(precision, A, B, R):
    """:func:`_riccati` for one sequence of precisions (T, d, d)."""
    T, d, _ = precision.shape
    BT = B.T
    V = np.zeros((2 * d, 2 * d))
    V[:d, :d] = precision[-1]
    K = np.empty((T - 1, d, 2 * d))
    L = np.empty((T - 1, d, 2 * d))
    closed = np.empty((T - 1, 2 * d, 2 * d))
    for t in range(T - 2, -1, -1):
        L[t] = np.linalg.solve(R + BT @ V @ B, BT)
        K[t] = L[t] @ V @ A
        closed[t] = A - B @ K[t]
        V = A.T @ V @ closed[t]
        V[:d, :d] += precision[t]
        V = 0.5 * (V + V.T)
    return K, L, closed


def _feedforward(mean, precision, L, closed):
    """The backward pass of the linear cost term, per test point: k (B, T - 1, d)."""
    n, T, d = mean.shape
    weighted = (precision @ mean[..., None])[..., 0]  # Q_t mu_t, (B, T, d); m is 1 or B
    s = np.zeros((n, 2 * d))
    s[:, :d] = weighted[:, -1]
    k = np.empty((n, T - 1, d))
    for t in range(T - 2, -1, -1):
        if len(L) > 1:  # one controller per test point
            k[:, t] = np.einsum("bij,bj->bi", L[:, t], s)
            s = np.einsum("bji,bj->bi", closed[:, t], s)
        else:
            k[:, t] = s @ L[0, t].T
            s = s @ closed[0, t]
        s[:, :d] += weighted[:, t]
    return k


def tracking_gains(mean, precision, dt: float, control_cost: float = DEFAULT_CONTROL_COST):
    """The time-varying feedback of the tracking controller (see the module docstring).

    Parameters
    ----------
    mean : ndarray (B, T, d)
        The TP-GMR means :math:`\\mu_t` of B test points.
    precision : ndarray (B, T, d, d)
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
    shared = _shared(precision)
    K, L, closed = _riccati(shared, dt, r)
    k = _feedforward(mean, shared, L, closed)
    return np.broadcast_to(K, (len(mean), *K.shape[1:])), k


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
    shared = _shared(precision)
    _, L, closed = _riccati(shared, dt, r)
    k = _feedforward(mean, shared, L, closed)
    _, B = _plant(d, dt)
    drive = k @ B.T  # B k_t, (n, T - 1, 2d)
    x = np.zeros((n, 2 * d))
    x[:, : start.shape[1]] = start
    states = np.empty((n, T, 2 * d))
    states[:, 0] = x
    for t in range(T - 1):
        if len(closed) > 1:  # one controller per test point
            x = np.einsum("bij,bj->bi", closed[:, t], x) + drive[:, t]
        else:
            x = x @ closed[0, t].T + drive[:, t]
        states[:, t + 1] = x
    if return_velocity:
        return states[..., :d], states[..., d:]
    return states[..., :d]
