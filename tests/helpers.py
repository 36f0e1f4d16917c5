"""Helpers shared by the tests: scripted maze demo sets and the outside reference data."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"
IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def maze_demos(layout, n_demos: int, seed: int, jitter: float = 0.004):
    """``n_demos`` scripted demos from random starts, and their frames."""
    rng = np.random.default_rng(seed)
    starts = layout.sample_starts(n_demos, rng)
    demos = [layout.reference_path(s, rng, jitter=jitter) for s in starts]
    return demos, [layout.frames(s) for s in starts]


def shared_file(name: str) -> Path:
    """A file of the outside reference data beside the repo; required in CI."""
    path = SHARED_DATA / name
    if not path.exists():
        if IN_CI:
            pytest.fail(
                f"reference data {path} is missing in CI (shared/ must sit beside the repo)"
            )
        pytest.skip(f"reference data {path} not available outside CI")
    return path
