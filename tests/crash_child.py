"""A maze teacher that keeps adding demonstrations until it is killed (for test_crash_safety).

Two ways to run it::

    python tests/crash_child.py serve
    python tests/crash_child.py teach SESSION_FILE [fsync|replace K]

``teach`` runs one teacher in this process. ``serve`` imports the tutor once, then reads
commands ``teach SESSION_FILE [fsync|replace K]`` on stdin and forks one teacher process
per command, so a test can kill many teachers without paying Python's start-up and the
imports each time. It reaps each teacher and prints ``PID ended CODE`` (``-9`` after
SIGKILL), and exits at the end of stdin.

A teacher is a real maze tutor, ``MazeTutor("VF", run_file=SESSION_FILE)``, which
resumes the file if it exists and autosaves on every ``add``. It prints, one line each
and flushed at once:

``PID resumed N``
    after the tutor is built (N = ``tutor.session.n_demos``);
``PID saved N``
    after each ``add`` returned (its autosave is done), cycling through the bundled
    ``maze_good`` demonstrations;
``PID in fsync`` / ``PID in replace``
    with ``fsync K`` / ``replace K``: on the K-th call of ``os.fsync`` / ``os.replace``
    since the tutor was built, before the real call runs; the teacher then sleeps so it
    can be killed at exactly that moment.
"""

from __future__ import annotations

import os
import sys
import time
import traceback

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy loads: forking with idle BLAS threads is safe
os.environ.setdefault("MPLBACKEND", "Agg")

from tutor.demofiles import bundled_demos  # noqa: E402
from tutor.views.maze_app import MazeTutor  # noqa: E402

HANGS = ("fsync", "replace")
#: how long a hung teacher waits to be killed
HANG_SECONDS = 600


def say(text: str) -> None:
    """One line on stdout, flushed (a line under PIPE_BUF is written whole)."""
    sys.stdout.write(f"{os.getpid()} {text}\n")
    sys.stdout.flush()


def hang_on(name: str, call_number: int) -> None:
    """Make the ``call_number``-th call of ``os.<name>`` announce itself and hang."""
    real = getattr(os, name)
    calls = 0

    def wrapper(*args, **kwargs):
        nonlocal calls
        calls += 1
        if calls == call_number:
            say(f"in {name}")
            time.sleep(HANG_SECONDS)
        return real(*args, **kwargs)

    setattr(os, name, wrapper)


def teach(run_file: str, hang: str | None = None, call_number: int = 0) -> None:
    """Resume ``run_file`` and add demonstrations until killed (never returns)."""
    demos = bundled_demos("maze_good")
    tutor = MazeTutor("VF", run_file=run_file)
    say(f"resumed {tutor.session.n_demos}")
    if hang is not None:
        hang_on(hang, call_number)
    for i in range(10**6):
        tutor.add(demos[i % len(demos)])
        say(f"saved {tutor.session.n_demos}")
    raise RuntimeError("a teacher ran out of demonstrations without being killed")


def parse_teach(args: list[str]) -> tuple[str, str | None, int]:
    """``SESSION_FILE [fsync|replace K]`` -> (file, hang, K)."""
    if len(args) == 1:
        return args[0], None, 0
    if len(args) == 3 and args[1] in HANGS and args[2].isdigit() and int(args[2]) >= 1:
        return args[0], args[1], int(args[2])
    raise SystemExit(f"usage: teach SESSION_FILE [fsync|replace K>=1], got {args}")


def fork_teacher(args: list[str]) -> None:
    """Fork one teacher for a ``teach`` command, wait for it to die and report how."""
    run_file, hang, call_number = parse_teach(args)
    sys.stdout.flush()
    pid = os.fork()
    if pid == 0:
        try:
            teach(run_file, hang, call_number)
        except BaseException:
            traceback.print_exc()
            sys.stderr.flush()
        finally:
            os._exit(1)
    _, status = os.waitpid(pid, 0)
    sys.stdout.write(f"{pid} ended {os.waitstatus_to_exitcode(status)}\n")
    sys.stdout.flush()


def serve() -> None:
    say("ready")
    for line in sys.stdin:
        words = line.split()
        if words and words[0] == "teach":
            fork_teacher(words[1:])
        elif words:
            raise SystemExit(f"unknown command {line.strip()!r}; expected 'teach ...'")


def main(argv: list[str]) -> None:
    if argv[:1] == ["serve"] and len(argv) == 1:
        serve()
    elif argv[:1] == ["teach"]:
        teach(*parse_teach(argv[1:]))
    else:
        raise SystemExit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
