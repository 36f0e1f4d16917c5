"""Reading the files of a class: the progress shown and the cache that spares a refresh
the files that did not change (the workers are :class:`tutor.engine.Engine`'s).

:func:`progress_bar` makes the progress callback (a tqdm bar on stderr, or the caller's own)
and :class:`ReadMemo` keeps what :func:`.classroom.read_class` learnt about each file while
the file's size and modification time stay the same (the dashboard's Refresh). They are
:mod:`.classroom`'s own helpers.
"""

from __future__ import annotations

import os
import sys

from ..errors import InvalidParameterError
from ..runtime import headless


def progress_bar(progress):
    """``progress`` checked; gives a function of the number of files that makes the
    progress callback (None for none): a tqdm bar on stderr, or the caller's own."""
    if not (progress is None or isinstance(progress, bool) or callable(progress)):
        raise InvalidParameterError(
            f"progress must be True, False, None or a function of (done, total), got {progress!r}"
        )

    def make(total: int):
        if total < 1 or progress is False:
            return None
        if callable(progress):
            return lambda done: progress(done, total)
        if progress is None and (headless() or not sys.stderr.isatty()):
            return None
        from tqdm import tqdm

        tqdm.monitor_interval = 0  # no monitor thread in a process that forks workers
        return _Bar(tqdm(total=total, desc="Reading the class", unit="file", file=sys.stderr))

    return make


class _Bar:
    """A tqdm bar as a function of the files done so far (closed at the last one)."""

    def __init__(self, bar):
        self.bar = bar

    def __call__(self, done: int) -> None:
        self.bar.update(done - self.bar.n)
        if done >= self.bar.total:
            self.bar.close()


class ReadMemo:
    """What :func:`read_class` learnt about each file, kept while the file is unchanged."""

    def __init__(self, cache, run_files: dict, context):
        self.cache, self.stamps = cache, {}
        if cache is None:
            return
        if cache.get("context") != context:  # another experiment or settings: start over
            cache.clear()
            cache["context"] = context
        for label, run_file in run_files.items():
            try:  # a run file in a trainee's zip changes with the zip
                info = os.stat(run_file.path)
                self.stamps[label] = (info.st_mtime_ns, info.st_size, info.st_ino)
            except OSError:
                self.stamps[label] = None

    def _known(self, label: str, step: str):
        if self.cache is None or self.stamps.get(label) is None:
            return None
        hit = self.cache.get((step, label))
        return hit[1] if hit is not None and hit[0] == self.stamps[label] else None

    def todo(self, labels, step: str) -> list:
        return [lab for lab in labels if self._known(lab, step) is None]

    def merge(self, labels, step: str, new: dict) -> list:
        if self.cache is not None:
            for label, value in new.items():
                self.cache[(step, label)] = (self.stamps.get(label), value)
        return [new[lab] if lab in new else self._known(lab, step) for lab in labels]
