r"""The pick-and-place scene of Experiment 2 in 3-D (Meshcat): robot, tray, bin, trails.

What the trainee sees
---------------------
- The table, the 10 x 10 tray and the bin (grey), and the Franka Panda with its
  meshes from example-robot-data (the paper used a Sawyer; see
  :mod:`tutor.tasks.pickplace`).
- The 100 plants, each a thin stem with a ball on top coloured as on the tray map
  (:func:`tutor.views.pickplace_app.tray_status`, the paper's good-versus-bad figure):
  green the robot succeeds, orange it fails (and no demo covers the plant), blue
  demonstrated, light grey not seen yet.
- The demonstrations as blue trails; the robot's attempts the trainee was shown as
  green (success) or orange (failure) trails.
- One trajectory animated: the arm follows it (:meth:`tutor.robot.Arm.follow` turns
  the tool path into joint configurations) while a ball between the fingers shows
  the hand, yellow when open and purple when closed (holding the plant); the
  fingers open and close too.

Two ways to show it
-------------------
``mode="live"``
    A Meshcat viewer in an iframe served by the kernel's loopback-only server
    (:mod:`tutor.views.meshcat_server`). Updates stream in; it works only when the
    browser runs on the same machine as the kernel.
``mode="static"``
    No server. In the notebook, meshcat's viewer runs in an iframe inside a widget
    and gets the scene over the widget's comm: all of it when a browser opens the
    view (about 4 MB with the Panda's meshes compressed), then only what changed
    after each step (a few kB, or ~0.3 MB with an animation), so the camera stays
    where the trainee turned it. :meth:`Scene3D.static_html` gives the scene as one
    self-contained page (meshcat's script inside; about 6 MB) and
    :meth:`Scene3D.save_html` writes it to a file. Works in Voila, on Binder or
    JupyterHub, from ``file://`` and in CI.

``mode="auto"`` (the default) is static under ``TUTOR_HEADLESS=1`` (no server is
started), behind JupyterHub or Binder and in Voila opened from another machine; live
otherwise.

Every Meshcat command goes through a :class:`SceneRecorder`, which keeps the scene
tree the way meshcat's server does (so the static page needs no server), forwards
the commands to the live server when there is one and tells its listeners (the
notebook viewer). Several :class:`Scene3D` in one kernel share that server: the live
viewer shows the one updated last. Drawing methods change the scene at once; the
notebook viewer receives the changes at :meth:`Scene3D.refresh` (which
:meth:`Scene3D.update` calls).

Shapes
------
path : (T, 4)
    x, y, z (m, robot base frame) and the hand g (0 open .. 1 closed) per sample.
status : (100,) of str
    "pass", "fail", "demo" or "unknown" per plant (index row * 10 + col).
"""

from __future__ import annotations

import base64
import gzip
import html
import os
import struct
import threading
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from urllib.parse import urlparse

import numpy as np

from ..errors import InvalidParameterError
from ..runtime import headless
from .style import DEMO, FAIL, PASS

__all__ = [
    "Scene3D",
    "SceneRecorder",
    "AnimationInfo",
    "STATUS_COLOURS",
    "HAND_OPEN",
    "HAND_CLOSED",
    "choose_mode",
]

UNKNOWN = "#d0d0d0"  # as tutor.views.pickplace_app.UNKNOWN
#: colour of a plant's ball by status (the tray map's colours)
STATUS_COLOURS = {"pass": PASS, "fail": FAIL, "demo": DEMO, "unknown": UNKNOWN}
HAND_OPEN = "#e6ab02"  #: the hand marker while the hand is open (yellow)
HAND_CLOSED = "#7b3294"  #: ... while it is closed, holding a plant (purple)
TABLE = "#c8b08a"
TRAY = "#5b5b5b"
BIN = "#8c8c8c"
STEM = "#5a7a3a"

#: Where the camera sits (m) relative to the point it looks at, the middle of the scene
#: (:meth:`Scene3D.scene_centre`). Meshcat's camera orbits the viewer's origin, so the
#: whole scene is shifted to put its middle there.
CAMERA_POSITION = (0.75, -0.7, 0.62)
ROOT = "/meshcat"
DYNAMIC = "/meshcat/lfd"  # everything one Scene3D draws itself (the robot is shared)


def _hex(colour: str) -> int:
    return int(colour.lstrip("#"), 16)


def _split(path: str) -> list[str]:
    return [p for p in path.split("/") if p]


# --------------------------------------------------------------------------- recorder


class _Node:
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
    :meth:`commands` and :meth:`static_html` need no server.

    Parameters
    ----------
    live : meshcat ViewerWindow, optional
        Forward each command to it too (its zmq socket should have a receive timeout).
    """

    def __init__(self, live=None):
        self.tree = _Node()
        self.live = live
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
        self._forward(kind, path, packed)
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
            self.tree.find(parts).animation = None if packed == _EMPTY_ANIMATION() else item
        elif kind == "delete":
            if parts:
                parent = self.tree.find(parts[:-1])
                parent.children.pop(parts[-1], None)
            else:
                self.tree = _Node()
        else:  # pragma: no cover - meshcat has no other scene commands
            raise InvalidParameterError(f"unknown Meshcat command {kind!r}")

    def _forward(self, kind, path, packed) -> None:
        live = self.live
        if live is None:
            return
        try:
            live.zmq_socket.send_multipart([kind.encode(), path.encode(), packed])
            live.zmq_socket.recv()
        except Exception as exc:  # zmq.Again (timeout) or a closed socket
            self.live = None
            self.live_error = f"the live viewer stopped answering ({type(exc).__name__})"
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
        data = base64.b64encode(_frame_commands(self.commands())).decode("ascii")
        chunk = f'<script type="application/octet-stream" class="scene-data">{data}</script>'
        return _page("MeshCat", chunk, "", "")

    def replay_to_live(self, clear: str | None = None) -> None:
        """Send the whole recorded scene to the live viewer (after ``delete clear``)."""
        if self.live is None:
            return
        if clear is not None:
            self._forward("delete", clear, _DELETE(clear))
        has_animation = False
        for kind, path, packed in self.commands():
            self._forward(kind, path, packed)
            has_animation |= kind == "set_animation"
        if not has_animation:
            self._forward("set_animation", "", _EMPTY_ANIMATION())


@lru_cache(maxsize=1)
def _EMPTY_ANIMATION() -> bytes:  # noqa: N802 - a constant, computed once
    import umsgpack

    empty = {"type": "set_animation", "animations": [], "options": {"play": False}, "path": ""}
    return umsgpack.packb(empty)


def _DELETE(path: str) -> bytes:  # noqa: N802 - like _EMPTY_ANIMATION
    import umsgpack

    return umsgpack.packb({"type": "delete", "path": path})


def _frame_commands(commands) -> bytes:
    """Commands as length-prefixed msgpack blobs, gzipped."""
    raw = b"".join(struct.pack(">I", len(c[2])) + c[2] for c in commands)
    return gzip.compress(raw, compresslevel=6, mtime=0)


# --------------------------------------------------------------------------- the robot


@dataclass(frozen=True)
class _RobotMeshes:
    """The robot's visual meshes as recorded Meshcat commands, built once per process."""

    commands: tuple  # (kind, path, packed) set_object commands
    gz: bytes  # their gzipped frames, for the in-notebook viewer
    chunk: str  # the same in base64, for static pages
    node_names: tuple  # Meshcat path (under ROOT) of each visual geometry


_ROBOT_LOCK = threading.Lock()


@lru_cache(maxsize=2)
def _robot_meshes(name: str) -> _RobotMeshes:
    import contextlib
    import io
    import warnings

    import meshcat
    from pinocchio.visualize import MeshcatVisualizer

    from ..robot import load_robot

    robot = load_robot(name)
    rec = SceneRecorder()
    viz = MeshcatVisualizer(robot.model, None, robot.visual_model)
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        viz.initViewer(viewer=meshcat.Visualizer(window=rec))
        viz.loadViewerModel(rootNodeName="robot")
    objects = tuple(c for c in rec.commands() if c[0] == "set_object")
    names = tuple(f"robot/visuals/{g.name}" for g in robot.visual_model.geometryObjects)
    gz = _frame_commands(objects)
    return _RobotMeshes(objects, gz, base64.b64encode(gz).decode("ascii"), names)


def robot_meshes(name: str = "panda") -> _RobotMeshes:
    with _ROBOT_LOCK:
        return _robot_meshes(name)


# --------------------------------------------------------------------------- modes


def choose_mode(mode: str = "auto") -> str:
    """``"live"`` or ``"static"`` for ``mode`` in {"auto", "live", "static"}.

    Auto is static when headless (``TUTOR_HEADLESS=1``), behind JupyterHub or on
    Binder, or in Voila opened from another machine (the live viewer is on the
    kernel's loopback, out of reach of a browser elsewhere), and live otherwise.
    """
    if mode not in ("auto", "live", "static"):
        raise InvalidParameterError(f"mode must be 'auto', 'live' or 'static', got {mode!r}")
    if mode != "auto":
        return mode
    remote = any(k in os.environ for k in ("JUPYTERHUB_SERVICE_PREFIX", "BINDER_SERVICE_HOST"))
    voila = os.environ.get("VOILA_REQUEST_URL")  # the address the browser asked Voila for
    if voila and urlparse(voila).hostname not in ("127.0.0.1", "localhost", "::1"):
        remote = True
    return "static" if headless() or remote else "live"


@dataclass(frozen=True)
class AnimationInfo:
    """What :meth:`Scene3D.animate` put on screen.

    Attributes
    ----------
    frames : int
        Samples of the path (one animation key per sample).
    fps : float
        Keys per second.
    duration : float
        Seconds from the first key to the last.
    label : str
        The caption shown with it.
    reached : bool
        The arm reached every sample of the path (inverse kinematics converged).
    """

    frames: int
    fps: float
    duration: float
    label: str
    reached: bool


# --------------------------------------------------------------------------- the scene


class Scene3D:
    """The pick-and-place scene in Meshcat, refreshed by :class:`PickPlaceTutor`.

    Parameters
    ----------
    task : PickPlaceTask, optional
        Its scene gives the geometry (default: the bundled scene).
    mode : {"auto", "live", "static"}
        See the module docstring. A live viewer starts the kernel's Meshcat server.
    height : int
        Height of the viewer in the notebook (px).
    seconds : float
        How long one animated trajectory lasts (s): 200 samples over 10 s is 20
        frames per second, interpolated by the viewer.
    robot : bool
        Draw the robot (tests draw it once without).
    live_timeout : float
        Seconds to wait for the live server's reply before showing the scene in the
        notebook instead.
    """

    def __init__(
        self, task=None, *, mode="auto", height=480, seconds=10.0, robot=True, live_timeout=10.0
    ):
        if task is None:
            from ..tasks.pickplace import PickPlaceTask

            task = PickPlaceTask()
        if not (hasattr(task, "scene") and hasattr(task, "conditions")):
            raise InvalidParameterError(
                f"task must be a PickPlaceTask (with a scene and conditions), got {task!r}"
            )
        self.task = task
        self.scene = task.scene
        if not (isinstance(height, int | np.integer) and 150 <= height <= 2000):
            raise InvalidParameterError(f"height must be 150 to 2000 pixels, got {height!r}")
        try:
            ok = 1.0 <= float(seconds) <= 120.0
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise InvalidParameterError(f"seconds must be between 1 and 120, got {seconds!r}")
        self.height = int(height)
        self.seconds = float(seconds)
        self.mode = choose_mode(mode)
        self.message = ""
        self.animation: AnimationInfo | None = None
        live = None
        if self.mode == "live":
            from .meshcat_server import MeshcatServerError, visualizer

            try:
                live = visualizer(timeout=live_timeout).window
            except (MeshcatServerError, OSError) as exc:
                self.mode = "static"
                last = (str(exc).strip().splitlines() or [type(exc).__name__])[-1]
                self.message = f"No live 3-D viewer ({last}): showing the scene in the notebook."
        self.recorder = SceneRecorder(live)
        import meshcat

        self.vis = meshcat.Visualizer(window=self.recorder)
        self._status = np.full(len(task.conditions), "", dtype=object)
        self._robot = robot_meshes(self.scene.robot) if robot else None
        self._arm = None
        self._widget = None
        self._view = None
        self._pending = None  # commands not yet sent to the notebook viewer
        self._shown_key = None
        self._claim_live(fresh=True)  # what follows streams to the live viewer as drawn
        self._draw_static_scene()
        self.set_status(np.full(len(task.conditions), "unknown", dtype=object))
        self._check_live()

    # ------------------------------------------------------------------ building

    def _draw_static_scene(self) -> None:
        import meshcat.geometry as mg
        import meshcat.transformations as tf

        from ..robot import scene_obstacles

        vis, sc = self.vis, self.scene
        vis["/Grid"].set_property("visible", False)
        vis["/Axes"].set_property("visible", False)
        vis.set_transform(tf.translation_matrix(-self.scene_centre()))
        x, y, z = CAMERA_POSITION
        vis["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])
        colours = {"table": TABLE, "tray": TRAY}
        for name, center, size in scene_obstacles(sc):
            node = "lfd/" + name.replace(" ", "_")
            colour = colours.get(name, BIN)
            vis[node].set_object(mg.Box(list(size)), mg.MeshLambertMaterial(color=_hex(colour)))
            vis[node].set_transform(tf.translation_matrix(center))
        upright = tf.rotation_matrix(np.pi / 2, [1, 0, 0])  # meshcat cylinders run along y
        stem = sc.plant_height
        for i, p in enumerate(sc.plant_positions):
            base = np.array([p[0], p[1], sc.tray_top])
            node = vis[f"lfd/plants/{i}"]
            node.set_transform(tf.translation_matrix(base))
            node["stem"].set_object(
                mg.Cylinder(stem, 0.5 * sc.plant_radius),
                mg.MeshLambertMaterial(color=_hex(STEM)),
            )
            node["stem"].set_transform(tf.translation_matrix([0, 0, stem / 2]) @ upright)
        self._ball = mg.Sphere(min(0.4 * sc.pitch, 1.6 * sc.plant_radius))
        if self._robot is not None:
            for kind, path, packed in self._robot.commands:
                self.recorder.send_packed(kind, path, packed)
            self.show_configuration(sc.start_configuration)
        hand = vis["lfd/hand"]
        hand["open"].set_object(mg.Sphere(0.016), mg.MeshLambertMaterial(color=_hex(HAND_OPEN)))
        hand["closed"].set_object(mg.Sphere(0.016), mg.MeshLambertMaterial(color=_hex(HAND_CLOSED)))
        hand["closed"].set_transform(tf.scale_matrix(1e-3))
        p, _ = self._get_arm().fk(sc.start_configuration)
        hand.set_transform(tf.translation_matrix(p))

    def scene_centre(self) -> np.ndarray:
        """The point the camera looks at (3,): between the tray and the bin, a little
        towards the robot, 20 cm above the table (chosen by eye for the bundled scene)."""
        sc = self.scene
        mid = (sc.tray_center[:2] + sc.bin_center[:2]) / 2
        return np.array([mid[0] / 2 + 0.1, mid[1], 0.2])

    def _get_arm(self):
        if self._arm is None:
            from ..robot import get_arm, scene_obstacles

            sc = self.scene
            self._arm = get_arm(scene_obstacles(sc), sc.robot, sc.tool_frame)
        return self._arm

    def _placements(self, qs: np.ndarray) -> np.ndarray:
        """Homogeneous placement (T, G, 4, 4) of each visual geometry for each q."""
        return self._get_arm().visual_placements(qs)

    # ------------------------------------------------------------------ public drawing

    def show_configuration(self, q) -> None:
        """Put the robot at configuration ``q`` (nq,) (no animation)."""
        if self._robot is None:
            return
        arm = self._get_arm()
        q = np.asarray(q, dtype=float)
        if q.shape != (arm.nq,) or not np.all(np.isfinite(q)):
            raise InvalidParameterError(f"q must be {arm.nq} finite numbers, got shape {q.shape}")
        T = self._placements(q[None])[0]
        for name, M in zip(self._robot.node_names, T, strict=True):
            self.vis[name].set_transform(M)

    def show_robot(self, visible: bool = True) -> None:
        """Show or hide the robot's meshes."""
        self.vis["robot"].set_property("visible", bool(visible))

    def set_status(self, status) -> None:
        """Colour the plants' balls by status (100,) of "pass"/"fail"/"demo"/"unknown"."""
        import meshcat.geometry as mg
        import meshcat.transformations as tf

        s = np.asarray(status, dtype=object).ravel()
        n = len(self.task.conditions)
        if s.shape != (n,):
            raise InvalidParameterError(f"status must have {n} entries, got shape {s.shape}")
        bad = sorted({str(v) for v in s if v not in STATUS_COLOURS})
        if bad:
            raise InvalidParameterError(
                f"unknown plant status {bad}; use one of {sorted(STATUS_COLOURS)}"
            )
        top = tf.translation_matrix([0, 0, self.scene.plant_height])
        for i in np.flatnonzero(s != self._status):
            ball = self.vis[f"lfd/plants/{i}/ball"]
            ball.set_object(self._ball, mg.MeshLambertMaterial(color=_hex(STATUS_COLOURS[s[i]])))
            ball.set_transform(top)
        self._status = s.copy()

    def draw_trails(self, name: str, paths, colour: str) -> None:
        """Draw ``paths`` (k, T, >= 3) as lines under ``lfd/trails/name`` (replacing them)."""
        import meshcat.geometry as mg

        node = self.vis[f"lfd/trails/{name}"]
        node.delete()
        for j, path in enumerate(paths):
            P = self._check_path(path, columns=3)[:, :3]
            node[str(j)].set_object(
                mg.Line(
                    mg.PointsGeometry(P.T.astype(np.float32)),
                    mg.LineBasicMaterial(color=_hex(colour), linewidth=2),
                )
            )

    def animate(self, path, label: str = "", colour: str | None = None) -> AnimationInfo:
        """Animate the arm along ``path`` (T, 4) over :attr:`seconds` and draw its trail.

        The tool path goes through :meth:`tutor.robot.Arm.follow` (inverse kinematics
        from the start configuration); the fingers follow the hand column.

        Returns
        -------
        AnimationInfo
        """
        import meshcat.animation as ma
        import meshcat.transformations as tf

        P = self._check_path(path, columns=4)
        T = len(P)
        if T < 2:
            raise InvalidParameterError("a path to animate needs at least 2 samples")
        arm = self._get_arm()
        track = arm.follow(
            P[:, :3], gripper=P[:, 3], q0=self.scene.start_configuration, check_collisions=False
        )
        fps = T / self.seconds  # 200 samples over 10 s: 20 keys per second
        anim = ma.Animation(default_framerate=fps)
        closed = P[:, 3] >= 0.5
        tiny, one = [1e-3] * 3, [1.0] * 3
        if self._robot is not None:
            placements = self._placements(track.qs)
        for t in range(T):
            with anim.at_frame(self.vis, t) as frame:
                if self._robot is not None:
                    for g, name in enumerate(self._robot.node_names):
                        frame[name].set_transform(placements[t, g])
                p, _ = arm.fk(track.qs[t])
                frame["lfd/hand"].set_transform(tf.translation_matrix(p))
                # a scale track: a transform track would animate position and rotation only
                frame["lfd/hand/open"].set_property("scale", "vector3", tiny if closed[t] else one)
                frame["lfd/hand/closed"].set_property(
                    "scale", "vector3", one if closed[t] else tiny
                )
        self.draw_trails("animated", [P], colour or "#222222")
        self.vis.set_animation(anim, play=True, repetitions=1)
        info = AnimationInfo(T, fps, (T - 1) / fps, label, bool(track.converged.all()))
        self.animation = info
        return info

    def clear_animation(self) -> None:
        """Stop any animation and put the robot back at the start configuration."""
        self.recorder.send_packed("set_animation", "", _EMPTY_ANIMATION())
        self.vis["lfd/trails/animated"].delete()
        self.show_configuration(self.scene.start_configuration)
        p, _ = self._get_arm().fk(self.scene.start_configuration)
        import meshcat.transformations as tf

        self.vis["lfd/hand"].set_transform(tf.translation_matrix(p))
        self.animation = None

    @staticmethod
    def _check_path(path, columns: int) -> np.ndarray:
        try:
            P = np.asarray(path, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"a path must be an array of shape (T, {columns})") from exc
        if P.ndim != 2 or P.shape[1] < columns or len(P) < 1:
            raise InvalidParameterError(
                f"a path must have shape (T, {columns}) (x, y, z{', g' if columns > 3 else ''}),"
                f" got {P.shape}"
            )
        if not np.all(np.isfinite(P)):
            raise InvalidParameterError("a path must be finite (no NaN or inf)")
        return P[:, :columns]

    # ------------------------------------------------------------------ the tutor's hook

    def update(self, run, status) -> None:
        """Show a teaching run: plant colours, demos, the shown attempts, one animation.

        Called by :class:`~tutor.views.pickplace_app.PickPlaceTutor` after each step.
        The animation is the robot's latest shown attempt (the plant just tested, the
        first failing one of the batch, or the replay), or the latest demonstration
        when the robot showed nothing (NF).
        """
        session, task = run.session, run.task
        key = (
            id(session),
            len(session.events),
            len(session.meta.get("tests", [])),
            run.finished,
            tuple(np.asarray(status, dtype=object).ravel()),
        )
        if key == self._shown_key:  # e.g. the trainee only selected another plant
            return
        self.set_status(status)
        demos = [d[:, -4:] for d in session.demos]
        self.draw_trails("demos", demos, DEMO)
        rec = session.latest
        shown = run.shown_plants() if rec is not None else np.zeros(0, int)
        if rec is not None and run.finished:
            shown = np.arange(len(task.conditions))
        R = session.realisations if rec is not None else None
        ok = [p for p in shown if rec.passed[p]] if rec is not None else []
        bad = [p for p in shown if not rec.passed[p]] if rec is not None else []
        if R is not None:
            self.draw_trails("passed", [R[p][:, -4:] for p in ok], PASS)
            self.draw_trails("failed", [R[p][:, -4:] for p in bad], FAIL)
        else:
            self.draw_trails("passed", [], PASS)
            self.draw_trails("failed", [], FAIL)
        plant = self._pick_plant(run, shown)
        if plant is not None:
            passed = bool(rec.passed[plant])
            reason = rec.reasons[plant]
            label = f"The robot's attempt at {task.plant_name(plant)}: " + (
                "success." if passed else f"fails ({reason})."
            )
            self.animate(R[plant][:, -4:], label, PASS if passed else FAIL)
        elif demos:
            plant = task.nearest_condition(session.conditions[-1])
            label = f"Your demonstration {len(demos)} ({task.plant_name(plant)})."
            self.animate(demos[-1], label, DEMO)
        else:
            self.clear_animation()
        self._shown_key = key
        self._claim_live()
        self.refresh()

    @staticmethod
    def _pick_plant(run, shown):
        rec = run.session.latest
        if rec is None or len(shown) == 0:
            return None
        tests = [t for t in run.session.meta.get("tests", []) if t["after_demo"] == rec.n_demos]
        if tests and tests[-1]["plants"]:
            return int(tests[-1]["plants"][-1])
        own = run.task.nearest_condition(run.session.conditions[-1])
        if own in set(int(p) for p in rec.shown):
            return int(own)
        failing = [int(p) for p in shown if not rec.passed[p]]
        return failing[0] if failing else int(shown[0])

    # ------------------------------------------------------------------ output

    def _claim_live(self, fresh: bool = False) -> None:
        """Make the shared live viewer show this scene (another Scene3D may have it).

        ``fresh``: nothing is drawn yet; only clear what another scene left.
        """
        global _LIVE_OWNER
        rec = self.recorder
        if rec.live is None:
            self._check_live()
            return
        with _LIVE_LOCK:
            if fresh:
                rec._forward("delete", DYNAMIC, _DELETE(DYNAMIC))
                rec._forward("set_animation", "", _EMPTY_ANIMATION())
                _LIVE_OWNER = self
            elif _LIVE_OWNER is not self:
                rec.replay_to_live(clear=DYNAMIC)
                _LIVE_OWNER = self
        self._check_live()

    def _check_live(self) -> None:
        if self.mode == "live" and self.recorder.live is None:
            self.mode = "static"
            self.message = (
                f"{self.recorder.live_error or 'no live viewer'}: showing the scene in the "
                "notebook instead."
            )

    def _scene_chunks(self) -> list[bytes]:
        """The whole scene as gzipped command frames: the robot's meshes (cached), the rest."""
        robot_ids = set()
        chunks = []
        if self._robot is not None:
            robot_ids = {id(c[2]) for c in self._robot.commands}
            chunks.append(self._robot.gz)
        rest = [c for c in self.recorder.commands() if id(c[2]) not in robot_ids]
        chunks.append(_frame_commands(rest))
        return chunks

    def static_html(self, title: str = "lfd-tutor: pick and place in 3-D") -> str:
        """The scene as one self-contained HTML page (meshcat's viewer script inside)."""
        chunks = self._scene_chunks()
        if self._robot is not None:  # its base64 is cached too
            chunks[0] = self._robot.chunk
        data = "".join(
            '<script type="application/octet-stream" class="scene-data">'
            + (c if isinstance(c, str) else base64.b64encode(c).decode("ascii"))
            + "</script>"
            for c in chunks
        )
        caption = html.escape(self.animation.label if self.animation else "")
        return _page(title, data, self.legend_html(), caption)

    def save_html(self, path) -> Path:
        """Write :meth:`static_html` to ``path``; returns the path."""
        path = Path(path)
        path.write_text(self.static_html(), encoding="utf-8")
        return path

    @staticmethod
    def legend_html() -> str:
        dot = (
            "<span style='display:inline-block;width:11px;height:11px;border-radius:50%;"
            "background:{};margin:0 4px 0 10px;vertical-align:middle'></span>{}"
        )
        line = (
            "<span style='display:inline-block;width:16px;height:3px;background:{};"
            "margin:0 4px 0 10px;vertical-align:middle'></span>{}"
        )
        items = [
            dot.format(PASS, "succeeds"),
            dot.format(FAIL, "fails"),
            dot.format(DEMO, "demonstrated"),
            dot.format(UNKNOWN, "not seen yet"),
            line.format(DEMO, "your demos"),
            dot.format(HAND_OPEN, "hand open"),
            dot.format(HAND_CLOSED, "hand closed"),
        ]
        return "<span style='font-size:12px'>" + "".join(items) + "</span>"

    def _make_view(self):
        """The viewer widget: an iframe to the live server, or the in-notebook viewer."""
        import ipywidgets as w

        if self.mode == "live":
            url = html.escape(self.recorder.web_url or "")
            style = f"width:100%;height:{self.height}px;border:1px solid #ccc"
            return w.HTML(f"<iframe src='{url}' style='{style}'></iframe>")
        view = _viewer_widget_class()(height=self.height, page=_page("3-D view", "", "", ""))
        view.on_msg(self._on_view_msg)
        self.recorder.listeners.append(self._collect)
        return view

    def _collect(self, kind, path, packed) -> None:
        if self._pending is not None:  # a browser shows the view: keep what changes
            self._pending.append((kind, path, packed))

    def _on_view_msg(self, _widget, content, _buffers) -> None:
        if isinstance(content, dict) and content.get("type") == "hello":
            # a browser (re)opened the view: send it the whole scene, then changes only
            self._pending = []
            self._view.send({"type": "full", "to": content.get("id")}, self._scene_chunks())

    def _flush(self) -> None:
        if self._pending:
            self._view.send({"type": "update"}, [_frame_commands(self._pending)])
            self._pending = []

    def _caption_html(self) -> str:
        parts = [self.legend_html()]
        if self.animation is not None:
            parts.append(f"<div><b>Animated:</b> {html.escape(self.animation.label)}</div>")
        how = (
            "Drag to turn, scroll to zoom, right-drag to move. To replay: <i>Open Controls "
            "▸ Animations ▸ default ▸ play</i> (top right of the view)."
        )
        if self.mode == "live" and self.recorder.web_url:
            url = html.escape(self.recorder.web_url)
            how += f" <a href='{url}' target='_blank'>Open in its own tab</a>."
        parts.append(f"<div style='font-size:12px;color:#555'>{how}</div>")
        if self.message:
            parts.append(f"<div class='lfd-message'>{html.escape(self.message)}</div>")
        return "".join(parts)

    @property
    def widget(self):
        """The view as an ipywidget (caption, legend and the viewer)."""
        if self._widget is None:
            import ipywidgets as w

            self._caption = w.HTML()
            self._view = self._make_view()
            self._widget = w.VBox([self._caption, self._view])
            self._widget.add_class("lfd-scene3d")
            self.refresh()
        return self._widget

    def refresh(self) -> None:
        """Update the widget: the caption, and the changes for the notebook viewer."""
        if self._widget is None:
            return
        self._caption.value = self._caption_html()
        if self.mode == "static" and isinstance(self._view, _viewer_widget_class()):
            self._flush()
        elif self.mode == "static":  # the live viewer died: switch to the notebook viewer
            self._view = self._make_view()
            self._widget.children = (self._caption, self._view)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


_LIVE_OWNER: Scene3D | None = None
_LIVE_LOCK = threading.Lock()


@lru_cache(maxsize=1)
def _viewer_js() -> str:
    import meshcat

    path = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
    return path.read_text(encoding="utf-8").replace("</script", "<\\/script")


def _page(title: str, data: str, legend: str, caption: str) -> str:
    overlay = (
        f'<div id="lfd-legend">{legend}<div id="lfd-caption">{caption}</div></div>'
        if legend or caption
        else ""
    )
    return _PAGE.format(title=html.escape(title), viewer=_viewer_js(), data=data, overlay=overlay)


@lru_cache(maxsize=1)
def _viewer_widget_class():
    import anywidget
    import traitlets

    class SceneView(anywidget.AnyWidget):
        """meshcat's viewer in an iframe fed over the widget's comm: the whole scene
        when a browser opens it, then only the changes (the camera stays put)."""

        _esm = _WIDGET_JS
        height = traitlets.Int(480).tag(sync=True)
        page = traitlets.Unicode("").tag(sync=True)

    return SceneView


_WIDGET_JS = """
function render({ model, el }) {
  const id = Math.random().toString(36).slice(2);
  const frame = document.createElement("iframe");
  frame.style.width = "100%";
  frame.style.height = model.get("height") + "px";
  frame.style.border = "1px solid #ccc";
  el.classList.add("lfd-scene3d-view");
  el.dataset.updates = "0";
  let ready = false;
  let chain = Promise.resolve();
  const apply = (buffers) => {
    for (const b of buffers) {
      const bytes = b instanceof ArrayBuffer
        ? new Uint8Array(b)
        : new Uint8Array(b.buffer, b.byteOffset, b.byteLength).slice();
      chain = chain.then(() => frame.contentWindow.lfdApply(bytes));
    }
    chain = chain
      .then(() => { el.dataset.updates = String(Number(el.dataset.updates) + 1); })
      .catch((err) => { el.dataset.error = String(err); });
  };
  const onMsg = (msg, buffers) => {
    if (msg.type === "full" && msg.to === id) { ready = true; apply(buffers); }
    else if (msg.type === "update" && ready) { apply(buffers); }
  };
  model.on("msg:custom", onMsg);
  // (re)loaded, e.g. when the page moves the output: ask for the whole scene again
  frame.addEventListener("load", () => { ready = false; model.send({ type: "hello", id: id }); });
  frame.srcdoc = model.get("page");
  el.appendChild(frame);
  return () => model.off("msg:custom", onMsg);
}
export default { render };
"""

_PAGE = """<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ margin: 0; font-family: sans-serif; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
#lfd-legend {{ position: absolute; left: 6px; top: 6px; background: rgba(255,255,255,.85);
  padding: 4px 8px 4px 0; border-radius: 4px; max-width: 92vw; }}
#lfd-caption {{ font-size: 12px; margin: 3px 0 0 10px; }}
</style></head>
<body>
<div id="meshcat-pane"></div>
{overlay}
{data}
<script>{viewer}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
// Apply gzipped, length-prefixed msgpack commands, in order.
async function lfdApply(gz) {{
  const stream = new Blob([gz]).stream().pipeThrough(new DecompressionStream("gzip"));
  const buf = new Uint8Array(await new Response(stream).arrayBuffer());
  const view = new DataView(buf.buffer);
  let i = 0;
  while (i < buf.length) {{
    const n = view.getUint32(i);
    viewer.handle_command_bytearray(buf.slice(i + 4, i + 4 + n));
    i += 4 + n;
  }}
}}
function lfdCaption(text) {{
  const el = document.getElementById("lfd-caption");
  if (el) el.textContent = text;
}}
window.lfdApply = lfdApply;
window.lfdCaption = lfdCaption;
(async function () {{
  for (const el of document.querySelectorAll("script.scene-data")) {{
    await lfdApply(Uint8Array.from(atob(el.textContent), c => c.charCodeAt(0)));
  }}
  document.body.dataset.ready = "1";
}})().catch(function (err) {{
  document.body.dataset.ready = "error";
  lfdCaption("This browser could not unpack the 3-D scene: " + err);
}});
</script>
</body>
</html>
"""
