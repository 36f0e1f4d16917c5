"""Shared fixtures."""

from __future__ import annotations

import pytest

from tutor.tasks.maze import load_layout


@pytest.fixture(scope="session")
def layout():
    return load_layout()


@pytest.fixture
def person(tmp_path, monkeypatch):
    """A person at the notebook (not headless, no trainee, condition or class plan set),
    whose runs are saved under tmp_path/sessions."""
    for var in (
        "TUTOR_HEADLESS",
        "TUTOR_TRAINEE",
        "TUTOR_CONDITION",
        "TUTOR_CLASS_PLAN",
        "TUTOR_HAND",
        "JUPYTERHUB_USER",
    ):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("TUTOR_SESSION_DIR", str(tmp_path / "sessions"))
    return monkeypatch
