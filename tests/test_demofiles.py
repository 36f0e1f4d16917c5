"""Demonstration files: columns by name, separators, versions, strict numbers, bundled
names, hostile files and uploads."""

from __future__ import annotations

import datetime
import json
import os
import threading
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tutor import fileio
from tutor.demofiles import (
    KNOWN_COLUMNS,
    bundled_demos,
    bundled_names,
    load_demos,
    save_demos,
)
from tutor.errors import (
    InvalidDemoError,
    InvalidFileError,
    InvalidParameterError,
    SaveError,
    TutorError,
)
from tutor.views.uploads import on_upload, safe_upload_name, shown_upload_name


def write(tmp_path, name, text: str | bytes) -> Path:
    path = tmp_path / name
    if isinstance(text, str):
        text = text.encode("utf-8")
    path.write_bytes(text)
    return path


# --------------------------------------------------------------------- CSV


def test_a_csv_with_a_byte_order_mark_loads(tmp_path):
    path = write(tmp_path, "excel.csv", b"\xef\xbb\xbfdemo,t,x,y\r\n1,0,0.1,0.2\r\n1,1,0.3,0.4\r\n")
    ds = load_demos(path)
    assert ds.columns == ["t", "x", "y"]
    np.testing.assert_array_equal(ds[0], [[0, 0.1, 0.2], [1, 0.3, 0.4]])


def test_a_json_with_a_byte_order_mark_loads(tmp_path):
    body = json.dumps({"format": "lfd-tutor-demos", "demos": [[[0, 1, 2]]]})
    ds = load_demos(write(tmp_path, "d.json", b"\xef\xbb\xbf" + body.encode()))
    np.testing.assert_array_equal(ds[0], [[0, 1, 2]])


@pytest.mark.parametrize("sep", [";", "\t"])
def test_semicolon_and_tab_separated_files_with_decimal_points_load(tmp_path, sep):
    rows = ["demo,t,x,y", "a,0,0.5,-1.25e-2", "a,0.1,0.6,1", "b,0,1.5,2"]
    path = write(tmp_path, "d.csv", "\n".join(r.replace(",", sep) for r in rows) + "\n")
    ds = load_demos(path)
    assert len(ds) == 2
    np.testing.assert_array_equal(ds[0], [[0, 0.5, -0.0125], [0.1, 0.6, 1]])


@pytest.mark.parametrize("sep, shown", [(";", "';'"), ("\t", "tab")])
def test_decimal_commas_are_refused_naming_the_separator(tmp_path, sep, shown):
    path = write(tmp_path, "d.csv", f"demo{sep}t{sep}x{sep}y\n1{sep}0{sep}0,5{sep}1.234,5\n")
    with pytest.raises(InvalidFileError) as info:
        load_demos(path)
    message = str(info.value)
    assert f"separated by {shown}" in message and "decimal comma" in message
    assert "'0,5'" in message and "decimal point" in message and "Re-export" in message


@pytest.mark.parametrize(
    "body, words",
    [
        ("demo;t;x;w\n1;0;1;2\n", "unknown column 'w'"),
        ("demo;t;x;y\n1;0;1\n", "line 2: 3 values but the header has 4 .* fix that line"),
        ("demo;t;x;y\n1;0;1;abc\n", "'abc' is not a number"),
        ("demo;t;x;y\n1;0;1;nan\n", "NaN or inf"),
        ("demo;t;x;y\n", "holds no samples.* at least 2 per demonstration"),
        ("t;x;y\n0;1;2\n", "needs one 'demo' column"),
        ("demo;x;y\n1;1;2\n", "no 't' column"),
        ("demo;t;x;x\n1;0;1;2\n", "appears twice"),
        ("demo;t;x;y\n;0;1;2\n", "label is empty"),
    ],
)
def test_every_message_about_a_semicolon_file_names_the_separator(tmp_path, body, words):
    with pytest.raises(InvalidFileError, match=words) as info:
        load_demos(write(tmp_path, "d.csv", body))
    assert "separated by ';'" in str(info.value)


def test_a_one_column_header_names_the_separators_it_knows(tmp_path):
    with pytest.raises(InvalidFileError, match="commas, ';' or tabs"):
        load_demos(write(tmp_path, "d.csv", "demo t x y\n1 0 1 2\n"))


@pytest.mark.parametrize("header", ["demo,t,y,x", "t,demo,y,x", "y,x,t,demo", "Demo, T , Y,X"])
def test_csv_columns_are_matched_by_name_in_any_order(tmp_path, header):
    names = [h.strip().lower() for h in header.split(",")]
    values = {"demo": "1", "t": "0.5", "x": "0.25", "y": "0.75"}
    path = write(tmp_path, "d.csv", f"{header}\n{','.join(values[n] for n in names)}\n")
    ds = load_demos(path)
    assert ds.columns == ["t", "x", "y"]
    np.testing.assert_array_equal(ds[0], [[0.5, 0.25, 0.75]])
    asked = load_demos(path, columns=("t", "y", "x"))
    assert asked.columns == ["t", "y", "x"]
    np.testing.assert_array_equal(asked[0], [[0.5, 0.75, 0.25]])


def test_unknown_csv_columns_are_refused_listing_the_known_ones(tmp_path):
    with pytest.raises(InvalidFileError, match="unknown column 'speed'") as info:
        load_demos(write(tmp_path, "d.csv", "demo,t,x,speed\n1,0,1,2\n"))
    assert "demo, t, x, y, z, g" in str(info.value)


def test_expected_columns_missing_or_extra_are_refused_by_name(tmp_path):
    maze = save_demos(tmp_path / "maze.csv", [np.zeros((2, 3))])
    with pytest.raises(InvalidFileError, match="has no 'z', 'g' column") as info:
        load_demos(maze, columns="txyzg")
    assert "t, x, y, z, g" in str(info.value)
    pick = save_demos(tmp_path / "pick.json", [np.zeros((2, 5))], columns="txyzg")
    with pytest.raises(InvalidFileError, match="'z', 'g', which this task does not use"):
        load_demos(pick, columns=("t", "x", "y"))
    assert load_demos(pick, columns=("t", "x", "y", "z", "g")).columns == list("txyzg")


@pytest.mark.parametrize("columns", [("t", "x", "speed"), ("x", "y"), ("t", "t"), (1, 2)])
def test_a_bad_columns_argument_is_a_parameter_error(tmp_path, columns):
    path = save_demos(tmp_path / "d.json", [np.zeros((2, 3))])
    with pytest.raises(InvalidParameterError):
        load_demos(path, columns=columns)


@pytest.mark.parametrize(
    "cell, words",
    [
        ("1+2j", "complex number"),
        ("1e400", "too large"),
        ("-1e400", "too large"),
        ("inf", "NaN or inf"),
        ("-Infinity", "NaN or inf"),
        ("NaN", "NaN or inf"),
        ("1_000", "not a number"),
        ("0x10", "not a number"),
        ("\u0661\u0662", "not a number"),  # Arabic-Indic digits float() would take
        ("", "not a number"),
    ],
)
def test_csv_numbers_are_plain_finite_decimals(tmp_path, cell, words):
    with pytest.raises(InvalidFileError, match=words) as info:
        load_demos(write(tmp_path, "d.csv", f"demo,t,x,y\n1,0,1,2\n1,1,2,{cell}\n"))
    assert "line 3" in str(info.value)


# --------------------------------------------------------------------- JSON


def demo_json(**fields) -> str:
    return json.dumps({"format": "lfd-tutor-demos", "demos": [[[0, 1, 2]]], **fields})


@pytest.mark.parametrize("version", [99, "1", 2, True, 1.0, None, [1]])
def test_unsupported_versions_are_refused_listing_the_supported(tmp_path, version):
    with pytest.raises(InvalidFileError, match="cannot read; it reads version 1") as info:
        load_demos(write(tmp_path, "d.json", demo_json(version=version)))
    assert repr(version) in str(info.value)


@pytest.mark.parametrize(
    "condition, shown",
    [("plant 3", "'plant 3'"), (3, "3"), ([], r"\[\]"), (True, "true"), ({"x": 1}, "{'x': 1}")],
)
def test_a_condition_that_is_not_a_list_of_numbers_is_refused(tmp_path, condition, shown):
    text = demo_json(demos=[[[0, 1, 2], [1, 2, 3]]] * 2, conditions=[[0.3, 0.1], condition])
    with pytest.raises(InvalidFileError, match=f"condition 2 is {shown}, not a list of numbers"):
        load_demos(write(tmp_path, "d.json", text))


def test_conditions_given_or_null_are_kept(tmp_path):
    text = demo_json(demos=[[[0, 1, 2], [1, 2, 3]]] * 2, conditions=[[0.3, 0.1], None])
    loaded = load_demos(write(tmp_path, "d.json", text))
    assert loaded.demo_points[0].tolist() == [0.3, 0.1] and loaded.demo_points[1] is None


def test_a_missing_version_is_version_1(tmp_path):
    assert len(load_demos(write(tmp_path, "d.json", demo_json()))) == 1
    assert len(load_demos(write(tmp_path, "e.json", demo_json(version=1)))) == 1


def test_json_columns_are_matched_by_name(tmp_path):
    path = write(tmp_path, "d.json", demo_json(columns=["y", "t", "x"]))
    ds = load_demos(path)
    assert ds.columns == ["t", "x", "y"]
    np.testing.assert_array_equal(ds[0], [[1, 2, 0]])
    for columns, words in [
        (["t", "x", "q"], "unknown column 'q'"),
        ("txy", "must be a list of names"),
        (["t", "x", 3], "must be a list of names"),
        (["x", "y", "z"], "no 't' column"),
    ]:
        with pytest.raises(InvalidFileError, match=words):
            load_demos(write(tmp_path, "d.json", demo_json(columns=columns)))


@pytest.mark.parametrize(
    "sample, words",
    [
        ("[0, 1, 1e400]", "too large"),
        ("[0, 1, " + "1" * 400 + "]", "too large"),
        ("[0, 1, NaN]", "NaN is not allowed"),
        ("[0, 1, -Infinity]", "Infinity is not allowed"),
        ("[0, 1, true]", "holds true"),
        ('[0, 1, "1+2j"]', "'1\\+2j'"),
        ("[0, 1, null]", "holds None"),
        ("[0, 1, [2]]", "not a finite number"),
    ],
)
def test_json_values_must_be_finite_numbers(tmp_path, sample, words):
    text = '{"format": "lfd-tutor-demos", "demos": [[[0, 1, 2], ' + sample + "]]}"
    with pytest.raises(InvalidFileError, match=words):
        load_demos(write(tmp_path, "d.json", text))


# --------------------------------------------------------------------- hostile files


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("name", ["x.csv", "x.json"])
def test_a_fifo_demo_file_is_refused_without_waiting(tmp_path, name):
    fifo = tmp_path / name
    os.mkfifo(fifo)
    outcome = {}

    def run():
        try:
            load_demos(fifo)
        except TutorError as exc:
            outcome["error"] = exc

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(10)
    if thread.is_alive():
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        pytest.fail("load_demos blocked on a FIFO")
    assert "not a regular file" in str(outcome["error"])


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="no /dev/zero")
def test_a_csv_that_is_a_device_or_a_folder_or_too_large_is_refused(tmp_path):
    (tmp_path / "zero.csv").symlink_to("/dev/zero")
    with pytest.raises(InvalidFileError, match="is a device, not a regular file"):
        load_demos(tmp_path / "zero.csv")
    (tmp_path / "folder.csv").mkdir()
    with pytest.raises(InvalidFileError, match="is a folder"):
        load_demos(tmp_path / "folder.csv")
    with open(tmp_path / "big.csv", "wb") as fh:
        fh.truncate(fileio.MAX_FILE_BYTES + 1)
    with pytest.raises(InvalidFileError, match="larger than the 50 MB"):
        load_demos(tmp_path / "big.csv")


@pytest.mark.parametrize("name", ["a\x00.csv", "n" * 256 + ".json"])
def test_impossible_names_are_invalid_files(tmp_path, name):
    with pytest.raises(InvalidFileError, match="NUL|more than the 255"):
        load_demos(tmp_path / name)


def test_a_not_utf8_csv_is_refused(tmp_path):
    with pytest.raises(InvalidFileError, match="not UTF-8"):
        load_demos(write(tmp_path, "d.csv", b"demo,t,x,y\n1,0,1,\xe9\n"))


# --------------------------------------------------------------------- bundled sets


@pytest.mark.parametrize(
    "name",
    ["../maze_good", "/etc/passwd", "maze_good.json", "demos/maze_good", "", "nope", None, 3],
)
def test_bundled_demos_takes_only_bundled_names(name):
    with pytest.raises(InvalidFileError, match="no bundled demonstration set") as info:
        bundled_demos(name)
    assert "maze_good" in str(info.value) and "pickplace_corners" in str(info.value)


def test_every_bundled_name_loads_with_its_tasks_columns():
    names = bundled_names()
    assert "maze_good" in names and "pickplace_wrong_plant" in names
    for name in names:
        columns = ("t", "x", "y") if name.startswith("maze") else ("t", "x", "y", "z", "g")
        ds = bundled_demos(name, columns=columns)
        assert ds.columns == list(columns) and all(d.shape[1] == len(columns) for d in ds)


# --------------------------------------------------------------------- saving


def test_save_refuses_what_it_could_not_load_back(tmp_path):
    with pytest.raises(InvalidDemoError, match="NaN or inf"):
        save_demos(tmp_path / "d.csv", [np.array([[0, 1, np.nan]])])
    with pytest.raises(InvalidDemoError, match="at least one sample of 3"):
        save_demos(tmp_path / "d.csv", [np.zeros((0, 3))])
    with pytest.raises(InvalidDemoError, match="at least one sample of 3"):
        save_demos(tmp_path / "d.json", [np.zeros((2, 4))])
    with pytest.raises(InvalidParameterError, match="unknown column 'w'"):
        save_demos(tmp_path / "d.json", [np.zeros((2, 3))], columns="twx")
    assert os.listdir(tmp_path) == []


def test_save_into_a_file_path_is_a_save_error(tmp_path):
    (tmp_path / "plain").write_text("x")
    with pytest.raises(SaveError, match="not a folder"):
        save_demos(tmp_path / "plain" / "d.csv", [np.zeros((2, 3))])


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@st.composite
def demo_tables(draw):
    extra = draw(st.lists(st.sampled_from(KNOWN_COLUMNS[1:]), unique=True, max_size=4))
    columns = draw(st.permutations(["t", *extra]))
    n_demos = draw(st.integers(1, 3))
    demos = [
        np.array(
            draw(
                st.lists(
                    st.lists(finite, min_size=len(columns), max_size=len(columns)),
                    min_size=1,
                    max_size=6,
                )
            ),
            dtype=float,
        )
        for _ in range(n_demos)
    ]
    return columns, demos


@settings(max_examples=60, deadline=None)
@given(table=demo_tables(), suffix=st.sampled_from([".csv", ".json"]))
def test_save_and_load_round_trip_any_finite_table(tmp_path_factory, table, suffix):
    columns, demos = table
    path = save_demos(tmp_path_factory.mktemp("rt") / f"d{suffix}", demos, columns=columns)
    same = load_demos(path, columns=columns)
    assert same.columns == columns and len(same) == len(demos)
    for a, b in zip(demos, same, strict=True):
        np.testing.assert_array_equal(a, b)
    canonical = load_demos(path)
    order = [columns.index(c) for c in canonical.columns]
    assert canonical.columns == [c for c in KNOWN_COLUMNS if c in columns]
    for a, b in zip(demos, canonical, strict=True):
        np.testing.assert_array_equal(a[:, order], b)


# --------------------------------------------------------------------- uploads


class Tutor:
    """The smallest real consumer of uploads: loads demos, naming the file as the trainee
    knows it (as the run controller does), and shows a message line (``tell``)."""

    def __init__(self, fail_with=None):
        self.message = ""
        self.refreshed = 0
        self.paths = []
        self.loaded = []
        self.fail_with = fail_with

    def refresh(self):
        self.refreshed += 1

    def tell(self, text):
        self.message = text
        self.refresh()

    def load(self, path, name):
        self.paths.append(path)
        assert path.exists()
        if self.fail_with is not None:
            raise self.fail_with
        try:
            self.loaded.append(load_demos(path))
            self.message = f"Added {len(self.loaded[-1])} demonstration(s) from {name}."
        except InvalidFileError as exc:
            self.message = f"Nothing was loaded: {str(exc).replace(path.name, name)}"


def upload(name, data: bytes):
    return {
        "new": (
            {
                "name": name,
                "type": "text/csv",
                "size": len(data),
                "content": memoryview(data),
                "last_modified": datetime.datetime.now(datetime.UTC),
            },
        )
    }


CSV = b"demo,t,x,y\n1,0,1,2\n"


@pytest.mark.parametrize(
    "name, stored",
    [
        ("mine.csv", "mine.csv"),
        ("my corners.csv", "my corners.csv"),
        ("../../etc/x.csv", "_.._etc_x.csv"),
        ("C:\\Users\\me\\x.csv", "C__Users_me_x.csv"),
        ("a\x00b.csv", "a_b.csv"),
        ("..", "upload.json"),
        ("", "upload.json"),
        (None, "upload.json"),
        ("noext", "noext.json"),
    ],
)
def test_upload_names_are_made_safe(name, stored):
    assert safe_upload_name(name) == stored


def test_a_name_over_255_bytes_keeps_its_extension_and_fits():
    stored = safe_upload_name("é" * 300 + ".csv")
    assert stored.endswith(".csv") and len(stored.encode()) <= 255
    assert shown_upload_name("é" * 300 + ".csv").endswith(".csv")


@pytest.mark.parametrize(
    "name", ["a\x00b.csv", "../../../tmp/evil.csv", "x/" * 200 + "y.csv", "é" * 300 + ".csv"]
)
def test_hostile_upload_names_load_under_a_safe_name(name):
    tutor = Tutor()
    on_upload(tutor.load, tutor.tell)(upload(name, CSV))
    (path,) = tutor.paths
    assert path.suffix == ".csv" and "\x00" not in str(path)
    assert len(path.name.encode()) <= 255 and path.parent.name.startswith("lfd-upload-")
    assert not path.parent.exists()  # removed after loading
    assert len(tutor.loaded) == 1 and "Added 1" in tutor.message


def test_errors_from_load_are_shown_not_raised_naming_the_trainees_file():
    tutor = Tutor()
    on_upload(tutor.load, tutor.tell)(upload("bad\x00name.csv", b"demo;t;x;y\n1;0;0,5;1\n"))
    assert tutor.message.startswith("Nothing was loaded: bad?name.csv (values separated by ';')")
    failing = Tutor(fail_with=SaveError("could not save s.json: the disk is full"))
    on_upload(failing.load, failing.tell)(upload("ok.csv", CSV))
    assert failing.message == "could not save s.json: the disk is full" and failing.refreshed
    broken = Tutor(fail_with=InvalidDemoError("demo 1 is too short"))
    shown = []
    on_upload(broken.load, report=shown.append)(upload("ok.csv", CSV))
    assert shown == ["Nothing was loaded: demo 1 is too short"]


def test_an_oversized_or_empty_upload_is_refused_unwritten(monkeypatch):
    tutor = Tutor()
    observer = on_upload(tutor.load, tutor.tell)
    observer({"new": ()})
    for item in ({"name": "x.csv"}, {"name": "x.csv", "content": 10**12}, None, "x"):
        tutor.message = ""
        observer({"new": (item,)})
        assert "arrived without its content" in tutor.message
    monkeypatch.setattr("tutor.payloads.MAX_UPLOAD_BYTES", 8)
    observer(upload("big.csv", CSV))
    assert "larger than the 8 bytes" in tutor.message and tutor.paths == []


def test_the_maze_tutor_shows_a_hostile_upload_in_its_panel(tmp_path):
    from tutor.views.maze_app import MazeTutor

    app = MazeTutor("VF", run_file=tmp_path / "vf.json")
    path = save_demos(tmp_path / "up.csv", list(bundled_demos("maze_good"))[:1])
    data = path.read_bytes()
    app.upload.value = (upload("../my\x00demo.csv", data)["new"][0],)
    assert app.session.n_demos == 1 and "Added 1" in app.message
    app.upload.value = (upload("n" * 300 + ".csv", b"demo;t;x;y\n1;0;0,5;1\n")["new"][0],)
    assert app.session.n_demos == 1 and "decimal comma" in app.panel.value
