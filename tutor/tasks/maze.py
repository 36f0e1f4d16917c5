r"""Experiment 1 of Sena & Howard: point-to-point reaching through a 2-D maze.

Section "Experiment 1" of the paper. Notation:

X
    Admissible space: the 20 cm x 30 cm workspace minus two obstacle blocks.
I
    Start zone, a 20 cm x 6 cm rectangle at the bottom of X.
beta
    Target, a circle of 0.5 cm diameter.
B^
    The objective approximation of the task space: one test point per point
    of a 20 x 7 grid over I (|B^| = 140).

A state is :math:`\xi = (t, x, y)` with normalised time t in [0, 1]; positions
are in metres. The TP-GMM sees four frames per condition: the start point, the
target and the two obstacles (all axis-aligned), with K = 11 components.

The paper gives no obstacle positions; ours live in ``assets/maze.json`` (one
editable place) and are chosen so that teaching is not trivial: obstacle 1
juts in from the left wall and obstacle 2 from the right wall, so a start on
the left must first travel right, and demos from one side do not generalise to
the other.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from ..errors import InvalidDemoError, InvalidParameterError
from ..fileio import read_json
from ..framework.task import Reason, Task, Verdict, control_cost_entry
from ..resources import asset
from ..tpgmm import TPGMM, Frame, FrameBatch, check_demo
from ..tpgmm.checks import check_number
from .paths import minimum_jerk_through

__all__ = ["Box", "MazeLayout", "MazeTask", "load_layout", "DEFAULT_LAYOUT_PATH"]

DEFAULT_LAYOUT_PATH = asset("maze.json")
#: the jitter (m) of a scripted demo's guide points (the steadiest simulated hand)
SCRIPTED_JITTER = 0.002


@dataclass(frozen=True)
class Box:
    """Axis-aligned rectangle ``[x0, x1] x [y0, y1]`` in metres."""

    x0: float
    x1: float
    y0: float
    y1: float
    name: str = ""  #: in sentences ("obstacle 2 (right-hand)")
    label: str = ""  #: short, on pictures and in counts ("obstacle 2"); the name if unset

    @property
    def center(self) -> np.ndarray:
        return np.array([(self.x0 + self.x1) / 2, (self.y0 + self.y1) / 2])

    def contains(self, points) -> np.ndarray:
        """Boolean mask (...,) of points (..., 2) inside the closed box."""
        p = np.asarray(points, dtype=float)
        return (
            (p[..., 0] >= self.x0)
            & (p[..., 0] <= self.x1)
            & (p[..., 1] >= self.y0)
            & (p[..., 1] <= self.y1)
        )

    @classmethod
    def from_dict(cls, data: dict, name: str = "") -> Box:
        (x0, x1), (y0, y1) = data["x"], data["y"]
        full = data.get("name", name)
        return cls(float(x0), float(x1), float(y0), float(y1), full, data.get("label", full))


@dataclass(frozen=True)
class MazeLayout:
    """Geometry of the maze (see the module docstring for the symbols)."""

    workspace: Box
    start_zone: Box
    target_center: np.ndarray
    target_diameter: float
    obstacles: tuple[Box, ...]
    guide_points: np.ndarray
    grid_shape: tuple[int, int] = (20, 7)
    grid_margin: float = 0.005
    n_components: int = 11
    n_samples: int = 200
    control_cost: float = 1e-2

    @property
    def target_radius(self) -> float:
        return self.target_diameter / 2

    @cached_property
    def test_starts(self) -> np.ndarray:
        """The B^ grid over the start zone, shape (nx * ny, 2), row-major in y."""
        nx, ny = self.grid_shape
        m, z = self.grid_margin, self.start_zone
        xs = np.linspace(z.x0 + m, z.x1 - m, nx)
        ys = np.linspace(z.y0 + m, z.y1 - m, ny)
        gx, gy = np.meshgrid(xs, ys)
        return np.column_stack([gx.ravel(), gy.ravel()])

    def sample_starts(self, n: int, rng=None) -> np.ndarray:
        """``n`` start points drawn uniformly in I (inside the grid margin), shape (n, 2)."""
        rng = np.random.default_rng(rng)
        m, z = self.grid_margin, self.start_zone
        return np.column_stack(
            [rng.uniform(z.x0 + m, z.x1 - m, n), rng.uniform(z.y0 + m, z.y1 - m, n)]
        )

    def frames(self, start) -> list[Frame]:
        """Task frames for a start point: start, target, obstacle 1, obstacle 2."""
        eye = np.eye(2)
        return [
            Frame(eye, np.asarray(start, dtype=float)),
            Frame(eye, self.target_center),
            *(Frame(eye, obs.center) for obs in self.obstacles),
        ]

    def frame_batch(self, starts) -> FrameBatch:
        """Frames for many start points (B, 2) as one :class:`FrameBatch`."""
        starts = np.asarray(starts, dtype=float).reshape(-1, 2)
        B, P = starts.shape[0], 2 + len(self.obstacles)
        fixed = np.vstack([self.target_center, *(o.center for o in self.obstacles)])
        b = np.concatenate([starts[:, None, :], np.broadcast_to(fixed, (B, P - 1, 2))], axis=1)
        eye = np.broadcast_to(np.eye(2), (B, P, 2, 2)).copy()
        return FrameBatch(eye, eye.copy(), b)

    #: the blocks' free sizes and places, in the order of :meth:`with_blocks`
    BLOCK_NAMES = ("reach", "low", "height", "gap")

    @property
    def blocks(self) -> dict[str, float]:
        """The two wall blocks' free geometry (m): how far each juts in from its wall
        (``reach``), block 1's lower edge (``low``), each block's ``height`` and the
        ``gap`` between block 1's top and block 2's bottom."""
        one, two = self.obstacles
        return {
            "reach": float(one.x1 - one.x0),
            "low": float(one.y0),
            "height": float(one.y1 - one.y0),
            "gap": float(two.y0 - one.y1),
        }

    def with_blocks(self, reach=None, low=None, height=None, gap=None) -> MazeLayout:
        """This maze with its two wall blocks sized and placed anew (None: as now).

        The paper gives X, I and the target but not the two blocks' sizes or places; the
        calibration (:mod:`tutor.study.calibration`) chooses them. Block 1 keeps its
        left wall and block 2 its right one; both jut ``reach`` in and are ``height``
        high, block 1 from ``low`` up, block 2 ``gap`` above it. The guide points stay
        in the middle of the gaps at their distances from the blocks (1.5 cm below block
        1 and above block 2; 2 cm, or 0.4 of a narrower gap, between them), so the
        bundled values give the bundled layout back.

        Raises
        ------
        InvalidParameterError
            Not the paper's two wall blocks, a value that is not a finite number, or a
            maze no hand can pass: a side gap under 1 cm, a block under 1 cm high, a
            gap between blocks under 2 cm, block 1 within 1.5 cm of the start zone or
            block 2 within 3 cm of the target.
        """
        if len(self.obstacles) != 2 or len(self.guide_points) != 4:
            raise InvalidParameterError(
                "with_blocks needs the two wall blocks and four guide points of the "
                "paper's maze"
            )
        now = self.blocks
        given = dict(zip(self.BLOCK_NAMES, (reach, low, height, gap), strict=True))
        b = {
            k: now[k] if v is None else check_number(v, f"the blocks' {k} (m)")
            for k, v in given.items()
        }
        x0, x1 = self.workspace.x0, self.workspace.x1
        top = b["low"] + 2 * b["height"] + b["gap"]
        target_low = self.target_center[1] - self.target_radius
        problems = [
            (0.01 <= b["reach"] <= (x1 - x0) - 0.01, "the reach must leave a side gap of 1 cm"),
            (b["height"] >= 0.01, "each block must be at least 1 cm high"),
            (b["gap"] >= 0.02, "the gap between the blocks must be at least 2 cm"),
            (b["low"] >= self.start_zone.y1 + 0.015,
             "block 1 must start at least 1.5 cm above the start zone"),
            (top <= target_low - 0.03, "block 2 must end at least 3 cm below the target"),
        ]
        for ok, why in problems:
            if not ok:
                raise InvalidParameterError(
                    f"no hand can pass this maze: {why} (reach {b['reach']:.3g}, low "
                    f"{b['low']:.3g}, height {b['height']:.3g}, gap {b['gap']:.3g} m)"
                )
        one, two = self.obstacles
        y2 = b["low"] + b["height"] + b["gap"]
        one = dataclasses.replace(
            one, x0=x0, x1=x0 + b["reach"], y0=b["low"], y1=b["low"] + b["height"]
        )
        two = dataclasses.replace(two, x0=x1 - b["reach"], x1=x1, y0=y2, y1=y2 + b["height"])
        between = min(0.02, 0.4 * b["gap"])  # 2 cm off each block, less in a narrow gap
        guides = np.array(
            [
                [(x0 + b["reach"] + x1) / 2, one.y0 - 0.015],  # the gap right of block 1
                [(x0 + b["reach"] + x1) / 2, one.y1 + between],
                [(x0 + x1 - b["reach"]) / 2, two.y0 - between],  # the gap left of block 2
                [(x0 + x1 - b["reach"]) / 2, two.y1 + 0.015],
            ]
        )
        return dataclasses.replace(self, obstacles=(one, two), guide_points=guides)

    def reference_path(self, start, rng=None, jitter: float = 0.0, n_samples=None) -> np.ndarray:
        """A smooth scripted demonstration from ``start`` through the gaps to the target.

        Parameters
        ----------
        start : array-like (2,)
        rng : numpy Generator, optional
            Used when ``jitter`` > 0 to move the guide points.
        jitter : float
            Standard deviation (m) of the random offset of each guide point.
        n_samples : int, optional
            Number of samples, default ``self.n_samples``.

        Returns
        -------
        ndarray (n_samples, 3)
            Columns (t, x, y), t from 0 to 1, bell-shaped speed profile.
        """
        n = self.n_samples if n_samples is None else n_samples
        guides = self.guide_points
        if jitter > 0:
            rng = np.random.default_rng(rng)
            guides = guides + rng.normal(scale=jitter, size=guides.shape)
        pts = np.vstack([np.asarray(start, dtype=float), guides, self.target_center])
        xy = minimum_jerk_through(pts, n)
        tau = np.linspace(0.0, 1.0, n)
        return np.column_stack([tau, xy])

    def hand_stroke(self, start, rng, duration: float, *, jitter: float, tremor: float,
                    guides=None, end_shift=(0.0, 0.0), rate_hz: float = 80.0) -> np.ndarray:
        """A stroke from ``start`` as a hand draws it, recorded at ``rate_hz``.

        The scripted path (:meth:`reference_path` through ``guides``, default the
        layout's, each moved by ``jitter``) plus a smoothed tremor of standard deviation
        ``tremor`` (m) that fades out at both ends, and an ``end_shift`` (m) growing
        towards the end (a stroke that misses the target). The simulated teachers and
        the bundled demo sets draw their strokes here.

        Returns
        -------
        ndarray (n, 3)
            Columns (t in s, x, y in m), n = ``duration`` x ``rate_hz`` + 1.
        """
        n = int(duration * rate_hz) + 1
        scripted = self if guides is None else dataclasses.replace(
            self, guide_points=np.asarray(guides, dtype=float)
        )
        path = scripted.reference_path(start, rng, jitter=jitter, n_samples=n)
        s = path[:, 0]
        noise = rng.normal(scale=tremor, size=(n, 2))
        kernel = np.hanning(9) / np.hanning(9).sum()
        noise = np.column_stack([np.convolve(noise[:, i], kernel, mode="same") for i in (0, 1)])
        xy = path[:, 1:] + noise * np.sin(np.pi * s)[:, None] + np.outer(s**3, end_shift)
        return np.column_stack([s * duration, xy])


def load_layout(path=None) -> MazeLayout:
    """Read a maze layout from JSON (default: the bundled ``assets/maze.json``)."""
    path = DEFAULT_LAYOUT_PATH if path is None else Path(path)
    data = read_json(path, "maze layout")
    grid = data.get("test_grid", {})
    return MazeLayout(
        workspace=Box.from_dict(data["workspace"], "workspace"),
        start_zone=Box.from_dict(data["start_zone"], "start zone"),
        target_center=np.array(data["target"]["center"], dtype=float),
        target_diameter=float(data["target"]["diameter"]),
        obstacles=tuple(
            Box.from_dict(o, f"obstacle {i + 1}") for i, o in enumerate(data["obstacles"])
        ),
        guide_points=np.array(data["guide_points"], dtype=float),
        grid_shape=(int(grid.get("nx", 20)), int(grid.get("ny", 7))),
        grid_margin=float(grid.get("margin", 0.005)),
        n_components=int(data.get("n_components", 11)),
        n_samples=int(data.get("n_samples", 200)),
        control_cost=control_cost_entry(data, f"maze layout {path}", 1e-2),
    )


class MazeTask(Task):
    """Experiment 1 as a :class:`~tutor.framework.Task`.

    Conditions are start points (x, y) on the 20 x 7 grid over I. A trajectory
    (demo or realisation) is in B iff (i) every sample lies in X (inside the
    workspace, outside both obstacles), (ii) its first sample lies in I and
    (iii) its last sample lies in beta.

    Parameters
    ----------
    layout : MazeLayout, optional
        Defaults to the bundled ``assets/maze.json``.
    """

    name = "maze"
    # All admissible paths share the route after the first gap, so whole demos are
    # on average only ~1 cm apart even from distant starts; 6 mm marks real repeats.
    ambiguity_distance = 0.006
    point_noun = "start point"
    point_noun_plural = "start points"
    #: a recorded stroke shorter than this (m) is junk, not a demonstration
    min_path_length = 0.02

    def __init__(self, layout: MazeLayout | None = None):
        self.layout = load_layout() if layout is None else layout
        self._times = np.linspace(0.0, 1.0, self.layout.n_samples)
        self._test_points = self.layout.test_starts
        self._batch = self.layout.frame_batch(self._test_points)
        nx, ny = self.layout.grid_shape
        z, m = self.layout.start_zone, self.layout.grid_margin
        self._half_cell = np.array(
            [(z.x1 - z.x0 - 2 * m) / max(nx - 1, 1) / 2, (z.y1 - z.y0 - 2 * m) / max(ny - 1, 1) / 2]
        )

    @property
    def test_points(self) -> np.ndarray:
        return self._test_points

    @property
    def times(self) -> np.ndarray:
        return self._times

    def frames(self, point) -> list[Frame]:
        return self.layout.frames(point)

    def frame_batch(self, points) -> FrameBatch:
        if points is self._test_points:
            return self._batch
        return self.layout.frame_batch(points)

    def make_learner(self) -> TPGMM:
        return TPGMM(self.layout.n_components, warm_start=True)

    @property
    def control_cost(self) -> float:
        """The pen's tracking control cost (``control_cost`` in the layout file)."""
        return self.layout.control_cost

    def start_states(self, points) -> np.ndarray:
        """The pen starts at rest on the start point itself."""
        return np.asarray(points, dtype=float).reshape(-1, 2)

    def format_distance(self, distance: float) -> str:
        return f"{100 * distance:.1f} cm"

    def obstacle_name(self, index: int) -> str:
        return self.layout.obstacles[int(index)].name

    def scripted_demo(self, index: int, rng) -> np.ndarray:
        """:meth:`MazeLayout.reference_path` from start point ``index`` with
        :data:`SCRIPTED_JITTER` of hand jitter on its guide points."""
        return self.layout.reference_path(self.test_points[index], rng, jitter=SCRIPTED_JITTER)

    def test_point_of(self, demo: np.ndarray) -> np.ndarray:
        return np.asarray(demo)[0, 1:3]

    # ---------------------------------------------------------------- demos

    def preprocess(self, raw) -> np.ndarray:
        """Check a recording of (t, x, y) in metres and resample it to the layout's length.

        Rejects (with :class:`InvalidDemoError`) NaN/inf, fewer than 2 samples, a
        wrong number of columns, time that does not increase, coordinates that
        look like centimetres or millimetres, and strokes too short to be a
        demonstration. Positions outside the maze are accepted (the demo is then
        judged incorrect).
        """
        demo = check_demo(raw, "the demonstration", n_columns=3)
        xy = demo[:, 1:]
        ws = self.layout.workspace
        size = max(ws.x1 - ws.x0, ws.y1 - ws.y0)
        extent = float(np.abs(xy).max())
        if extent > 3 * size:
            unit = ""
            if extent <= 150 * size:
                unit = " It looks like centimetres: divide the positions by 100."
            elif extent <= 1500 * size:
                unit = " It looks like millimetres: divide the positions by 1000."
            raise InvalidDemoError(
                f"positions reach {extent:.4g}, far outside the "
                f"{100 * (ws.x1 - ws.x0):.0f} x {100 * (ws.y1 - ws.y0):.0f} cm maze; "
                f"positions must be in metres.{unit}"
            )
        length = float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum())
        if length < self.min_path_length:
            raise InvalidDemoError(
                f"the stroke is only {100 * length:.1f} cm long; a demonstration goes from "
                "the start zone to the target"
            )
        t = demo[:, 0]
        s = (t - t[0]) / (t[-1] - t[0])
        x = np.interp(self._times, s, xy[:, 0])
        y = np.interp(self._times, s, xy[:, 1])
        return np.column_stack([self._times, x, y])

    # ---------------------------------------------------------------- criteria

    def judge(self, trajectories: np.ndarray, points=None, context=None) -> Verdict:
        """Criteria (i)-(iii) for trajectories (B, T, 2), with the reason for each failure."""
        traj = np.asarray(trajectories, dtype=float)
        lay = self.layout
        in_obstacle = np.stack([o.contains(traj) for o in lay.obstacles])  # (O, B, T)
        outside = ~lay.workspace.contains(traj)
        bad_sample = outside | in_obstacle.any(axis=0)  # violates (i)
        starts_ok = lay.start_zone.contains(traj[:, 0])  # (ii)
        end_dist = np.linalg.norm(traj[:, -1] - lay.target_center, axis=1)
        ends_ok = end_dist <= lay.target_radius  # (iii)
        path_ok = ~bad_sample.any(axis=1)
        passed = path_ok & starts_ok & ends_ok
        causes = [()] * traj.shape[0]
        n_samples = traj.shape[1]
        for i in np.flatnonzero(~passed):
            parts = []
            if not starts_ok[i]:
                parts.append(Reason("start"))
            if not path_ok[i]:
                k = int(np.argmax(bad_sample[i]))
                hit = np.flatnonzero(in_obstacle[:, i, k])
                if hit.size:
                    parts.append(Reason("obstacle", k, n_samples, obstacle=int(hit[0])))
                else:
                    parts.append(Reason("outside", k, n_samples))
            if not ends_ok[i]:
                parts.append(Reason("end", distance=float(end_dist[i])))
            causes[i] = tuple(parts)
        return self.verdict(passed, causes)

    # ---------------------------------------------------------------- coverage

    def demonstrated(self, demo_points) -> np.ndarray:
        """Grid points within half a grid cell (in x and in y) of a demo's start."""
        starts = np.asarray(demo_points, dtype=float).reshape(-1, 2)
        gap = np.abs(self._test_points[:, None, :] - starts[None, :, :])  # (n, m, 2)
        return np.any(np.all(gap <= self._half_cell * (1 + 1e-9), axis=2), axis=1)

    def describe_where(self, mask) -> str:
        """Which part of the start zone holds most of the masked start points."""
        mask = np.asarray(mask, dtype=bool)
        if mask.all():
            return "everywhere in the start zone"
        if mask.mean() >= 0.8:
            return "almost everywhere in the start zone"
        pts = self._test_points[mask]
        if pts.size == 0:
            return "nowhere"
        z = self.layout.start_zone
        col = np.clip(((pts[:, 0] - z.x0) / (z.x1 - z.x0) * 3).astype(int), 0, 2)
        row = np.clip(((pts[:, 1] - z.y0) / (z.y1 - z.y0) * 2).astype(int), 0, 1)
        counts = np.zeros((2, 3), dtype=int)
        np.add.at(counts, (row, col), 1)
        cols = np.array(["left", "middle", "right"])
        rows = np.array(["bottom", "top"])
        by_col = counts.sum(axis=0)
        if by_col.max() >= 0.6 * len(pts):
            c = int(np.argmax(by_col))
            by_row = counts[:, c]
            side = f"{rows[int(np.argmax(by_row))]} " if by_row.max() >= 0.75 * by_row.sum() else ""
            return f"mostly {side}{cols[c]} of the start zone"
        return "spread across the start zone"
