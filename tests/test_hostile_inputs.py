"""Hostile inputs through the entry points a trainee or an educator uses.

Every case of the review (and more) is one row of a table below, thrown at the tutors
(:class:`~tutor.views.maze_app.MazeTutor`, :class:`~tutor.views.pickplace_app.PickPlaceTutor`:
their actions, Load, the upload widget, resuming a run file), at the library
(``trainee_dir``, ``load_demos``, ``bundled_demos``, ``TeachingSession``, ``TPGMM``,
``Frame``) and at the command line (real subprocesses). For each case:

1. nothing escapes: a tutor action returns and ``app.message`` is a plain sentence (no
   traceback, no ``[Errno ..]``, not the tutor's "Something went wrong inside" fallback,
   which means an exception nobody expected); a library call raises a
   :class:`~tutor.errors.TutorError`; the CLI exits with 2 and one line on stderr;
2. nothing is lost: after a refused action the run in memory (``app.record``) and the run
   file's bytes are as before, and the completed demos are still in the file; after a
   failed save every demo is still in memory and the old file is whole;
3. the message says what was wrong AND how to fix it: each row has a regular expression
   for each (searched case-insensitively).

Real files, FIFOs, symbolic links, devices, tmpfs mounts (a full disk, a read-only disk)
and subprocesses; no mocks.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from tests.helpers import IN_CI, REPO
from tutor.demofiles import DEMOS_FORMAT, bundled_demos, load_demos
from tutor.errors import (
    InvalidDemoError,
    InvalidFileError,
    InvalidFrameError,
    InvalidParameterError,
    SaveError,
    TutorError,
)
from tutor.framework import RunRecord, TeachingSession, Trainee
from tutor.runtime import trainee_dir
from tutor.tasks.maze import MazeTask
from tutor.tasks.maze_run import MazeRun
from tutor.tasks.pickplace import PickPlaceTask
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.tpgmm import TPGMM, Frame
from tutor.views.maze_app import MazeTutor
from tutor.views.pickplace_app import PickPlaceTutor

TRAINEE = "Mai Anh"
COLUMNS = ("t", "x", "y", "z", "g")
HUGE_INT = "1" + "0" * 400  # 10**400: no float holds it
MB = 1024 * 1024

#: what a message must never look like: a traceback, a raw OSError, the tutor's fallback
#: for an exception nobody expected, or a bare built-in exception name
RAW = re.compile(
    r"Traceback|\[Errno \d+\]|File \"|Something went wrong inside the tutor|"
    r"\b(?:Type|Value|Key|Index|Attribute|OS|Overflow|ZeroDivision|Recursion|Unicode\w*|"
    r"FileNotFound|IsADirectory|NotADirectory|Permission|FileExists)Error\b"
)


# ====================================================================== helpers


class Hung(BaseException):
    """A case blocked (e.g. on a FIFO); a BaseException so no tutor handler swallows it."""


@contextmanager
def deadline(seconds: float = 10.0):
    """Fail a case that blocks for more than ``seconds`` instead of hanging the run."""

    def alarm(signum, frame):
        raise Hung(f"still blocked after {seconds:g} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def assert_plain(text, what=None, fix=None):
    """``text`` is a non-empty plain sentence naming what was wrong and how to fix it."""
    assert isinstance(text, str) and text.strip(), f"no message at all: {text!r}"
    assert not RAW.search(text), f"not a plain sentence: {text!r}"
    if what is not None:
        assert re.search(what, text, re.I | re.S), f"does not say what was wrong ({what}): {text!r}"
    if fix is not None:
        assert re.search(fix, text, re.I | re.S), f"does not say how to fix it ({fix}): {text!r}"


def act(fn, *args, **kwargs):
    """Run a tutor action: nothing may escape it."""
    try:
        with deadline():
            return fn(*args, **kwargs)
    except BaseException as exc:  # noqa: BLE001 - the point is that nothing escapes
        pytest.fail(f"{type(exc).__name__} escaped the tutor action: {exc}")


def raised(fn) -> TutorError:
    """Run a library call that must refuse its input with a named error."""
    try:
        with deadline():
            fn()
    except TutorError as exc:
        return exc
    except BaseException as exc:  # noqa: BLE001
        pytest.fail(f"{type(exc).__name__} escaped instead of a tutor.errors error: {exc}")
    pytest.fail("the input was accepted; a named tutor.errors error was expected")


def file_bytes(path):
    """The bytes of ``path``, or what it is when it is not a regular file."""
    path = Path(path)
    if path.is_symlink():
        return ("symlink", os.readlink(path))
    if not path.exists():
        return None
    if not path.is_file():
        return ("not a regular file", path.stat().st_mode)
    return path.read_bytes()


def saved_record(path) -> RunRecord:
    return RunRecord.from_dict(json.loads(Path(path).read_text()))


def every_demo(record: RunRecord) -> list:
    return [d for a in record.attempts for d in (*a.demos, *a.undone)]


def temp_files(folder) -> list[str]:
    folder = Path(folder)
    return sorted(p.name for p in folder.glob(".*.tmp")) if folder.is_dir() else []


def demo_doc(demos, columns=("t", "x", "y"), **extra) -> dict:
    """A demonstration file (format lfd-tutor-demos)."""
    return {
        "format": DEMOS_FORMAT,
        "version": 1,
        "task": None,
        "columns": list(columns),
        "description": "",
        "demos": [d if isinstance(d, list) else np.asarray(d, float).tolist() for d in demos],
        **extra,
    }


def swap(doc, placeholder: str, raw: str) -> str:
    """``doc`` as JSON with the string ``placeholder`` replaced by the raw JSON ``raw``."""
    text = json.dumps(doc)
    assert f'"{placeholder}"' in text
    return text.replace(f'"{placeholder}"', raw, 1)


def poke(demo, row: int, col: int, value):
    """``demo`` as nested lists with one value replaced (which may be a string)."""
    rows = np.asarray(demo, float).tolist()
    rows[row][col] = value
    return rows


def csv_of(demos, header=("demo", "t", "x", "y"), sep=",", decimal=".", bom=False, newline="\n"):
    """A CSV demonstration file; ``header`` says which column goes where."""
    lines = [sep.join(header)]
    for i, demo in enumerate(demos, start=1):
        for row in np.asarray(demo, float):
            cells = [repr(float(row[COLUMNS.index(c)])).replace(".", decimal) for c in header[1:]]
            lines.append(sep.join([str(i), *cells]))
    return ("\ufeff" if bom else "") + newline.join(lines) + newline


def writes(content):
    """A maker writing ``content`` (bytes, text, or a function of the world giving them)."""

    def make(path: Path, w) -> None:
        data = content(w) if callable(content) else content
        if isinstance(data, dict | list):
            data = json.dumps(data)
        path.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))

    return make


def fifo(path: Path, w) -> None:
    os.mkfifo(path)


def folder(path: Path, w) -> None:
    path.mkdir()


def symlink_loop(path: Path, w) -> None:
    other = path.with_name(f"other-{path.name}")
    os.symlink(other.name, path)
    os.symlink(path.name, other)


def to_dev_zero(path: Path, w) -> None:
    os.symlink("/dev/zero", path)


def sparse_60mb(path: Path, w) -> None:
    with open(path, "wb") as fh:
        fh.truncate(60 * MB)


def nested_deeply(w) -> str:
    return "[" * 100_000 + "]" * 100_000


# ---------------------------------------------------------------- run files


def maze_record(w, condition="VF", trainee=TRAINEE, n=2) -> dict:
    run = MazeRun.new(condition, w.maze_task, trainee=Trainee.from_name(trainee))
    for demo in w.good[2 : 2 + n]:
        run.add_demo(demo)
    return run.to_dict()


def pp_record(w, condition="BF", run=1) -> dict:
    pp = PickPlaceRun(condition, task=w.pp_task, trainee=Trainee.from_name(TRAINEE), run=run)
    pp.demonstrate(10, raw=w.pp_raw[10])
    return pp.to_dict()


def huge_run(w) -> str:
    """A run file with 10**400 as a sample value."""
    doc = maze_record(w)
    doc["attempts"][0]["demos"][0]["samples"][2][1] = "HUGE"
    return swap(doc, "HUGE", HUGE_INT)


def edited(doc: dict, change) -> dict:
    change(doc)
    return doc


def without_finished(doc: dict) -> dict:
    for attempt in doc["attempts"]:
        attempt.pop("finished")
    return doc


def sorted_keys(doc: dict) -> str:
    return json.dumps(doc, sort_keys=True, indent=1)


def duplicate_key(doc: dict, key: str, first) -> str:
    """``doc`` as JSON whose top level says ``key`` twice: ``first``, then the real value."""
    text = json.dumps(doc)
    return "{" + f'"{key}": {json.dumps(first)}, ' + text[1:]


def pp_file(w, demos, conditions) -> dict:
    return demo_doc(
        demos,
        COLUMNS,
        conditions=[None if c is None else np.asarray(c, float).tolist() for c in conditions],
    )


def in_cm(raw) -> np.ndarray:
    out = np.array(raw, float)
    out[:, 1:4] *= 100
    return out


# ====================================================================== the world and a case


class World:
    """What every case shares (built once): the tasks and some real demonstrations."""

    def __init__(self):
        self.maze_task = MazeTask()
        self.good = [np.asarray(d, float) for d in bundled_demos("maze_good")]
        self.pp_task = PickPlaceTask()
        rng = np.random.default_rng(0)
        self.pp_raw = {p: self.pp_task.demonstrate(p, rng) for p in (0, 10, 44, 99)}


@pytest.fixture(scope="module")
def w():
    return World()


@pytest.fixture
def mount(tmp_path):
    """``mount(name, options)``: a real tmpfs at ``tmp_path/name`` (root only)."""
    mounted = []

    def do(name: str, options: str) -> Path:
        where = tmp_path / name
        where.mkdir()
        done = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)],
            capture_output=True,
            text=True,
        )
        if done.returncode != 0:
            why = f"cannot mount a tmpfs here ({done.stderr.strip() or done.returncode})"
            if IN_CI:
                pytest.fail(why)
            pytest.skip(why)
        mounted.append(where)
        return where

    yield do
    for where in reversed(mounted):
        subprocess.run(["umount", "-l", str(where)], capture_output=True)


class Ctx:
    """One case's world: a fresh folder, and tutors made the way a notebook makes them."""

    def __init__(self, w, tmp: Path, mount, monkeypatch):
        self.w, self.tmp, self.mount, self.monkeypatch = w, tmp, mount, monkeypatch
        self.apps = []
        self.procs = []

    def keep(self, app):
        self.apps.append(app)
        return app

    def maze(self, condition="VF", demos=1, finished=False, path=None, trainee=TRAINEE):
        path = self.tmp / "runs" / f"{condition}.json" if path is None else path
        app = self.keep(MazeTutor(condition, run_file=path, trainee=trainee))
        for demo in self.w.good[:demos]:
            app.add(demo)
        if finished:
            app.finish()
        assert app.session.n_demos == demos and app.finished == finished, app.message
        return app

    def pp(self, condition="BF", demos=1, finished=False, run=1):
        path = self.tmp / "runs" / f"{condition}-{run}.json"
        app = self.keep(
            PickPlaceTutor(
                condition, run_file=path, task=self.w.pp_task, seed=0, trainee=TRAINEE, run=run
            )
        )
        for plant in (44, 0, 99)[:demos]:
            app.demonstrate(plant)
        if finished:
            app.finish()
        assert app.run.n_demos == demos and app.finished == finished, app.message
        return app

    def close(self):
        for proc in self.procs:
            if proc.poll() is None:
                proc.kill()
            proc.wait(30)
        for app in self.apps:
            try:
                app.controller.release_lock()
            except Exception:  # noqa: BLE001 - cleaning up only
                pass


@pytest.fixture
def c(w, tmp_path, mount, monkeypatch):
    monkeypatch.delenv("JUPYTERHUB_USER", raising=False)
    monkeypatch.delenv("TUTOR_RUNS_DIR", raising=False)
    ctx = Ctx(w, tmp_path, mount, monkeypatch)
    yield ctx
    ctx.close()


@dataclass
class Snapshot:
    record: RunRecord
    n_demos: int
    run_file: Path
    data: object
    elapsed: float | None

    @classmethod
    def of(cls, app) -> Snapshot:
        return cls(
            app.record,
            app.run.n_demos,
            app.run_file,
            file_bytes(app.run_file),
            getattr(app.run, "elapsed", None),
        )


def upload(app, name, content: bytes) -> None:
    """What the browser does when the trainee picks a file in the Load button."""
    app.upload.value = (
        {
            "name": name,
            "type": "application/json",
            "size": len(content),
            "content": memoryview(content),
            "last_modified": dt.datetime.now(dt.UTC),
        },
    )


# ====================================================================== 1. refused tutor actions

#: (id, tutor, setup options, action(app, c) -> tutor whose message counts or None,
#:  what was wrong, how to fix it)
#: tutor: "maze" (VF) or "pp" (BF); options: condition, demos, finished
ACTIONS = [
    # --- the review's cases
    ("reset-once-over-a-finished-run", "maze", {"finished": True},
     lambda app, c: app.request_reset(), r"press reset again", r"within 5 seconds"),
    ("reset-button-once-over-a-finished-pp-run", "pp", {"finished": True},
     lambda app, c: app.buttons["Reset"].click(), r"press reset again", r"within 5 seconds"),
    ("second-tutor-on-one-file-adds", "maze", {},
     lambda app, c: second_tutor(app, c, lambda o: o.add(c.w.good[1])),
     r"open in another tutor|read-only", r"close (it|the other)"),
    ("second-tutor-on-one-file-resets-and-finishes", "maze", {},
     lambda app, c: second_tutor(app, c, lambda o: (o.reset(), o.finish(), o.undo())),
     r"read-only", r"close (it|the other)"),
    ("second-kernel-on-one-file", "maze", {"demos": 2},
     lambda app, c: second_kernel(app, c), r"open in another tutor|read-only",
     r"close (it|the other)"),
    # --- maze actions my own
    ("add-text", "maze", {}, lambda app, c: app.add("hello"),
     r"not a numeric table|not.*numbers", r"array of shape|time in column 0"),
    ("add-nan", "maze", {}, lambda app, c: app.add(poke(c.w.good[1], 3, 1, float("nan"))),
     r"NaN", r"remove or interpolate"),
    ("add-one-sample", "maze", {}, lambda app, c: app.add(c.w.good[1][:1]),
     r"1 sample", r"at least 2"),
    ("add-time-backwards", "maze", {}, lambda app, c: app.add(c.w.good[1][::-1]),
     r"not strictly increasing", r"sort the samples by time"),
    ("add-complex", "maze", {}, lambda app, c: app.add(c.w.good[1] + 1j),
     r"complex|not a numeric table|not.*real", r"real number|array of shape"),
    ("add-10**400", "maze", {}, lambda app, c: app.add(poke(c.w.good[1], 3, 1, 10**400)),
     r"too large|overflow", r"fix|remove|smaller"),
    ("add-seven-columns", "maze", {}, lambda app, c: app.add(np.zeros((20, 7))),
     r"7 columns|columns", r"3 are needed|column order|drop"),
    ("add-none", "maze", {}, lambda app, c: app.add(None),
     r"not a numeric table|2-d array|no demonstration", r"array of shape|\(T"),
    ("add-to-a-finished-run", "maze", {"finished": True}, lambda app, c: app.add(c.w.good[1]),
     r"finished", r"reset"),
    ("finish-without-demos", "maze", {"demos": 0}, lambda app, c: app.finish(),
     r"at least one demonstration", r"give"),
    ("bring-back-attempt-99", "maze", {}, lambda app, c: app.restore(99),
     r"no earlier attempt 99", r"attempts 1 to|choose"),
    ("bring-back-attempt-True", "maze", {"two_attempts": True}, lambda app, c: app.restore(True),
     r"attempt.*(number|true)|true", r"number"),
    ("bring-back-attempt-1.7", "maze", {"two_attempts": True}, lambda app, c: app.restore(1.7),
     r"attempt.*(whole|number)|1\.7", r"whole number|number"),
    ("load-None", "maze", {}, lambda app, c: app.load(None),
     r"file|path|none", r"give|choose|pick"),
    ("load-a-number", "maze", {}, lambda app, c: app.load(123),
     r"file|path|123", r"give|choose|pick"),
    ("load-/dev/zero", "maze", {}, lambda app, c: app.load("/dev/zero"),
     r"\.json or \.csv|device", r"load a|saved file"),
    ("save-a-copy-onto-a-folder", "maze", {},
     lambda app, c: app.save((c.tmp / "a-folder").mkdir() or c.tmp / "a-folder"),
     r"is a folder", r"file name inside it"),
    ("save-a-copy-named-with-NUL", "maze", {}, lambda app, c: app.save(c.tmp / "co\x00py.json"),
     r"NUL", r"name"),
    # --- pick-and-place actions
    ("demonstrate-plant-10**30", "pp", {}, lambda app, c: app.demonstrate(10**30),
     r"plant is a number", r"0 to 99"),
    ("demonstrate-plant-True", "pp", {}, lambda app, c: app.demonstrate(True),
     r"plant is a number.*true", r"0 to 99"),
    ("demonstrate-plant--1", "pp", {}, lambda app, c: app.demonstrate(-1),
     r"plant is a number", r"0 to 99"),
    ("demonstrate-plant-2.5", "pp", {}, lambda app, c: app.demonstrate(2.5),
     r"plant is a number", r"0 to 99"),
    ("demonstrate-plant-text", "pp", {}, lambda app, c: app.demonstrate("forty-four"),
     r"plant is a number", r"0 to 99"),
    ("demonstrate-unknown-mistake", "pp", {},
     lambda app, c: app.demonstrate(44, mistake="teleport"), r"unknown mistake", r"use None"),
    ("demonstrate-after-the-run", "pp", {"finished": True}, lambda app, c: app.demonstrate(44),
     r"run is over|finished", r"next run|reset"),
    ("test-no-plants", "pp", {"condition": "SF"}, lambda app, c: app.test([]),
     r"no plant|empty|none", r"choose|at least one|pick"),
    ("test-plant-10**30", "pp", {"condition": "SF"}, lambda app, c: app.test([10**30]),
     r"plant is a number", r"0 to 99"),
    ("test-during-a-BF-run", "pp", {}, lambda app, c: app.test([5]),
     r"only after the run", r"after the run|finish"),
    ("test-a-plant-list-that-is-text", "pp", {"condition": "SF"}, lambda app, c: app.test("44"),
     r"plant", r"0 to 99|choose"),
]  # fmt: skip


def second_tutor(app, c, do):
    """The same run opened again in this kernel (its cell run again): the newer tutor
    carries on, and the older view, now read-only, changes nothing and says why."""
    other = c.keep(MazeTutor("VF", run_file=app.run_file, trainee=TRAINEE))
    assert not other.read_only and app.read_only, (other.message, app.message)
    assert "replaced by a newer one" in app.message
    do(app)
    assert other.record == app.record  # the old view changed nothing
    return app


CHILD = textwrap.dedent(
    """
    import sys
    from tutor.views.maze_app import MazeTutor
    app = MazeTutor("VF", run_file=sys.argv[1], trainee=sys.argv[2])
    print("ready", app.read_only, app.session.n_demos, flush=True)
    sys.stdin.readline()  # hold the file until told to go
    """
)


def second_kernel(app, c):
    """Another kernel (a real process) holds the run's file; this one opens it too."""
    app.close()  # let go, as a restarted notebook would, so the other kernel takes the file
    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg"}
    proc = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(app.run_file), TRAINEE],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    c.procs.append(proc)
    line = proc.stdout.readline()
    assert line.split() == ["ready", "False", "2"], (line, proc.stderr.read())
    other = c.keep(MazeTutor("VF", run_file=app.run_file, trainee=TRAINEE))
    assert other.read_only and other.session.n_demos == 2, other.message
    other.add(c.w.good[3])
    other.undo()
    other.undo()
    return other


@pytest.mark.parametrize(
    "tutor, options, action, what, fix",
    [pytest.param(*row[1:], id=row[0]) for row in ACTIONS],
)
def test_a_refused_action_changes_nothing_and_says_why(c, tutor, options, action, what, fix):
    options = dict(options)
    two = options.pop("two_attempts", False)
    app = c.maze(**options) if tutor == "maze" else c.pp(**options)
    if two:  # an earlier attempt to bring back
        app.reset()
        app.add(c.w.good[2])
    before = Snapshot.of(app)
    shown = act(action, app, c)
    target = shown if shown is not None else app
    assert_plain(target.message, what, fix)
    after = Snapshot.of(app)
    assert after.record == before.record, "the run in memory changed"
    assert after.n_demos == before.n_demos and after.elapsed == before.elapsed
    assert after.run_file == before.run_file
    assert after.data == before.data, "the run file changed"
    if before.data is not None:  # the completed demos are still in the file
        assert saved_record(app.run_file).current.n_demos == before.n_demos


# ====================================================================== 2. Load: refused files

#: (id, tutor, options, file name, maker(path, w), what, fix)
LOADS = [
    # --- the review's cases
    ("another-conditions-run-file", "maze", {}, "VR.json",
     writes(lambda w: maze_record(w, "VR")), r"VR run.*VF run|VF run.*VR run", r"matching tutor"),
    ("a-run-file-into-a-finished-run", "maze", {"finished": True}, "copy.json",
     writes(lambda w: maze_record(w, "VF")), r"finished", r"press reset"),
    ("a-demo-file-into-a-finished-run", "maze", {"finished": True}, "more.csv",
     writes(lambda w: csv_of(w.good[1:3])), r"finished", r"reset"),
    ("10**400-in-a-demo-file", "maze", {}, "huge.json",
     writes(lambda w: swap(demo_doc([poke(w.good[1], 4, 1, "HUGE")]), "HUGE", HUGE_INT)),
     r"too large for a floating-point number", r"fix or remove"),
    ("1e400-in-a-demo-file", "maze", {}, "huge.json",
     writes(lambda w: swap(demo_doc([poke(w.good[1], 4, 1, "HUGE")]), "HUGE", "1e400")),
     r"too large for a floating-point number", r"fix or remove"),
    ("10**400-in-a-run-file", "maze", {}, "VF-copy.json", writes(huge_run), r"too large",
     r"fix or remove|original file|new run"),
    ("1e400-in-a-csv", "maze", {}, "huge.csv",
     writes("demo,t,x,y\n1,0.0,0.1,0.1\n1,1e400,0.2,0.2\n"),
     r"too large for a floating-point number", r"fix or remove"),
    ("a-fifo-named-.json", "maze", {}, "pipe.json", fifo, r"pipe|fifo",
     r"regular file|saved file"),
    ("a-link-to-/dev/zero-named-.json", "maze", {}, "zero.json", to_dev_zero, r"device",
     r"saved file|regular file"),
    ("a-folder-named-x.json", "maze", {}, "x.json", folder, r"is a folder",
     r"file inside it|path of a saved file"),
    ("a-symlink-loop", "maze", {}, "loop.json", symlink_loop, r"loop of symbolic links",
     r"(remove|replace|fix|point).*link|link.*(remove|replace|fix|point)"),
    ("a-sparse-60-MB-file", "maze", {}, "big.json", sparse_60mb, r"60 MB.*50 MB",
     r"right file"),
    ("a-missing-file", "maze", {}, "gone.json", lambda p, w: None, r"does not exist",
     r"check the name"),
    ("a-.txt-file", "maze", {}, "notes.txt", writes("t,x,y\n"), r"\.json or \.csv",
     r"load a"),
    # --- misread files
    ("semicolons-with-decimal-commas", "maze", {}, "excel.csv",
     writes(lambda w: csv_of(w.good[1:2], sep=";", decimal=",")), r"separated by ';'",
     r"decimal point"),
    ("demo-file-version-99", "maze", {}, "v99.json",
     writes(lambda w: demo_doc(w.good[1:2], version=99)), r"version 99", r"reads version 1"),
    ("demo-file-version-text", "maze", {}, "v1.json",
     writes(lambda w: demo_doc(w.good[1:2], version="1")), r"version '1'", r"whole number"),
    ("run-file-version-99", "maze", {}, "VF-v99.json",
     writes(lambda w: edited(maze_record(w), lambda d: d.update(version=99))),
     r"version 99", r"reads version 1"),
    ("an-old-session-format", "maze", {}, "old.json",
     writes({"format": "lfd-tutor-session", "version": 3, "demos": []}),
     r"older lfd-tutor", r"that version|new run"),
    ("complex-values-in-a-csv", "maze", {}, "complex.csv",
     writes("demo,t,x,y\n1,0.0,0.1,0.1\n1,1.0,0.2+1j,0.2\n"), r"complex", r"real number"),
    ("an-unknown-csv-column", "maze", {}, "q.csv",
     writes(lambda w: csv_of(w.good[1:2]).replace("demo,t,x,y", "demo,t,x,q")),
     r"unknown column 'q'", r"known columns are"),
    # --- my own
    ("a-repeated-csv-column", "maze", {}, "xx.csv",
     writes("demo,t,x,x\n1,0,0.1,0.1\n1,1,0.2,0.2\n"), r"'x' appears twice", r"keep one"),
    ("a-csv-with-only-a-header", "maze", {}, "empty.csv", writes("demo,t,x,y\n"),
     r"no samples", r"add|give|at least|rows"),
    ("a-ragged-csv", "maze", {}, "ragged.csv",
     writes("demo,t,x,y\n1,0,0.1,0.1\n1,1,0.2\n"), r"3 values but the header has 4",
     r"(each|every) (row|line)|same number|add|fill"),
    ("a-csv-demo-of-one-sample", "maze", {}, "one.csv", writes("demo,t,x,y\n1,0,0.1,0.1\n"),
     r"1 sample", r"at least 2"),
    ("a-csv-demo-with-time-going-backwards", "maze", {}, "back.csv",
     writes(lambda w: csv_of([w.good[1][::-1]])), r"not strictly increasing",
     r"sort the samples by time"),
    ("the-second-demo-bad-first-not-kept", "maze", {}, "two.json",
     writes(lambda w: demo_doc([w.good[1], w.good[2][:1]])), r"demo 2", r"at least 2"),
    ("a-demos-list-that-is-a-dict", "maze", {}, "dict.json",
     writes(lambda w: edited(demo_doc(w.good[1:2]), lambda d: d.update(demos={"1": d["demos"]}))),
     r"'demos'", r"must be a list"),
    ("json-with-duplicate-keys", "maze", {}, "dup.json",
     writes(lambda w: duplicate_key(demo_doc(w.good[1:3]), "demos", [[[0, 0, 0]]])),
     r"twice|duplicate|more than once", r"keep one|remove|one of them"),
    ("a-run-file-with-duplicate-keys", "maze", {}, "VF-dup.json",
     writes(lambda w: duplicate_key(maze_record(w), "condition", "VR")),
     r"twice|duplicate|more than once", r"keep one|remove|original file"),
    ("a-nul-escape-in-a-column-name", "maze", {}, "nul.json",
     writes(lambda w: demo_doc(w.good[1:2], ["t", "x\u0000", "y"])),
     r"unknown column", r"known columns are"),
    ("a-nul-escape-in-the-trainee-name", "maze", {}, "VF-nul.json",
     writes(lambda w: edited(maze_record(w), lambda d: d["trainee"].update(name="Mai\u0000Anh"))),
     r"control character|NUL", r"original file|new run|name"),
    ("events-naming-attempt-7-of-1", "maze", {}, "VF-events.json",
     writes(lambda w: edited(maze_record(w), lambda d: d["events"][-1].update(attempt=6))),
     r"attempt 7 of 1", r"original file|new run"),
    ("a-test-after-demo-9-of-2", "maze", {}, "VF-tests.json",
     writes(lambda w: edited(maze_record(w), lambda d: d["attempts"][0].update(
         tests=[{"after_demo": 9, "plants": [0]}]))), r"after demo 9 of 2",
     r"original file|new run"),
    ("negative-seconds-in-a-run-file", "maze", {}, "VF-seconds.json",
     writes(lambda w: edited(maze_record(w), lambda d: d["attempts"][0]["demos"][0].update(
         seconds=-5))), r">= 0", r"original file|new run"),
    ("an-unknown-entry-in-a-run-file", "maze", {}, "VF-extra.json",
     writes(lambda w: edited(maze_record(w), lambda d: d.update(hacked=1))),
     r"unknown entries 'hacked'", r"original file|new run"),
    ("a-trainee-name-that-is-null", "maze", {}, "VF-null.json",
     writes(lambda w: edited(maze_record(w), lambda d: d["trainee"].update(name=None))),
     r"trainee.name: must be text", r"original file|new run"),
    ("experiment-true-in-a-run-file", "maze", {}, "VF-bool.json",
     writes(lambda w: edited(maze_record(w), lambda d: d.update(experiment=True))),
     r"whole number", r"original file|new run"),
    ("a-json-list", "maze", {}, "list.json", writes("[1, 2, 3]"),
     r"neither a demonstration file", r'"format"'),
    ("an-empty-json-file", "maze", {}, "empty.json", writes(""), r"is empty", r"right file"),
    ("bytes-that-are-not-utf-8", "maze", {}, "garbage.json", writes(b"\xff\xfe\x00\x81" * 50),
     r"not UTF-8", r"save it as UTF-8"),
    ("json-nested-100000-deep", "maze", {}, "deep.json", writes(nested_deeply),
     r"nested too deeply", r"right file"),
    ("NaN-in-a-demo-file", "maze", {}, "nan.json",
     writes(lambda w: swap(demo_doc([poke(w.good[1], 4, 1, "X")]), "X", "NaN")),
     r"NaN is not allowed", r"finite number"),
    ("true-as-a-sample-value", "maze", {}, "bool.json",
     writes(lambda w: demo_doc([poke(w.good[1], 4, 1, True)])), r"holds true",
     r"plain number"),
    ("a-pick-and-place-run-into-the-maze", "maze", {}, "pp.json", writes(pp_record),
     r"experiment 2.*experiment 1|experiment 1.*experiment 2", r"matching tutor"),
    # --- pick-and-place loads
    ("pp-malformed-condition-row", "pp", {}, "rows.json",
     writes(lambda w: pp_file(w, [w.pp_raw[0], w.pp_raw[10]], [w.pp_task.test_points[0],
                                                               [0.34, -0.2]])),
     r"demo 2|condition 2", r"3 numbers|x, y, z|three|shape \(3,\)"),
    ("pp-condition-row-that-is-text", "pp", {}, "text.json",
     writes(lambda w: pp_file(w, [w.pp_raw[0], w.pp_raw[10]], [w.pp_task.test_points[0],
                                                               None]) | {
         "conditions": [w.pp_task.test_points[0].tolist(), "plant 3"]}),
     r"condition 2", r"list of numbers|null"),
    ("pp-far-away-condition", "pp", {}, "far.json",
     writes(lambda w: pp_file(w, [w.pp_raw[0], w.pp_raw[10]], [w.pp_task.test_points[0],
                                                               [5.0, 5.0, 5.0]])),
     r"demo 2.*cm from the nearest plant", r"metres|half a plant"),
    ("pp-condition-far-above-a-plant", "pp", {}, "high.json",
     writes(lambda w: pp_file(w, [w.pp_raw[0], w.pp_raw[10]], [
         w.pp_task.test_points[0], [*w.pp_task.test_points[10][:2], 2.0]])),
     r"demo 2.*(cm|far|above|height)", r"metres|plant"),
    ("pp-positions-in-centimetres", "pp", {}, "cm.json",
     writes(lambda w: pp_file(w, [in_cm(w.pp_raw[10])], [None])), r"centimetres",
     r"divide the positions by 100"),
    ("pp-positions-and-conditions-in-centimetres", "pp", {}, "cm2.json",
     writes(lambda w: pp_file(w, [in_cm(w.pp_raw[10])], [100 * w.pp_task.test_points[10]])),
     r"centimetres", r"divide .*by 100"),
    ("pp-a-3-column-csv", "pp", {}, "maze.csv", writes(lambda w: csv_of(w.good[1:2])),
     r"no 'z', 'g' column", r"t, x, y, z, g"),
    ("pp-more-time-than-is-left", "pp", {}, "slow.json",
     writes(lambda w: pp_file(w, [w.pp_raw[10] * [100, 1, 1, 1, 1]], [None])),
     r"only \d+ s of this run are left", r"fewer|shorter|next run|remove"),
    ("pp-time-going-backwards", "pp", {}, "back.json",
     writes(lambda w: pp_file(w, [w.pp_raw[10][::-1]], [None])), r"not strictly increasing",
     r"sort the samples by time"),
    ("pp-another-run-number", "pp", {}, "run2.json", writes(lambda w: pp_record(w, run=2)),
     r"BF run 2.*BF run 1|BF run 1.*BF run 2", r"matching tutor"),
]  # fmt: skip


@pytest.mark.parametrize(
    "tutor, options, name, make, what, fix",
    [pytest.param(*row[1:], id=row[0]) for row in LOADS],
)
def test_a_refused_load_changes_nothing_and_says_why(c, tutor, options, name, make, what, fix):
    app = c.maze(**options) if tutor == "maze" else c.pp(**options)
    path = c.tmp / name
    make(path, c.w)
    loaded = file_bytes(path)
    before = Snapshot.of(app)
    act(app.load, path)
    assert_plain(app.message, what, fix)
    assert "nothing was loaded" in app.message.lower()
    after = Snapshot.of(app)
    assert after.record == before.record, "the run in memory changed"
    assert after.n_demos == before.n_demos and after.elapsed == before.elapsed
    assert after.data == before.data, "the run file changed"
    assert file_bytes(path) == loaded, "the loaded file changed"
    assert saved_record(app.run_file).current.n_demos == before.n_demos


# ================================================================ 3. Load: files that must load


def loaded_as(app, before, raws):
    """The demos ``raws`` were added after the ones already there, in the right columns."""
    assert app.run.n_demos == before.n_demos + len(raws), app.message
    got = app.record.current.demos[-len(raws) :]
    for demo, raw in zip(got, raws, strict=True):
        assert np.allclose(demo.samples, app.task.preprocess(raw))


def new_attempt(app, before, n):
    assert len(app.record.attempts) == len(before.record.attempts) + 1, app.message
    assert app.run.n_demos == n and "attempt 2" in app.message


#: (id, file name, maker, check(app, before, w))
GOOD_LOADS = [
    ("a-csv-with-a-utf-8-bom", "bom.csv", writes(lambda w: csv_of(w.good[1:3], bom=True)),
     lambda app, b, w: loaded_as(app, b, w.good[1:3])),
    ("header-demo,t,y,x", "yx.csv",
     writes(lambda w: csv_of(w.good[1:3], header=("demo", "t", "y", "x"))),
     lambda app, b, w: loaded_as(app, b, w.good[1:3])),
    ("header-in-capitals-with-spaces", "caps.csv",
     writes(lambda w: csv_of(w.good[1:2]).replace("demo,t,x,y", " Demo , T ,X, Y")),
     lambda app, b, w: loaded_as(app, b, w.good[1:2])),
    ("semicolons-with-decimal-points", "semi.csv",
     writes(lambda w: csv_of(w.good[1:3], sep=";")),
     lambda app, b, w: loaded_as(app, b, w.good[1:3])),
    ("tabs-and-windows-line-ends", "tabs.csv",
     writes(lambda w: csv_of(w.good[1:2], sep="\t", newline="\r\n")),
     lambda app, b, w: loaded_as(app, b, w.good[1:2])),
    ("a-run-file-saved-with-sorted-keys", "VF-sorted.json",
     writes(lambda w: sorted_keys(maze_record(w))), lambda app, b, w: new_attempt(app, b, 2)),
    ("a-run-file-without-finished", "VF-old.json",
     writes(lambda w: without_finished(maze_record(w))),
     lambda app, b, w: new_attempt(app, b, 2)),
]  # fmt: skip


@pytest.mark.parametrize(
    "name, make, check", [pytest.param(*row[1:], id=row[0]) for row in GOOD_LOADS]
)
def test_a_good_file_loads_and_keeps_the_earlier_demos(c, name, make, check):
    app = c.maze(demos=1)
    path = c.tmp / name
    make(path, c.w)
    before = Snapshot.of(app)
    act(app.load, path)
    assert_plain(app.message)
    check(app, before, c.w)
    on_disk = every_demo(saved_record(app.run_file))
    assert all(d in on_disk for d in every_demo(before.record)), "an earlier demo was lost"
    assert saved_record(app.run_file) == app.record


# ====================================================================== 4. the upload button


def demo_json_bytes(w) -> bytes:
    return json.dumps(demo_doc(w.good[1:3])).encode()


#: (id, file name as the browser sends it, content(w) -> bytes, what, fix) - refused
UPLOADS = [
    ("empty-content", "demos.json", lambda w: b"", r"is empty", r"right file"),
    ("60-MB", "demos.json", lambda w: bytes(60 * MB), r"60 MB.*10 MB", r"right file"),
    ("an-.exe", "demos.exe", demo_json_bytes, r"\.json or \.csv", r"load a"),
    ("not-utf-8", "demos.json", lambda w: b"\xff\xfe\x81" * 30, r"not UTF-8", r"UTF-8"),
    ("another-conditions-run", "VR.json", lambda w: json.dumps(maze_record(w, "VR")).encode(),
     r"VR run.*VF run|VF run.*VR run", r"matching tutor"),
    ("a-nul-name-and-10**400", "de\x00mos.json",
     lambda w: swap(demo_doc([poke(w.good[1], 2, 1, "H")]), "H", HUGE_INT).encode(),
     r"too large", r"fix or remove"),
]  # fmt: skip


@pytest.mark.parametrize(
    "name, content, what, fix", [pytest.param(*row[1:], id=row[0]) for row in UPLOADS]
)
def test_a_refused_upload_changes_nothing_and_says_why(c, name, content, what, fix):
    app = c.maze(demos=1)
    before = Snapshot.of(app)
    act(upload, app, name, content(c.w))
    assert_plain(app.message, what, fix)
    assert "nothing was loaded" in app.message.lower()
    after = Snapshot.of(app)
    assert after.record == before.record and after.data == before.data


#: (id, file name as the browser sends it) - a good demo file under a hostile name
GOOD_UPLOADS = [
    ("a-NUL-in-the-name", "de\x00mos.json"),
    ("a-name-of-400-bytes", "é" * 200 + ".json"),
    ("a-name-of-300-ascii-bytes", "d" * 300 + ".json"),
    ("a-path-up-and-out", "../../../../../../tmp/lfd-hostile-escape.json"),
    ("an-absolute-path", "/etc/lfd-hostile-escape.json"),
    ("a-name-with-rtl-override", "\u202enosj.demos.json"),
    ("no-name", ""),
]


@pytest.mark.parametrize("name", [pytest.param(n, id=i) for i, n in GOOD_UPLOADS])
def test_an_upload_under_a_hostile_name_loads_and_writes_nowhere_else(c, name):
    app = c.maze(demos=1)
    before = Snapshot.of(app)
    act(upload, app, name, demo_json_bytes(c.w))
    assert_plain(app.message, r"added 2 demonstration")
    loaded_as(app, before, c.w.good[1:3])
    assert "\x00" not in app.message
    for outside in (Path("/tmp/lfd-hostile-escape.json"), Path("/etc/lfd-hostile-escape.json")):
        assert not outside.exists()
    assert saved_record(app.run_file) == app.record


def test_an_upload_into_a_finished_run_is_refused(c):
    app = c.maze(demos=1, finished=True)
    before = Snapshot.of(app)
    act(upload, app, "more.json", demo_json_bytes(c.w))
    assert_plain(app.message, r"finished", r"reset")
    assert Snapshot.of(app).record == before.record and file_bytes(app.run_file) == before.data


# ====================================================================== 5. opening over a bad file

#: (id, maker of what lies at the run's path, what, fix)
RESUMES = [
    ("10**400-in-the-run-file", writes(huge_run), r"too large", r"kept in VF-2\.json"),
    ("a-truncated-run-file", writes(lambda w: json.dumps(maze_record(w))[:3000]),
     r"not valid JSON", r"kept in VF-2\.json"),
    ("an-empty-run-file", writes(""), r"is empty", r"kept in VF-2\.json"),
    ("a-fifo", fifo, r"not a regular file", r"kept in VF-2\.json"),
    ("a-folder", folder, r"not a regular file", r"kept in VF-2\.json"),
    ("a-link-to-/dev/zero", to_dev_zero, r"not a regular file", r"kept in VF-2\.json"),
    ("a-sparse-60-MB-file", sparse_60mb, r"50 MB", r"kept in VF-2\.json"),
    ("version-99", writes(lambda w: edited(maze_record(w), lambda d: d.update(version=99))),
     r"version 99", r"update lfd-tutor"),
    ("another-trainees-run", writes(lambda w: maze_record(w, trainee="Mai_Anh")),
     r"Mai_Anh's", r"kept in VF-2\.json"),
    ("another-conditions-run", writes(lambda w: maze_record(w, "VR")), r"VR run",
     r"kept in VF-2\.json"),
    ("events-naming-attempt-7-of-1",
     writes(lambda w: edited(maze_record(w), lambda d: d["events"][-1].update(attempt=6))),
     r"attempt 7 of 1", r"kept in VF-2\.json"),
    ("duplicate-keys", writes(lambda w: duplicate_key(maze_record(w), "attempts", [])),
     r"twice|duplicate|more than once", r"kept in VF-2\.json"),
    ("a-nul-in-the-trainee-name",
     writes(lambda w: edited(maze_record(w), lambda d: d["trainee"].update(name="Mai\u0000Anh"))),
     r"control character|NUL", r"kept in VF-2\.json"),
]  # fmt: skip


@pytest.mark.parametrize("make, what, fix", [pytest.param(*r[1:], id=r[0]) for r in RESUMES])
def test_a_bad_run_file_is_left_alone_and_the_run_goes_elsewhere(c, make, what, fix):
    path = c.tmp / "runs" / "VF.json"
    path.parent.mkdir()
    make(path, c.w)
    there = file_bytes(path)
    app = act(lambda: c.keep(MazeTutor("VF", run_file=path, trainee=TRAINEE)))
    assert_plain(app.message, what, fix)
    assert app.run_file != path and app.session.n_demos == 0
    act(app.add, c.w.good[0])
    assert saved_record(app.run_file).current.n_demos == 1
    assert file_bytes(path) == there, "the file that was there changed"


def make_then_close(steps):
    """A maker that teaches a run with a real tutor (``steps(app, w)``) and closes it."""

    def make(path: Path, w) -> None:
        app = MazeTutor("VF", run_file=path, trainee=TRAINEE)
        steps(app, w)
        app.close()

    return make


#: (id, maker, trainee who opens it, check(app))
GOOD_RESUMES = [
    ("sorted-keys", writes(lambda w: sorted_keys(maze_record(w))), TRAINEE,
     lambda app: app.session.n_demos == 2),
    ("without-finished", writes(lambda w: without_finished(maze_record(w))), TRAINEE,
     lambda app: app.session.n_demos == 2 and not app.finished),
    ("undo-events-survive",
     make_then_close(lambda app, w: (*[app.add(d) for d in w.good[:3]], app.undo())), TRAINEE,
     lambda app: [e.kind for e in app.record.events] == ["start", "add", "add", "add", "undo"]
     and len(app.run.attempt.undone) == 1 and app.session.n_demos == 2),
    ("a-confirmed-reset-keeps-the-finished-attempt",
     make_then_close(lambda app, w: (app.add(w.good[0]), app.finish(), app.request_reset(),
                                     app.request_reset())), TRAINEE,
     lambda app: [(a.n_demos, a.finished) for a in app.record.attempts] == [(1, True), (0, False)]),
    ("zoe-nfc-opened-as-nfd",
     writes(lambda w: maze_record(w, trainee="Zo\u00eb")), "Zoe\u0308",
     lambda app: app.session.n_demos == 2),
]  # fmt: skip


@pytest.mark.parametrize(
    "make, trainee, check", [pytest.param(*r[1:], id=r[0]) for r in GOOD_RESUMES]
)
def test_a_good_run_file_resumes_with_nothing_lost(c, make, trainee, check):
    path = c.tmp / "runs" / "VF.json"
    path.parent.mkdir()
    make(path, c.w)
    app = act(lambda: c.keep(MazeTutor("VF", run_file=path, trainee=trainee)))
    assert_plain(app.message, r"resumed")
    assert app.run_file == path and check(app), (app.message, app.record)
    before = app.record
    act(app.add, c.w.good[4])
    on_disk = saved_record(path)
    assert all(d in every_demo(on_disk) for d in every_demo(before))
    assert [e.kind for e in on_disk.events][: len(before.events)] == [e.kind for e in before.events]


# ====================================================================== 6. saving that fails


def full_disk(c):
    disk = c.mount("full", "size=64k")
    filler = disk / "filler"

    def fill():
        try:
            with open(filler, "wb") as fh:
                while True:
                    fh.write(b"\0" * 4096)
                    fh.flush()
        except OSError:  # the disk is full now
            pass

    return disk / "VF.json", fill, filler.unlink


def read_only_disk(c, sub=""):
    disk = c.mount("ro", "ro,size=64k")

    def fix():
        done = subprocess.run(["mount", "-o", "remount,rw", str(disk)], capture_output=True)
        assert done.returncode == 0, done.stderr

    return disk / sub / "VF.json", None, fix


def through_a_file(c):
    blocker = c.tmp / "not-a-folder"
    blocker.write_text("a file where the folder should be")

    def fix():
        blocker.unlink()
        blocker.mkdir()

    return blocker / "VF.json", None, fix


def folder_replaced_by_a_file(c):
    where = c.tmp / "class"
    moved = c.tmp / "class-moved"

    def swap_out():
        where.rename(moved)
        where.write_text("someone made this a file")

    def fix():
        where.unlink()
        moved.rename(where)

    return where / "VF.json", swap_out, fix


#: (id, setup(c) -> (run path, break() after demo 1 or None, fix()), what, fix)
SAVES = [
    ("autosave-on-a-full-disk", full_disk, r"disk is full", r"free some space"),
    ("autosave-after-the-folder-became-a-file", folder_replaced_by_a_file,
     r"part of the path is a file", r"another folder"),
]  # fmt: skip

#: (id, setup(c) -> (run path, None, fix()), what, fix): no lock can be taken from the start
LOCKLESS = [
    ("open-on-a-read-only-disk", read_only_disk, r"read-only disk", r"another folder"),
    ("open-in-a-folder-that-cannot-be-made", lambda c: read_only_disk(c, "sub"),
     r"read-only disk", r"another folder"),
    ("open-through-a-file", through_a_file, r"part of the path is a file",
     r"another folder"),
]  # fmt: skip


@pytest.mark.parametrize("setup, what, fix", [pytest.param(*r[1:], id=r[0]) for r in SAVES])
def test_a_failed_save_keeps_every_demo_and_the_old_file(c, setup, what, fix):
    path, breaks, repair = setup(c)
    app = act(lambda: c.keep(MazeTutor("VF", run_file=path, trainee=TRAINEE)))
    act(app.add, c.w.good[0])
    if breaks is not None:
        assert not app.unsaved and saved_record(path).current.n_demos == 1, app.message
        breaks()
    on_disk = file_bytes(path)
    act(app.add, c.w.good[1])
    assert_plain(app.message, what, fix)
    assert re.search(r"not saved.*kept", app.message, re.I), app.message
    assert app.session.n_demos == 2 and app.unsaved  # nothing lost in memory
    assert file_bytes(path) == on_disk, "the old file was damaged"
    assert temp_files(path.parent) == [], "a temporary file was left behind"
    repair()
    act(app.save)
    assert_plain(app.message, r"saved to")
    assert not app.unsaved and saved_record(path) == app.record


@pytest.mark.parametrize("setup, what, fix", [pytest.param(*r[1:], id=r[0]) for r in LOCKLESS])
def test_a_run_that_cannot_be_locked_opens_read_only_and_writes_nothing(c, setup, what, fix):
    """The lock cannot be taken, so the tutor fails closed: read-only, said in plain words;
    once the folder is fixed, Try again takes the file and saving works."""
    path, _, repair = setup(c)
    app = act(lambda: c.keep(MazeTutor("VF", run_file=path, trainee=TRAINEE)))
    assert app.read_only
    assert_plain(app.message, what, fix)
    assert re.search(r"cannot be locked.*read-only", app.message, re.I | re.S), app.message
    act(app.add, c.w.good[0])
    assert_plain(app.message, what, fix)
    assert app.session.n_demos == 0 and file_bytes(path) is None
    assert temp_files(path.parent) == [], "a temporary file was left behind"
    repair()
    act(app.try_again)
    assert not app.read_only, app.message
    act(app.add, c.w.good[0])
    assert not app.unsaved and saved_record(path) == app.record


# ====================================================================== 7. making a tutor

#: (id, make(c) -> tutor, what, fix): a named error, or a tutor whose message says it
CONSTRUCTIONS = [
    ("condition-in-lower-case", lambda c: MazeTutor("vf"), r"'vf'", r"one of NF, VF, VR"),
    ("condition-that-is-a-list", lambda c: MazeTutor(["VF"]), r"\['VF'\]|condition",
     r"one of NF, VF, VR"),
    ("pp-condition-of-the-maze", lambda c: PickPlaceTutor("VF", task=c.w.pp_task),
     r"'VF'", r"one of NF, RF, BF, SF"),
    ("empty-trainee", lambda c: MazeTutor("VF", trainee=""), r"empty", r"type a name"),
    ("blank-trainee", lambda c: MazeTutor("VF", trainee=" \t "), r"empty", r"type a name"),
    ("trainee-that-is-a-number", lambda c: MazeTutor("VF", trainee=3), r"must be text",
     r"trainee = "),
    ("trainee-with-a-control-character", lambda c: MazeTutor("VF", trainee="Mai\x07Anh"),
     r"control characters", r"type a name"),
    ("trainee-of-300-characters", lambda c: MazeTutor("VF", trainee="x" * 300),
     r"300 characters", r"at most 200"),
    ("run-0", lambda c: PickPlaceTutor("BF", task=c.w.pp_task, run=0), r"got 0",
     r"whole number >= 1"),
    ("run-True", lambda c: PickPlaceTutor("BF", task=c.w.pp_task, run=True), r"got True",
     r"whole number >= 1"),
    ("run-as-text", lambda c: PickPlaceTutor("BF", task=c.w.pp_task, run="2"), r"got '2'",
     r"whole number >= 1"),
    ("session-file-with-NUL", lambda c: MazeTutor("VF", run_file=c.tmp / "V\x00F.json"),
     r"NUL", r"name"),
    ("session-file-name-of-300-bytes",
     lambda c: MazeTutor("VF", run_file=c.tmp / ("v" * 300 + ".json")),
     r"bytes long|too long", r"shorter"),
    ("session-file-that-is-a-number", lambda c: MazeTutor("VF", run_file=123),
     r"123|path", r"give|file name|path"),
]  # fmt: skip


@pytest.mark.parametrize("make, what, fix", [pytest.param(*r[1:], id=r[0]) for r in CONSTRUCTIONS])
def test_a_bad_tutor_argument_gets_a_named_error_or_a_message(c, make, what, fix):
    try:
        with deadline():
            app = make(c)
    except TutorError as exc:
        assert_plain(str(exc), what, fix)
        return
    except BaseException as exc:  # noqa: BLE001
        pytest.fail(f"{type(exc).__name__} escaped instead of a tutor.errors error: {exc}")
    c.keep(app)
    assert_plain(app.message, what, fix)
    act(app.add, c.w.good[0])  # and it still teaches without a traceback
    assert app.session.n_demos == 1


# ====================================================================== 8. the library


def fit_tpgmm(w, **params):
    task = w.maze_task
    demos = [task.preprocess(d) for d in w.good[:2]]
    frames = [task.frames(task.test_point_of(d)) for d in demos]
    return TPGMM(**params).fit(demos, frames)


def demo_file(c, name, make) -> Path:
    path = c.tmp / name
    make(path, c.w)
    return path


def set_session_dir(c, value) -> None:
    c.monkeypatch.setenv("TUTOR_RUNS_DIR", str(value))


def session_dir_in_a_file(c, below: str = ""):
    (c.tmp / "afile").write_text("x")
    set_session_dir(c, c.tmp / "afile" / below)
    return trainee_dir(TRAINEE)


def session_dir_on_a_read_only_disk(c):
    set_session_dir(c, c.mount("ro", "ro,size=64k") / "class")
    return trainee_dir(TRAINEE)


#: (id, call(c), error class, what, fix)
LIBRARY = [
    # --- files
    ("load_demos-fifo", lambda c: load_demos(demo_file(c, "p.json", fifo)), InvalidFileError,
     r"pipe", r"saved file|regular file"),
    ("load_demos-60-MB", lambda c: load_demos(demo_file(c, "b.csv", sparse_60mb)),
     InvalidFileError, r"50 MB", r"right file"),
    ("load_demos-a-device", lambda c: load_demos(demo_file(c, "z.json", to_dev_zero)),
     InvalidFileError, r"device", r"saved file|regular file"),
    ("load_demos-/dev/zero", lambda c: load_demos("/dev/zero"), InvalidFileError,
     r"\.json or \.csv|device", r"must end in|saved file"),
    ("load_demos-version-99",
     lambda c: load_demos(demo_file(c, "v.json", writes(lambda w: demo_doc(w.good[:1],
                                                                           version=99)))),
     InvalidFileError, r"version 99", r"reads version 1"),
    ("load_demos-10**400", lambda c: load_demos(demo_file(c, "h.json", writes(
        lambda w: swap(demo_doc([poke(w.good[1], 2, 1, "H")]), "H", HUGE_INT)))),
     InvalidFileError, r"too large", r"fix or remove"),
    ("load_demos-NUL-in-the-name", lambda c: load_demos(c.tmp / "a\x00b.json"),
     InvalidFileError, r"NUL", r"no file name can hold"),
    ("load_demos-name-of-300-bytes", lambda c: load_demos(c.tmp / ("d" * 300 + ".csv")),
     InvalidFileError, r"304 bytes long", r"shorter name"),
    ("load_demos-unknown-expected-column",
     lambda c: load_demos(demo_file(c, "ok.csv", writes(lambda w: csv_of(w.good[:1]))),
                          columns=("t", "x", "q")),
     InvalidParameterError, r"unknown column 'q'", r"known columns are"),
    ("load_demos-a-3-column-file-for-5-columns",
     lambda c: load_demos(demo_file(c, "ok.csv", writes(lambda w: csv_of(w.good[:1]))),
                          columns=COLUMNS),
     InvalidFileError, r"no 'z', 'g' column", r"t, x, y, z, g"),
    ("bundled_demos-a-path-up", lambda c: bundled_demos("../demos/maze_good"),
     InvalidFileError, r"no bundled demonstration set", r"maze_good"),
    ("bundled_demos-with-.json", lambda c: bundled_demos("maze_good.json"), InvalidFileError,
     r"no bundled demonstration set", r"without a folder or \.json"),
    ("bundled_demos-/etc/passwd", lambda c: bundled_demos("/etc/passwd"), InvalidFileError,
     r"no bundled demonstration set", r"maze_good"),
    ("bundled_demos-None", lambda c: bundled_demos(None), InvalidFileError,
     r"no bundled demonstration set", r"maze_good"),
    # --- a teaching session
    ("add_demo-complex", lambda c: TeachingSession(c.w.maze_task).add_demo(c.w.good[0] + 1j),
     InvalidDemoError, r"complex|not a numeric table|real", r"real number|array of shape"),
    ("add_demo-10**400",
     lambda c: TeachingSession(c.w.maze_task).add_demo(poke(c.w.good[0], 1, 1, 10**400)),
     InvalidDemoError, r"too large|overflow", r"fix|remove|smaller"),
    ("add_demo-text", lambda c: TeachingSession(c.w.maze_task).add_demo("abc"),
     InvalidDemoError, r"not a numeric table|2-d", r"array of shape|\(T"),
    ("add_demo-a-dict", lambda c: TeachingSession(c.w.maze_task).add_demo({"t": [0, 1]}),
     InvalidDemoError, r"not a numeric table|2-d", r"array of shape|\(T"),
    ("add_demo-point-of-text",
     lambda c: TeachingSession(c.w.maze_task).add_demo(c.w.good[0], point="start"),
     InvalidParameterError, r"point", r"shape|finite array"),
    ("spend-negative-seconds",
     lambda c: PickPlaceRun("BF", task=c.w.pp_task).spend(-5), InvalidParameterError,
     r"got -5", r">= 0"),
    ("spend-seconds-as-text", lambda c: PickPlaceRun("BF", task=c.w.pp_task).spend("5"),
     InvalidParameterError, r"'5'", r"finite number"),
    ("spend-10**400-seconds", lambda c: PickPlaceRun("BF", task=c.w.pp_task).spend(10**400),
     InvalidParameterError, r"seconds", r"finite number"),
    # --- the learner (another engineer's fix)
    ("tpgmm-n_components-True", lambda c: fit_tpgmm(c.w, n_components=True),
     InvalidParameterError, r"n_components.*True", r"positive integer|whole number"),
    ("tpgmm-max_iter-True", lambda c: fit_tpgmm(c.w, max_iter=True), InvalidParameterError,
     r"max_iter.*True", r"positive integer|whole number"),
    ("tpgmm-n_components-text", lambda c: fit_tpgmm(c.w, n_components="3"),
     InvalidParameterError, r"n_components", r"positive integer|whole number"),
    ("tpgmm-reg_covar-text", lambda c: fit_tpgmm(c.w, reg_covar="0.001"),
     InvalidParameterError, r"reg_covar", r"positive number"),
    ("tpgmm-tol-text", lambda c: fit_tpgmm(c.w, tol="1e-5"), InvalidParameterError, r"tol",
     r">= 0|number"),
    ("tpgmm-random_state-text",
     lambda c: fit_tpgmm(c.w, init_params="random", random_state="seed"),
     InvalidParameterError, r"random_state", r"integer|seed|Generator"),
    ("tpgmm-random_state-True",
     lambda c: fit_tpgmm(c.w, init_params="random", random_state=True),
     InvalidParameterError, r"random_state", r"integer|seed|Generator"),
    ("frame-A-1e-310-I", lambda c: Frame(1e-310 * np.eye(2), [0.0, 0.0]), InvalidFrameError,
     r"small|scale|singular", r"scale|rotation"),
    ("frame-of-text", lambda c: Frame([["a", "b"], ["c", "d"]], [0, 0]), InvalidFrameError,
     r"numbers|numeric", r"\(d, d\)|matrix"),
    ("frame-offset-10**400", lambda c: Frame(np.eye(2), [10**400, 0]), InvalidFrameError,
     r"finite|too large", r"number|finite"),
    ("frame-complex", lambda c: Frame(np.eye(2) * 1j, [0, 0]), InvalidFrameError,
     r"complex|real|numbers", r"real|matrix"),
    # --- trainees and their folders
    ("trainee_dir-empty-name", lambda c: trainee_dir(""), InvalidParameterError, r"empty",
     r"type a name"),
    ("trainee_dir-300-characters", lambda c: trainee_dir("x" * 300), InvalidParameterError,
     r"300 characters", r"at most 200"),
    ("trainee_dir-a-number", lambda c: trainee_dir(7), InvalidParameterError, r"must be text",
     r"trainee = "),
    ("trainee_dir-TUTOR_RUNS_DIR-is-a-file", lambda c: session_dir_in_a_file(c),
     InvalidParameterError, r"is a file, not a folder", r"point it at a folder"),
    ("trainee_dir-TUTOR_RUNS_DIR-through-a-file",
     lambda c: session_dir_in_a_file(c, "class"), SaveError, r"cannot make the folder",
     r"folder you can write to"),
    ("trainee_dir-on-a-read-only-disk", session_dir_on_a_read_only_disk, SaveError,
     r"read-only", r"folder you can write to"),
    ("trainee_dir-no-name-and-none-set",
     lambda c: [c.monkeypatch.delenv(v, raising=False) for v in ("TUTOR_TRAINEE",
                "JUPYTERHUB_USER")] and trainee_dir(None),
     InvalidParameterError, r"no name was given", r"type your name"),
    ("trainee-from-a-hub-user-with-a-control-character",
     lambda c: c.monkeypatch.setenv("JUPYTERHUB_USER", "st\x01udent") or trainee_dir(None),
     InvalidParameterError, r"control characters", r"type a name"),
]  # fmt: skip


@pytest.mark.parametrize("call, error, what, fix", [pytest.param(*r[1:], id=r[0]) for r in LIBRARY])
def test_the_library_refuses_with_a_named_error(c, call, error, what, fix):
    c.monkeypatch.setenv("TUTOR_RUNS_DIR", str(c.tmp / "sessions"))
    exc = raised(lambda: call(c))
    assert isinstance(exc, error), f"{type(exc).__name__}, not {error.__name__}: {exc}"
    assert_plain(str(exc), what, fix)


def folders_differ(c, a, b):
    return trainee_dir(a) != trainee_dir(b)


def same_folder_or_refused(c, typed, plain):
    """A name with invisible direction marks: the plain name's folder, or a named error."""
    try:
        got = trainee_dir(typed)
    except InvalidParameterError as exc:
        assert_plain(str(exc), r"invisible|direction|control|format", r"type a name|remove")
        return True
    return got == trainee_dir(plain)


def no_bidi_override_kept(c):
    """Trainee names are shown in the educator's list; an override must not reorder them."""
    try:
        trainee = Trainee.from_name("Mai\u202eAnh")
    except InvalidParameterError as exc:
        assert_plain(str(exc), r"invisible|direction|control|format", r"type a name|remove")
        return True
    return not any(
        ch in trainee.name for ch in "\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069"
    )


def fits_in_a_name(c, name):
    folder = trainee_dir(name)
    return folder.is_dir() and len(folder.name.encode()) <= 255


#: (id, check(c) -> True)
LIBRARY_OK = [
    ("folders-Mai-Anh-and-Mai_Anh", lambda c: folders_differ(c, "Mai Anh", "Mai_Anh")),
    ("folders-two-devanagari-names", lambda c: folders_differ(c, "नमस्ते", "नमस्ती")),
    ("folders-two-emoji", lambda c: folders_differ(c, "😀", "😁")),
    ("folders-Anna-and-anna", lambda c: folders_differ(c, "Anna", "anna")),
    ("folder-of-Zoe-NFC-and-NFD", lambda c: trainee_dir("Zo\u00eb") == trainee_dir("Zoe\u0308")),
    ("folder-of-a-name-of-400-bytes", lambda c: fits_in_a_name(c, "é" * 200)),
    ("folder-of-200-emoji", lambda c: fits_in_a_name(c, "😀" * 200)),
    ("folder-of-None-is-the-hub-user",
     lambda c: c.monkeypatch.setenv("JUPYTERHUB_USER", "mai")
     or trainee_dir(None) == trainee_dir("mai")),
    ("folder-of-a-name-with-rtl-marks",
     lambda c: same_folder_or_refused(c, "\u200fMai Anh\u200e", "Mai Anh")),
    ("folder-of-a-name-with-zero-width-space",
     lambda c: same_folder_or_refused(c, "Mai\u200b Anh", "Mai Anh")),
    ("trainee-name-with-a-bidi-override", no_bidi_override_kept),
]  # fmt: skip


@pytest.mark.parametrize("check", [pytest.param(r[1], id=r[0]) for r in LIBRARY_OK])
def test_the_library_accepts_what_it_should(c, check):
    c.monkeypatch.setenv("TUTOR_RUNS_DIR", str(c.tmp / "sessions"))
    try:
        with deadline():
            assert check(c) is True
    except TutorError as exc:
        pytest.fail(f"refused: {type(exc).__name__}: {exc}")


# ====================================================================== 9. the command line

#: (id, argv ({file}, {ro}, {tmp} filled in), what, fix, may it simulate and succeed?)
CLI = [
    ("reproduce-out-is-a-file",
     ["reproduce", "--experiment", "1", "--n", "3", "--workers", "1", "--out", "{file}"],
     r"is a file|not a folder", r"another|choose|give|--out", False),
    ("reproduce-out-below-a-file",
     ["reproduce", "--experiment", "1", "--n", "3", "--workers", "1", "--out", "{file}/res"],
     r"is a file|not a folder", r"another|choose|give|--out", False),
    ("reproduce-out-on-a-read-only-disk",
     ["reproduce", "--experiment", "1", "--n", "3", "--workers", "1", "--out", "{ro}"],
     r"read-only", r"somewhere else|another|--out", False),
    ("reproduce-out-below-a-read-only-disk",
     ["reproduce", "--experiment", "1", "--n", "3", "--workers", "1", "--out", "{ro}/res"],
     r"read-only", r"somewhere else|another|--out", False),
    ("robustness-out-is-a-file",
     ["robustness", "--experiment", "1", "--n", "3", "--seeds", "1", "--workers", "1",
      "--out", "{file}"],
     r"is a file|not a folder", r"another|choose|give|--out", False),
    ("robustness-out-on-a-read-only-disk",
     ["robustness", "--experiment", "1", "--n", "3", "--seeds", "1", "--workers", "1",
      "--out", "{ro}"],
     r"read-only", r"somewhere else|another|--out", False),
    ("console-script-out-is-a-file",
     ["@lfd-tutor", "reproduce", "--experiment", "1", "--n", "3", "--workers", "1",
      "--out", "{file}"],
     r"is a file|not a folder", r"another|choose|give|--out", False),
    ("a-trillion-teachers",
     ["reproduce", "--experiment", "1", "--n", "1000000000000", "--workers", "1",
      "--out", "{tmp}/big"],
     r"teachers|--n", r"at most|fewer|smaller", False),
    ("workers-0",
     ["reproduce", "--experiment", "1", "--n", "3", "--workers", "0", "--out", "{tmp}/w0"],
     r"workers.*got 0", r">= 1", False),
    ("the-smallest-cohort-n-2",
     ["reproduce", "--experiment", "1", "--n", "2", "--workers", "1", "--out", "{tmp}/n2"],
     r"teachers", r"at least", True),
]  # fmt: skip

#: every CLI case must have finished (or been refused) within this many seconds; a
#: request that is refused up front takes an import (about 2 s) and no simulation
CLI_SECONDS = 60.0
CLI_LIMITS = {"a-trillion-teachers": 12.0}


@dataclass
class Ran:
    code: int | None
    stdout: str
    stderr: str
    seconds: float
    note: str = ""


@pytest.fixture(scope="module")
def cli(tmp_path_factory):
    """Every CLI case, run at once as real subprocesses (they mostly wait on imports)."""
    tmp = tmp_path_factory.mktemp("cli")
    (tmp / "afile").write_text("not a folder")
    ro = tmp / "ro"
    ro.mkdir()
    mounted = (
        subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(ro)], capture_output=True
        ).returncode
        == 0
    )
    script = Path(sys.executable).with_name("lfd-tutor")
    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg"}
    procs = {}
    for case_id, argv, *_ in CLI:
        if "{ro}" in " ".join(argv) and not mounted:
            continue
        args = [a.format(file=tmp / "afile", ro=ro, tmp=tmp) for a in argv]
        if args[0] == "@lfd-tutor":
            if not script.exists():
                continue
            command = [str(script), *args[1:]]
        else:
            command = [sys.executable, "-m", "tutor", *args]
        out, err = tmp / f"{case_id}.out", tmp / f"{case_id}.err"
        with open(out, "w") as stdout, open(err, "w") as stderr:
            proc = subprocess.Popen(
                [*command, "--no-progress"], stdout=stdout, stderr=stderr, env=env, cwd=tmp
            )
        procs[case_id] = (proc, time.monotonic(), out, err)
    results, running = {}, dict(procs)
    while running:  # poll, so that a case past its limit is stopped at once
        for case_id, (proc, started, out, err) in list(running.items()):
            seconds = time.monotonic() - started
            note = ""
            if proc.poll() is None:
                if seconds < CLI_LIMITS.get(case_id, CLI_SECONDS):
                    continue
                proc.kill()
                note = "still running"
            proc.wait()
            code = None if note else proc.returncode
            results[case_id] = Ran(code, out.read_text(), err.read_text(), seconds, note)
            del running[case_id]
        time.sleep(0.1)
    yield results, mounted, script.exists()
    if mounted:
        subprocess.run(["umount", "-l", str(ro)], capture_output=True)


@pytest.mark.parametrize(
    "argv, what, fix, may_succeed", [pytest.param(*r[1:], id=r[0]) for r in CLI]
)
def test_the_command_line_fails_in_one_line_before_simulating(
    cli, request, argv, what, fix, may_succeed
):
    results, mounted, has_script = cli
    case_id = request.node.callspec.id
    if case_id not in results:
        why = "no read-only tmpfs could be mounted" if not mounted else "no lfd-tutor script"
        if IN_CI:
            pytest.fail(why)
        pytest.skip(why)
    ran = results[case_id]
    assert ran.code is not None, f"{ran.note} after {ran.seconds:.0f} s: {ran.stderr[-500:]!r}"
    last = (ran.stderr.strip().splitlines() or [""])[-1]
    assert "Traceback" not in ran.stderr, f"a raw traceback (exit {ran.code}) ending {last!r}"
    if may_succeed and ran.code == 0:
        assert "written:" in ran.stdout
        return
    assert ran.code == 2, (ran.code, ran.stderr[-800:])
    lines = ran.stderr.strip().splitlines()
    assert len(lines) == 1, f"not one line: {ran.stderr!r}"
    assert_plain(lines[0].split(": ", 1)[-1], what, fix)
    if not may_succeed:
        assert ran.stdout.strip() == "", "it simulated before checking its arguments"
