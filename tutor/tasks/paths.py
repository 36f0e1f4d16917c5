"""Smooth scripted motions shared by the tasks' demonstration generators.

A person's guided movement between two rests has a bell-shaped speed profile; the
minimum-jerk profile s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 (Flash & Hogan 1985)
is the standard model. Here it runs along a cubic spline through via points, so
the movement passes through them without stopping.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import make_interp_spline

__all__ = ["minimum_jerk_through"]


def minimum_jerk_through(points, n_samples: int) -> np.ndarray:
    """Sample a rest-to-rest movement through ``points`` (k, dim) at ``n_samples`` instants.

    Returns
    -------
    ndarray (n_samples, dim)
        Positions at equal time steps; the first and last equal ``points[0]`` and
        ``points[-1]``.
    """
    pts = np.asarray(points, dtype=float)
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))]
    k = min(3, len(pts) - 1)
    spline = make_interp_spline(
        chord / chord[-1], pts, k=k, **({"bc_type": "natural"} if k == 3 else {})
    )
    dense_u = np.linspace(0.0, 1.0, 2000)
    dense = spline(dense_u)
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))]
    tau = np.linspace(0.0, 1.0, n_samples)
    progress = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    out = spline(np.interp(progress * arc[-1], arc, dense_u))
    out[0], out[-1] = pts[0], pts[-1]
    return out
