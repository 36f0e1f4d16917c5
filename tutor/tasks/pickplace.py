r"""Experiment 2 of Sena & Howard: pick a plant from a 10 x 10 tray and drop it in a bin.

Section "Experiment 2" of the paper. Notation:

B^
    One test point per plant (|B^| = 100); a condition is the plant's index.
X
    The admissible space: the gripper path is reachable (inverse kinematics
    succeeds) without self-collision or collision with the table, tray or bin.
delta_g, delta_r
    Grab and release thresholds: the mean grab (release) distance in the demo set
    plus 2 standard deviations plus 1 mm.

A state is :math:`\xi = (t, x, y, z, g)`: normalised time, the gripper (tool centre
point) position in the robot base frame in metres, and the hand g (1 closed, 0 open).
The gripper keeps pointing down, so orientation is not part of the state. The TP-GMM
sees three frames per condition: the start pose, the target plant and the bin. The
paper used K = 7; the tutor uses 9 (see ``_learner`` in ``assets/pickplace.json``,
where the scene and the learner settings live).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from ..compiled import compiled
from ..errors import InvalidDemoError, InvalidParameterError
from ..fileio import read_json
from ..framework.task import Reason, Task, Verdict, control_cost_entry
from ..resources import asset
from ..robot.feasibility import first_bad_sample
from ..tpgmm import TPGMM, Frame, FrameBatch, check_demo
from . import kinesthetic

__all__ = ["PickPlaceScene", "PickPlaceTask", "load_scene", "start_position", "DEFAULT_SCENE_PATH"]

DEFAULT_SCENE_PATH = asset("pickplace.json")


@dataclass(frozen=True)
class PickPlaceScene:
    """Geometry of the pick-and-place scene (metres, robot base frame)."""

    robot: str
    tool_frame: str
    start_configuration: np.ndarray  # (nq,)
    table_center: np.ndarray
    table_size: np.ndarray
    tray_center: np.ndarray
    tray_size: np.ndarray
    rows: int
    cols: int
    pitch: float
    grasp_height: float  # grasp point above the tray top
    plant_height: float
    plant_radius: float
    bin_center: np.ndarray
    bin_size: np.ndarray
    bin_wall: float
    release_height: float  # release point height (z)
    generalisation_plants: tuple[tuple[int, int], ...]
    n_components: int = 9
    reg_covar: float = 1e-4
    warm_start: bool = False
    n_samples: int = 200
    control_cost: float = 1e-4
    realisation_seconds: float = 25.0
    run_seconds: float = 900.0

    @property
    def tray_top(self) -> float:
        return float(self.tray_center[2] + self.tray_size[2] / 2)

    @cached_property
    def plant_positions(self) -> np.ndarray:
        """Grasp points of the plants, shape (rows * cols, 3), index = row * cols + col."""
        r, c = np.meshgrid(np.arange(self.rows), np.arange(self.cols), indexing="ij")
        x = self.tray_center[0] + (r.ravel() - (self.rows - 1) / 2) * self.pitch
        y = self.tray_center[1] + (c.ravel() - (self.cols - 1) / 2) * self.pitch
        z = np.full(x.shape, self.tray_top + self.grasp_height)
        return np.column_stack([x, y, z])

    @property
    def release_point(self) -> np.ndarray:
        """Where the plant is released: above the bin's centre, shape (3,)."""
        return np.array([self.bin_center[0], self.bin_center[1], self.release_height])

    def plant_index(self, row: int, col: int) -> int:
        return int(row) * self.cols + int(col)

    @property
    def generalisation_indices(self) -> np.ndarray:
        """The paper's generalisation sampling set: 4 corner plants and the centre one."""
        return np.array([self.plant_index(r, c) for r, c in self.generalisation_plants])


def load_scene(path=None) -> PickPlaceScene:
    """Read the scene from JSON (default: the bundled ``assets/pickplace.json``)."""
    path = DEFAULT_SCENE_PATH if path is None else Path(path)
    data = read_json(path, "pick-and-place scene")
    tray, plant, bin_ = data["tray"], data["plant"], data["bin"]
    arr = np.asarray
    return PickPlaceScene(
        robot=data["robot"],
        tool_frame=data["tool_frame"],
        start_configuration=arr(data["start_configuration"], float),
        table_center=arr(data["table"]["center"], float),
        table_size=arr(data["table"]["size"], float),
        tray_center=arr(tray["center"], float),
        tray_size=arr(tray["size"], float),
        rows=int(tray["rows"]),
        cols=int(tray["cols"]),
        pitch=float(tray["pitch"]),
        grasp_height=float(plant["grasp_height"]),
        plant_height=float(plant["height"]),
        plant_radius=float(plant["radius"]),
        bin_center=arr(bin_["center"], float),
        bin_size=arr(bin_["size"], float),
        bin_wall=float(bin_["wall"]),
        release_height=float(bin_["release_height"]),
        generalisation_plants=tuple(tuple(p) for p in data["generalisation_plants"]),
        n_components=int(data.get("n_components", 9)),
        reg_covar=float(data.get("reg_covar", 1e-4)),
        warm_start=bool(data.get("warm_start", False)),
        n_samples=int(data.get("n_samples", 200)),
        control_cost=control_cost_entry(data, f"pick-and-place scene {path}", 1e-4),
        realisation_seconds=float(data.get("realisation_seconds", 25.0)),
        run_seconds=float(data.get("run_seconds", 900.0)),
    )


# --- the task ------------------------------------------------------------------------------

GRAB_LEVEL = 0.5  # the hand counts as closed when g >= 0.5


#: Positions (m) beyond this are not metres: the arm reaches about 0.9 m.
MAX_EXTENT = 3.0


def _unit_hint(extent: float) -> str:
    """Which unit positions reaching ``extent`` (> MAX_EXTENT) were probably given in.

    A recording in metres reaches 0.5 to 0.9 m (the start pose, the tray and the bin),
    so in centimetres it reaches 50 to 90 and in millimetres 500 to 900; anything
    beyond a millimetre reading of :data:`MAX_EXTENT` gets no guess.
    """
    if extent <= 100 * MAX_EXTENT:
        return " It looks like centimetres: divide the positions by 100."
    if extent <= 1000 * MAX_EXTENT:
        return " It looks like millimetres: divide the positions by 1000."
    return ""


def _first(mask: np.ndarray) -> np.ndarray:
    """Index of the first True along the last axis, or -1 where there is none."""
    idx = np.argmax(mask, axis=-1)
    return np.where(mask.any(axis=-1), idx, -1)


def start_position(scene: PickPlaceScene) -> np.ndarray:
    """The tool centre point at the start configuration (:meth:`Arm.fk`), shape (3,)."""
    from ..robot import get_arm, scene_obstacles

    arm = get_arm(scene_obstacles(scene), scene.robot, scene.tool_frame)
    return arm.fk(scene.start_configuration)[0]


class PickPlaceTask(Task):
    """Experiment 2 as a :class:`~tutor.framework.Task`.

    Conditions are the plants' grasp points (100, 3). A trajectory (T, 4) of
    (x, y, z, g) is in B iff (i) it stays in X (above the table and tray, and
    inside the arm's collision-free reachable workspace when a feasibility map is
    given), (ii) the hand closes within delta_g of the plant and (iii) opens again
    within delta_r of the release point over the bin.

    Parameters
    ----------
    scene : PickPlaceScene, optional
    feasibility : object with ``contains(points (..., 3)) -> bool (...)``, optional
        The arm's reachable, collision-free workspace (see :mod:`tutor.robot`).
    """

    name = "pickplace"
    point_noun = "plant"
    point_noun_plural = "plants"
    ambiguity_distance = 0.01
    #: a recording whose gripper path is shorter than this (m) is junk
    min_path_length = 0.05

    def __init__(self, scene: PickPlaceScene | None = None, feasibility="map"):
        self.scene = load_scene() if scene is None else scene
        self.feasibility = self._feasibility(feasibility)
        self.start = start_position(self.scene)
        self._times = np.linspace(0.0, 1.0, self.scene.n_samples)
        self._frame_rows: dict[bytes, tuple[Frame, ...]] = {}
        self._test_points = self.scene.plant_positions
        self._batch = self.frame_batch(self._test_points)

    def _feasibility(self, how):
        from ..robot import FullCheck, MapCheck, default_map, get_arm, scene_obstacles

        sc = self.scene
        if isinstance(how, str):
            boxes = scene_obstacles(sc)
            if how == "map":
                fmap = default_map(boxes, sc.robot, sc.tool_frame)
                return MapCheck(fmap, get_arm(boxes, sc.robot, sc.tool_frame))
            if how == "full":
                return FullCheck(get_arm(boxes, sc.robot, sc.tool_frame))
            raise InvalidParameterError(
                f"feasibility must be 'map', 'full', None or a checker, got {how!r}"
            )
        if how is not None and not callable(getattr(how, "contains", None)):
            raise InvalidParameterError(
                "feasibility must have a contains(points, gripper) method, "
                f"got {type(how).__name__}"
            )
        return how

    @property
    def test_points(self) -> np.ndarray:
        return self._test_points

    @property
    def times(self) -> np.ndarray:
        return self._times

    def frames(self, point) -> list[Frame]:
        point = np.asarray(point, float)
        key = point.tobytes()
        row = self._frame_rows.get(key)
        # frames are immutable, so each plant's are made once: a refit needs every demo's,
        # and checking a frame takes a singular value decomposition
        if row is None:
            eye = np.eye(4)
            pad = [0.0]
            row = (
                Frame(eye, np.r_[self.start, pad]),
                Frame(eye, np.r_[point, pad]),
                Frame(eye, np.r_[self.scene.release_point, pad]),
            )
            if len(self._frame_rows) < 1024:
                self._frame_rows[key] = row
        return list(row)

    def frame_batch(self, points) -> FrameBatch:
        if points is getattr(self, "_test_points", None) and hasattr(self, "_batch"):
            return self._batch
        plants = np.asarray(points, float).reshape(-1, 3)
        B = plants.shape[0]
        b = np.zeros((B, 3, 4))
        b[:, 0, :3] = self.start
        b[:, 1, :3] = plants
        b[:, 2, :3] = self.scene.release_point
        eye = np.broadcast_to(np.eye(4), (B, 3, 4, 4)).copy()
        return FrameBatch(eye, eye.copy(), b)

    #: the tool point (x, y, z) moves; the hand (g) is a command
    moving_dims = 3

    @property
    def control_cost(self) -> float:
        """The tool point's tracking control cost (``control_cost`` in the scene file)."""
        return self.scene.control_cost

    def start_states(self, points) -> np.ndarray:
        """Every attempt starts with the tool point at the arm's start pose, at rest."""
        return np.broadcast_to(self.start, (len(np.asarray(points).reshape(-1, 3)), 3)).copy()

    def commands(self, modelled) -> np.ndarray:
        """The hand opens and closes as the model says, within its range (0 open, 1 closed)."""
        return np.clip(modelled, 0.0, 1.0)

    def make_learner(self) -> TPGMM:
        sc = self.scene
        return TPGMM(sc.n_components, reg_covar=sc.reg_covar, warm_start=sc.warm_start)

    def format_distance(self, distance: float) -> str:
        return f"{100 * distance:.1f} cm"

    def test_point_of(self, demo) -> np.ndarray:
        """The plant nearest to where the hand first closes (when no choice was recorded)."""
        demo = np.asarray(demo)
        k = _first(demo[:, 4] >= GRAB_LEVEL)
        grab = demo[k if k >= 0 else len(demo) // 2, 1:4]
        return self._test_points[self.nearest_test_point(grab)].copy()

    def plant_name(self, index: int) -> str:
        r, c = divmod(int(index), self.scene.cols)
        return f"plant ({r + 1}, {c + 1})"

    def point_name(self, index: int) -> str:
        return self.plant_name(index)

    # ---------------------------------------------------------------- demos

    def preprocess(self, raw) -> np.ndarray:
        """Check a recording (t, x, y, z, g) in seconds and metres; resample to T samples."""
        demo = check_demo(raw, "the demonstration", n_columns=5)
        xyz, g = demo[:, 1:4], demo[:, 4]
        extent = float(np.abs(xyz).max())
        if extent > MAX_EXTENT:
            raise InvalidDemoError(
                f"positions reach {extent:.4g}, beyond the arm's reach of about 0.9 m; positions "
                f"must be in metres.{_unit_hint(extent)}"
            )
        if g.min() < -1e-6 or g.max() > 1 + 1e-6:
            raise InvalidDemoError(
                "the hand column (last) must be between 0 (open) and 1 (closed), "
                f"got values from {g.min():.3g} to {g.max():.3g}"
            )
        length = float(np.linalg.norm(np.diff(xyz, axis=0), axis=1).sum())
        if length < self.min_path_length:
            raise InvalidDemoError(
                f"the gripper moved only {100 * length:.1f} cm; a demonstration carries a plant "
                "from the tray to the bin"
            )
        t = demo[:, 0]
        s = (t - t[0]) / (t[-1] - t[0])
        cols = [np.interp(self._times, s, demo[:, j]) for j in range(1, 5)]
        return np.column_stack([self._times, *cols])

    def scripted_demo(self, index: int, rng) -> np.ndarray:
        """:meth:`demonstrate` to plant ``index`` with no mistake."""
        return self.demonstrate(int(index), rng)

    def demonstrate(self, plant: int, rng=None, mistake: str | None = None, rate_hz=20.0):
        """A kinesthetic-style demonstration to ``plant`` as a person would give it.

        See :func:`tutor.tasks.kinesthetic.demonstrate` (the simulated teacher's hand:
        via points, variability, tremor and the mistakes it can make).

        Returns
        -------
        ndarray (T, 5)
            t (s), x, y, z (m), g (0 open, 1 closed).
        """
        return kinesthetic.demonstrate(self.scene, self.start, plant, rng, mistake, rate_hz)

    @staticmethod
    def duration(raw) -> float:
        """How long a recorded demonstration took (s): it costs the teacher that much time."""
        t = np.asarray(raw, float)[:, 0]
        return float(t[-1] - t[0])

    # ---------------------------------------------------------------- criteria

    def _events(self, traj):
        """Grab and release sample indices (B,), -1 when missing."""
        hand = np.ascontiguousarray(np.asarray(traj, float)[..., 3].reshape(-1, np.shape(traj)[-2]))
        return _hand_events(hand, GRAB_LEVEL)

    def criteria_context(self, demos, points) -> dict:
        """delta_g and delta_r: mean demo distance + 2 std + 1 mm (right-plant demos only)."""
        traj = np.array([d[:, 1:] for d in demos])
        grab, release = self._events(traj)
        rows = np.arange(len(demos))
        grab_d = np.linalg.norm(traj[rows, np.maximum(grab, 0), :3] - points, axis=1)
        rel_d = np.linalg.norm(
            traj[rows, np.maximum(release, 0), :3] - self.scene.release_point, axis=1
        )
        grabbed_at = traj[rows, np.maximum(grab, 0), :3]
        nearest = np.array([self.nearest_test_point(p) for p in grabbed_at])
        own = np.array([self.nearest_test_point(c) for c in points])
        use_g = (grab >= 0) & (nearest == own)
        use_r = release >= 0

        def rule(d, use):
            d = d[use]
            return float(d.mean() + 2 * d.std() + 0.001) if d.size else 0.001

        return {"delta_g": rule(grab_d, use_g), "delta_r": rule(rel_d, use_r)}

    def judge(self, trajectories, points, context=None) -> Verdict:
        traj = np.ascontiguousarray(trajectories, dtype=float)
        ctx = context or {"delta_g": 0.01, "delta_r": 0.02}
        pos = traj[..., :3]
        sc = self.scene
        bad, grab, release, grab_d, rel_d = _path_facts(
            traj,
            np.ascontiguousarray(np.broadcast_to(np.asarray(points, float), (len(traj), 3))),
            np.asarray(sc.tray_center, float),
            np.asarray(sc.tray_size, float) / 2,
            np.asarray(sc.release_point, float),
            GRAB_LEVEL,
        )
        n = traj.shape[1]
        if self.feasibility is None:
            first_bad = first_bad_sample(bad)
        else:  # a path is judged by its first failure: the arm is followed up to it
            first_bad = self.feasibility.first_outside(pos, traj[..., 3], known_bad=bad)
        path_ok = first_bad == n
        grab_ok = (grab >= 0) & (grab_d <= ctx["delta_g"])
        rel_ok = (release >= 0) & (rel_d <= ctx["delta_r"])
        passed = path_ok & grab_ok & rel_ok
        causes = [()] * len(traj)
        for i in np.flatnonzero(~passed):
            parts = []
            if not path_ok[i]:
                k = int(first_bad[i])
                kind = _failure_kind(pos[i, k], sc)
                parts.append(Reason(kind, k, n))
            if grab[i] < 0:
                parts.append(Reason("no_grab"))
            elif not grab_ok[i]:
                parts.append(Reason("grab", distance=float(grab_d[i])))
            if grab[i] >= 0 and release[i] < 0:
                parts.append(Reason("no_release"))
            elif grab[i] >= 0 and not rel_ok[i]:
                parts.append(Reason("release", distance=float(rel_d[i])))
            causes[i] = tuple(parts)
        return self.verdict(passed, causes)

    def judge_demo(self, demo, point, context=None) -> Verdict:
        """A demo is correct when it grabs the chosen plant and releases over the bin."""
        traj = np.asarray(demo)[None, :, 1:]
        grab, release = self._events(traj)
        sc = self.scene
        chosen = self.nearest_test_point(point)
        parts = []
        if (traj[0, :, 2] < 0.0).any():
            parts.append(Reason("table"))
        if grab[0] < 0:
            parts.append(Reason("no_grab"))
        else:
            grabbed = self.nearest_test_point(traj[0, grab[0], :3])
            off = np.linalg.norm(traj[0, grab[0], :3] - sc.plant_positions[grabbed])
            if grabbed != chosen:
                parts.append(Reason("wrong_plant", plant=int(grabbed), chosen=int(chosen)))
            elif off > sc.pitch / 2:
                parts.append(Reason("grab", distance=float(off)))
            if release[0] < 0:
                parts.append(Reason("no_release"))
            else:
                p = traj[0, release[0], :3]
                inside = np.all(np.abs(p[:2] - sc.bin_center[:2]) <= sc.bin_size[:2] / 2)
                if not inside:
                    parts.append(Reason("outside_bin"))
        return self.verdict([not parts], [tuple(parts)])

    # ---------------------------------------------------------------- coverage

    def demonstrated(self, demo_points) -> np.ndarray:
        mask = np.zeros(len(self._test_points), dtype=bool)
        for c in np.asarray(demo_points, float).reshape(-1, 3):
            mask[self.nearest_test_point(c)] = True
        return mask

    def describe_where(self, mask) -> str:
        mask = np.asarray(mask, dtype=bool)
        if mask.all():
            return "all over the tray"
        if mask.mean() >= 0.8:
            return "almost all over the tray"
        idx = np.flatnonzero(mask)
        if idx.size == 0:
            return "nowhere"
        r, c = np.divmod(idx, self.scene.cols)
        near = np.mean(r < self.scene.rows / 2)
        left = np.mean(c >= self.scene.cols / 2)  # larger y is the robot's left
        words = []
        if near >= 0.75 or near <= 0.25:
            words.append("near" if near >= 0.75 else "far")
        if left >= 0.75 or left <= 0.25:
            words.append("left" if left >= 0.75 else "right")
        if not words:
            return "spread over the tray"
        return f"mostly on the {' '.join(words)} side of the tray (seen from the robot)"


# ---------------------------------------------------------------- compiled criteria
# What judging 100 realisations needs of each path, in one pass per path (numpy's
# arithmetic, term by term: the same verdicts); the reasons are then worded only for
# the paths that fail.


def _failure_kind(position, scene) -> str:
    """Why a path's first bad sample at ``position`` (3,) is bad: below the table, in
    the tray, or (neither) out of the arm's reach or in collision."""
    if position[2] < 0.0:
        return "table"
    if np.all(np.abs(position - scene.tray_center) <= scene.tray_size / 2):
        return "tray"
    return "unreachable"


@compiled
def _first_grab_release(hand, level):
    """The first sample with the hand closed (-1: none) and the first open after it."""
    T = hand.shape[0]
    for grab in range(T):
        if hand[grab] >= level:
            for release in range(grab + 1, T):
                if not hand[release] >= level:
                    return grab, release
            return grab, -1
    return -1, -1


@compiled
def _hand_events(hand, level):
    """Grab and release indices (B,) of hand commands (B, T); -1 when missing."""
    B = hand.shape[0]
    grab = np.empty(B, dtype=np.int64)
    release = np.empty(B, dtype=np.int64)
    for b in range(B):
        grab[b], release[b] = _first_grab_release(hand[b], level)
    return grab, release


@compiled
def _distance(x, y, z, point):
    dx, dy, dz = x - point[0], y - point[1], z - point[2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)  # numpy's norm, term by term


@compiled
def _path_facts(traj, points, tray_center, half, release_point, level):
    """Per path of ``traj`` (B, T, 4): samples below the table or in the tray (B, T),
    grab and release indices (B,) and their distances to the path's plant and to the
    release point (B,), taken at sample 0 when the event is missing."""
    B, T = traj.shape[0], traj.shape[1]
    bad = np.empty((B, T), dtype=np.bool_)
    grab = np.empty(B, dtype=np.int64)
    release = np.empty(B, dtype=np.int64)
    grab_d = np.empty(B)
    rel_d = np.empty(B)
    for b in range(B):
        for t in range(T):
            x, y, z = traj[b, t, 0], traj[b, t, 1], traj[b, t, 2]
            bad[b, t] = z < 0.0 or (
                abs(x - tray_center[0]) <= half[0]
                and abs(y - tray_center[1]) <= half[1]
                and abs(z - tray_center[2]) <= half[2]
            )
        g, r = _first_grab_release(traj[b, :, 3], level)
        grab[b], release[b] = g, r
        g, r = max(g, 0), max(r, 0)
        grab_d[b] = _distance(traj[b, g, 0], traj[b, g, 1], traj[b, g, 2], points[b])
        rel_d[b] = _distance(traj[b, r, 0], traj[b, r, 1], traj[b, r, 2], release_point)
    return bad, grab, release, grab_d, rel_d
