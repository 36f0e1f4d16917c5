"""Helpers shared by the tests: scripted maze demo sets."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def maze_demos(layout, n_demos: int, seed: int, jitter: float = 0.004):
    """``n_demos`` scripted demos from random starts, and their frames."""
    rng = np.random.default_rng(seed)
    starts = layout.sample_starts(n_demos, rng)
    demos = [layout.reference_path(s, rng, jitter=jitter) for s in starts]
    return demos, [layout.frames(s) for s in starts]
