"""The 3-D pick-and-place scene (Meshcat): loopback server, static export, animation."""

from __future__ import annotations

import base64
import gzip
import os
import re
import socket
import struct
import subprocess
import sys
import textwrap
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from tutor.errors import InvalidParameterError
from tutor.views import meshcat_server
from tutor.views.meshcat_server import (
    LOOPBACK,
    MeshcatServerError,
    get_server,
    start_server,
    visualizer,
)
from tutor.views.pickplace_app import PickPlaceTutor, tray_status
from tutor.views.scene3d import STATUS_COLOURS, Scene3D, SceneRecorder, choose_mode
from tutor.views.scene_meshes import hex_string

REPO = Path(__file__).resolve().parents[1]


# --------------------------------------------------------------------------- helpers


def _gone(pid: int) -> bool:
    """The process has exited (no such process, or a zombie nobody reaped yet)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return True
    state = re.search(r"^State:\s+(\S)", status, re.M)
    return state is not None and state.group(1) in "ZX"


def _wait_gone(pid: int, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if _gone(pid):
            return True
        time.sleep(0.1)
    return _gone(pid)


def _listening(pid: int) -> list[tuple[str, int]]:
    """(address, port) of every listening TCP socket of ``pid`` (from /proc)."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    out = []
    for table, family in (("tcp", socket.AF_INET), ("tcp6", socket.AF_INET6)):
        path = Path(f"/proc/{pid}/net/{table}")
        if not path.exists():
            continue
        for line in path.read_text().splitlines()[1:]:
            fields = line.split()
            local, state, inode = fields[1], fields[3], fields[9]
            if state != "0A" or inode not in inodes:  # 0A = LISTEN
                continue
            hex_addr, hex_port = local.split(":")
            raw = bytes.fromhex(hex_addr)
            # /proc prints the address as 32-bit words in host (little-endian) order
            raw = b"".join(raw[i : i + 4][::-1] for i in range(0, len(raw), 4))
            out.append((socket.inet_ntop(family, raw), int(hex_port, 16)))
    return out


def _non_loopback_addresses() -> set[str]:
    """IPv4 addresses of this machine other than 127.x (may be empty)."""
    found = set()
    try:
        out = subprocess.run(["hostname", "-I"], capture_output=True, text=True, timeout=5)
        found.update(a for a in out.stdout.split() if "." in a)
    except (OSError, subprocess.SubprocessError):
        pass
    try:
        found.update(
            info[4][0] for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET)
        )
    except OSError:
        pass
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:  # no packet is sent: this only asks the kernel for the outgoing address
            s.connect(("192.0.2.1", 9))
            found.add(s.getsockname()[0])
        except OSError:
            pass
    return {a for a in found if not a.startswith("127.") and a != "0.0.0.0"}


def _scene_commands(html_text: str) -> list[dict]:
    """Decode the commands packed into a static page."""
    import umsgpack

    out = []
    chunks = re.findall(r'class="scene-data">([^<]*)</script>', html_text)
    for chunk in chunks:
        raw = gzip.decompress(base64.b64decode(chunk))
        i = 0
        while i < len(raw):
            (n,) = struct.unpack(">I", raw[i : i + 4])
            out.append(umsgpack.unpackb(raw[i + 4 : i + 4 + n]))
            i += 4 + n
    return out


def _instance_colours(obj: dict) -> np.ndarray:
    """An instanced mesh's colours (count, 3) as sent (a Float32Array's bytes)."""
    assert obj["type"] == "InstancedMesh" and obj["frustumCulled"] is False
    rgb = np.frombuffer(obj["instanceColor"]["array"].data, dtype=np.float32).reshape(-1, 3)
    assert len(rgb) == obj["count"] and obj["instanceColor"]["itemSize"] == 3
    return rgb


# --------------------------------------------------------------------------- the server


def test_server_listens_on_loopback_only():
    server = get_server()
    assert server.alive()
    with urllib.request.urlopen(server.web_url, timeout=10) as r:
        assert r.status == 200 and b"meshcat" in r.read().lower()
    assert server.web_url.startswith(f"http://{LOOPBACK}:")
    assert server.zmq_url.startswith(f"tcp://{LOOPBACK}:")
    # Every listening socket of the server process is bound to 127.0.0.1.
    sockets = _listening(server.pid)
    ports = {port for _, port in sockets}
    assert server.port in ports and int(server.zmq_url.rsplit(":", 1)[1]) in ports
    assert {addr for addr, _ in sockets} == {LOOPBACK}, sockets
    # ... and the machine's other addresses do not reach it.
    for addr in _non_loopback_addresses():
        for port in ports:
            with socket.socket() as s:
                s.settimeout(2)
                with pytest.raises(OSError):
                    s.connect((addr, port))


def test_server_is_reused_and_restarted():
    a = get_server()
    assert get_server() is a
    vis = visualizer()
    assert vis.window.web_url == a.web_url
    a.stop()
    b = get_server()  # a dead server is replaced
    assert b is not a and b.alive() and _wait_gone(a.pid, 5)
    with pytest.raises(InvalidParameterError):
        meshcat_server._loopback_url("tcp://0.0.0.0:6000")


CHILD = textwrap.dedent(
    """
    import sys, time
    from tutor.views.meshcat_server import get_server
    s = get_server()
    print(s.pid, flush=True)
    if sys.argv[1] == "wait":
        time.sleep(120)
    """
)


@pytest.mark.parametrize("how", ["kill -9", "normal exit"])
def test_server_dies_with_its_parent(how):
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, "wait" if how == "kill -9" else "exit"],
        stdout=subprocess.PIPE,
        text=True,
        cwd=REPO,
    )
    try:
        pid = int(child.stdout.readline())
        if how == "kill -9":
            assert not _gone(pid)
            child.kill()  # SIGKILL: no atexit hook runs in the child
        child.wait(30)
        assert _wait_gone(pid, 5), f"the Meshcat server {pid} outlived its parent ({how})"
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


def test_server_that_cannot_start_is_a_named_error():
    busy = get_server().port
    with pytest.raises(MeshcatServerError, match="exited with code") as info:
        start_server(port=busy)
    assert "in use" in str(info.value)  # the server's own message is passed on


def test_dead_live_viewer_falls_back():
    server = start_server()
    vis = visualizer(server, timeout=1.0)
    rec = SceneRecorder(vis.window)
    import meshcat
    import meshcat.geometry as mg

    scene = meshcat.Visualizer(window=rec)
    scene["box"].set_object(mg.Box([0.1, 0.1, 0.1]))
    assert rec.live is not None and not rec.live_error  # the live viewer took the first box
    server.stop()
    scene["box2"].set_object(mg.Box([0.1, 0.1, 0.1]))
    assert rec.live is None and "stopped answering" in rec.live_error
    assert [c[1] for c in rec.commands()] == ["/meshcat/box", "/meshcat/box2"]
    # meshcat's own static export works from the recording, without a server
    page = scene.static_html()
    assert [c["path"] for c in _scene_commands(page)] == ["/meshcat/box", "/meshcat/box2"]


# --------------------------------------------------------------------------- the scene


def test_headless_scene_is_static_without_a_server(pickplace_task, monkeypatch, tmp_path):
    monkeypatch.setenv("TUTOR_HEADLESS", "1")

    def no_server(*args, **kwargs):
        raise AssertionError("a headless Scene3D must not start a server")

    monkeypatch.setattr(meshcat_server, "get_server", no_server)
    scene = Scene3D(pickplace_task)
    assert scene.mode == "static" and scene.recorder.live is None
    path = scene.save_html(tmp_path / "scene.html")
    text = path.read_text()
    # the arm's 21k triangles compressed (its 135k as COLLADA text were 5 MB; meshcat's
    # own export was ~15 MB)
    assert 0.5e6 < len(text) < 4e6
    assert "MeshCat.Viewer" in text and "<iframe" not in text
    commands = _scene_commands(text)
    paths = {c.get("path") for c in commands}
    assert "/meshcat/robot/visuals/panda_link0_0/mesh" in paths  # one mesh a link
    # the 100 balls are one instanced mesh (one draw call)
    assert "/meshcat/lfd/balls" in paths and not any("/plants/" in p for p in paths)
    # the 100 stems are one mesh (one draw call), not 100
    assert "/meshcat/lfd/stems" in paths and not any(p.endswith("/stem") for p in paths)
    view = scene.widget.children[1]
    assert "MeshCat.Viewer" in view.page and 'scene-data">' not in view.page  # no scene in it


def test_mode_is_static_where_the_browser_cannot_reach_loopback(monkeypatch):
    for var in ("TUTOR_HEADLESS", "JUPYTERHUB_SERVICE_PREFIX", "BINDER_SERVICE_HOST"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.delenv("VOILA_REQUEST_URL", raising=False)
    assert choose_mode() == "live" and choose_mode("static") == "static"
    monkeypatch.setenv("VOILA_REQUEST_URL", "http://localhost:8866/")
    assert choose_mode() == "live"
    monkeypatch.setenv("VOILA_REQUEST_URL", "http://192.0.2.7:8866/voila/render/03.ipynb")
    assert choose_mode() == "static"
    monkeypatch.delenv("VOILA_REQUEST_URL")
    monkeypatch.setenv("JUPYTERHUB_SERVICE_PREFIX", "/user/ada/")
    assert choose_mode() == "static" and choose_mode("live") == "live"
    monkeypatch.delenv("JUPYTERHUB_SERVICE_PREFIX")
    monkeypatch.setenv("TUTOR_HEADLESS", "1")
    assert choose_mode() == "static"


def test_bad_input_is_named(pickplace_task):
    scene = Scene3D(pickplace_task, mode="static", robot=False)
    with pytest.raises(InvalidParameterError, match="entries"):
        scene.set_status(["pass"] * 3)
    with pytest.raises(InvalidParameterError, match="unknown plant status"):
        scene.set_status(["great"] * 100)
    with pytest.raises(InvalidParameterError, match="finite"):
        scene.animate(np.full((10, 4), np.nan))
    with pytest.raises(InvalidParameterError, match="shape"):
        scene.animate(np.zeros((10, 2)))
    with pytest.raises(InvalidParameterError, match="mode"):
        Scene3D(pickplace_task, mode="web")
    with pytest.raises(InvalidParameterError, match="seconds"):
        Scene3D(pickplace_task, mode="static", seconds=0)


def _track(clip, name):
    """A packed track's key times (k,) and values (k, n), decoded from Float32Arrays."""
    (t,) = [t for t in clip["tracks"] if t["name"] == name]
    times = np.frombuffer(t["times"].data, dtype="<f4") / clip["fps"]
    values = np.frombuffer(t["values"].data, dtype="<f4").reshape(len(times), -1)
    return times, values, t["interpolation"]


def test_one_realisation_animates_smoothly(pickplace_task):
    tutor = PickPlaceTutor("RF", task=pickplace_task, seed=4)
    tutor.demonstrate(44)
    run = tutor.run
    path = run.session.realisations[44][:, -4:]
    scene = Scene3D(pickplace_task, mode="static")
    info = scene.animate(path, "test")
    assert info.frames == 200 and 20 <= info.fps <= 30 and 8 <= info.duration <= 12
    assert 40 <= info.keys <= 60  # 5 keys a second, not every sample
    (anim,) = [c for c in _scene_commands(scene.static_html()) if c["type"] == "set_animation"]
    assert anim["options"] == {"play": True, "repetitions": 1}  # plays once by itself
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    links = [p for p in clips if "/robot/visuals/" in p]
    assert len(links) == 10 and not any("link0" in p for p in links)  # the base never moves
    times, xyz, interpolation = _track(clips["/meshcat/lfd/hand"], ".position")
    assert len(times) == info.keys and interpolation == 2301  # linear between keys
    assert times[0] == 0 and times[-1] == pytest.approx(info.duration, abs=1e-5)
    keys = np.round(times * info.fps).astype(int)
    assert np.allclose(times * info.fps, keys, atol=1e-3)  # keys sit on samples
    assert np.abs(xyz - path[keys, :3]).max() < 0.01  # the hand follows the path
    # linear interpolation between the keys stays within 1 cm of every sample
    between = np.column_stack(
        [np.interp(np.arange(len(path)) / info.fps, times, xyz[:, j]) for j in range(3)]
    )
    assert np.abs(between - path[:, :3]).max() < 0.01
    # every link's rotation track is unit quaternions without sign flips from key to key
    for link in links:
        _, q, _ = _track(clips[link], ".quaternion")
        assert np.allclose(np.linalg.norm(q, axis=1), 1, atol=1e-5)
        assert np.all(np.sum(q[1:] * q[:-1], axis=1) > 0)
    # the "closed" marker is shown exactly while the hand is closed: one key per switch
    times, scale, interpolation = _track(clips["/meshcat/lfd/hand/closed"], ".scale")
    assert interpolation == 2300  # discrete: it switches, it does not grow
    closed = path[:, 3] >= 0.5
    switches = np.flatnonzero(np.diff(closed)) + 1
    assert len(times) == 1 + len(switches)
    assert np.allclose(times[1:] * info.fps, switches)
    shown = scale[:, 0] > 0.5
    assert shown[0] == closed[0] and np.array_equal(shown[1:], closed[switches])


def test_replay_sends_the_same_animation_again(pickplace_task):
    scene = Scene3D(pickplace_task, mode="static", robot=False)
    assert scene.replay() is False  # nothing animated yet
    sent = _open_view(scene)
    tutor = PickPlaceTutor("RF", task=pickplace_task, scene3d=scene, seed=2)
    tutor.demonstrate(30)
    *_, first = [c for _, b in sent for c in _frames(b[0]) if c["type"] == "set_animation"]
    assert first["animations"]
    assert not scene.replay_button.disabled
    sent.clear()
    scene.replay_button.click()
    ((content, buffers),) = sent
    assert content == {"type": "update"}
    assert _frames(buffers[0]) == [first]  # only the animation, played again


def test_unchanged_trails_are_not_sent_again(pickplace_task):
    scene = Scene3D(pickplace_task, mode="static", robot=False)
    tutor = PickPlaceTutor("NF", task=pickplace_task, scene3d=scene, seed=3)
    tutor.demonstrate(10)
    sent = _open_view(scene)
    tutor.demonstrate(60)
    (_, buffers), *_ = sent
    trails = {c["path"] for c in _frames(buffers[0]) if "/trails/" in c["path"]}
    # the new demo's trail and the animated one; demo 1's trail stays as it was
    assert trails == {"/meshcat/lfd/trails/demos/1", "/meshcat/lfd/trails/animated/0"}


def test_tutor_updates_the_scene(pickplace_task):
    scene = Scene3D(pickplace_task, mode="static", robot=False)
    tutor = PickPlaceTutor("RF", task=pickplace_task, scene3d=scene, seed=5)
    assert scene.animation is None
    tutor.demonstrate(12)
    status = tray_status(tutor.run)
    assert "plant (2, 3)" in scene.animation.label  # the replay of the demonstrated plant
    (balls,) = [
        c["object"]["object"]
        for c in _scene_commands(scene.static_html())
        if c["type"] == "set_object" and c["path"] == "/meshcat/lfd/balls"
    ]
    rgb = _instance_colours(balls)
    for i in (12, 0, 99):
        assert hex_string(np.round(rgb[i] * 255)) == STATUS_COLOURS[status[i]]
    # selecting another plant changes nothing in 3-D (no replay, nothing sent)
    sent = _open_view(scene)
    tutor.select(3)
    assert sent == []
    nf = PickPlaceTutor(
        "NF", task=pickplace_task, scene3d=Scene3D(pickplace_task, mode="static", robot=False)
    )
    nf.demonstrate(7)
    assert nf.scene3d.animation.label.startswith("Your demonstration 1")
    assert "Animated" in nf.scene3d._caption.value


def test_sf_scene_animates_the_plant_just_tested(pickplace_task):
    scene = Scene3D(pickplace_task, mode="static", robot=False)
    tutor = PickPlaceTutor("SF", task=pickplace_task, scene3d=scene, seed=6)
    tutor.demonstrate(12)
    tutor.test([87])
    assert "plant (9, 8)" in scene.animation.label  # the test, not the demonstration
    tutor.demonstrate(40)  # a new demo: the old test no longer counts
    assert "plant (9, 8)" not in scene.animation.label


def test_recorder_keeps_the_tree_as_the_server_does():
    import meshcat
    import meshcat.animation as ma
    import meshcat.geometry as mg

    rec = SceneRecorder()
    vis = meshcat.Visualizer(window=rec)
    vis["a/b"].set_object(mg.Box([1, 1, 1]))
    vis["a/b"].set_property("visible", False)
    vis["a/b"].set_object(mg.Sphere(1.0))  # a new object drops the old one's properties
    vis["a"].set_transform(np.eye(4))
    vis["c"].set_object(mg.Box([1, 1, 1]))
    anim = ma.Animation()
    with anim.at_frame(vis, 0) as frame:
        frame["c"].set_transform(np.eye(4))
    vis.set_animation(anim)
    kinds = [(k, p) for k, p, _ in rec.commands()]
    assert kinds == [
        ("set_transform", "/meshcat/a"),
        ("set_object", "/meshcat/a/b"),
        ("set_object", "/meshcat/c"),
        ("set_animation", ""),  # animations last: they need the objects
    ]
    vis["a"].delete()
    assert [p for _, p, _ in rec.commands()] == ["/meshcat/c", ""]
    from tutor.views.meshcat_recorder import empty_animation

    rec.send_packed("set_animation", "", empty_animation())
    assert [p for _, p, _ in rec.commands()] == ["/meshcat/c"]


def test_page_is_filled_from_the_static_files_in_one_pass():
    from tutor.views.scene_page import page, static_text

    for name in ("scene3d_page.html", "scene3d_page.js", "scene3d_view.js"):
        assert static_text(name).strip(), name  # packaged beside sketchpad.js
    template = static_text("scene3d_page.html")
    assert {"{{title}}", "{{overlay}}", "{{data}}", "{{viewer}}", "{{script}}"} <= set(
        re.findall(r"\{\{\w+\}\}", template)
    )
    text = page("a <b> & c", "<p>{{title}}</p>", "", "")
    assert "<title>a &lt;b&gt; &amp; c</title>" in text
    assert "<p>{{title}}</p>" in text  # the scene data is not searched for slots
    assert "MeshCat.Viewer" in text and "window.lfdApply = lfdApply" in text
    assert 'id="lfd-legend"' not in text  # no legend, no caption: no overlay
    assert text.count("{{") == 1


def _open_view(scene) -> list:
    """Pretend a browser opened the notebook viewer; returns the list of messages sent."""
    sent = []
    view = scene.widget.children[1]

    def send(content, buffers=None):  # the "working" line is not part of the scene
        if content.get("type") != "working":
            sent.append((content, buffers))

    view.send = send
    scene._on_view_msg(view, {"type": "hello", "id": "v1"}, [])
    assert sent[0][0] == {"type": "full", "to": "v1"}
    sent.clear()
    return sent


def _frames(gz: bytes) -> list[dict]:
    import umsgpack

    raw, out, i = gzip.decompress(gz), [], 0
    while i < len(raw):
        (n,) = struct.unpack(">I", raw[i : i + 4])
        out.append(umsgpack.unpackb(raw[i + 4 : i + 4 + n]))
        i += 4 + n
    return out


def test_notebook_viewer_gets_the_scene_once_then_changes(pickplace_task):
    scene = Scene3D(pickplace_task, mode="static")
    view = scene.widget.children[1]
    sent = []

    def send(content, buffers=None):  # the "working" line is not part of the scene
        if content.get("type") != "working":
            sent.append((content, buffers))

    view.send = send
    scene._on_view_msg(view, {"type": "hello", "id": "a"}, [])
    (full, buffers) = sent.pop()
    assert full == {"type": "full", "to": "a"} and len(buffers) == 2
    assert len(buffers[0]) > 2e5  # the Panda's meshes (decimated), once per opened view
    paths = {c["path"] for b in buffers for c in _frames(b)}
    assert "/meshcat/robot/visuals/panda_hand_0" in paths and "/meshcat/lfd/bin" in paths
    status = np.full(100, "unknown", dtype=object)
    status[[3, 4]] = "pass"
    scene.set_status(status)
    scene.refresh()
    (update, buffers) = sent.pop()
    assert update == {"type": "update"} and len(buffers) == 1 and len(buffers[0]) < 12_000
    changed = [c for c in _frames(buffers[0]) if c["type"] == "set_object"]
    assert [c["path"] for c in changed] == ["/meshcat/lfd/balls"]  # one object, all colours
    rgb = _instance_colours(changed[0]["object"]["object"])
    assert [hex_string(np.round(c * 255)) for c in rgb[[3, 4, 5]]] == [
        STATUS_COLOURS["pass"], STATUS_COLOURS["pass"], STATUS_COLOURS["unknown"]
    ]
    scene.refresh()
    assert sent == []  # nothing new, nothing sent


def test_live_scene_streams_to_the_loopback_server(pickplace_task):
    scene = Scene3D(pickplace_task, mode="live", robot=False)
    assert scene.mode == "live"
    url = scene.recorder.web_url
    assert url == get_server().web_url and url.startswith(f"http://{LOOPBACK}:")
    # the tutor's page of this scene: meshcat's, with the stamp
    page = url.replace("/static/", f"/lfd/{scene.scene_id}/")
    assert scene.widget.children[1].src == page
    with urllib.request.urlopen(page, timeout=10) as reply:
        assert b"lfd-stamp" in reply.read()
    # the server's own snapshot of this scene's tree
    socket = scene.recorder.live.zmq_socket
    socket.send_multipart([b"get_scene", scene.scene_id.encode()])
    served = socket.recv().decode()
    paths = {c.get("path") for c in _server_commands(served)}
    assert "/meshcat/lfd/balls" in paths and "/meshcat/lfd/table" in paths


def _server_commands(html_text: str) -> list[dict]:
    import umsgpack

    blobs = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html_text)
    return [umsgpack.unpackb(base64.b64decode(b)) for b in blobs]


# --------------------------------------------------------------------------- in a browser


def _render(html_path: Path, png: Path, page) -> np.ndarray:
    from PIL import Image

    page.goto(html_path.as_uri())
    page.wait_for_function("document.body.dataset.ready", timeout=90_000)
    assert page.evaluate("document.body.dataset.ready") == "1"
    page.evaluate("() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
    time.sleep(0.5)
    page.screenshot(path=str(png))
    return np.asarray(Image.open(png).convert("RGB")).astype(int)


@pytest.mark.browser
def test_static_export_shows_the_robot_in_chromium(pickplace_task, tmp_path):
    from playwright.sync_api import sync_playwright

    from tests.browser.conftest import ARTIFACTS, CHROMIUM, CHROMIUM_FLAGS

    if not Path(CHROMIUM).exists():
        pytest.fail("Debian's chromium is missing: scripts/test.sh installs it")
    ARTIFACTS.mkdir(exist_ok=True)
    with_robot = Scene3D(pickplace_task, mode="static")
    without = Scene3D(pickplace_task, mode="static", robot=False)
    status = np.full(100, "unknown", dtype=object)
    status[:50] = "pass"
    for s in (with_robot, without):
        s.set_status(status)
    files = {
        "robot": with_robot.save_html(tmp_path / "robot.html"),
        "none": without.save_html(tmp_path / "none.html"),
    }
    with sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            str(tmp_path / "profile"),  # a fresh user-data-dir
            executable_path=CHROMIUM,
            args=CHROMIUM_FLAGS,
            headless=True,
            viewport={"width": 900, "height": 650},
        )
        try:
            page = context.new_page()
            img = {k: _render(f, ARTIFACTS / f"scene3d_{k}.png", page) for k, f in files.items()}
        finally:
            context.close()
    a, b = img["robot"], img["none"]
    h, w, _ = a.shape
    changed = np.abs(a - b).sum(axis=2) > 60
    ys, xs = np.nonzero(changed)
    # The Panda covers a good part of the picture, where the camera sees it: left of
    # centre and above the table (the tray and bin are lower right).
    assert changed.mean() > 0.03, f"only {changed.mean():.2%} of the pixels show the robot"
    assert w * 0.2 < xs.mean() < w * 0.6 and ys.mean() < h * 0.55
    # ... and it is the Panda's white and dark grey, not the blue background or the table.
    robot_pixels = a[changed]
    grey = (robot_pixels.max(axis=1) - robot_pixels.min(axis=1)) < 40
    assert grey.mean() > 0.8
    # The plants are coloured by status: many green (succeeds) pixels in both pictures.
    green = np.array([int(STATUS_COLOURS["pass"][i : i + 2], 16) for i in (1, 3, 5)])
    for im in (a, b):
        near = np.abs(im - green).sum(axis=2) < 90
        assert near.sum() > 200


def test_the_arm_is_example_robot_datas_meshes_with_fewer_triangles():
    """Each visual geometry of the Panda is drawn from its own COLLADA file: every part
    coloured, about ROBOT_KEEP of the triangles, the same extent as Pinocchio's (coal's)
    copy of the mesh, unit normals; and the recorded commands are one object per part."""
    from tutor.robot import load_robot
    from tutor.views.scene_meshes import ROBOT_KEEP, robot_meshes, robot_parts

    robot = load_robot("panda")
    kept = whole = 0
    for geom in robot.visual_model.geometryObjects:
        parts = robot_parts(geom.meshPath, geom.meshScale)
        assert parts
        V_all = np.concatenate([V for V, _, _, _ in parts])
        reference = np.asarray(geom.geometry.vertices())
        np.testing.assert_allclose(V_all.min(0), reference.min(0), atol=4e-3)
        np.testing.assert_allclose(V_all.max(0), reference.max(0), atol=4e-3)
        for V, F, N, colour in parts:
            assert re.fullmatch(r"#[0-9a-f]{6}", colour)
            assert F.min() >= 0 and F.max() < len(V) and N.shape == V.shape
            np.testing.assert_allclose(np.linalg.norm(N, axis=1), 1.0, atol=1e-3)
            kept += len(F)
        whole += geom.geometry.num_tris
    assert whole > 100_000 and kept < 2 * ROBOT_KEEP * whole
    meshes = robot_meshes("panda")
    paths = {c[1] for c in meshes.commands}
    assert all(any(p.startswith(f"/meshcat/{n}/") for p in paths) for n in meshes.node_names)


def test_the_3d_view_shows_what_the_tray_shows(pickplace_task):
    """One rule decides what a trainee may see (the run's visibility): a practice run's
    3-D view, like its tray, shows every plant's attempt after a demo; a counted BF run's
    only the batch, until it is finished."""
    from tutor.tasks.pickplace_protocol import PickPlaceRun
    from tutor.views.pickplace_app import tray_status

    for practice, counted in ((True, 100), (False, 5)):
        run = PickPlaceRun("BF", pickplace_task, practice=practice)
        run.demonstrate(44, rng=np.random.default_rng(0))
        scene = Scene3D(pickplace_task, mode="static")
        scene.update(run, tray_status(run))
        drawn = len(scene._trails.get("passed", [])) + len(scene._trails.get("failed", []))
        seen = int(np.isin(tray_status(run), ["pass", "fail"]).sum())
        assert drawn == counted and seen >= counted - 1, (practice, drawn, seen)
        run.finish()
        scene.update(run, tray_status(run))
        drawn = len(scene._trails.get("passed", [])) + len(scene._trails.get("failed", []))
        assert drawn == 100


def test_the_stems_are_one_mesh_standing_on_each_plant(pickplace_task):
    from tutor.views.scene_meshes import PLANT_STEM_SEGMENTS, stem_mesh

    sc = pickplace_task.scene
    V, F, N = stem_mesh(sc)
    k = len(sc.plant_positions)
    assert V.shape == N.shape and V.shape[1] == 3 and F.shape[1] == 3
    assert F.max() == len(V) - 1 and F.min() == 0
    per = len(V) // k  # each stem's vertices, in plant order
    stems = V.reshape(k, per, 3)
    bases = np.asarray(sc.plant_positions, dtype=float)[:, :2]
    # every vertex within the stem's radius of its own plant, from the tray to the plant top
    off = np.linalg.norm(stems[..., :2] - bases[:, None], axis=2)
    assert off.max() <= 0.5 * sc.plant_radius + 1e-6
    assert np.allclose(stems[..., 2].min(axis=1), sc.tray_top, atol=1e-6)
    assert np.allclose(stems[..., 2].max(axis=1), sc.tray_top + sc.plant_height, atol=1e-6)
    # a closed 8-sided cylinder per plant: its sides and two caps, lit by unit normals
    assert len(F) == k * 4 * PLANT_STEM_SEGMENTS
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0, atol=1e-5)


def test_each_robot_link_is_one_mesh_with_its_parts_colours():
    from tutor.views.scene_meshes import merged_parts

    a = (np.zeros((3, 3), np.float32), np.array([[0, 1, 2]]), np.ones((3, 3)), "#ff0000")
    b = (np.ones((4, 3), np.float32), np.array([[0, 1, 2], [1, 2, 3]]), np.ones((4, 3)), "#0080ff")
    V, F, N, C = merged_parts([a, b])
    assert V.shape == (7, 3) and N.shape == (7, 3) and C.shape == (7, 3)
    assert F.tolist() == [[0, 1, 2], [3, 4, 5], [4, 5, 6]]  # the second part's faces moved on
    assert np.allclose(C[:3], [1, 0, 0]) and np.allclose(C[3:], [0, 128 / 255, 1])


def test_the_balls_are_one_instanced_mesh_on_top_of_each_stem(pickplace_task):
    from tutor.views.scene_meshes import plant_balls

    sc = pickplace_task.scene
    k = len(sc.plant_positions)
    colours = ["#ff0000"] * k
    colours[7] = "#0080ff"
    data = plant_balls(sc, colours).lower()
    obj = data["object"]
    assert obj["type"] == "InstancedMesh" and obj["count"] == k
    assert data["materials"][0]["color"] == 0xFFFFFF  # the instance's colour is the ball's
    rgb = _instance_colours(obj)
    assert np.allclose(rgb[7], [0, 128 / 255, 1]) and np.allclose(np.delete(rgb, 7, 0), [1, 0, 0])
    # three.js reads each instance's matrix column-major: a translation, nothing else
    M = np.frombuffer(obj["instanceMatrix"]["array"].data, dtype=np.float32).reshape(k, 4, 4)
    M = M.transpose(0, 2, 1)  # row-major, as numpy writes a matrix
    assert np.allclose(M[:, :3, :3], np.eye(3))
    tops = np.column_stack([
        np.asarray(sc.plant_positions, dtype=float)[:, :2],
        np.full(k, sc.tray_top + sc.plant_height),
    ])
    assert np.allclose(M[:, :3, 3], tops, atol=1e-6)
    with pytest.raises(InvalidParameterError, match="colours must have 100 entries, got 99"):
        plant_balls(sc, colours[:-1])


def test_a_corner_whose_faces_cancel_still_gets_a_unit_normal():
    import trimesh

    from tutor.views.scene_meshes import _unit_normals

    # a square (two faces) and, on its corner 0, a sliver folded back on itself: corner 4's
    # two faces face opposite ways, so their mean normal is zero
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1]], float)
    F = np.array([[0, 1, 2], [0, 2, 3], [4, 0, 5], [4, 5, 0]])
    mesh = trimesh.Trimesh(V, F, process=False)
    assert np.linalg.norm(mesh.vertex_normals[4]) < 0.5
    N = _unit_normals(mesh)
    np.testing.assert_allclose(np.linalg.norm(N, axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(N[:4], mesh.vertex_normals[:4], atol=1e-6)  # the rest as they were
