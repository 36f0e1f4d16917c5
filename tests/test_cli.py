"""The command line (``python -m tutor``) refuses bad arguments at once, with a named
error and exit code 2, before any simulation starts."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tutor.errors import SaveError
from tutor.study.report import check_out_dir

ROOT = Path(__file__).resolve().parents[1]
# a full default cohort takes minutes: a check that ran after it would time out here
FAST = 120


def _tutor(*args: str, cwd: Path, prefix: tuple[str, ...] = ()) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    return subprocess.run(
        [*prefix, sys.executable, "-m", "tutor", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=FAST,
    )


def _refused(proc: subprocess.CompletedProcess, *words: str) -> None:
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    assert proc.stdout == "", "nothing may be simulated or reported"
    for word in words:
        assert word in proc.stderr, proc.stderr


def test_out_that_is_a_file_is_refused(tmp_path):
    target = tmp_path / "results"
    target.write_text("keep me")
    proc = _tutor(
        "reproduce", "--experiment", "1", "--no-progress", "--out", str(target), cwd=tmp_path
    )
    _refused(proc, "SaveError", str(target), "not a folder")
    assert target.read_text() == "keep me"


@pytest.mark.parametrize("command", ["reproduce", "robustness"])
def test_out_through_a_file_is_refused(tmp_path, command):
    blocker = tmp_path / "file"
    blocker.write_text("")
    target = blocker / "sub" / "results"  # ENOTDIR on the way
    proc = _tutor(command, "--experiment", "1", "--no-progress", "--out", str(target), cwd=tmp_path)
    _refused(proc, "SaveError", f"goes through the file {blocker}, which is a file, not a folder")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def _read_only_prefix(folder: Path) -> tuple[str, ...] | None:
    """A command prefix that runs the CLI with ``folder`` mounted read-only (a private
    mount namespace, gone when the process ends), or None where that is not permitted."""
    unshare = shutil.which("unshare")
    if unshare is None:
        return None
    script = 'mount -t tmpfs -o ro,size=1m tmpfs "$0" && exec "$@"'
    prefix = (unshare, "-m", "sh", "-c", script, str(folder))
    probe = subprocess.run([*prefix, "true"], capture_output=True, timeout=30)
    return prefix if probe.returncode == 0 else None


def test_read_only_out_is_refused(tmp_path):
    folder = tmp_path / "readonly"
    folder.mkdir()
    if os.geteuid() != 0:
        folder.chmod(0o555)
        prefix: tuple[str, ...] = ()
    else:  # root writes through permission bits: mount a read-only file system instead
        prefix = _read_only_prefix(folder)
        if prefix is None:
            pytest.skip("cannot mount a read-only tmpfs here (needs unshare and mount)")
    for out in (folder, folder / "new"):
        proc = _tutor(
            "reproduce", "--experiment", "1", "--no-progress", "--out", str(out),
            cwd=tmp_path, prefix=prefix,
        )  # fmt: skip
        _refused(proc, "SaveError", "cannot write in", str(folder))


@pytest.mark.parametrize(
    "args, words",
    [
        (["reproduce", "--experiment", "1", "--n", "-3"], ["--n", "whole number >= 1", "-3"]),
        (["reproduce", "--experiment", "1", "--n", "many"], ["--n", "'many'"]),
        (["reproduce", "--experiment", "1", "--seed", "-1"], ["--seed", "whole number >= 0"]),
        (["reproduce", "--experiment", "1", "--seed", "1.5"], ["--seed", "'1.5'"]),
        (["reproduce", "--experiment", "1", "--workers", "0"], ["--workers", ">= 1"]),
        (["reproduce", "--experiment", "1", "--workers", "all"], ["--workers", "'all'"]),
        (["robustness", "--experiment", "1", "--seeds", "0"], ["--seeds", ">= 1"]),
        (["robustness", "--experiment", "1", "--seeds", "ten"], ["--seeds", "'ten'"]),
        (["reproduce", "--experiment", "3"], ["--experiment", "invalid choice: 3"]),
        (["reproduce", "--experiment", "2", "--n", "7"], ["ParameterError", "multiple of 4"]),
        (["reproduce", "--experiment", "1", "--n", "2"], ["InvalidParameterError", "at least 3"]),
        (["reproduce", "--experiment", "1", "--n", str(10**12)], ["at most 3000 teachers"]),
        (["robustness", "--experiment", "2", "--n", "3004"], ["at most 3000 teachers"]),
    ],
)
def test_bad_number_is_refused_with_a_message(tmp_path, args, words):
    proc = _tutor(*args, "--no-progress", "--out", str(tmp_path / "out"), cwd=tmp_path)
    _refused(proc, *words)
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert not (tmp_path / "out").exists()


def test_the_smallest_allowed_cohort_is_analysed(tmp_path):
    from tutor.study.cohort import min_teachers

    n = min_teachers(1)
    proc = _tutor(
        "reproduce", "--experiment", "1", "--n", str(n), "--workers", "1", "--no-progress",
        "--no-figures", "--out", str(tmp_path / "out"), cwd=tmp_path,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert f"Experiment 1: {n} simulated teachers" in proc.stdout


def test_check_out_dir_accepts_a_new_nested_folder_and_makes_nothing(tmp_path):
    target = tmp_path / "a" / "b"
    assert check_out_dir(target) == target
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(SaveError):
        check_out_dir(Path(__file__))


def test_small_run_writes_into_a_new_nested_folder(tmp_path):
    out = tmp_path / "new" / "results"
    proc = _tutor(
        "reproduce", "--experiment", "1", "--n", "6", "--workers", "1", "--no-progress",
        "--no-figures", "--out", str(out), cwd=tmp_path,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert sorted(p.name for p in out.iterdir()) == [
        "experiment1_demos.csv",
        "experiment1_report.txt",
        "experiment1_runs.csv",
        "experiment1_summary.json",
    ]
    assert "written:" in proc.stdout
