"""The paper's results, re-exported from :mod:`tutor.paper` (where every number from
Sena & Howard lives) for the study's modules and older imports."""

from __future__ import annotations

from ..paper import EXPERIMENT_1, EXPERIMENT_2

__all__ = ["EXPERIMENT_1", "EXPERIMENT_2"]
