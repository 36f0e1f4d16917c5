"""How the tutor is being run: by a person, or headless (CI, nbmake).

``TUTOR_HEADLESS=1`` (set by ``scripts/test.sh``) switches the notebooks to headless
mode: cells that would wait for a person instead feed bundled demonstrations.
nbmake runs a real kernel, so "am I in a notebook?" checks cannot tell a test from a
person; the environment variable can.

``TUTOR_SESSION_DIR`` moves where teaching runs are autosaved (default ``./sessions``
next to the notebooks).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["headless", "session_dir"]


def headless() -> bool:
    """True when TUTOR_HEADLESS is set to a true value (1, true, yes)."""
    return os.environ.get("TUTOR_HEADLESS", "").strip().lower() in ("1", "true", "yes")


def session_dir(trainee: str = "trainee") -> Path:
    """The folder for one trainee's session files (created if needed)."""
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in trainee.strip()) or "trainee"
    base = Path(os.environ.get("TUTOR_SESSION_DIR", "sessions"))
    folder = base / safe
    folder.mkdir(parents=True, exist_ok=True)
    return folder
