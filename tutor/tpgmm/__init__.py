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

Modules
-------
checks
    The ``check_*`` validators of every input (demos, times, settings, seeds).
frames
    :class:`Frame` and :class:`FrameBatch`, the task parameters.
frame_views
    Each frame's regression mapped into the world, and the frames' disagreement.
model
    :class:`TPGMM`: data preparation, fit, score, reproduce.
em
    EM on sufficient statistics with SQUAREM acceleration.
regression
    Gaussian mixture regression over time and the product over frames.
tracking
    Linear quadratic tracking of the TP-GMR from the robot's own start state (a robot
    running the model: tight where the demos agree, loose where they do not).
linalg
    Small linear algebra shared by the above.

Implementation notes
--------------------
* Each frame's local data are standardised (per dimension) before EM, so that
  ``reg_covar`` is a variance *relative to the data's spread*, in any units. That
  spread is the whole movement's, far larger than a start or goal frame's spread at
  its own end, so ``reg_covar`` must be small (default 3e-5; 1e-3 cost 3-6 mm at the
  start points, see :class:`TPGMM`).
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

from .checks import (
    check_choice,
    check_count,
    check_demo,
    check_flag,
    check_number,
    check_real_array,
    check_seed,
    check_times,
)
from .frame_views import frame_disagreement, frame_views
from .frames import Frame, FrameBatch, check_frame_matrix, check_frame_row
from .model import TPGMM

__all__ = [
    "Frame",
    "FrameBatch",
    "TPGMM",
    "check_choice",
    "check_count",
    "check_demo",
    "check_flag",
    "check_frame_matrix",
    "check_frame_row",
    "check_number",
    "check_real_array",
    "check_seed",
    "check_times",
    "frame_disagreement",
    "frame_views",
]
