"""A Meshcat server for the tutor: loopback only, one per kernel, gone when the kernel is.

meshcat-python 0.3.2 (the newest release) starts its server with tornado's
``listen(port)`` and no address, so the viewer is served on *every* interface
(0.0.0.0:7000): anyone in a workshop room could open a trainee's scene. Its server is
also stopped only by an ``atexit`` hook, so a kernel killed by a signal leaves it
running. This module fixes both without patching meshcat:

- :class:`LoopbackBridge` subclasses ``meshcat.servers.zmqserver.ZMQWebSocketBridge``
  so that its web server binds 127.0.0.1 and its ZeroMQ socket ``tcp://127.0.0.1``.
  Besides meshcat's page (``/static/``) it serves the tutor's (``static/scene3d_live.html``):
  the same viewer, which also records when each update of the tutor was applied (the
  browser tests read it). Its websocket sends each command at once (TCP_NODELAY;
  tornado's default delayed small ones by ~200 ms).
- One server holds many scenes. meshcat's server has one scene tree, shown by every
  page that connects, so the three runs of a notebook drew over each other. Each
  :class:`~tutor.views.scene3d.Scene3D` names its own scene (an id, see
  :data:`~tutor.views.scene_page.SCENE_ID`): its commands carry the id as a fourth
  ZeroMQ frame, and its page ``/lfd/<id>/`` connects to the websocket
  ``/lfd-ws/<id>``, which sends that scene's tree and its changes only. Commands of
  three frames (meshcat's own) go to meshcat's scene, shown at ``/static/``. Large
  objects equal in two scenes (the robot's meshes, ~10 MB) are held once.
- ``python -m tutor.views.meshcat_server --parent-pid PID`` runs it and prints
  ``zmq_url=...`` and ``web_url=...`` like meshcat does. A tornado ``PeriodicCallback``
  checks twice a second that the parent process (the kernel) still lives and stops
  the server when it does not (this also covers ``kill -9`` of the kernel).
- :func:`get_server` starts that process once per kernel process and hands the same
  :class:`MeshcatServer` to every caller (a module-level singleton); an ``atexit`` hook
  stops it when the kernel exits normally. :func:`visualizer` returns a
  ``meshcat.Visualizer`` connected to it.

Nothing listens beyond the loopback interface, so the live viewer works only in a
browser on the same machine as the kernel; :mod:`tutor.views.scene3d` falls back to a
self-contained HTML export elsewhere (Binder, JupyterHub, Voila served remotely, CI).
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import importlib.util
import io
import os
import queue
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import urlparse

from ..errors import InvalidParameterError, TutorError
from .scene_page import LIVE_PAGE, LIVE_SOCKET, SCENE_ID

__all__ = [
    "LOOPBACK",
    "MeshcatServer",
    "MeshcatServerError",
    "get_server",
    "start_server",
    "stop_server",
    "visualizer",
]

#: The only address the tutor's Meshcat server binds.
LOOPBACK = "127.0.0.1"
#: How often (s) the server checks that its parent process is alive.
PARENT_POLL_SECONDS = 0.5
#: meshcat's scene commands (a fourth frame names the tutor's scene they go to)
_SCENE_COMMANDS = ("set_transform", "set_object", "delete", "set_property", "set_animation")
#: Objects at least this large (bytes) that two scenes hold alike are kept once.
_SHARED_BYTES = 16_384


class MeshcatServerError(TutorError, RuntimeError):
    """The Meshcat server could not be started or does not answer."""


# --------------------------------------------------------------------------- server side


def _loopback_url(url: str) -> str:
    """``url`` if it names 127.0.0.1 (tcp), else a named error."""
    parsed = urlparse(url)
    if parsed.scheme != "tcp" or parsed.hostname != LOOPBACK or parsed.port is None:
        raise InvalidParameterError(
            f"the tutor's Meshcat server binds only tcp://{LOOPBACK}:<port>, got {url!r}"
        )
    return url


def _bridge_class():
    """The loopback bridge class (meshcat and tornado imported only when needed)."""
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class LoopbackBridge(ZMQWebSocketBridge):
        """meshcat's ZMQ/websocket bridge with every socket on 127.0.0.1.

        Parameters
        ----------
        zmq_url : str, optional
            ``tcp://127.0.0.1:<port>``; by default the first free port from 6000.
        port : int, optional
            Web server port; by default the first free port from 7000.
        """

        def __init__(self, zmq_url=None, port=None):
            if zmq_url is not None:
                _loopback_url(zmq_url)
            self.scenes: dict[str, _Scene] = {}  # the tutor's scenes by id
            self._shared: dict[bytes, bytes] = {}  # large objects by digest, held once
            super().__init__(zmq_url=zmq_url, host=LOOPBACK, port=port)

        def scene(self, sid: str) -> _Scene:
            """The tutor's scene ``sid`` (a new, empty one the first time)."""
            if sid not in self.scenes:
                self.scenes[sid] = _Scene()
            return self.scenes[sid]

        def handle_zmq(self, frames):
            # [kind, path, packed, scene id]: a command to one of the tutor's scenes;
            # [get_scene, scene id]: that scene as meshcat's self-contained page
            cmd = frames[0].decode("utf-8", "replace")
            sid = frames[-1].decode("utf-8", "replace") if len(frames) > 1 else ""
            if cmd in _SCENE_COMMANDS and len(frames) == 4 and SCENE_ID.fullmatch(sid):
                self._scene_command(self.scene(sid), cmd, frames[1], frames[2])
                self.zmq_socket.send(b"ok")
            elif cmd == "get_scene" and len(frames) == 2 and SCENE_ID.fullmatch(sid):
                tree, self.tree = self.tree, self.scene(sid).tree
                try:  # meshcat's page of the tree, built by meshcat
                    super().handle_zmq(frames[:1])
                finally:
                    self.tree = tree
            elif cmd in _SCENE_COMMANDS and len(frames) == 4:
                self.zmq_socket.send(b"error: a scene id is 1 to 64 of 0-9 and a-z")
            else:
                super().handle_zmq(frames)

        def _scene_command(self, scene, cmd, path_frame, data) -> None:
            """Apply one command to ``scene`` and send it to the pages showing it, as
            meshcat's server does with its one tree."""
            from meshcat.servers.tree import SceneTree, find_node

            path = [p for p in path_frame.decode("utf-8", "replace").split("/") if p]
            if cmd == "set_object" and len(data) >= _SHARED_BYTES:
                data = self._shared.setdefault(hashlib.blake2b(data).digest(), data)
            node = find_node(scene.tree, path)
            if not (cmd == "set_object" and node.object == data):  # the same object: cached
                for socket in scene.sockets:
                    socket.write_message(data, binary=True)
            if cmd == "set_transform":
                node.transform = data
            elif cmd == "set_object":
                node.object = data
                node.properties = []
            elif cmd == "set_property":
                node.properties.append(data)
            elif cmd == "set_animation":
                node.animation = data
            elif path:  # delete
                parent = find_node(scene.tree, path[:-1])
                parent.pop(path[-1], None)
            else:
                scene.tree = SceneTree()

        def make_app(self):
            import tornado.web
            from meshcat.servers import zmqserver as mz

            # meshcat's two routes, with a websocket that sends each command at once, and
            # the tutor's: a scene's viewer page (meshcat's, plus the "update applied"
            # stamp) and its websocket
            app = tornado.web.Application(
                [
                    (
                        r"/static/(.*)",
                        mz.StaticFileHandlerNoCache,
                        {"path": mz.VIEWER_ROOT, "default_filename": mz.VIEWER_HTML},
                    ),
                    (r"/", _no_delay_websocket(), {"bridge": self}),
                    (f"{LIVE_PAGE}({SCENE_ID.pattern})/", _live_page_handler()),
                    (f"{LIVE_SOCKET}({SCENE_ID.pattern})", _scene_websocket(), {"bridge": self}),
                ]
            )
            listen = app.listen

            def listen_on_loopback(port, address=None, **kwargs):
                # meshcat calls app.listen(port): every interface. Bind loopback only.
                return listen(port, address=LOOPBACK, **kwargs)

            app.listen = listen_on_loopback
            return app

    return LoopbackBridge


def _no_delay_websocket():
    """meshcat's websocket handler with Nagle's algorithm off (TCP_NODELAY).

    Tornado leaves it on, so after a large command (an animation, a trail) each small
    one waited for the browser's delayed acknowledgement: measured here, ~200 ms gaps
    between the commands of one update, 0.5-1 s in all.
    """
    from meshcat.servers.zmqserver import WebSocketHandler

    class NoDelayWebSocket(WebSocketHandler):
        def open(self):
            self.set_nodelay(True)
            super().open()

    return NoDelayWebSocket


class _Scene:
    """One of the tutor's scenes on the server: its tree, as meshcat's server keeps its
    one tree, and the websockets of the pages that show it."""

    def __init__(self):
        from meshcat.servers.tree import SceneTree

        self.tree = SceneTree()
        self.sockets: set = set()

    def blobs(self):
        """The scene as meshcat's server sends it to a page that connects."""
        from meshcat.servers.tree import walk

        for node in walk(self.tree):
            if node.object is not None:
                yield node.object
            yield from node.properties
            if node.transform is not None:
                yield node.transform
            if node.animation is not None:
                yield node.animation


def _scene_websocket():
    """The websocket of one of the tutor's scenes (``/lfd-ws/<id>``): that scene's tree
    when a page connects, then its changes (each sent at once, as above)."""
    base = _no_delay_websocket()

    class SceneWebSocket(base):
        def open(self, sid):
            self.set_nodelay(True)
            self.lfd_scene = self.bridge.scene(sid)
            self.lfd_scene.sockets.add(self)
            for blob in self.lfd_scene.blobs():
                self.write_message(blob, binary=True)

        def on_close(self):
            scene = getattr(self, "lfd_scene", None)
            if scene is not None:
                scene.sockets.discard(self)

    return SceneWebSocket


def _live_page_handler():
    """The tornado handler of the tutor's live viewer page (``static/scene3d_live.html``)."""
    import tornado.web

    from .scene_page import live_page

    class LivePage(tornado.web.RequestHandler):
        def get(self, _sid):  # the page finds its scene id in its own address
            self.set_header("Content-Type", "text/html; charset=utf-8")
            self.set_header("Cache-Control", "no-store")
            self.write(live_page())

    return LivePage


def _parent_alive(pid: int) -> bool:
    if sys.platform == "win32":  # pragma: no cover - not tested here
        # os.kill(pid, 0) would terminate the process on Windows: ask for its exit code
        import ctypes

        kernel32 = ctypes.windll.kernel32
        handle = kernel32.OpenProcess(0x1000, False, pid)  # PROCESS_QUERY_LIMITED_INFORMATION
        if not handle:
            return False
        code = ctypes.c_ulong()
        kernel32.GetExitCodeProcess(handle, ctypes.byref(code))
        kernel32.CloseHandle(handle)
        return code.value == 259  # STILL_ACTIVE
    if os.getppid() != pid:  # re-parented: the parent has died
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - alive, someone else's
        return True
    return True


def main(argv=None) -> int:
    """Run the loopback server until the parent process dies (or SIGTERM)."""
    import argparse
    import signal

    parser = argparse.ArgumentParser(
        description="The tutor's Meshcat server: loopback only, stops when its parent does."
    )
    parser.add_argument("--zmq-url", default=None, help="tcp://127.0.0.1:<port>")
    parser.add_argument("--port", type=int, default=None, help="web server port")
    parser.add_argument(
        "--parent-pid",
        type=int,
        default=None,
        help="stop when this process (default: the parent) is gone",
    )
    args = parser.parse_args(argv)
    parent = os.getppid() if args.parent_pid is None else args.parent_pid
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a cell interrupt must not stop it

    import tornado.ioloop

    bridge = _bridge_class()(zmq_url=args.zmq_url, port=args.port)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    # From here on nobody reads our stdout: send stray prints to stderr instead.
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())

    loop = tornado.ioloop.IOLoop.current()

    def watch_parent():
        if not _parent_alive(parent):
            loop.stop()

    watch_parent()
    tornado.ioloop.PeriodicCallback(watch_parent, PARENT_POLL_SECONDS * 1000).start()
    bridge.run()
    return 0


# --------------------------------------------------------------------------- client side


@dataclass
class MeshcatServer:
    """A running server process started by :func:`start_server`.

    Attributes
    ----------
    process : subprocess.Popen
    zmq_url : str
        ``tcp://127.0.0.1:<port>``, for ``meshcat.Visualizer(zmq_url=...)``.
    web_url : str
        ``http://127.0.0.1:<port>/static/``, the viewer page.
    owner : int
        Process id that started it (a forked child does not reuse it).
    """

    process: subprocess.Popen
    zmq_url: str
    web_url: str
    owner: int = field(default_factory=os.getpid)
    _log: object = field(default=None, repr=False)

    @property
    def pid(self) -> int:
        return self.process.pid

    @property
    def port(self) -> int:
        return int(urlparse(self.web_url).port)

    def alive(self) -> bool:
        return self.process.poll() is None

    def stop(self, timeout: float = 5.0) -> None:
        """Terminate the server (kill it after ``timeout`` seconds)."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        if self._log is not None:
            with contextlib.suppress(OSError):
                self._log.close()
            self._log = None


def start_server(timeout: float = 30.0, port: int | None = None) -> MeshcatServer:
    """Start a new loopback Meshcat server process, child of this one.

    Most code wants :func:`get_server` (one server per process) instead.

    Parameters
    ----------
    timeout : float
        Seconds to wait for the server to print its URLs.
    port : int, optional
        Web server port (default: the first free one from 7000).

    Returns
    -------
    MeshcatServer

    Raises
    ------
    MeshcatServerError
        The process exited or stayed silent for ``timeout`` seconds.
    """
    # the child imports tutor from wherever this process found it (an installed wheel,
    # an editable checkout or a notebook's sys.path), not from the repository's layout
    root = str(Path(importlib.util.find_spec("tutor").origin).parent.parent)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    cmd = [sys.executable, "-u", "-m", "tutor.views.meshcat_server"]
    if port is not None:
        cmd += ["--port", str(int(port))]
    log = tempfile.TemporaryFile()  # stderr: read on failure, never fills a pipe
    proc = subprocess.Popen(
        [*cmd, "--parent-pid", str(os.getpid())],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=log,
        env=env,
        start_new_session=True,  # a SIGINT to the kernel's process group spares it
    )
    lines: queue.Queue = queue.Queue()

    def read_lines():  # in a thread: a pipe cannot be polled portably (Windows)
        with proc.stdout:
            for raw in proc.stdout:
                lines.put(raw)
        lines.put(None)  # end of file: the server exited or moved stdout to stderr

    threading.Thread(target=read_lines, daemon=True, name="meshcat-server-urls").start()
    urls: dict[str, str] = {}
    deadline = time.monotonic() + timeout
    while len(urls) < 2:
        left = deadline - time.monotonic()
        if left <= 0:
            break
        try:
            raw = lines.get(timeout=min(left, 0.5))
        except queue.Empty:
            continue
        if raw is None:
            break
        key, _, value = raw.decode("utf-8", "replace").strip().partition("=")
        if key in ("zmq_url", "web_url"):
            urls[key] = value
    if len(urls) < 2:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        log.seek(0)
        tail = log.read().decode("utf-8", "replace")[-2000:]
        log.close()
        what = f"exited with code {proc.returncode}" if proc.returncode else "did not answer"
        raise MeshcatServerError(f"the Meshcat server {what} within {timeout:.0f} s:\n{tail}")
    server = MeshcatServer(proc, urls["zmq_url"], urls["web_url"], _log=log)
    atexit.register(server.stop)
    return server


_SERVER: MeshcatServer | None = None
_LOCK = threading.Lock()


def get_server(timeout: float = 30.0) -> MeshcatServer:
    """The kernel's Meshcat server: started on first use, then reused (restarted if it died).

    Returns
    -------
    MeshcatServer
    """
    global _SERVER
    with _LOCK:
        s = _SERVER
        if s is None or s.owner != os.getpid() or not s.alive():
            _SERVER = start_server(timeout)
        return _SERVER


def stop_server() -> None:
    """Stop the kernel's server if this process started one."""
    global _SERVER
    with _LOCK:
        if _SERVER is not None and _SERVER.owner == os.getpid():
            _SERVER.stop()
        _SERVER = None


def visualizer(server: MeshcatServer | None = None, timeout: float = 10.0):
    """A ``meshcat.Visualizer`` connected to ``server`` (default :func:`get_server`).

    Replies from the server are awaited at most ``timeout`` seconds, so a dead server
    raises ``zmq.Again`` instead of hanging the kernel.
    """
    import meshcat
    import zmq
    from meshcat.visualizer import ViewerWindow

    server = get_server() if server is None else server
    with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints the URL
        window = ViewerWindow(zmq_url=server.zmq_url, start_server=False, server_args=[])
    window.zmq_socket.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
    window.zmq_socket.setsockopt(zmq.SNDTIMEO, int(timeout * 1000))
    window.zmq_socket.setsockopt(zmq.LINGER, 0)
    return meshcat.Visualizer(window=window)


if __name__ == "__main__":
    status = main()
    sys.stderr.flush()
    # Leave at once: a zmq context with a client still connected can block a normal exit.
    os._exit(status)
