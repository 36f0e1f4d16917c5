"""Each run keeps its own 3-D view (issue 20): three scenes in one kernel, one server.

Three :class:`Scene3D` (the three runs of notebook 03) each have their own scene on the
kernel's live Meshcat server, with its own page and websocket: what one run draws or
replays reaches neither the other runs' scenes on the server nor the pages that show
them. In the notebook viewer (no server), each scene keeps its own recording.
"""

from __future__ import annotations

import asyncio
import base64
import re
import urllib.error
import urllib.request

import numpy as np
import pytest

from tests.test_scene3d import _frames  # the notebook viewer's recorded frames
from tutor.errors import InvalidParameterError
from tutor.views.meshcat_recorder import SceneRecorder
from tutor.views.meshcat_server import get_server, visualizer
from tutor.views.pickplace_app import PickPlaceTutor
from tutor.views.scene3d import Scene3D

#: the plant each of the three runs demonstrates
PLANTS = (12, 47, 83)


def _page_commands(text: str) -> list[dict]:
    """The commands in meshcat's self-contained page of a server's scene tree."""
    import umsgpack

    blobs = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", text)
    return [umsgpack.unpackb(base64.b64decode(b)) for b in blobs]


def _served(scene: Scene3D) -> list[dict]:
    """What the live server holds for ``scene``: its tree as meshcat's page of it."""
    socket = scene.recorder.live.zmq_socket
    socket.send_multipart([b"get_scene", scene.scene_id.encode()])
    return _page_commands(socket.recv().decode())


def _demo_trail(commands: list[dict]) -> np.ndarray:
    """The points (n, 3) of demo 1's trail among ``commands``."""
    (trail,) = [
        c
        for c in commands
        if c["type"] == "set_object" and c["path"] == "/meshcat/lfd/trails/demos/0"
    ]
    data = trail["object"]["geometries"][0]["data"]["attributes"]["position"]["array"]
    data = getattr(data, "data", data)  # a msgpack extension holding the float32 bytes
    return np.frombuffer(data, dtype=np.float32).reshape(-1, 3)


def _animation(commands: list[dict]) -> dict | None:
    anims = [c for c in commands if c["type"] == "set_animation" and c["animations"]]
    return anims[-1] if anims else None


def _near(points: np.ndarray, task, plant: int) -> float:
    """How close (m, horizontally) a trail comes to ``plant``."""
    xy = task.scene.plant_positions[plant, :2]
    return float(np.min(np.linalg.norm(points[:, :2] - xy, axis=1)))


def _recorded(scene: Scene3D) -> list[dict]:
    """What ``scene`` recorded (the notebook viewer and the static page are built from it)."""
    import umsgpack

    return [umsgpack.unpackb(packed) for _, _, packed in scene.recorder.commands()]


def test_three_live_scenes_have_their_own_address_and_tree(pickplace_task):
    scenes = [Scene3D(pickplace_task, mode="live", robot=False) for _ in range(3)]
    assert all(s.mode == "live" for s in scenes)
    ids = {s.scene_id for s in scenes}
    assert len(ids) == 3
    web = get_server().web_url
    pages = [web.replace("/static/", f"/lfd/{s.scene_id}/") for s in scenes]
    for s, page in zip(scenes, pages, strict=True):
        assert s.widget.children[1].src == page  # the live frame's address
        with urllib.request.urlopen(page, timeout=10) as reply:
            assert b"lfd-ws" in reply.read()
    tutors = [
        PickPlaceTutor("RF", task=pickplace_task, scene3d=s, seed=k, run=k + 1)
        for k, s in enumerate(scenes)
    ]
    held = []
    for tutor, plant in zip(tutors, PLANTS, strict=True):
        tutor.demonstrate(plant)
        held.append(_served(tutor.scene3d))
    # what each scene holds now is what it held right after its own demo: the later runs
    # changed nothing of it
    for k, s in enumerate(scenes):
        assert _served(s) == held[k], f"run {k + 1}'s scene changed after a later run"
    # each holds its own demo (to its own plant) and its own animation
    trails = [_demo_trail(h) for h in held]
    anims = [_animation(h) for h in held]
    for k, plant in enumerate(PLANTS):
        mine = _near(trails[k], pickplace_task, plant)
        others = [_near(trails[k], pickplace_task, p) for p in PLANTS if p != plant]
        assert mine < min(others), (k, mine, others)
        assert anims[k] is not None and anims[k] == _animation(_recorded(scenes[k]))
    assert anims[0] != anims[1] != anims[2] != anims[0]
    # Replay of run 1 after the later runs: its own clip, in its own scene only
    assert scenes[0].replay()
    assert _animation(_served(scenes[0])) == anims[0]
    assert _served(scenes[1]) == held[1] and _served(scenes[2]) == held[2]


def test_a_page_gets_its_own_scene_and_its_changes_only(pickplace_task):
    from tornado.websocket import websocket_connect

    a, b = (Scene3D(pickplace_task, mode="live", robot=False) for _ in range(2))
    port = get_server().port

    async def listen():
        sockets = [
            await websocket_connect(f"ws://127.0.0.1:{port}/lfd-ws/{s.scene_id}") for s in (a, b)
        ]
        counts = []
        for ws in sockets:  # the scene as it is, on connecting
            n = 0
            while (await _next(ws, 2.0)) is not None:
                n += 1
            counts.append(n)
        a.show_robot(False)  # one change to scene a only
        got_a = await _next(sockets[0], 5.0)
        got_b = await _next(sockets[1], 1.0)
        for ws in sockets:
            ws.close()
        return counts, got_a, got_b

    import umsgpack

    counts, got_a, got_b = asyncio.run(listen())
    assert min(counts) >= 20  # the fixtures, the stems and the 100 plants' balls of each
    assert umsgpack.unpackb(got_a)["path"] == "/meshcat/robot"
    assert got_b is None, "a page of another scene received the change"


async def _next(ws, timeout: float):
    try:
        return await asyncio.wait_for(ws.read_message(), timeout)
    except TimeoutError:
        return None


def test_meshcat_own_scene_and_bad_scene_ids(pickplace_task):
    import meshcat.geometry as mg

    scene = Scene3D(pickplace_task, mode="live", robot=False)
    vis = visualizer()  # meshcat's own commands (three frames) go to meshcat's scene
    vis["t20/box"].set_object(mg.Box([0.1, 0.1, 0.1]))
    own_paths = {c.get("path") for c in _page_commands(vis.static_html())}
    assert "/meshcat/t20/box" in own_paths and "/meshcat/lfd/table" not in own_paths
    assert "/meshcat/t20/box" not in {c.get("path") for c in _served(scene)}
    # a command to a scene whose id is not one is refused, and the server goes on
    socket = scene.recorder.live.zmq_socket
    socket.send_multipart([b"delete", b"/meshcat", b"x", b"../etc"])
    assert socket.recv().startswith(b"error")
    served = {c.get("path") for c in _served(scene)}
    assert {"/meshcat/lfd/balls", "/meshcat/lfd/stems", "/meshcat/lfd/table"} <= served
    web = get_server().web_url
    with pytest.raises(urllib.error.HTTPError) as info:
        urllib.request.urlopen(web.replace("/static/", "/lfd/NOT_AN_ID/"), timeout=10)
    assert info.value.code == 404
    for bad in ("", "A" * 3, "a" * 65, 7, "a/b"):
        with pytest.raises(InvalidParameterError, match="scene id"):
            SceneRecorder(scene_id=bad)


def test_three_notebook_viewers_keep_their_own_scene(pickplace_task):
    """The notebook viewer (no server): each run's view gets its own recording, and a
    later run's demo sends nothing to an earlier run's view."""
    scenes = [Scene3D(pickplace_task, mode="static", robot=False) for _ in range(3)]
    sent = []
    for s in scenes:
        view = s.widget.children[1]
        box: list = []

        def send(content, buffers=None, box=box):  # the scene's messages, not the working line
            if content.get("type") != "working":
                box.append((content, buffers))

        view.send = send
        s._on_view_msg(view, {"type": "hello", "id": "v"}, [])
        box.clear()
        sent.append(box)
    tutors = [
        PickPlaceTutor("RF", task=pickplace_task, scene3d=s, seed=k, run=k + 1)
        for k, s in enumerate(scenes)
    ]
    held = []
    for k, (tutor, plant) in enumerate(zip(tutors, PLANTS, strict=True)):
        before = [len(box) for box in sent]
        tutor.demonstrate(plant)
        after = [len(box) for box in sent]
        assert [a - b for a, b in zip(after, before, strict=True)] == [
            int(j == k) for j in range(3)
        ], "a demo sent an update to another run's view"
        held.append(_recorded(scenes[k]))
    for k, s in enumerate(scenes):
        assert _recorded(s) == held[k]
        assert f"plant ({PLANTS[k] // 10 + 1}, {PLANTS[k] % 10 + 1})" in s.animation.label
    # Replay of run 1 sends run 1's own clip to run 1's view only
    counts = [len(box) for box in sent]
    scenes[0].replay_button.click()
    assert [len(box) for box in sent] == [counts[0] + 1, counts[1], counts[2]]
    (replayed,) = _frames(sent[0][-1][1][0])
    assert replayed == _animation(held[0])


def test_both_3d_pages_carry_the_wheel_rule():
    """The wheel's focus rule (scene3d_wheel.js) is in the notebook viewer's page and in
    the live server's page; the browser test checks what it does."""
    from tutor.views.scene_page import live_page, page

    for text in (live_page(), page("t", "", "", "")):
        assert "{{wheel}}" not in text
        assert "Click to zoom with the wheel" in text and "stopPropagation" in text
