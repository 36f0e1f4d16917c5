"""What is sent to Meshcat: a recorder of the scene tree that can replay it anywhere.

Every Meshcat command of the 3-D view goes through a :class:`SceneRecorder`, which
keeps the scene tree the way meshcat's server does (an object, its properties, a
transform and an animation per path), so the scene can be rebuilt without a server:
as a static page or in the notebook viewer. It forwards each command to the live
server when there is one (to its own scene there, named by ``scene_id``) and tells its
listeners (the notebook viewer).

A command is ``(kind, path, packed)``: meshcat's command type ("set_object",
"set_transform", "set_property", "set_animation", "delete"), the scene path and the
command packed with msgpack, as meshcat's own window sends it over zmq.
"""

from __future__ import annotations

import gzip
import struct
from functools import lru_cache

from ..errors import InvalidParameterError
from .scene_page import SCENE_ID

__all__ = ["SceneRecorder", "delete_command", "empty_animation", "frame_commands"]


def _split(path: str) -> list[str]:
    return [p for p in path.split("/") if p]


class _Node:
    """One path of the scene tree: its object, properties, transform and animation."""

    __slots__ = ("object", "transform", "properties", "animation", "children")

    def __init__(self):
        self.object = None  # (type, path, packed)
        self.transform = None
        self.properties: dict[str, tuple] = {}
        self.animation = None
        self.children: dict[str, _Node] = {}

    def find(self, parts) -> _Node:
        node = self
        for p in parts:
            node = node.children.setdefault(p, _Node())
        return node

    def walk(self):
        yield self
        for child in self.children.values():
            yield from child.walk()


class SceneRecorder:
    """A Meshcat window that records the scene tree and forwards to a live viewer.

    It stands in for ``meshcat.visualizer.ViewerWindow``: ``meshcat.Visualizer(window=
    recorder)`` sends every command here. The tree is kept as meshcat's server keeps
    it (an object, its properties, a transform and an animation per path), so
    :meth:`commands` and :meth:`get_scene` need no server.

    Parameters
    ----------
    live : meshcat ViewerWindow, optional
        Forward each command to it too (its zmq socket should have a receive timeout).
    scene_id : str, optional
        The scene on the tutor's live server that the commands go to
        (:mod:`tutor.views.meshcat_server`; 1 to 64 of 0-9 and a-z). None: meshcat's
        own scene, which every page of meshcat's shows.
    """

    def __init__(self, live=None, scene_id: str | None = None):
        if scene_id is not None and not (
            isinstance(scene_id, str) and SCENE_ID.fullmatch(scene_id)
        ):
            raise InvalidParameterError(
                f"a scene id is 1 to 64 of the characters 0-9 and a-z, got {scene_id!r}"
            )
        self.tree = _Node()
        self.live = live
        self.scene_id = scene_id
        #: callables ``f(kind, path, packed)`` told of every command (the notebook viewer)
        self.listeners: list = []
        self.web_url = getattr(live, "web_url", None)
        self.live_error: str | None = None

    # meshcat's Visualizer calls window.send(command)
    def send(self, command) -> None:
        import umsgpack

        data = command.lower()
        self.send_packed(data["type"], data.get("path", ""), umsgpack.packb(data))

    def send_packed(self, kind: str, path: str, packed: bytes) -> None:
        """Record one command (and forward it when live)."""
        self._record(kind, path, packed)
        self.forward(kind, path, packed)
        for listener in self.listeners:
            listener(kind, path, packed)

    def _record(self, kind, path, packed) -> None:
        parts = _split(path)
        item = (kind, path, packed)
        if kind == "set_object":
            node = self.tree.find(parts)
            node.object = item
            node.properties = {}
        elif kind == "set_transform":
            self.tree.find(parts).transform = item
        elif kind == "set_property":
            import umsgpack

            key = umsgpack.unpackb(packed)["property"]
            self.tree.find(parts).properties[key] = item
        elif kind == "set_animation":
            self.tree.find(parts).animation = None if packed == empty_animation() else item
        elif kind == "delete":
            if parts:
                parent = self.tree.find(parts[:-1])
                parent.children.pop(parts[-1], None)
            else:
                self.tree = _Node()
        else:  # pragma: no cover - meshcat has no other scene commands
            raise InvalidParameterError(f"unknown Meshcat command {kind!r}")

    def forward(self, kind: str, path: str, packed: bytes) -> None:
        """Send one command to the live viewer only (not recorded); drop a dead viewer."""
        live = self.live
        if live is None:
            return
        frames = [kind.encode(), path.encode(), packed]
        if self.scene_id is not None:
            frames.append(self.scene_id.encode())
        try:
            live.zmq_socket.send_multipart(frames)
            live.zmq_socket.recv()
        except Exception as exc:  # zmq.Again (timeout) or a closed socket
            self.live = None
            self.live_error = f"the live viewer stopped answering ({type(exc).__name__}: {exc})"
            try:
                live.zmq_socket.close(linger=0)
            except Exception:  # pragma: no cover - already closed
                pass

    def commands(self) -> list[tuple[str, str, bytes]]:
        """The scene as a list of commands, in an order that rebuilds it.

        Objects, their properties and transforms node by node (parents first), then
        the animations (which need the objects to exist).
        """
        out, animations = [], []
        for node in self.tree.walk():
            if node.object is not None:
                out.append(node.object)
            out.extend(node.properties.values())
            if node.transform is not None:
                out.append(node.transform)
            if node.animation is not None:
                animations.append(node.animation)
        return out + animations

    def get_scene(self) -> str:
        """The recorded scene as a self-contained page (``meshcat.Visualizer.static_html``)."""
        from .scene_page import page, scene_data

        return page("MeshCat", scene_data([frame_commands(self.commands())]), "", "")


@lru_cache(maxsize=1)
def empty_animation() -> bytes:
    """The packed command that stops and removes every animation."""
    import umsgpack

    empty = {"type": "set_animation", "animations": [], "options": {"play": False}, "path": ""}
    return umsgpack.packb(empty)


def delete_command(path: str) -> bytes:
    """The packed command that deletes ``path`` and everything under it."""
    import umsgpack

    return umsgpack.packb({"type": "delete", "path": path})


def frame_commands(commands) -> bytes:
    """Commands as length-prefixed msgpack blobs, gzipped (what the viewer pages unpack)."""
    raw = b"".join(struct.pack(">I", len(c[2])) + c[2] for c in commands)
    return gzip.compress(raw, compresslevel=6, mtime=0)
