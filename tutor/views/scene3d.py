r"""The pick-and-place scene of Experiment 2 in 3-D (Meshcat): robot, tray, bin, trails.

(About 680 lines, over the project's ~600: :class:`Scene3D` is one object whose drawing
methods share the recorder, the scene's state and what was sent last, which is what
lets it send only what changed; its recorder, meshes, page and animation packing are
already modules of their own.)

What the trainee sees
---------------------
- The table, the 10 x 10 tray and the bin (grey), and the Franka Panda with its
  meshes from example-robot-data (the paper used a Sawyer; see
  :mod:`tutor.tasks.pickplace`).
- The 100 plants, each a thin stem with a ball on top coloured as on the tray map
  (:func:`tutor.views.pickplace_app.tray_status`, the paper's good-versus-bad figure):
  green the robot succeeds, dark red it fails, blue
  demonstrated, light grey not seen yet.
- The demonstrations as blue trails; the robot's attempts the trainee was shown as
  green (success) or dark red (failure) trails.
- One trajectory animated: the arm follows it (:meth:`tutor.robot.Arm.follow` turns
  the tool path into joint configurations) while a ball between the fingers shows
  the hand, yellow when open and purple when closed (holding the plant); the
  fingers open and close too.

Two ways to show it
-------------------
``mode="live"``
    A Meshcat viewer in an iframe served by the kernel's loopback-only server
    (:mod:`tutor.views.meshcat_server`), at the address of this scene's own scene on
    it (``/lfd/<scene_id>/``). Updates stream in; it works only when the browser runs
    on the same machine as the kernel.
``mode="static"``
    No server. In the notebook, meshcat's viewer runs in an iframe inside a widget
    and gets the scene over the widget's comm: all of it when a browser opens the
    view (about 0.5 MB with the Panda's meshes compressed), then only what changed
    after each step (a few kB, or ~0.3 MB with an animation), so the camera stays
    where the trainee turned it. :meth:`Scene3D.static_html` gives the scene as one
    self-contained page (meshcat's script inside; about 1.5 MB) and
    :meth:`Scene3D.save_html` writes it to a file. Works in Voila, on Binder or
    JupyterHub, from ``file://`` and in CI.

``mode="auto"`` (the default) is static under ``TUTOR_HEADLESS=1`` (no server is
started), behind JupyterHub or Binder and in Voila opened from another machine; live
otherwise.

Every Meshcat command goes through a :class:`SceneRecorder`
(:mod:`tutor.views.meshcat_recorder`), which keeps the scene tree the way meshcat's
server does (so the static page needs no server), forwards the commands to the live
server when there is one and tells its listeners (the notebook viewer). Several
:class:`Scene3D` in one kernel (the three runs of a notebook) share that server, each
with a scene of its own (:attr:`Scene3D.scene_id`): a finished run's view keeps its
picture and its Replay when the next run draws. Drawing methods change the scene at
once; the
notebook viewer receives the changes at :meth:`Scene3D.refresh` (which
:meth:`Scene3D.update` calls).

The modules
-----------
This one draws (:class:`Scene3D`: the plants' status colours, trails, the animation,
the widget); :mod:`tutor.views.meshcat_recorder` records and replays the commands;
:mod:`tutor.views.scene_meshes` holds the geometry (robot meshes, table, tray, bin,
plants, hand); :mod:`tutor.views.scene_page` chooses live or static and builds the
page and the notebook widget from the static files in ``tutor/views/static/``.

Shapes
------
path : (T, 4)
    x, y, z (m, robot base frame) and the hand g (0 open .. 1 closed) per sample.
status : (100,) of str
    "pass", "fail", "demo" or "unknown" per plant (index row * 10 + col).
"""

from __future__ import annotations

import contextlib
import hashlib
import html
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, InvalidPayloadError
from ..fileio import atomic_write_text
from ..payloads import check_view_message, safely
from .meshcat_recorder import SceneRecorder, empty_animation, frame_commands
from .scene_animation import (
    Track,
    key_samples,
    moving,
    pack_animation,
    step_track,
    transform_tracks,
)
from .scene_guide import GUIDE_MESSAGES, Guide
from .scene_meshes import (
    HAND_CLOSED,
    HAND_OPEN,
    draw_fixtures,
    draw_hand,
    hex_colour,
    plant_ball,
    robot_meshes,
)
from .scene_page import choose_mode, live_page_url, page, scene_data, viewer_widget_class
from .style import DEMO, FAIL, PASS, UNKNOWN

__all__ = [
    "Scene3D",
    "SceneRecorder",
    "AnimationInfo",
    "STATUS_COLOURS",
    "WORKING",
    "HAND_OPEN",
    "HAND_CLOSED",
    "choose_mode",
]

#: colour of a plant's ball by status (the tray map's colours)
STATUS_COLOURS = {"pass": PASS, "fail": FAIL, "demo": DEMO, "unknown": UNKNOWN}

#: Where the camera sits (m) relative to the point it looks at, the middle of the scene
#: (:meth:`Scene3D.scene_centre`). Meshcat's camera orbits the viewer's origin, so the
#: whole scene is shifted to put its middle there.
CAMERA_POSITION = (0.75, -0.7, 0.62)
#: The path of the live viewer's "update applied" stamp (its page handles it; not drawn).
STAMP = "/lfd-stamp"
#: What the view says while the kernel learns from a demonstration (:meth:`Scene3D.working`).
WORKING = "Working: the robot is learning from your demo..."


@dataclass(frozen=True)
class AnimationInfo:
    """What :meth:`Scene3D.animate` put on screen.

    Attributes
    ----------
    frames : int
        Samples of the path.
    fps : float
        Samples per second (the path is played at this rate).
    duration : float
        Seconds from the first key to the last.
    label : str
        The caption shown with it.
    reached : bool
        The arm reached every sample of the path (inverse kinematics converged).
    keys : int
        Animation keys sent to the viewer per moving node (it interpolates between
        them; see :mod:`tutor.views.scene_animation`).
    """

    frames: int
    fps: float
    duration: float
    label: str
    reached: bool
    keys: int = 0


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

    Attributes
    ----------
    scene_id : str
        This scene's name on the live server (32 hex digits, new for each Scene3D):
        its page there is ``/lfd/<scene_id>/`` and shows this scene only.
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
        self.scene_id = uuid.uuid4().hex
        self.recorder = SceneRecorder(live, scene_id=self.scene_id)
        import meshcat

        self.vis = meshcat.Visualizer(window=self.recorder)
        self._status = np.full(len(task.conditions), "", dtype=object)
        self._robot = robot_meshes(self.scene.robot) if robot else None
        self._arm = None
        self._widget = None
        self._view = None
        self._pending = None  # commands not yet sent to the notebook viewer
        self._shown_key = None
        self._trails: dict[str, list[bytes]] = {}  # what each trail group shows (digests)
        self._stamp = 0  # updates sent to the live viewer (it reports the last applied)
        self._working = ""  # the "working" line shown until the next refresh
        self.replay_button = None
        self._guide: Guide | None = None
        self._draw_static_scene()  # streams to this scene on the live server as drawn
        self.set_status(np.full(len(task.conditions), "unknown", dtype=object))
        self._check_live()

    # ------------------------------------------------------------------ building

    def _draw_static_scene(self) -> None:
        import meshcat.transformations as tf

        vis, sc = self.vis, self.scene
        vis["/Grid"].set_property("visible", False)
        vis["/Axes"].set_property("visible", False)
        vis.set_transform(tf.translation_matrix(-self.scene_centre()))
        x, y, z = CAMERA_POSITION
        vis["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])
        draw_fixtures(vis, sc)
        self._ball = plant_ball(sc)
        if self._robot is not None:
            for kind, path, packed in self._robot.commands:
                self.recorder.send_packed(kind, path, packed)
            self.show_configuration(sc.start_configuration)
        draw_hand(vis, self._get_arm().fk(sc.start_configuration)[0])

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
            ball.set_object(
                self._ball, mg.MeshLambertMaterial(color=hex_colour(STATUS_COLOURS[s[i]]))
            )
            ball.set_transform(top)
        self._status = s.copy()

    def draw_trails(self, name: str, paths, colour: str) -> None:
        """Draw ``paths`` (k, T, >= 3) as lines under ``lfd/trails/name`` (replacing them).

        Only what changed is sent: a line already drawn with the same points and colour
        stays, new ones are added and lines no longer there are deleted.
        """
        import meshcat.geometry as mg

        node = self.vis[f"lfd/trails/{name}"]
        points = [self._check_path(p, columns=3)[:, :3].astype(np.float32) for p in paths]
        digests = [
            hashlib.blake2b(P.tobytes() + colour.encode(), digest_size=16).digest() for P in points
        ]
        old = self._trails.get(name, [])
        if not digests and old:
            node.delete()
        for j, (P, d) in enumerate(zip(points, digests, strict=True)):
            if j >= len(old) or old[j] != d:
                node[str(j)].set_object(
                    mg.Line(
                        mg.PointsGeometry(P.T),
                        mg.LineBasicMaterial(color=hex_colour(colour), linewidth=2),
                    )
                )
        if digests:
            for j in range(len(digests), len(old)):
                node[str(j)].delete()
        self._trails[name] = digests

    def animate(self, path, label: str = "", colour: str | None = None) -> AnimationInfo:
        """Animate the arm along ``path`` (T, 4) over :attr:`seconds` and draw its trail.

        The tool path goes through :meth:`tutor.robot.Arm.follow` (inverse kinematics
        from the start configuration); the fingers follow the hand column. It plays once
        by itself; :meth:`replay` plays it again. The viewer gets a few keys a second of
        the links that move (:mod:`tutor.views.scene_animation`), not every sample.

        Returns
        -------
        AnimationInfo
        """
        P = self._check_path(path, columns=4)
        T = len(P)
        if T < 2:
            raise InvalidParameterError("a path to animate needs at least 2 samples")
        arm = self._get_arm()
        track = arm.follow(
            P[:, :3], gripper=P[:, 3], q0=self.scene.start_configuration, check_collisions=False
        )
        fps = T / self.seconds  # 200 samples over 10 s: 20 samples per second
        every = np.arange(T) / fps
        keys = key_samples(T, every[-1])
        times = every[keys]
        clips: dict[str, list[Track]] = {}
        if self._robot is not None:
            placements = self._placements(track.qs[keys])  # (k, G, 4, 4)
            for g in np.flatnonzero(moving(placements)):
                name = self._robot.node_names[g]
                clips[self._node_path(name)] = transform_tracks(times, placements[:, g])
        hand = np.array([arm.fk(q)[0] for q in track.qs[keys]])
        clips[self._node_path("lfd/hand")] = [Track(".position", "vector3", times, hand)]
        closed = (P[:, 3] >= 0.5)[:, None]
        tiny, one = np.full(3, 1e-3), np.ones(3)
        # a scale track: one key per switch of the hand (open <-> closed)
        clips[self._node_path("lfd/hand/open")] = [
            step_track(".scale", "vector3", every, np.where(closed, tiny, one))
        ]
        clips[self._node_path("lfd/hand/closed")] = [
            step_track(".scale", "vector3", every, np.where(closed, one, tiny))
        ]
        self.draw_trails("animated", [P], colour or "#222222")
        self.recorder.send_packed("set_animation", "", pack_animation(clips, play=True))
        info = AnimationInfo(
            T, fps, (T - 1) / fps, label, bool(track.converged.all()), keys=len(keys)
        )
        self.animation = info
        return info

    def _node_path(self, name: str) -> str:
        """The full Meshcat path of ``name`` under this scene's root ("/meshcat/...")."""
        return self.vis[name].path.lower()

    def replay(self) -> bool:
        """Play the animated trajectory again from its start; False when there is none."""
        item = self.recorder.tree.animation
        if item is None:
            return False
        self.recorder.send_packed(*item)
        self.refresh()
        self._stamp_live()
        return True

    def clear_animation(self) -> None:
        """Stop any animation and put the robot back at the start configuration."""
        self.recorder.send_packed("set_animation", "", empty_animation())
        self.draw_trails("animated", [], "#222222")
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
            len(run.record.events),
            len(run.record.attempts),
            run.finished,
            tuple(np.asarray(status, dtype=object).ravel()),
        )
        if key == self._shown_key:  # e.g. the trainee only selected another plant
            return
        self.set_status(status)
        demos = [d[:, -4:] for d in session.demos]
        self.draw_trails("demos", demos, DEMO)
        rec = session.latest
        shown = np.zeros(0, int)
        if rec is not None:  # what the trainee may see: the run decides, as for the tray
            vis = run.visibility()
            shown = np.arange(len(task.conditions)) if vis.everything else vis.shown
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
        self._check_live()
        self.refresh()
        self._stamp_live()

    def _stamp_live(self) -> None:
        """Tell the live viewer that an update is complete: its page (the tutor's, see
        :mod:`tutor.views.meshcat_server`) records the number and the time it applied
        it (``document.body.dataset.updates`` and ``.appliedAt``)."""
        if self.recorder.live is None:
            return
        import umsgpack

        self._stamp += 1
        command = {
            "type": "set_property",
            "path": STAMP,
            "property": "update",
            "value": self._stamp,
        }
        self.recorder.forward("set_property", STAMP, umsgpack.packb(command))

    @staticmethod
    def _pick_plant(run, shown):
        rec = run.session.latest
        if rec is None or len(shown) == 0:
            return None
        tests = _tests_after(run, rec.n_demos)
        if tests and tests[-1].plants:
            return int(tests[-1].plants[-1])
        own = run.task.nearest_condition(run.session.conditions[-1])
        if own in set(int(p) for p in rec.shown):
            return int(own)
        failing = [int(p) for p in shown if not rec.passed[p]]
        return failing[0] if failing else int(shown[0])

    # ------------------------------------------------------------------ output

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
        chunks.append(frame_commands(rest))
        return chunks

    def static_html(self, title: str = "lfd-tutor: pick and place in 3-D") -> str:
        """The scene as one self-contained HTML page (meshcat's viewer script inside)."""
        chunks = self._scene_chunks()
        if self._robot is not None:  # its base64 is cached too
            chunks[0] = self._robot.chunk
        caption = html.escape(self.animation.label if self.animation else "")
        return page(title, scene_data(chunks), self.legend_html(), caption)

    def save_html(self, path) -> Path:
        """Write :meth:`static_html` to ``path`` (atomically); returns the path.

        Raises
        ------
        SaveError
            In plain words: a name or path too long, no permission, a full disk
            (:func:`tutor.fileio.atomic_write_text`).
        """
        return atomic_write_text(path, self.static_html())

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
        """The viewer widget: meshcat's page in a frame, from the live server (``src``) or
        fed over the widget's comm (``page``); both pass the guide's messages."""
        cls = viewer_widget_class()
        if self.mode == "live":
            url = live_page_url(self.recorder.web_url or "", self.scene_id)
            view = cls(height=self.height, src=url)
        else:
            view = cls(height=self.height, page=page("3-D view", "", "", ""))
            self.recorder.listeners.append(self._collect)
        view.on_msg(self._on_view_msg)
        return view

    def _collect(self, kind, path, packed) -> None:
        if self._pending is not None:  # a browser shows the view: keep what changes
            self._pending.append((kind, path, packed))

    def _on_view_msg(self, _widget, content, buffers) -> None:
        """A message from the page's view (:meth:`receive`). One the tutor does not
        understand is said in the caption and changes nothing (a refused guide message
        is answered, so that the page guides on); nothing raises out of here."""

        def act():
            try:
                self.receive(content, buffers)
            except InvalidPayloadError as exc:
                kind = content.get("type") if isinstance(content, dict) else None
                if self._guide is not None and kind in GUIDE_MESSAGES:
                    self._send_view(
                        {"type": "guide", "cmd": "refused", "what": kind, "words": str(exc)}
                    )
                raise

        def say(text: str) -> None:
            self.message = f"{text[:1].upper()}{text[1:]}" + ("" if text.endswith(".") else ".")
            self.refresh()

        safely(act, say)

    def receive(self, content, buffers=()) -> None:
        """Act on a message the page's view sent: a hello (a browser opened the view: the
        whole scene goes to it, then changes only) or the guide's move, end or cancel
        (:mod:`tutor.views.scene_guide`).

        Raises
        ------
        InvalidPayloadError
            A message the tutor does not know, or a guide message that is not one
            (:mod:`tutor.payloads`); nothing changes and guiding goes on.
        """
        kind = content.get("type") if isinstance(content, dict) else None
        if kind in GUIDE_MESSAGES:
            self._guide_message(kind, content, list(buffers or []))
            return
        view = check_view_message(content)
        if view is None:
            return
        if self.mode == "static":
            # a browser (re)opened the view: send it the whole scene, then changes only
            self._pending = []
            self._send_view({"type": "full", "to": view}, self._scene_chunks())
        if self._guide is not None:  # a reloaded page is armed again
            self._send_view(self._guide.start_message())

    def _send_view(self, content: dict, buffers=None) -> None:
        if self._view is not None:
            self._view.send(content, buffers)

    # ------------------------------------------------------------------ guiding the arm

    @property
    def guiding(self) -> bool:
        """Whether the trainee is guiding the arm in this view now."""
        return self._guide is not None

    def start_guide(self, follower, on_end, on_cancel=None) -> None:
        """Let the trainee guide the arm with the handle in the view (keys, mouse, gamepad).

        The animation stops and the robot goes to the follower's start; the page arms its
        guide. When the trainee presses Enter, ``on_end`` gets the recording
        (:class:`~tutor.views.scene_guide.GuideEnd`); Escape calls ``on_cancel``. After
        either, the view shows the arm at its start again.

        Parameters
        ----------
        follower : HandFollower
            :class:`tutor.robot.follow.HandFollower` of this scene.
        on_end : callable(GuideEnd)
        on_cancel : callable(), optional
        """
        from ..robot.follow import guide_limits

        sc = self.scene
        links = [self._node_path(n) for n in self._robot.node_names] if self._robot else []
        top = float(sc.table_center[2] + sc.table_size[2] / 2)
        guide = Guide(
            follower,
            on_end,
            on_cancel,
            links,
            self._node_path("lfd/hand"),
            guide_limits(sc),
            table=top,
        )
        self.clear_animation()
        self.show_configuration(guide.state.q)
        self._guide = guide
        self.refresh()
        self._stamp_live()
        self._send_view(guide.start_message())

    def stop_guide(self) -> None:
        """Stop guiding (no callback is called); the view shows the arm at its start."""
        if self._guide is None:
            return
        self._guide = None
        self._send_view({"type": "guide", "cmd": "stop"})
        self.show_configuration(self.scene.start_configuration)
        self.refresh()
        self._stamp_live()

    def _guide_message(self, kind: str, content: dict, buffers: list) -> None:
        guide = self._guide
        if guide is None:
            return  # a move still on its way when guiding stopped
        if kind == "guide-move":
            self._send_view(*guide.move(content))
        elif kind == "guide-end":
            end = guide.end(content, buffers)
            self.stop_guide()
            self.message = ""
            guide.on_end(end)
        else:
            self.stop_guide()
            if guide.on_cancel is not None:
                guide.on_cancel()

    def _flush(self) -> None:
        if self._pending:
            self._view.send({"type": "update"}, [frame_commands(self._pending)])
            self._pending = []

    def _caption_html(self) -> str:
        parts = [self.legend_html()]
        if self.animation is not None:
            parts.append(f"<div><b>Animated:</b> {html.escape(self.animation.label)}</div>")
        how = (
            "The attempt plays once by itself after each step; <b>Replay</b> plays it again. "
            "Drag to turn, right-drag to move; click the view, then scroll to zoom "
            "(Escape gives the wheel back to the page)."
        )
        if self.mode == "live" and self.recorder.web_url:
            url = html.escape(live_page_url(self.recorder.web_url, self.scene_id))
            how += f" <a href='{url}' target='_blank'>Open in its own tab</a>."
        parts.append(f"<div style='font-size:12px;color:#555'>{how}</div>")
        if self.message:
            parts.append(f"<div class='lfd-message'>{html.escape(self.message)}</div>")
        if self._working:
            parts.append(
                "<div class='lfd-working' role='status' style='font-weight:bold'>"
                f"&#8987; {html.escape(self._working)}</div>"
            )
        return "".join(parts)

    @property
    def widget(self):
        """The view as an ipywidget (caption, legend and the viewer)."""
        if self._widget is None:
            import ipywidgets as w

            self._caption = w.HTML()
            self.replay_button = w.Button(
                description="Replay",
                icon="play",
                tooltip="Play the robot's motion shown here again",
                layout=w.Layout(width="100px", flex="0 0 auto"),
            )
            self.replay_button.add_class("lfd-replay")
            self.replay_button.on_click(lambda _: self.replay())
            self._view = self._make_view()
            self._header = w.HBox([self.replay_button, self._caption])
            self._widget = w.VBox([self._header, self._view])
            self._widget.add_class("lfd-scene3d")
            self.refresh()
        return self._widget

    def refresh(self) -> None:
        """Update the widget: the caption (the :meth:`working` line goes), and the changes
        for the notebook viewer."""
        if self._widget is None:
            self._working = ""
            return
        was_working, self._working = self._working, ""
        self._caption.value = self._caption_html()
        if was_working and isinstance(self._view, viewer_widget_class()):
            self._view.send({"type": "working", "text": ""})
        self.replay_button.disabled = self.animation is None
        if self.mode == "static" and not self._view.src:
            self._flush()
        elif self.mode == "static":  # the live viewer died: switch to the notebook viewer
            self._view = self._make_view()
            self._widget.children = (self._header, self._view)

    def working(self, text: str = WORKING) -> None:
        """Say ``text`` over the view now (the caption's line and, in the notebook viewer,
        a line over the picture) until the next :meth:`refresh`.

        Call it before a slow step (a demonstration the robot learns from, a batch of
        tests): the line reaches the browser at once, while the step runs.

        Raises
        ------
        InvalidParameterError
            ``text`` is not a non-empty string of at most 200 characters.
        """
        if not (isinstance(text, str) and 0 < len(text.strip()) <= 200):
            raise InvalidParameterError(
                f"the working line must be a text of 1 to 200 characters, got {text!r}"
            )
        self._working = text.strip()
        self._show_working()

    @contextlib.contextmanager
    def busy(self, text: str = WORKING):
        """``with scene.busy(): ...``: :meth:`working` for the block; the line goes when
        the block ends, even if the block drew nothing (or raised)."""
        self.working(text)
        try:
            yield self
        finally:
            if self._working:
                self.refresh()

    def _show_working(self) -> None:
        if self._widget is None:
            return
        self._caption.value = self._caption_html()
        if isinstance(self._view, viewer_widget_class()):
            self._view.send({"type": "working", "text": self._working})

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


def _tests_after(run, n_demos: int | None = None) -> list:
    """The robot's tests the trainee asked for in ``run``'s current attempt, after
    ``n_demos`` demos (all of them when None): :class:`~tutor.framework.record.Test`
    records, read from the typed run record."""
    tests = run.attempt.tests
    return list(tests) if n_demos is None else [t for t in tests if t.after_demo == n_demos]
