"""Files a trainee uploads with an ``ipywidgets.FileUpload`` button."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

__all__ = ["on_upload"]


def on_upload(load: Callable[[Path], None]) -> Callable[[dict], None]:
    """An observer for ``FileUpload.value`` that hands the first file to ``load(path)``.

    The upload is written to a temporary file that keeps its name and suffix (so
    ``.json`` and ``.csv`` are told apart and messages name the trainee's file) and is
    removed after ``load`` returns.
    """

    def observer(change: dict) -> None:
        files = change["new"]
        if not files:
            return
        item = files[0]
        name = Path(item["name"]).name or "upload.json"
        if not Path(name).suffix:
            name += ".json"
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / name
            path.write_bytes(bytes(item["content"]))
            load(path)

    return observer
