"""Experiment 2's four conditions and the teaching clock."""

from __future__ import annotations

import numpy as np
import pytest

from tutor.errors import InvalidParameterError
from tutor.tasks.pickplace_protocol import SHORTEST_DEMO_SECONDS, PickPlaceRun, RunOverError


def test_what_each_condition_shows_and_costs(pickplace_task):
    rng = np.random.default_rng(0)
    raw = pickplace_task.demonstrate(12, rng)
    seconds = pickplace_task.duration(raw)
    expected = {"NF": (0, 0.0), "RF": (1, 25.0), "BF": (5, 125.0), "SF": (0, 0.0)}
    for cond, (n_shown, cost) in expected.items():
        run = PickPlaceRun(cond, pickplace_task)
        rec = run.demonstrate(12, raw=raw)
        assert len(rec.shown) == n_shown
        assert run.elapsed == pytest.approx(seconds + cost)
    bf = PickPlaceRun("BF", pickplace_task)
    assert sorted(bf.demonstrate(12, raw=raw).shown.tolist()) == [0, 9, 44, 90, 99]
    rf = PickPlaceRun("RF", pickplace_task)
    assert rf.demonstrate(12, raw=raw).shown.tolist() == [12]


def test_selected_tests_cost_time_and_others_wait(pickplace_task):
    rng = np.random.default_rng(1)
    sf = PickPlaceRun("SF", pickplace_task)
    sf.demonstrate(0, rng=rng)
    before = sf.elapsed
    result = sf.test([5, 50])
    assert result.shape == (2,) and sf.elapsed == pytest.approx(before + 50.0)
    assert set(sf.shown_plants().tolist()) == {5, 50}
    nf = PickPlaceRun("NF", pickplace_task)
    nf.demonstrate(0, rng=rng)
    with pytest.raises(RunOverError, match="only after the run"):
        nf.test([3])
    nf.finish()
    nf.test([3])  # after the run, free
    assert nf.elapsed == pytest.approx(nf.attempt.demos[0].seconds)
    assert [(t.after_demo, t.plants, t.after_run) for t in nf.attempt.tests] == [(1, (3,), True)]
    assert [(t.after_demo, t.plants, t.after_run) for t in sf.attempt.tests] == [
        (1, (5, 50), False)
    ]


def test_the_fifteen_minute_cap(pickplace_task):
    rng = np.random.default_rng(2)
    run = PickPlaceRun("BF", pickplace_task)
    n = 0
    while not run.finished:
        run.demonstrate(int(rng.integers(100)), rng=rng)
        n += 1
    # every demo ended by 15:00 (~11 s demo + 125 s of feedback each); no room for another
    assert run.elapsed <= run.cap and n <= 7
    assert run.remaining < SHORTEST_DEMO_SECONDS + 125.0 and run.out_of_time
    assert run.attempt.stopped == ""  # over by the clock, not finished yet: undo still allowed
    before = run.record
    with pytest.raises(RunOverError, match=r"over: only \d:\d\d of the 15 minutes is left"):
        run.demonstrate(3, rng=rng)
    assert run.record == before  # refused: nothing changed
    assert run.elapsed <= run.cap and "of 15:00 used" in run.clock_text()
    run.finish()
    assert run.attempt.stopped == "time" and run.n_demos == n
    used = run.elapsed
    run.undo()  # the cap's one Undo: the time stays spent, the run stays over
    assert run.n_demos == n - 1 and run.finished and run.elapsed == pytest.approx(used)
    after = run.record
    with pytest.raises(RunOverError, match="its one Undo is used"):
        run.undo()  # only one
    assert run.record == after and run.n_demos == n - 1


def test_a_demo_that_cannot_end_by_the_cap_is_not_started(pickplace_task):
    """The paper's rule: a demo that would push the clock past 15:00 is not started."""
    rng = np.random.default_rng(3)
    raw = pickplace_task.demonstrate(44, rng)
    seconds = pickplace_task.duration(raw)
    run = PickPlaceRun("BF", pickplace_task)
    run.spend(run.cap - (seconds + 125.0) + 0.5)  # half a second short of this demo's cost
    assert not run.finished and run.fits(seconds - 1.0) and not run.fits(seconds)
    used = run.elapsed
    with pytest.raises(RunOverError, match=r"Only 2:\d\d of the 15 minutes is left.*not started"):
        run.demonstrate(44, raw=raw)
    assert run.n_demos == 0 and run.elapsed == used and not run.attempt.finished
    shorter = raw[raw[:, 0] <= raw[-1, 0] - 1.0]  # a second shorter: it fits
    run.demonstrate(44, raw=shorter)
    assert run.n_demos == 1 and run.elapsed <= run.cap and run.finished  # nothing else fits
    # RF pays one attempt, SF and NF none: a demo fits with less time left
    for cond, attempts in (("RF", 1), ("SF", 0), ("NF", 0)):
        other = PickPlaceRun(cond, pickplace_task)
        other.spend(other.cap - seconds - 25.0 * attempts)
        assert other.fits(seconds) and not other.fits(seconds + 0.5)
        other.demonstrate(44, raw=raw)
        assert other.elapsed == pytest.approx(other.cap)


def test_a_resumed_run_near_the_cap_refuses_and_ends(pickplace_task, tmp_path):
    rng = np.random.default_rng(4)
    run = PickPlaceRun("RF", pickplace_task)
    run.demonstrate(5, rng=rng)
    run.spend(run.cap - run.elapsed - 30.0)  # 0:30 left: shorter than a demo and a replay
    path = run.save(tmp_path / "run.json")
    again = PickPlaceRun.load(path, pickplace_task)
    assert again.finished and again.out_of_time and again.attempt.stopped == ""
    with pytest.raises(RunOverError, match="0:30 of the 15 minutes is left.*last complete"):
        again.demonstrate(6, rng=rng)
    assert again.n_demos == 1
    again.finish()
    assert again.attempt.stopped == "time"


def test_bad_plants_and_conditions(pickplace_task):
    with pytest.raises(InvalidParameterError):
        PickPlaceRun("XF", pickplace_task)
    run = PickPlaceRun("SF", pickplace_task)
    for bad in (100, -1, 2.5, "a"):
        with pytest.raises(InvalidParameterError):
            run.demonstrate(bad)
    with pytest.raises(InvalidParameterError, match="demonstration before"):
        run.test([1])
