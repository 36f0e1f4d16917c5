"""The checked file reader and the atomic writer refuse hostile files and report failed saves."""

from __future__ import annotations

import errno
import json
import os
import shutil
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tutor import fileio
from tutor.errors import InvalidFileError, SaveError, TutorError
from tutor.fileio import atomic_write_text, read_json, read_text, write_json

LINUX_ROOT = sys.platform.startswith("linux") and os.geteuid() == 0 and shutil.which("mount")


def finishes(fn, seconds=10.0):
    """Run ``fn`` in a thread; the exception it raised, or fail if it is still running."""
    outcome = {}

    def run():
        try:
            outcome["value"] = fn()
        except BaseException as exc:  # noqa: BLE001 - handed back to the test
            outcome["error"] = exc

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    return thread, outcome


# --------------------------------------------------------------------- reading


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    fifo = tmp_path / "x.json"
    os.mkfifo(fifo)
    thread, outcome = finishes(lambda: read_json(fifo, "run file"))
    if thread.is_alive():  # release the blocked reader before failing
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        pytest.fail("read_json blocked on a FIFO")
    assert isinstance(outcome.get("error"), InvalidFileError)
    assert "pipe (FIFO), not a regular file" in str(outcome["error"])


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="no /dev/zero")
def test_a_device_is_refused_unread(tmp_path):
    link = tmp_path / "zero.json"
    link.symlink_to("/dev/zero")
    for path in (Path("/dev/zero"), link):
        thread, outcome = finishes(lambda p=path: read_json(p, "run file"))
        assert not thread.is_alive(), "read_json kept reading a device"
        assert isinstance(outcome.get("error"), InvalidFileError)
        assert "is a device, not a regular file" in str(outcome["error"])


def test_a_file_over_the_cap_is_refused_before_reading(tmp_path):
    big = tmp_path / "big.json"
    with open(big, "wb") as fh:  # sparse: costs no disk
        fh.truncate(fileio.MAX_FILE_BYTES + 1)
    with pytest.raises(InvalidFileError, match="50 MB or more, larger than the 50 MB"):
        read_json(big)


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="no /proc")
def test_the_cap_holds_when_the_size_on_disk_says_less(monkeypatch):
    """A /proc file is a regular file whose stat size is 0 but that has content: only the
    capped read loop can stop it, as it would stop a file growing while being read."""
    assert os.stat("/proc/self/status").st_size == 0
    monkeypatch.setattr(fileio, "MAX_FILE_BYTES", 64)
    with pytest.raises(InvalidFileError, match="bytes or more, larger than the 64 bytes"):
        fileio.read_bytes("/proc/self/status", "status")
    monkeypatch.setattr(fileio, "MAX_FILE_BYTES", 1 << 20)
    assert b"Name:" in fileio.read_bytes("/proc/self/status", "status")


def test_a_utf8_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "excel.json"
    path.write_bytes(b'\xef\xbb\xbf{"a": [1, 2.5]}')
    assert read_json(path) == {"a": [1, 2.5]}
    assert read_text(path) == '{"a": [1, 2.5]}'


@pytest.mark.parametrize(
    "text, words",
    [
        ("[1e400]", "1e400 is too large"),
        ("[-1e400]", "-1e400 is too large"),
        ("[" + "1" * 400 + "]", "400 digits"),
        ("[" + "9" * 5000 + "]", "5000 digits"),
        ("[NaN]", "NaN is not allowed"),
        ("[Infinity]", "Infinity is not allowed"),
        ("[-Infinity]", "-Infinity is not allowed"),
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        ("", "is empty"),
        ("  \n", "is empty"),
        ('{"a": ', "not valid JSON"),
    ],
)
def test_numbers_json_cannot_hold_and_broken_json_are_refused(tmp_path, text, words):
    path = tmp_path / "f.json"
    path.write_text(text)
    with pytest.raises(InvalidFileError, match=words):
        read_json(path, "layout")


def test_numbers_a_float_can_hold_are_kept(tmp_path):
    path = tmp_path / "f.json"
    path.write_text("[1e308, -1.5e-400, " + "9" * 300 + ", 0]")
    value = read_json(path)
    assert value[0] == 1e308 and value[1] == 0.0 and value[2] == int("9" * 300)


@pytest.mark.parametrize(
    "text, key",
    [
        ('{"a": 1, "a": 2}', "a"),
        ('{"demos": [], "b": {"x": 1, "y": 2, "x": 3}}', "x"),
        ('[{"ok": 1}, {"t": 0, "t": 0}]', "t"),
        ('{"' + "k" * 60 + '": 1, "' + "k" * 60 + '": 1}', "k" * 40 + "..."),
    ],
)
def test_a_key_given_twice_in_one_object_is_refused_by_name(tmp_path, text, key):
    path = tmp_path / "f.json"
    path.write_text(text)
    with pytest.raises(InvalidFileError) as info:
        read_json(path, "run file")
    message = str(info.value)
    assert f'the key "{key}" appears twice' in message and "keep one" in message


def test_the_same_key_in_different_objects_is_kept(tmp_path):
    path = tmp_path / "f.json"
    path.write_text('{"a": {"a": 1}, "b": [{"a": 2}, {"a": 3}]}')
    assert read_json(path) == {"a": {"a": 1}, "b": [{"a": 2}, {"a": 3}]}


def test_a_loop_of_symbolic_links_says_how_to_fix_it(tmp_path):
    os.symlink("b.json", tmp_path / "a.json")
    os.symlink("a.json", tmp_path / "b.json")
    with pytest.raises(InvalidFileError, match="loop of symbolic links") as info:
        read_json(tmp_path / "a.json", "run file")
    assert "point it at the real file" in str(info.value)


def test_not_utf8_is_refused(tmp_path):
    path = tmp_path / "f.json"
    path.write_bytes(b'{"a": "\xff"}')
    with pytest.raises(InvalidFileError, match="not UTF-8 text"):
        read_json(path)


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda d: d, "is a folder"),
        (lambda d: d / "missing.json", "does not exist"),
        (lambda d: d / "x\x00y.json", "NUL character"),
        (lambda d: d / ("n" * 256 + ".json"), "more than the 255"),
        (lambda d: d / "plain.txt" / "x.json", "part of the path is a file"),
        (lambda d: 42, "not a file path"),
    ],
)
def test_bad_paths_give_a_named_error_not_a_raw_one(tmp_path, make, words):
    (tmp_path / "plain.txt").write_text("x")
    with pytest.raises(InvalidFileError, match=words) as info:
        read_json(make(tmp_path), "run file")
    assert isinstance(info.value, TutorError) and not isinstance(info.value, OSError)


# --------------------------------------------------------------------- writing


def test_write_round_trip_leaves_no_temp_and_keeps_permissions(tmp_path):
    path = tmp_path / "deep" / "er" / "s.json"
    write_json(path, {"a": [1, 2.5]})
    assert read_json(path) == {"a": [1, 2.5]}
    os.chmod(path, 0o640)
    write_json(path, {"a": 3})
    assert read_json(path) == {"a": 3}
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o640
    assert os.listdir(path.parent) == ["s.json"]


def test_a_long_name_still_fits_its_temp_file(tmp_path):
    path = tmp_path / ("s" * 250 + ".json")
    atomic_write_text(path, "[]")
    assert read_json(path) == [] and os.listdir(tmp_path) == [path.name]


def test_stale_temp_files_of_the_target_are_removed(tmp_path):
    path = tmp_path / "s.json"
    stale = tmp_path / ".s.json.k1ll3d.tmp"
    fresh = tmp_path / ".s.json.busy01.tmp"  # another writer, still saving
    other = tmp_path / ".t.json.k1ll3d.tmp"  # another target's
    for p in (stale, fresh, other):
        p.write_text("half")
    old = time.time() - 2 * fileio.STALE_TEMP_SECONDS
    os.utime(stale, (old, old))
    os.utime(other, (old, old))
    atomic_write_text(path, "[1]")
    assert not stale.exists() and fresh.exists() and other.exists()
    assert read_json(path) == [1]


def test_a_path_through_a_file_is_a_save_error(tmp_path):
    (tmp_path / "plain.txt").write_text("keep")
    for target in (tmp_path / "plain.txt" / "s.json", tmp_path / "plain.txt" / "a" / "s.json"):
        with pytest.raises(SaveError, match="part of the path is a file, not a folder") as info:
            write_json(target, {"a": 1})
        assert isinstance(info.value, OSError) and isinstance(info.value, TutorError)
    assert (tmp_path / "plain.txt").read_text() == "keep"
    assert os.listdir(tmp_path) == ["plain.txt"]


@pytest.mark.parametrize(
    "name, words",
    [
        ("x\x00y.json", "NUL character"),
        ("n" * 256 + ".json", "more than the 255"),
        (".", "is a folder"),
    ],
)
def test_names_that_cannot_be_files_are_save_errors(tmp_path, name, words):
    with pytest.raises(SaveError, match=words):
        atomic_write_text(tmp_path / name if name != "." else tmp_path, "x")
    assert os.listdir(tmp_path) == []


def test_an_existing_folder_as_target_is_a_save_error(tmp_path):
    (tmp_path / "s.json").mkdir()
    with pytest.raises(SaveError, match="that is a folder"):
        atomic_write_text(tmp_path / "s.json", "x")
    assert os.listdir(tmp_path) == ["s.json"]


def test_data_json_cannot_hold_is_a_save_error_and_writes_nothing(tmp_path):
    for data in (float("nan"), {"a": float("inf")}, {"a": object()}):
        with pytest.raises(SaveError, match="cannot be written as JSON"):
            write_json(tmp_path / "s.json", data)
    assert os.listdir(tmp_path) == []


def _cannot(reason: str):
    """Skip on a developer's machine that cannot mount; in CI (root, Linux) it must work."""
    if os.environ.get("CI"):
        pytest.fail(f"CI must run the real-disk tests: {reason}")
    pytest.skip(reason)


@pytest.fixture
def tmpfs(tmp_path):
    """Make small real tmpfs mounts (root on Linux only); unmounted afterwards."""
    mounted = []

    def make(size="64k"):
        if not LINUX_ROOT:
            _cannot("mounting a tmpfs needs root on Linux")
        folder = tmp_path / f"mnt{len(mounted)}"
        folder.mkdir()
        done = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
            capture_output=True,
            text=True,
        )
        if done.returncode:
            _cannot(f"mounting a tmpfs is not permitted here: {done.stderr.strip()}")
        mounted.append(folder)
        return folder

    yield make
    for folder in reversed(mounted):
        subprocess.run(["umount", "-l", str(folder)], capture_output=True)


def test_disk_full_is_a_save_error_and_the_old_file_stays(tmpfs):
    """A real full disk: a 64 KiB tmpfs asked to hold 200 KB."""
    disk = tmpfs("64k")
    path = disk / "s.json"
    write_json(path, {"demos": [1, 2, 3]})
    before = path.read_bytes()
    with pytest.raises(SaveError, match="the disk is full: free some space, then save again"):
        write_json(path, {"demos": list(range(40_000))})
    assert path.read_bytes() == before
    assert os.listdir(disk) == ["s.json"]
    write_json(path, {"demos": [4]})  # once there is room, saving works again
    assert read_json(path) == {"demos": [4]}


def test_a_read_only_disk_is_a_save_error_and_the_file_stays(tmpfs):
    disk = tmpfs("64k")
    path = disk / "s.json"
    write_json(path, {"a": 1})
    done = subprocess.run(["mount", "-o", "remount,ro", str(disk)], capture_output=True)
    if done.returncode:
        _cannot("remounting read-only is not permitted here")
    for target in (path, disk / "new" / "s.json"):
        with pytest.raises(SaveError, match="on a read-only disk: save somewhere else") as info:
            write_json(target, {"a": 2})
        assert info.value.__cause__.errno == errno.EROFS
    assert read_json(path) == {"a": 1} and os.listdir(disk) == ["s.json"]


def test_save_error_message_names_each_cause_in_plain_words(tmp_path):
    """The wording for causes this machine cannot provoke (root ignores permissions)."""
    path = tmp_path / "s.json"
    for code, words in [
        (errno.EACCES, "no permission to write in"),
        (errno.EDQUOT, "quota is used up"),
        (errno.ENAMETOOLONG, "too long"),
        (errno.EIO, "the disk reported an error"),
    ]:
        error = fileio.save_error(path, OSError(code, os.strerror(code)))
        assert isinstance(error, SaveError) and words in str(error)
        assert str(path) in str(error) and "Nothing was changed on disk" in str(error)


def test_written_json_reads_back_exactly(tmp_path):
    data = {"x": [0.1, -2e-300, 1.7976931348623157e308], "s": 'é\n"', "n": None, "b": True}
    path = write_json(tmp_path / "s.json", data)
    assert read_json(path) == data == json.loads(path.read_text(encoding="utf-8"))
