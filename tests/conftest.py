"""Shared fixtures."""

from __future__ import annotations

import pytest

from tutor.tasks.maze import load_layout


@pytest.fixture(scope="session")
def layout():
    return load_layout()
