r"""The pick-and-place scene of Experiment 2 in 3-D (Meshcat): robot, tray, bin, trails.

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
This one draws (:class:`Scene3D`: the scene, the robot, the plants' status colours,
trails, the animation). :class:`Scene3D` is one object whose parts share the recorder,
the scene's state and what was sent last (which lets it send only what changed); its
other jobs are in their own modules, two of them as mixins of the class:
:mod:`tutor.views.scene_widget` shows it (the notebook widget and its caption, the
page's messages, the working line, the static page); :mod:`tutor.views.scene_guide`
guides the arm with the trainee's hand; :mod:`tutor.views.scene_run` says what a
teaching run shows (the trails, the one animation); :mod:`tutor.views.meshcat_recorder`
records and replays the commands; :mod:`tutor.views.scene_animation` packs an
animation; :mod:`tutor.views.scene_meshes` holds the geometry (robot meshes, table,
tray, bin, plants, hand); :mod:`tutor.views.scene_page` chooses live or static and
builds the page and the notebook widget from the static files in
``tutor/views/static/``.

Shapes
------
path : (T, 4)
    x, y, z (m, robot base frame) and the hand g (0 open .. 1 closed) per sample.
status : (100,) of str
    "pass", "fail", "demo" or "unknown" per plant (index row * 10 + col).
"""

from __future__ import annotations

import hashlib
import uuid
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from .meshcat_recorder import SceneRecorder, empty_animation
from .scene_animation import (
    Track,
    key_samples,
    moving,
    pack_animation,
    step_track,
    transform_tracks,
)
from .scene_guide import Guide, GuidingMixin
from .scene_meshes import (
    HAND_CLOSED,
    HAND_OPEN,
    draw_fixtures,
    draw_hand,
    hex_colour,
    plant_balls,
    robot_meshes,
)
from .scene_page import choose_mode
from .scene_run import run_picture
from .scene_widget import SceneWidgetMixin
from .style import DEMO, FAIL, PASS, UNKNOWN

__all__ = [
    "Scene3D",
    "SceneRecorder",
    "AnimationInfo",
    "STATUS_COLOURS",
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


class Scene3D(GuidingMixin, SceneWidgetMixin):
    """The pick-and-place scene in Meshcat, refreshed by :class:`PickPlaceTutor`.

    It draws; showing it (the widget, :meth:`refresh`, :meth:`working`,
    :meth:`static_html`) is :class:`~tutor.views.scene_widget.SceneWidgetMixin`'s and
    guiding the arm (:meth:`start_guide`) :class:`~tutor.views.scene_guide.GuidingMixin`'s.

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
        if not (hasattr(task, "scene") and hasattr(task, "test_points")):
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
        self._status = np.full(len(task.test_points), "", dtype=object)
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
        self.set_status(np.full(len(task.test_points), "unknown", dtype=object))
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
        s = np.asarray(status, dtype=object).ravel()
        n = len(self.task.test_points)
        if s.shape != (n,):
            raise InvalidParameterError(f"status must have {n} entries, got shape {s.shape}")
        bad = sorted({str(v) for v in s if v not in STATUS_COLOURS})
        if bad:
            raise InvalidParameterError(
                f"unknown plant status {bad}; use one of {sorted(STATUS_COLOURS)}"
            )
        if (s != self._status).any():  # one object: the balls' colours are sent together
            colours = [STATUS_COLOURS[v] for v in s]
            self.vis["lfd/balls"].set_object(plant_balls(self.scene, colours))
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
        when the robot showed nothing (NF); :func:`tutor.views.scene_run.run_picture`
        chooses what to draw.
        """
        key = (
            id(run.session),
            len(run.record.events),
            len(run.record.attempts),
            run.finished,
            tuple(np.asarray(status, dtype=object).ravel()),
        )
        if key == self._shown_key:  # e.g. the trainee only selected another plant
            return
        self.set_status(status)
        picture = run_picture(run)
        for name, (paths, colour) in picture.trails.items():
            self.draw_trails(name, paths, colour)
        if picture.animation is not None:
            self.animate(*picture.animation)
        else:
            self.clear_animation()
        self._shown_key = key
        self._check_live()
        self.refresh()
        self._stamp_live()
