"""The trainee's own hand on the arm in the pick-and-place tutor (issue 20).

The tutor, its 3-D view (the notebook viewer, as behind a hub) and the real follower
(Pinocchio IK) together, driven through what the page sends: Guide, moves, the
recording at Enter. A demonstration given this way is one like any other; while the
trainee guides, nothing else may change the run; a recording the tutor cannot use is
refused in words, and the run is as it was.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from tutor.tasks.recording import steady_hand
from tutor.views.pickplace_app import CANCEL_GUIDE, GUIDE, PickPlaceTutor
from tutor.views.scene3d import Scene3D


@pytest.fixture
def own(pickplace_task, monkeypatch, tmp_path):
    monkeypatch.delenv("TUTOR_HAND", raising=False)
    scene = Scene3D(task=pickplace_task, mode="static")
    assert scene.widget is not None  # the view as a browser would have it
    return PickPlaceTutor(
        "RF", task=pickplace_task, scene3d=scene, seed=3, run_file=tmp_path / "rf.json"
    )


def _end(tutor, raw, setup=1.5):
    raw = np.ascontiguousarray(raw, dtype=float)
    tutor.scene3d.receive({"type": "guide-end", "n": len(raw), "setup": setup}, [raw.tobytes()])


def _state(tutor) -> tuple:
    return (tutor.run.n_demos, round(tutor.run.elapsed, 6), len(tutor.run.attempt.demos))


def test_the_own_hand_is_the_default_and_has_no_mistake_menu(own):
    assert own.hand == "own"
    row = own.demo_row.children
    assert own.buttons[GUIDE] in row and own.mistake not in row
    assert own.buttons["Demonstrate"] not in row
    assert "Enter" in own.how.value and "kbd" in own.how.value


def test_a_guided_demonstration_counts_its_duration_and_setup(own, pickplace_task):
    own.select(45)
    own.guide()
    assert own.guiding and own.buttons[GUIDE].description == CANCEL_GUIDE
    assert own.buttons["Undo"].disabled and own.buttons["Finish run"].disabled
    raw = steady_hand(pickplace_task, 45, np.random.default_rng(0))
    before = own.run.elapsed
    _end(own, raw, setup=2.5)
    assert not own.guiding and own.run.n_demos == 1
    demo = own.run.attempt.demos[-1]
    assert demo.given == "own"
    np.testing.assert_allclose(np.asarray(demo.recording), raw, atol=6e-5)  # kept to 0.1 mm
    assert demo.point == tuple(pickplace_task.test_points[45])
    spent = own.run.elapsed - before
    duration = raw[-1, 0] - raw[0, 0]
    # the demo, its setup and RF's one replay (25 s)
    assert spent == pytest.approx(duration + 2.5 + 25.0, abs=0.05)
    saved = json.loads(own.run_file.read_text())
    assert "own" in json.dumps(saved)


def test_while_guiding_the_plant_and_the_run_stay_put(own):
    own.select(12)
    own.guide()
    own.select(80)
    assert own.selected == 12 and "guiding" in own.message
    own.demonstrate()
    assert own.run.n_demos == 0 and "guiding" in own.message
    own.guide()  # pressed again: cancel
    assert not own.guiding and own.run.n_demos == 0 and own.run.elapsed == 0
    assert "cancelled" in own.message


def test_the_page_cancelling_ends_guiding_without_a_demo(own):
    own.guide()
    own.scene3d.receive({"type": "guide-cancel"}, [])
    assert not own.guiding and own.run.n_demos == 0 and "cancelled" in own.message


@pytest.mark.parametrize(
    "spoil, words",
    [
        (lambda r: np.where(np.arange(r.size).reshape(r.shape) == 40, np.nan, r), "NaN|number"),
        (lambda r: np.column_stack([r[:, :4], np.zeros(len(r))]), "never closes"),
        (lambda r: np.column_stack([r[:, :4], (r[:, 0] > r[len(r) // 3, 0]) * 1.0]), "open"),
        (lambda r: r[:1], "sample"),
        (lambda r: np.vstack([r[:60], r[60:] + [0, 0.4, 0, 0, 0]]), "jump"),
        (lambda r: r * [1, 4, 4, 1, 1], "reach"),
        (lambda r: r * [1200 / r[-1, 0], 1, 1, 1, 1], "minutes|seconds|long"),
    ],
    ids=["nan", "never-closes", "never-opens", "one-sample", "jump", "out-of-reach", "20-min"],
)
def test_a_recording_the_tutor_cannot_use_is_refused_and_nothing_changes(
    own, pickplace_task, spoil, words
):
    own.guide_as_steady_hand(30)
    before = _state(own)
    saved = own.run_file.read_bytes()
    raw = steady_hand(pickplace_task, 31, np.random.default_rng(1))
    own.select(31)
    own.guide()
    _end(own, spoil(raw))
    assert _state(own) == before, own.message
    assert own.run_file.read_bytes() == saved
    assert re.search(words, own.message, re.I), own.message


def test_a_recording_that_does_not_fit_the_clock_is_refused(own, pickplace_task):
    raw = steady_hand(pickplace_task, 50, np.random.default_rng(2))
    own.run.spend(own.run.cap - 30.0)  # less than the demo and RF's replay need
    before = _state(own)
    own.select(50)
    own.guide()
    _end(own, raw)
    assert _state(own) == before and "left" in own.message


def test_hostile_messages_from_the_page_do_not_raise(own):
    own.guide()
    for content, buffers in [
        ({"type": "guide-move", "seq": 1, "x": "a", "y": 0, "z": 0, "g": 0}, []),
        ({"type": "guide-end", "n": 10, "setup": 1.0}, [b"\x00" * 7]),
        ({"type": "guide-end", "n": -1, "setup": 1.0}, []),
        ({"type": "guide-end", "n": 2, "setup": 1e9}, [np.zeros(10).tobytes()]),
        ({"type": "nonsense"}, []),
    ]:
        try:
            own.scene3d.receive(content, buffers)
        except Exception as exc:  # the kernel's handler says it; the tutor must not change
            from tutor.errors import TutorError

            assert isinstance(exc, TutorError), exc
    assert own.run.n_demos == 0


def test_the_guided_hand_by_environment_and_without_a_view(pickplace_task, monkeypatch):
    monkeypatch.setenv("TUTOR_HAND", "guided")
    scene = Scene3D(task=pickplace_task, mode="static")
    guided = PickPlaceTutor("BF", task=pickplace_task, scene3d=scene, seed=0)
    assert guided.hand == "guided"
    row = guided.demo_row.children
    assert guided.buttons["Demonstrate"] in row and guided.mistake in row
    guided.demonstrate(44)
    assert guided.run.attempt.demos[-1].given == "guided"
    monkeypatch.delenv("TUTOR_HAND")
    bare = PickPlaceTutor("NF", task=pickplace_task, hand="own")
    assert bare.hand == "guided" and "Demonstrate" in bare.message


def test_autoplay_guides_with_a_steady_hand_when_headless(pickplace_task, monkeypatch):
    monkeypatch.setenv("TUTOR_HEADLESS", "1")
    monkeypatch.delenv("TUTOR_HAND", raising=False)
    scene = Scene3D(task=pickplace_task, mode="static")
    tutor = PickPlaceTutor("NF", task=pickplace_task, scene3d=scene, seed=1)
    tutor.autoplay([11, 45, 88])
    assert tutor.run.finished and tutor.run.n_demos == 3
    assert {d.given for d in tutor.run.attempt.demos} == {"own"}
