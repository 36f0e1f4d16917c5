"""Issue 20, part A: own-hand recordings - their check, the scripted hand, hostile ones.

Each hostile recording raises InvalidRecordingError (a named error saying what and how
to fix it) and leaves the run as it was: its demos, its clock and its record file.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tutor.errors import InvalidDemoError, InvalidParameterError, InvalidRecordingError
from tutor.limits import MAX_RECORDING_SAMPLES, MAX_RECORDING_SECONDS
from tutor.tasks.pickplace_protocol import PickPlaceRun
from tutor.tasks.recording import MAX_JUMP, check_recording, steady_hand

PLANT = 45


@pytest.fixture(scope="module")
def good(pickplace_task):
    return steady_hand(pickplace_task, PLANT, rng=3)


def test_the_scripted_hand_is_a_recording_a_person_could_make(pickplace_task):
    for plant in (0, 9, 11, 45, 90, 99):
        for seed in range(3):
            raw = steady_hand(pickplace_task, plant, rng=seed)
            checked = check_recording(raw, pickplace_task.scene)
            np.testing.assert_array_equal(checked, raw)
            t, xyz, g = raw[:, 0], raw[:, 1:4], raw[:, 4]
            assert t[0] == 0 and np.allclose(np.diff(t), 1 / 40)
            assert 6 < t[-1] < 30  # seconds, like a kinesthetic demo
            speed = np.linalg.norm(np.diff(xyz, axis=0), axis=1) * 40
            assert 0.1 < speed.max() < 1.5  # a hand's peak speed, not a jump
            assert set(np.unique(g)) == {0.0, 1.0}
            demo = pickplace_task.preprocess(raw)
            verdict = pickplace_task.judge_demo(demo, pickplace_task.test_points[plant])
            assert verdict.passed[0], verdict.reasons
            assert pickplace_task.nearest_test_point(pickplace_task.test_point_of(demo)) == plant
    a, b = steady_hand(pickplace_task, 45, rng=1), steady_hand(pickplace_task, 45, rng=2)
    assert a.shape != b.shape or not np.allclose(a, b)  # people differ
    np.testing.assert_array_equal(steady_hand(pickplace_task, 45, rng=1), a)  # a seed is a person


def test_the_scripted_hand_refuses_what_is_not_a_plant_or_rate(pickplace_task):
    for plant in (-1, 100, 2.5, "3", True):
        with pytest.raises(InvalidParameterError):
            steady_hand(pickplace_task, plant)
    for rate in (0, -5, np.nan, "fast", 1e6):
        with pytest.raises(InvalidParameterError):
            steady_hand(pickplace_task, 3, rate_hz=rate)


def _hostile(good):
    """(name, recording, words the message must hold) for every hostile kind."""
    g = good.copy()
    n = len(g)
    out = [
        ("text", "a recording", "5 columns"),
        ("ragged", [[0, 0.3, 0, 0.4, 0], [1, 0.3, 0]], "5 columns"),
        ("three columns", g[:, :3], "5 columns"),
        ("3-D", g[None], "5 columns"),
        ("one sample", g[:1], "1 sample"),
        ("no sample", g[:0], "0 samples"),
    ]
    nan = g.copy()
    nan[n // 2, 2] = np.nan
    out.append(("NaN", nan, f"sample {n // 2 + 1} of {n} is not a number"))
    inf = g.copy()
    inf[3, 0] = np.inf
    out.append(("inf", inf, "sample 4"))
    back = g.copy()
    back[10, 0] = back[9, 0]
    out.append(("time stands", back, "time does not increase at sample 11"))
    jump = g.copy()
    jump[100, 1:4] += [0.3, 0.0, 0.0]
    out.append(("jump", jump, "between samples 100 and 101"))
    grip = g.copy()
    grip[50, 4] = 2.0
    out.append(("g above 1", grip, "sample 51 is 2"))
    grip = g.copy()
    grip[5, 4] = -0.5
    out.append(("g below 0", grip, "must be from 0 (open) to 1 (closed)"))
    never = g.copy()
    never[:, 4] = 0.0
    out.append(("never closes", never, "never closes"))
    stays = g.copy()
    stays[np.argmax(stays[:, 4] > 0.5) :, 4] = 1.0
    out.append(("never opens", stays, "never opens again"))
    far = g.copy()
    far[:, 1] *= 2.0
    out.append(("out of reach", far, "out of the arm's reach"))
    low = g.copy()
    low[:, 3] -= 0.2
    out.append(("below the table", low, "below the table top"))
    slow = g.copy()
    slow[:, 0] *= 20 * 60 / slow[-1, 0]  # the same hand moves for 20 minutes
    out.append(("20 minutes", slow, "20.0 minutes"))
    t = np.arange(MAX_RECORDING_SAMPLES + 1) / 200.0
    many = np.column_stack([t, np.tile(g[0, 1:], (len(t), 1))])
    out.append(("too many samples", many, f"more than the {MAX_RECORDING_SAMPLES}"))
    return out


def test_each_hostile_recording_is_refused_and_the_run_is_unchanged(pickplace_task, good, tmp_path):
    run = PickPlaceRun("RF", pickplace_task)
    run.demonstrate(PLANT, raw=good, given="own", setup_seconds=4.0)
    before_file = run.save(tmp_path / "before.json")
    before = (run.record, run.elapsed, run.session.n_demos, len(run.record.events))
    for name, raw, words in _hostile(good):
        with pytest.raises(InvalidRecordingError, match="cannot be a demonstration") as info:
            run.demonstrate(12, raw=raw, given="own", setup_seconds=2.0)
        assert words in str(info.value), (name, str(info.value))
        assert isinstance(info.value, InvalidDemoError)  # generic handlers still catch it
        assert (run.record, run.elapsed, run.session.n_demos, len(run.record.events)) == before
        after_file = run.save(tmp_path / "after.json")
        assert after_file.read_bytes() == before_file.read_bytes(), name


def test_an_own_hand_demo_needs_its_recording_and_takes_no_mistake(pickplace_task, good):
    run = PickPlaceRun("NF", pickplace_task)
    for options in (
        {"given": "own"},
        {"given": "own", "raw": good, "mistake": "wrong_plant"},
        {"given": "hand"},
        {"given": "loaded", "raw": good, "mistake": "sloppy_grab"},
        {"given": "own", "raw": good, "setup_seconds": -1.0},
        {"given": "own", "raw": good, "setup_seconds": np.nan},
        {"given": "own", "raw": good, "setup_seconds": "10"},
    ):
        with pytest.raises(InvalidParameterError):
            run.demonstrate(PLANT, **options)
    assert run.n_demos == 0 and run.elapsed == 0.0 and len(run.record.events) == 1


def test_an_own_hand_demo_costs_its_duration_and_set_up_time(pickplace_task, good):
    run = PickPlaceRun("BF", pickplace_task)
    rec = run.demonstrate(PLANT, raw=good, given="own", setup_seconds=7.5)
    demo = run.attempt.demos[-1]
    duration = good[-1, 0] - good[0, 0]
    assert demo.seconds == pytest.approx(duration + 7.5)
    assert run.elapsed == pytest.approx(duration + 7.5 + 5 * 25.0)
    assert demo.given == "own" and demo.mistake == ""
    np.testing.assert_allclose(np.array(demo.recording), good, atol=6e-4)
    assert len(rec.shown) == 5
    guided = run.demonstrate(12, rng=0)  # the tutor's hand: the default, no recording kept
    assert run.attempt.demos[-1].given == "guided" and run.attempt.demos[-1].recording is None
    assert guided is run.session.latest


def test_a_grab_elsewhere_is_a_real_demonstration_error(pickplace_task):
    """The plant selected before guiding is the plant meant: an own-hand demo that grabs
    a neighbour is kept, and judged as a wrong-plant demo."""
    raw = steady_hand(pickplace_task, PLANT + 1, rng=5)
    run = PickPlaceRun("NF", pickplace_task)
    run.demonstrate(PLANT, raw=raw, given="own")
    demo = np.asarray(run.attempt.demos[-1].samples)
    verdict = pickplace_task.judge_demo(demo, pickplace_task.test_points[PLANT])
    assert not verdict.passed[0] and "instead of the chosen" in verdict.reasons[0]


def test_a_refused_demo_that_would_pass_the_cap_changes_nothing(pickplace_task, good):
    run = PickPlaceRun("NF", pickplace_task)
    run.demonstrate(PLANT, raw=good, given="own")
    before = run.record
    with pytest.raises(Exception, match="not enough"):
        run.demonstrate(PLANT, raw=good, given="own", setup_seconds=10_000.0)
    assert run.record is before


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    kind=st.sampled_from(["nan", "time", "jump", "grip", "far"]),
    where=st.floats(0.0, 1.0),
    size=st.floats(1.01, 100.0),
)
def test_any_corrupted_sample_is_named(pickplace_task, good, kind, where, size):
    raw = good.copy()
    k = 1 + int(where * (len(raw) - 3))
    if kind == "nan":
        raw[k, 1 + k % 4] = np.nan
    elif kind == "time":
        raw[k, 0] = raw[k - 1, 0] - size / 100
    elif kind == "jump":
        raw[k:, 1] += MAX_JUMP * size
    elif kind == "grip":
        raw[k, 4] = size
    else:
        raw[k, 1:4] = [0.0, 0.9, 0.12 + 0.7 * min(size, 1.5)]
        raw[k - 1, 1:4] = raw[k + 1, 1:4] = raw[k, 1:4]
    with pytest.raises(InvalidRecordingError) as info:
        check_recording(raw, pickplace_task.scene)
    assert "sample" in str(info.value)


def test_the_longest_recordings_are_bounded():
    assert MAX_RECORDING_SECONDS == 300.0
    assert MAX_RECORDING_SAMPLES >= MAX_RECORDING_SECONDS * 100
