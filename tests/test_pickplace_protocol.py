"""Experiment 2's four conditions and the teaching clock."""

from __future__ import annotations

import numpy as np
import pytest

from tutor.errors import InvalidParameterError
from tutor.tasks.pickplace import PickPlaceTask
from tutor.tasks.pickplace_protocol import PickPlaceRun, RunOverError


@pytest.fixture(scope="module")
def task():
    return PickPlaceTask()


def test_what_each_condition_shows_and_costs(task):
    rng = np.random.default_rng(0)
    raw = task.demonstrate(12, rng)
    seconds = task.duration(raw)
    expected = {"NF": (0, 0.0), "RF": (1, 25.0), "BF": (5, 125.0), "SF": (0, 0.0)}
    for cond, (n_shown, cost) in expected.items():
        run = PickPlaceRun(cond, task)
        rec = run.demonstrate(12, raw=raw)
        assert len(rec.shown) == n_shown
        assert run.elapsed == pytest.approx(seconds + cost)
    bf = PickPlaceRun("BF", task)
    assert sorted(bf.demonstrate(12, raw=raw).shown.tolist()) == [0, 9, 44, 90, 99]
    rf = PickPlaceRun("RF", task)
    assert rf.demonstrate(12, raw=raw).shown.tolist() == [12]


def test_selected_tests_cost_time_and_others_wait(task):
    rng = np.random.default_rng(1)
    sf = PickPlaceRun("SF", task)
    sf.demonstrate(0, rng=rng)
    before = sf.elapsed
    result = sf.test([5, 50])
    assert result.shape == (2,) and sf.elapsed == pytest.approx(before + 50.0)
    assert set(sf.shown_plants().tolist()) == {5, 50}
    nf = PickPlaceRun("NF", task)
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


def test_the_fifteen_minute_cap(task):
    rng = np.random.default_rng(2)
    run = PickPlaceRun("BF", task)
    n = 0
    while not run.finished:
        run.demonstrate(int(rng.integers(100)), rng=rng)
        n += 1
    assert run.elapsed >= run.cap and n <= 7  # ~11 s demo + 125 s of feedback each
    with pytest.raises(RunOverError, match="15 minutes"):
        run.demonstrate(3, rng=rng)
    assert "15:00" in run.clock_text()
    # the demo that ran past the cap may still be taken back; no time comes back
    used = run.elapsed
    run.undo()
    assert run.n_demos == n - 1 and run.finished and run.elapsed == pytest.approx(used)
    run.finish()
    assert run.attempt.stopped == "time"
    with pytest.raises(RunOverError):
        run.undo()  # once finished, nothing changes
    assert run.n_demos == n - 1


def test_bad_plants_and_conditions(task):
    with pytest.raises(InvalidParameterError):
        PickPlaceRun("XF", task)
    run = PickPlaceRun("SF", task)
    for bad in (100, -1, 2.5, "a"):
        with pytest.raises(InvalidParameterError):
            run.demonstrate(bad)
    with pytest.raises(InvalidParameterError, match="demonstration before"):
        run.test([1])
