"""Guiding the arm in the 3-D view, the kernel's side (issue 20, part D).

The page's messages are given to :meth:`Scene3D.receive` (what the widget's message
handler calls) as the page would send them; the real :class:`HandFollower` steps the
arm, and what the scene sends back to the page is caught on the view widget.
"""

from __future__ import annotations

import numpy as np
import pytest

from tutor.errors import InvalidPayloadError
from tutor.payloads import MAX_GUIDE_SAMPLES, check_guide_end, check_guide_move
from tutor.robot.follow import HandFollower, guide_limits
from tutor.views.scene3d import Scene3D
from tutor.views.scene_guide import GuideEnd


@pytest.fixture
def guided(pickplace_task):
    """A static scene whose view was opened, guiding; (scene, sent, ends, cancels)."""
    scene = Scene3D(pickplace_task, mode="static")
    view = scene.widget.children[1]
    sent = []
    view.send = lambda content, buffers=None: sent.append((content, buffers))
    scene._on_view_msg(view, {"type": "hello", "id": "v1"}, [])
    ends, cancels = [], []
    scene.start_guide(
        HandFollower.for_scene(pickplace_task.scene), ends.append, lambda: cancels.append(1)
    )
    return scene, sent, ends, cancels


def _guide_sent(sent, cmd):
    return [(c, b) for c, b in sent if c.get("type") == "guide" and c.get("cmd") == cmd]


def _recording(n=40, start=(0.4, 0.0, 0.3)):
    t = np.arange(n) * 0.025
    raw = np.zeros((n, 5))
    raw[:, 0] = t
    raw[:, 1:4] = np.asarray(start) + np.outer(t, [0.1, 0.05, -0.05])
    raw[n // 2 :, 4] = 1.0
    return raw


def test_start_arms_the_page_with_the_handle_box_and_the_links(guided, pickplace_task):
    scene, sent, _, _ = guided
    assert scene.guiding
    ((start, _),) = _guide_sent(sent, "start")
    assert start["limits"] == {
        k: [float(v) for v in lo_hi] for k, lo_hi in guide_limits(pickplace_task.scene).items()
    }
    assert len(start["links"]) == 11 and start["links"][0].startswith("/meshcat/robot/visuals/")
    assert start["hand"] == "/meshcat/lfd/hand"
    assert start["limits"]["z"][0] > start["table"]  # the handle stays above the table
    assert np.allclose(start["start"], HandFollower.for_scene(pickplace_task.scene).state.position)


def test_a_move_steps_the_arm_and_the_answer_carries_the_links(guided):
    scene, sent, _, _ = guided
    start = np.array(_guide_sent(sent, "start")[0][0]["start"])
    target = start + [0.05, -0.03, -0.04]
    scene.receive(
        {"type": "guide-move", "seq": 7, "x": target[0], "y": target[1], "z": target[2], "g": 0.0},
        [],
    )
    ((msg, buffers),) = _guide_sent(sent, "arm")
    assert msg["seq"] == 7 and msg["reached"] and msg["collision"] is None
    assert np.allclose(msg["position"], target, atol=2e-3)
    P = np.frombuffer(buffers[0], dtype=np.float32).reshape(-1, 4, 4).transpose(0, 2, 1)
    state = scene._guide.state
    assert np.allclose(P, state.placements, atol=1e-5)  # column-major for three.js
    assert not np.allclose(P, HandFollower.for_scene(scene.scene).state.placements, atol=1e-3)


def test_a_move_into_the_table_is_held_above_it_and_said(guided):
    scene, sent, _, _ = guided
    scene.receive({"type": "guide-move", "seq": 1, "x": 0.45, "y": 0.0, "z": -0.3, "g": 0.0})
    ((msg, _),) = _guide_sent(sent, "arm")
    assert msg["clamped"] == "table" and msg["words"]
    assert msg["target"][2] >= guide_limits(scene.scene)["z"][0] - 1e-9


def test_a_link_in_contact_is_named_for_the_page_to_paint_red(guided):
    scene, sent, _, _ = guided
    lo = guide_limits(scene.scene)["z"][0]
    hits = []
    for k, (x, y) in enumerate([(0.1, 0.0), (0.05, 0.05), (0.15, -0.1), (0.2, 0.2)]):
        for z in (lo, lo + 0.02):
            scene.receive({"type": "guide-move", "seq": k, "x": x, "y": y, "z": z, "g": 0.0})
    for msg, _ in _guide_sent(sent, "arm"):
        if msg["collision"]:
            hits.append(msg)
    assert hits, "no pose near the base touched anything"
    links = _guide_sent(sent, "start")[0][0]["links"]
    for msg in hits:
        if msg["collision"].startswith("panda_"):
            assert msg["red"] and all(msg["collision"] in links[i] for i in msg["red"])


def test_enter_gives_on_end_the_recording_and_stops_guiding(guided):
    scene, sent, ends, cancels = guided
    raw = _recording()
    scene._on_view_msg(
        None, {"type": "guide-end", "n": len(raw), "setup": 3.5}, [raw.astype("<f8").tobytes()]
    )
    assert len(ends) == 1 and isinstance(ends[0], GuideEnd)
    assert np.array_equal(ends[0].raw, raw) and ends[0].setup_seconds == 3.5
    assert not scene.guiding and not cancels
    assert _guide_sent(sent, "stop")
    # a move still on its way after the end changes nothing and says nothing
    n = len(sent)
    scene._on_view_msg(
        None, {"type": "guide-move", "seq": 9, "x": 0.4, "y": 0, "z": 0.3, "g": 0}, []
    )
    assert len(sent) == n and scene.message == ""


def test_escape_cancels(guided):
    scene, sent, ends, cancels = guided
    scene.receive({"type": "guide-cancel"}, [])
    assert cancels == [1] and not ends and not scene.guiding
    assert _guide_sent(sent, "stop")


def test_stop_guide_calls_nothing(guided):
    scene, sent, ends, cancels = guided
    scene.stop_guide()
    assert not scene.guiding and not ends and not cancels
    scene.stop_guide()  # twice is fine


def test_a_reloaded_page_is_armed_again(guided):
    scene, sent, _, _ = guided
    sent.clear()
    scene._on_view_msg(None, {"type": "hello", "id": "v2"}, [])
    assert sent[0][0] == {"type": "full", "to": "v2"}
    assert _guide_sent(sent, "start")


HOSTILE_MOVES = [
    ("not an object", [1, 2]),
    ("no seq", {"type": "guide-move", "x": 0.4, "y": 0, "z": 0.3, "g": 0}),
    ("seq text", {"type": "guide-move", "seq": "1", "x": 0.4, "y": 0, "z": 0.3, "g": 0}),
    ("seq negative", {"type": "guide-move", "seq": -1, "x": 0.4, "y": 0, "z": 0.3, "g": 0}),
    ("seq bool", {"type": "guide-move", "seq": True, "x": 0.4, "y": 0, "z": 0.3, "g": 0}),
    ("NaN", {"type": "guide-move", "seq": 1, "x": float("nan"), "y": 0, "z": 0.3, "g": 0}),
    ("inf", {"type": "guide-move", "seq": 1, "x": 0.4, "y": float("inf"), "z": 0.3, "g": 0}),
    ("text", {"type": "guide-move", "seq": 1, "x": "0.4", "y": 0, "z": 0.3, "g": 0}),
    ("null", {"type": "guide-move", "seq": 1, "x": 0.4, "y": None, "z": 0.3, "g": 0}),
    ("grip 2", {"type": "guide-move", "seq": 1, "x": 0.4, "y": 0, "z": 0.3, "g": 2}),
    ("missing z", {"type": "guide-move", "seq": 1, "x": 0.4, "y": 0, "g": 0}),
]


@pytest.mark.parametrize("name, content", HOSTILE_MOVES, ids=[h[0] for h in HOSTILE_MOVES])
def test_hostile_moves_are_refused_and_guiding_goes_on(guided, name, content):
    scene, sent, ends, _ = guided
    before = scene._guide.state
    if isinstance(content, dict):
        with pytest.raises(InvalidPayloadError):
            scene.receive(content, [])
    scene._on_view_msg(None, content, [])  # the widget's handler: said, not raised
    assert scene.guiding and scene._guide.state is before and not ends
    assert scene.message
    if isinstance(content, dict):
        ((refused, _),) = _guide_sent(sent, "refused")
        assert refused["what"] == "guide-move" and refused["words"]


def _end(n, setup=1.0, nbytes=None):
    raw = _recording(max(n, 1))
    data = raw.tobytes()[: (n * 40 if nbytes is None else nbytes)]
    return {"type": "guide-end", "n": n, "setup": setup}, [data]


HOSTILE_ENDS = [
    ("n zero", *_end(0)),
    ("n text", {"type": "guide-end", "n": "40", "setup": 1.0}, [_recording().tobytes()]),
    ("n too many", {"type": "guide-end", "n": MAX_GUIDE_SAMPLES + 1, "setup": 1.0}, [b""]),
    ("short buffer", *_end(40, nbytes=39 * 40)),
    ("no buffer", {"type": "guide-end", "n": 40, "setup": 1.0}, []),
    ("two buffers", {"type": "guide-end", "n": 1, "setup": 1.0}, [b"\0" * 40, b"\0" * 40]),
    ("text buffer", {"type": "guide-end", "n": 1, "setup": 1.0}, ["x" * 40]),
    ("setup NaN", *_end(40, setup=float("nan"))),
    ("setup negative", *_end(40, setup=-1.0)),
    ("setup hours", *_end(40, setup=3600.0)),
]


@pytest.mark.parametrize("name, content, buffers", HOSTILE_ENDS, ids=[h[0] for h in HOSTILE_ENDS])
def test_hostile_ends_are_refused_and_the_page_guides_on(guided, name, content, buffers):
    scene, sent, ends, _ = guided
    with pytest.raises(InvalidPayloadError):
        scene.receive(content, buffers)
    scene._on_view_msg(None, content, buffers)
    assert scene.guiding and not ends and scene.message
    refused = _guide_sent(sent, "refused")
    assert refused and refused[-1][0]["what"] == "guide-end"


def test_validators_return_what_the_kernel_uses():
    seq, xyz, g = check_guide_move(
        {"type": "guide-move", "seq": 3, "x": 1, "y": 2.5, "z": 0, "g": 1}
    )
    assert seq == 3 and xyz.tolist() == [1.0, 2.5, 0.0] and g == 1.0
    raw = _recording(3)
    got, setup = check_guide_end(
        {"type": "guide-end", "n": 3, "setup": 0}, [memoryview(raw.tobytes())]
    )
    assert np.array_equal(got, raw) and setup == 0.0
    got.flags.writeable = True  # its own copy, not a view of the message's buffer


def test_the_live_view_is_a_widget_on_the_live_page(pickplace_task):
    scene = Scene3D(pickplace_task, mode="live", robot=False)
    if scene.mode != "live":
        pytest.skip(scene.message)
    view = scene.widget.children[1]
    assert view.src.endswith(f"/lfd/{scene.scene_id}/") and not view.page
    sent = []
    view.send = lambda content, buffers=None: sent.append((content, buffers))
    scene._on_view_msg(view, {"type": "hello", "id": "v1"}, [])
    assert sent == []  # the live page gets its scene from the server
