"""A kill -9 never loses a saved demonstration nor leaves a half-written run file.

Teachers (tests/crash_child.py) are real maze tutors in their own processes that add
bundled demonstrations until they are killed with SIGKILL: at random moments, and
exactly inside ``os.fsync`` and ``os.replace`` during a save. After each kill the session
file must load and hold every demonstration the teacher had announced as saved (and at
most the one it was adding), and the next teacher on the same file must resume it.

``TUTOR_CRASH_KILLS`` sets the number of random kills (default 20, 5 when ``CI`` is set);
``TUTOR_CRASH_SEED`` replays one run's random moments (the seed is in every message).
"""

from __future__ import annotations

import os
import queue
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tests.helpers import IN_CI, REPO
from tutor.tasks.maze import MazeTask
from tutor.tasks.maze_run import MazeRun

CHILD = Path(__file__).with_name("crash_child.py")
#: random kills on one run file before the next file (keeps files, and loads, small)
KILLS_PER_FILE = 4
#: a random kill lands this long after the teacher resumed (s)
DELAY_RANGE = (0.0, 0.35)
#: (function, call number) of the kills inside a save, all on one file, in this order:
#: the first save of a new file, then saves over an existing one
HANG_KILLS = (("fsync", 1), ("replace", 3), ("fsync", 2), ("replace", 1))
#: longest wait for one line from a teacher (s): a slow shared machine, not a hang
LINE_TIMEOUT = 60.0


def _kill_count() -> int:
    text = os.environ.get("TUTOR_CRASH_KILLS")
    if text is None:
        return 5 if IN_CI else 20
    if not text.strip().isdigit():
        pytest.fail(f"TUTOR_CRASH_KILLS must be a whole number of kills, got {text!r}")
    return int(text)


def _saved_demos(path: Path, task: MazeTask) -> int:
    """How many demonstrations the run file at ``path`` holds (it must load and replay)."""
    return MazeRun.load(path, task).n_demos


def _child_env() -> dict[str, str]:
    """This environment, with the tutor under test first on the children's path."""
    paths = [str(REPO), *filter(None, [os.environ.get("PYTHONPATH")])]
    return {**os.environ, "PYTHONPATH": os.pathsep.join(paths), "MPLBACKEND": "Agg"}


def _temp_files(folder: Path) -> list[Path]:
    """Temporary files left by interrupted atomic writes (``.NAME.*.tmp``)."""
    return sorted(folder.glob(".*.tmp"))


class Teachers:
    """The ``serve`` child: forks teachers on request; its stdout read by a thread."""

    def __init__(self, folder: Path, seed: int):
        self.seed = seed
        self.log = folder / "child_stderr.txt"
        self._stderr = self.log.open("w")
        self.proc = subprocess.Popen(
            [sys.executable, str(CHILD), "serve"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            text=True,
            bufsize=1,
            cwd=folder,
            env=_child_env(),
        )
        self.lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()
        self.expect(lambda words: words[1:] == ["ready"], "the child to start")

    def _read(self) -> None:
        for line in self.proc.stdout:
            self.lines.put(line)
        self.lines.put(None)

    def fail(self, why: str):
        self._stderr.flush()
        pytest.fail(f"{why} (seed {self.seed}); child stderr:\n{self.log.read_text()[-3000:]}")

    def expect(self, matches, what: str, on_line=None) -> list[str]:
        """Read lines until one ``matches`` (its words, pid first); returns its words.

        ``on_line`` sees every line's words on the way.
        """
        deadline = time.monotonic() + LINE_TIMEOUT
        while True:
            try:
                line = self.lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                self.fail(f"no line within {LINE_TIMEOUT:.0f} s while waiting for {what}")
            if line is None:
                self.fail(f"the child's output ended while waiting for {what}")
            words = line.split()
            if on_line is not None:
                on_line(words)
            if matches(words):
                return words

    def teach(self, path: Path, hang: tuple[str, int] | None = None) -> tuple[int, int]:
        """Start a teacher on ``path``; returns (pid, n_demos it resumed)."""
        extra = "" if hang is None else f" {hang[0]} {hang[1]}"
        self.proc.stdin.write(f"teach {path}{extra}\n")
        self.proc.stdin.flush()
        words = self.expect(lambda w: w[1:2] == ["resumed"], f"a teacher to resume {path.name}")
        return int(words[0]), int(words[2])

    def kill(self, pid: int, when, what: str) -> int:
        """SIGKILL teacher ``pid`` once ``when(words)`` is true for one of its lines (or at
        once if ``when`` is None); returns the last ``saved N`` it printed."""
        last = {"saved": None}

        def note(words):
            if words[:2] == [str(pid), "saved"]:
                last["saved"] = int(words[2])

        if when is not None:
            self.expect(lambda w: w[0] == str(pid) and when(w), what, note)
        os.kill(pid, signal.SIGKILL)
        words = self.expect(lambda w: w[:2] == [str(pid), "ended"], f"teacher {pid} to die", note)
        if words[2] != str(-signal.SIGKILL):
            self.fail(f"teacher {pid} ended with {words[2]}, not by the SIGKILL")
        return last["saved"]

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.stdin.close()
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._stderr.close()


@pytest.fixture
def teachers(tmp_path):
    seed = int(os.environ.get("TUTOR_CRASH_SEED", random.SystemRandom().randrange(2**32)))
    child = Teachers(tmp_path, seed)
    yield child
    child.close()


def _check_after_kill(path: Path, task, resumed: int, last_saved: int | None, seed: int) -> int:
    """The file after a kill: absent only if nothing was saved, else whole and holding
    every announced demo (and at most the one in flight). Returns its demo count."""
    announced = resumed if last_saved is None else last_saved
    where = f"{path.name} (seed {seed})"
    if not path.exists():
        assert announced == 0, f"{where} is gone but {announced} demos were saved"
        return 0
    held = _saved_demos(path, task)
    assert announced <= held <= announced + 1, (
        f"{where} holds {held} demos after a kill; the teacher had saved {announced}"
    )
    return held


def test_random_kills_lose_nothing(teachers, tmp_path, maze_task):
    rng = random.Random(teachers.seed)
    kills = _kill_count()
    held = {}
    for k in range(kills):
        path = tmp_path / f"run{k // KILLS_PER_FILE}.json"
        pid, resumed = teachers.teach(path)
        assert resumed == held.get(path, 0), (
            f"a teacher resumed {resumed} demos from {path.name}, which held "
            f"{held.get(path, 0)} (seed {teachers.seed})"
        )
        delay = rng.uniform(*DELAY_RANGE)
        time.sleep(delay)
        last = teachers.kill(pid, None, f"a kill {delay:.3f} s after resuming")
        held[path] = _check_after_kill(path, maze_task, resumed, last, teachers.seed)
    # the last file once more, by a teacher that resumes and saves on top
    path = tmp_path / f"run{(kills - 1) // KILLS_PER_FILE}.json"
    pid, resumed = teachers.teach(path)
    assert resumed == held[path]
    last = teachers.kill(pid, lambda w: w[1] == "saved", "one more save")
    assert _check_after_kill(path, maze_task, resumed, last, teachers.seed) > held[path]
    # a kill mid-save may leave its temporary file; a finished save leaves none
    assert len(_temp_files(tmp_path)) <= kills + 1


def test_kills_inside_fsync_and_replace_lose_nothing(teachers, tmp_path, maze_task):
    path = tmp_path / "run.json"
    held = 0
    for name, call_number in HANG_KILLS:
        pid, resumed = teachers.teach(path, (name, call_number))
        assert resumed == held, f"resumed {resumed} demos from a file holding {held}"
        last = teachers.kill(pid, lambda w, n=name: w[1:] == ["in", n], f"the hang in {name}")
        held = _check_after_kill(path, maze_task, resumed, last, teachers.seed)
        if call_number == 1:
            assert held == resumed, f"the save interrupted in {name} changed the file"
    assert held > 0
    # each interrupted save may leave its temporary file, and nothing else does
    assert len(_temp_files(tmp_path)) <= len(HANG_KILLS)
    # a teacher started afresh (its own Python, no fork) resumes the same file
    with (tmp_path / "fresh_stderr.txt").open("w+") as stderr:
        proc = subprocess.Popen(
            [sys.executable, str(CHILD), "teach", str(path)],
            stdout=subprocess.PIPE,
            stderr=stderr,
            text=True,
            env=_child_env(),
            cwd=tmp_path,
        )
        try:
            first = proc.stdout.readline().split()
        finally:
            proc.kill()
            proc.wait()
        stderr.seek(0)
        assert first[1:] == ["resumed", str(held)], (
            f"a fresh teacher said {first}:\n" + (stderr.read()[-3000:])
        )
