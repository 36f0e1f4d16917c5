"""lfd-tutor: a tutor for teaching Learning from Demonstration (LfD) to novices.

The package backs a set of JupyterLab notebooks. It is organised in layers; each
layer only imports from the layers to its left:

    tpgmm  <-  framework  <-  tasks, robot  <-  views  <-  teachers  <-  notebooks / CLI

- ``tpgmm``: the learner, a Task-Parameterised Gaussian Mixture Model (TP-GMM) with
  Gaussian Mixture Regression for reproduction (numpy/scipy only).
- ``framework``: the teaching-behaviour measures of Sena & Howard, "Quantifying
  Teaching Behaviour in Robot Learning from Demonstration": the sets B, R, b, r,
  efficacy eps = |R & B| / |B| and efficiency eta = eps / |b|.
- ``tasks``: the maze and pick-and-place tasks the learner is taught.
- ``robot``: the simulated arm (Pinocchio + example-robot-data).
- ``views``: plots (matplotlib) and 3-D rendering (Meshcat).
- ``teachers``: simulated teachers (the paper's teacher model: Q, omega, Omega).
- ``study``: the paper's two experiments rerun with simulated cohorts, their
  statistics and figures (``python -m tutor reproduce --experiment 1|2``).

This module imports nothing so that ``import tutor`` stays cheap.
"""

__version__ = "0.1.0"
