"""Criterion (i), the admissible space X: a precomputed voxel map, or full IK checks.

Checking a whole realisation with IK and collision tests takes tens of milliseconds;
judging 100 realisations at every step of a session uses :class:`FeasibilityMap`
instead, a voxel map of X built by ``scripts/make_feasibility_map.py`` and bundled as
``tutor/assets/feasibility_map.npz``. :class:`FullCheck` follows every path with the
arm; :class:`MapCheck` uses the map inside its grid and the full check outside.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from ..compiled import compiled
from ..errors import InvalidFileError, InvalidParameterError
from ..resources import asset
from .arm import Arm
from .checks import check_paths, check_vector
from .model import DOWN, REACH_TOL, TILT_TOL
from .obstacles import check_boxes

__all__ = [
    "first_bad_sample",
    "FeasibilityMap",
    "FullCheck",
    "MapCheck",
    "default_map",
    "DEFAULT_MAP_PATH",
    "MAP_FORMAT",
    "MAP_VERSION",
]

DEFAULT_MAP_PATH = asset("feasibility_map.npz")
MAP_FORMAT = "lfd-tutor-feasibility-map"
MAP_VERSION = 1



def first_bad_sample(bad) -> np.ndarray:
    """Index of the first True along the last axis of ``bad`` (..., T); T when none."""
    bad = np.asarray(bad, dtype=bool)
    return np.where(bad.any(axis=-1), np.argmax(bad, axis=-1), bad.shape[-1])


class _PathCriterion:
    """What the three checks of criterion (i) share: a path is judged by its first
    sample outside X (:meth:`first_outside`, each check's own)."""

    def path_ok(self, paths, gripper=None) -> np.ndarray:
        """Whether every sample of each path (..., T, 3) is in X; bool (...)."""
        P, _ = check_paths(paths, gripper)
        return self.first_outside(P, gripper) == P.shape[-2]


def _known_bad(known_bad, shape) -> np.ndarray:
    """``known_bad`` as a bool array of the paths' sample shape (all False when None)."""
    if known_bad is None:
        return np.zeros(shape, dtype=bool)
    try:
        return np.broadcast_to(np.asarray(known_bad, dtype=bool), shape)
    except ValueError as exc:
        raise InvalidParameterError(
            f"known_bad must have shape {shape} like the paths' samples, got "
            f"{np.shape(known_bad)}"
        ) from exc


_FIRST_DOC = """Index of each path's first sample outside X or in ``known_bad``.

        A realisation is judged by its first failure (criterion (i) and the task's own
        criteria alike), so this is what a task needs; {how}

        Parameters
        ----------
        paths : array_like (..., T, 3)
            Tool positions (m, base frame).
        gripper : array_like (..., T), optional
            Hand command per sample (default open).
        known_bad : array_like of bool (..., T), optional
            Samples already known to fail for another reason (e.g. below the table).

        Returns
        -------
        ndarray of int (...)
            T for a path whose every sample is in X and not known bad.
        """

class FeasibilityMap(_PathCriterion):
    """A voxel map of X: where the tool can be, pointing down, reached and collision-free.

    Each voxel centre stores a signed margin (m): positive inside X. Near the border
    the margin is the smaller of the arm's clearance to obstacles and itself and
    ``REACH_TOL`` minus the IK error; away from the border it is only a sign. A point
    is in X when the trilinear interpolation of the margins is positive, which puts
    the border between voxel centres where the margins say, not half way. Points
    outside the grid are not in X.

    The map has two layers: fingers open (layer 0) and closed (layer 1). Without a
    hand command the open layer answers (the conservative choice: open fingers stick
    out further); with one, samples whose hand is closed (g >= 0.5) use layer 1.

    Parameters
    ----------
    margin : ndarray (nx, ny, nz) or (2, nx, ny, nz)
        Signed margin at the voxel centres ``origin + spacing * (i, j, k)``: one layer
        (used for both hand states) or the open and closed layers.
    origin : array_like (3,)
        Centre of voxel (0, 0, 0) (m).
    spacing : float
        Voxel edge (m).
    meta : dict, optional
        What the map was built for (robot, tool frame, obstacles, tolerances).
    """

    def __init__(self, margin, origin, spacing: float, meta: dict | None = None):
        m = np.asarray(margin, dtype=np.float32)
        if m.ndim == 3:
            m = np.stack([m, m])
        if m.ndim != 4 or m.shape[0] != 2 or min(m.shape[1:]) < 2:
            raise InvalidParameterError(
                f"margin must be a 3-D grid or two of them (2, nx, ny, nz), got shape {m.shape}"
            )
        if not np.all(np.isfinite(m)):
            raise InvalidParameterError("margin must be finite")
        self.margin = m
        self.origin = check_vector(origin, 3, "origin")
        self.spacing = float(spacing)
        if not (np.isfinite(self.spacing) and self.spacing > 0):
            raise InvalidParameterError(f"spacing must be positive, got {spacing!r}")
        self.shape = m.shape[1:]
        self.meta = dict(meta or {})
        self._flat = m.ravel()
        nx, ny, nz = self.shape
        self._layer = nx * ny * nz
        self._strides = np.array([ny * nz, nz, 1])
        self._cell_sign = self._cell_signs(m).ravel()

    def __repr__(self) -> str:
        return (
            f"FeasibilityMap({self.shape} voxels of {100 * self.spacing:g} cm from "
            f"{self.origin.round(3).tolist()} to {self.upper.round(3).tolist()}, "
            f"{self.feasible().mean():.0%} in X)"
        )

    @property
    def upper(self) -> np.ndarray:
        """Centre of the last voxel, shape (3,)."""
        return self.origin + self.spacing * (np.array(self.shape) - 1)

    @property
    def obstacles(self) -> tuple[tuple[str, tuple[float, ...], tuple[float, ...]], ...]:
        """The boxes the map was built for, to build a matching :class:`Arm`."""
        names = [str(n) for n in np.asarray(self.meta.get("obstacle_names", [])).reshape(-1)]
        centers = np.asarray(self.meta.get("obstacle_centers", np.zeros((0, 3)))).reshape(-1, 3)
        sizes = np.asarray(self.meta.get("obstacle_sizes", np.zeros((0, 3)))).reshape(-1, 3)
        return check_boxes(zip(names, centers, sizes, strict=True))

    def feasible(self, closed: bool = False) -> np.ndarray:
        """Voxel centres in X with the hand open (or closed), bool (nx, ny, nz)."""
        return self.margin[int(bool(closed))] > 0

    def grid_points(self) -> np.ndarray:
        """Voxel centres, shape (nx, ny, nz, 3)."""
        axes = [self.origin[i] + self.spacing * np.arange(self.shape[i]) for i in range(3)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    @staticmethod
    def _cell_signs(m: np.ndarray) -> np.ndarray:
        """Per voxel, the sign its cell's interpolation must have (2, nx, ny, nz), int8.

        The cell whose lowest corner is the voxel: +1 when all eight corner margins are
        positive, -1 when none is, 0 when they differ. The interpolation is a weighted
        sum of the corners with weights in [0, 1], one of each pair at least 1/2, so its
        sign is known exactly without computing it in the first two cases (no rounding
        can make a sum of positive terms zero or negative). Voxels on the grid's upper
        faces start no cell (0).
        """
        low = m[:, :-1, :-1, :-1]
        high = low.copy()
        for dx in (0, 1):
            for dy in (0, 1):
                for dz in (0, 1):
                    corner = m[:, dx:m.shape[1] - 1 + dx, dy:m.shape[2] - 1 + dy,
                               dz:m.shape[3] - 1 + dz]
                    low = np.minimum(low, corner)
                    high = np.maximum(high, corner)
        sign = np.zeros(m.shape, dtype=np.int8)
        sign[:, :-1, :-1, :-1] = np.where(low > 0, 1, np.where(high <= 0, -1, 0))
        return sign

    def _points(self, points, gripper):
        """The checked points (n, 3), their shape and each one's hand command (n,)."""
        P = np.asarray(points, dtype=float)
        if P.ndim < 1 or P.shape[-1] != 3:
            raise InvalidParameterError(f"points must have shape (..., 3), got {P.shape}")
        shape = P.shape[:-1]
        P = np.ascontiguousarray(P.reshape(-1, 3))
        if gripper is None:
            return P, shape, np.zeros(len(P))
        try:
            g = np.broadcast_to(np.asarray(gripper, dtype=float), shape).reshape(-1)
        except ValueError as exc:
            raise InvalidParameterError(
                f"gripper must have shape {shape} like the points, got {np.shape(gripper)}"
            ) from exc
        return P, shape, np.ascontiguousarray(g)

    @property
    def _grid(self) -> tuple:
        """What the compiled lookups need of the map (see :func:`_status`)."""
        return (
            self.origin,
            self.spacing,
            np.array(self.shape, dtype=np.int64),
            self._strides.astype(np.int64),
            self._layer,
            self._flat,
            self._cell_sign,
        )

    def value(self, points, gripper=None) -> np.ndarray:
        """Interpolated margin (m) at ``points`` (..., 3); -inf outside the grid.

        Parameters
        ----------
        points : array_like (..., 3)
        gripper : array_like (...), optional
            Hand command per point (0 open .. 1 closed); default open.

        Returns
        -------
        ndarray (...) of float
        """
        P, shape, g = self._points(points, gripper)
        return _values(P, g, *self._grid).reshape(shape)

    def _positive(self, points, gripper=None):
        """``value(points, gripper) > 0`` (...) exactly, interpolating only in the cells
        whose corners disagree (see :meth:`_cell_signs`), and whether each point is off
        the grid (...)."""
        P, shape, g = self._points(points, gripper)
        positive, inside = _positives(P, g, *self._grid)
        return positive.reshape(shape), ~inside.reshape(shape)

    def contains(self, points, gripper=None) -> np.ndarray:
        """Whether each point (..., 3) is in X (tool pointing down).

        Parameters
        ----------
        points : array_like (..., 3)
            Tool positions (m, base frame).
        gripper : array_like (...), optional
            Hand command per point (0 open .. 1 closed). Without it the fingers are
            taken open, which is never less strict than closed.

        Returns
        -------
        ndarray (...) of bool
        """
        return self._positive(points, gripper)[0]

    def first_outside(self, paths, gripper=None, known_bad=None) -> np.ndarray:
        # no reach: every off-grid sample is outside X
        P, _, (first, _, _) = self._scan(paths, gripper, known_bad, np.zeros(3), -1.0)
        return first.reshape(P.shape[:-2])

    def _scan(self, paths, gripper, known_bad, shoulder, reach):
        """The checked paths P (..., T, 3) and hands G (..., T), and the compiled scan's
        (first, redo, first_known) per path, flattened (see _scan_paths)."""
        P, G = check_paths(paths, gripper)
        known = _known_bad(known_bad, P.shape[:-1])
        T = P.shape[-2]
        scan = _scan_paths(
            np.ascontiguousarray(P.reshape(-1, T, 3)),
            np.ascontiguousarray(G.reshape(-1, T)),
            np.ascontiguousarray(known.reshape(-1, T)),
            *self._grid,
            shoulder,
            reach,
        )
        return P, G, scan

    first_outside.__doc__ = _FIRST_DOC.format(how="a lookup.")


    def matches(
        self,
        obstacles,
        robot: str = "panda",
        tool_frame: str = "panda_hand_tcp",
        atol: float = 1e-6,
    ) -> bool:
        """Whether the map was built for these obstacles, robot and tool frame."""
        boxes = check_boxes(obstacles)
        meta = self.meta
        if meta.get("robot") != robot or meta.get("tool_frame") != tool_frame:
            return False
        names = list(meta.get("obstacle_names", []))
        if sorted(names) != sorted(b[0] for b in boxes):
            return False
        centers = np.asarray(meta["obstacle_centers"]).reshape(-1, 3)
        sizes = np.asarray(meta["obstacle_sizes"]).reshape(-1, 3)
        for name, c, s in boxes:
            k = names.index(name)
            if not (np.allclose(centers[k], c, atol=atol) and np.allclose(sizes[k], s, atol=atol)):
                return False
        return True

    # ------------------------------------------------------------------ files

    def save(self, path) -> None:
        """Write the map as a compressed ``.npz`` (plain arrays only, no pickle)."""
        meta = self.meta
        names = list(meta.get("obstacle_names", []))
        np.savez_compressed(
            path,
            format=np.array(MAP_FORMAT),
            version=np.array(MAP_VERSION),
            margin=self.margin,
            origin=self.origin,
            spacing=np.array(self.spacing),
            robot=np.array(meta.get("robot", "panda")),
            tool_frame=np.array(meta.get("tool_frame", "panda_hand_tcp")),
            obstacle_names=np.array(names, dtype=str).reshape(-1),
            obstacle_centers=np.asarray(meta.get("obstacle_centers", np.zeros((0, 3))), float),
            obstacle_sizes=np.asarray(meta.get("obstacle_sizes", np.zeros((0, 3))), float),
            rotation=np.asarray(meta.get("rotation", DOWN), float),
            reach_tol=np.array(float(meta.get("reach_tol", REACH_TOL))),
            tilt_tol=np.array(float(meta.get("tilt_tol", TILT_TOL))),
        )

    @classmethod
    def load(cls, path=None) -> FeasibilityMap:
        """Read a map written by :meth:`save` (default: ``assets/feasibility_map.npz``).

        Raises
        ------
        InvalidFileError
            The file is missing, not a map, of another version, or malformed.
        """
        path = DEFAULT_MAP_PATH if path is None else Path(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
        except FileNotFoundError as exc:
            raise InvalidFileError(
                f"no feasibility map at {path}; build it with scripts/make_feasibility_map.py"
            ) from exc
        except (OSError, ValueError, EOFError) as exc:
            raise InvalidFileError(f"{path} is not a readable feasibility map: {exc}") from exc
        needed = {"format", "version", "margin", "origin", "spacing"}
        if not needed <= set(arrays) or str(arrays["format"]) != MAP_FORMAT:
            raise InvalidFileError(f"{path} is not an lfd-tutor feasibility map")
        if int(arrays["version"]) != MAP_VERSION:
            raise InvalidFileError(
                f"{path} is a version {int(arrays['version'])} map; this tutor reads "
                f"version {MAP_VERSION}: rebuild it with scripts/make_feasibility_map.py"
            )
        meta = {
            k: (str(v) if v.dtype.kind == "U" and v.ndim == 0 else v)
            for k, v in arrays.items()
            if k not in needed
        }
        try:
            return cls(arrays["margin"], arrays["origin"], float(arrays["spacing"]), meta)
        except InvalidParameterError as exc:
            raise InvalidFileError(f"{path}: {exc}") from exc


@lru_cache(maxsize=2)
def _load_map(path: str) -> FeasibilityMap:
    return FeasibilityMap.load(path)


def default_map(obstacles, robot: str = "panda", tool_frame: str = "panda_hand_tcp", path=None):
    """The bundled :class:`FeasibilityMap` (read once per process), checked against a scene.

    Parameters
    ----------
    obstacles : sequence of (name, center (3,), size (3,))
        The scene's boxes (:func:`scene_obstacles`).
    robot, tool_frame : str
    path : path, optional
        Another map file (default :data:`DEFAULT_MAP_PATH`).

    Raises
    ------
    InvalidParameterError
        The map was built for other obstacles, robot or tool frame (the scene was
        edited): rebuild it, or judge with :class:`FullCheck`.
    """
    fmap = _load_map(str(DEFAULT_MAP_PATH if path is None else Path(path)))
    if not fmap.matches(obstacles, robot, tool_frame):
        raise InvalidParameterError(
            "the feasibility map was built for another scene (table, tray, bin or robot "
            "differ): rebuild it with 'python scripts/make_feasibility_map.py', or use the "
            "slower full check (feasibility='full')"
        )
    return fmap


class FullCheck(_PathCriterion):
    """Criterion (i) at full fidelity: :meth:`Arm.follow` along every path.

    Same interface as :meth:`FeasibilityMap.contains`, so a task can use either; this
    one runs inverse kinematics and a collision check at every sample (about 20-30 ms
    per 200-sample path), the map a lookup.

    Parameters
    ----------
    arm : Arm
        The arm with the scene's obstacles.
    """

    def __init__(self, arm: Arm):
        self.arm = arm

    def __repr__(self) -> str:
        return f"FullCheck({self.arm!r})"

    def contains(self, points, gripper=None) -> np.ndarray:
        """Whether the arm reaches each sample of each path without collision.

        Parameters
        ----------
        points : array_like (..., T, 3)
            Paths; each is followed from the start configuration, warm-starting IK
            from the previous sample as the robot would move.
        gripper : array_like (..., T), optional
            Hand command per sample (default open).

        Returns
        -------
        ndarray (..., T) of bool
        """
        P, G = check_paths(points, gripper)
        shape = P.shape[:-1]
        paths = P.reshape(-1, shape[-1], 3)
        G = G.reshape(paths.shape[:2])
        out = np.empty(paths.shape[:2], dtype=bool)
        for i, (path, g) in enumerate(zip(paths, G, strict=True)):
            tr = self.arm.follow(path, g)
            out[i] = tr.converged & ~tr.collision
        return out.reshape(shape)

    def first_outside(self, paths, gripper=None, known_bad=None) -> np.ndarray:
        P, G = check_paths(paths, gripper)
        shape = P.shape[:-2]
        T = P.shape[-2]
        limit = first_bad_sample(_known_bad(known_bad, P.shape[:-1])).reshape(-1)
        paths, G = P.reshape(-1, T, 3), G.reshape(-1, T)
        rows = zip(paths, G, limit, strict=True)
        out = np.array([self.first_problem(p, g, n) for p, g, n in rows])
        return out.reshape(shape).astype(int)

    first_outside.__doc__ = _FIRST_DOC.format(
        how="each path is followed only up to its first problem or known-bad sample."
    )

    def first_problem(self, path, gripper, limit: int) -> int:
        """The first problem of the arm along ``path[:limit]`` (``limit`` when none)."""
        if limit <= 0:
            return 0
        tr = self.arm.follow(path[:limit], gripper[:limit], stop_at_problem=True)
        return limit if tr.first_problem is None else tr.first_problem



class MapCheck(_PathCriterion):
    """Criterion (i) fast: the feasibility map inside its grid, :class:`FullCheck` outside.

    The map covers where realisations usually go; a realisation that leaves the grid
    (models taught with one or two demos swing wide) but stays within the arm's reach
    is followed with full IK and collision checks instead of being called outside X.
    Samples beyond ``reach`` of ``shoulder`` are outside X without further checks, and
    so are off-grid samples after a path's first sample the map rejects (a path is
    judged by its first failure).

    Parameters
    ----------
    fmap : FeasibilityMap
    arm : Arm
        The arm with the scene's obstacles (the same the map was built for).
    shoulder : array_like (3,)
        Centre of the sphere the tool can reach pointing down (m): the Panda's
        shoulder (joint 2 at z = 0.333 m) less the 0.103 m from its flange down to
        the tool centre point.
    reach : float
        Radius of that sphere (m): the flange stays within 0.858 m of the shoulder
        (measured over 20 000 random configurations), plus a little margin.
    """

    def __init__(self, fmap: FeasibilityMap, arm: Arm, shoulder=(0.0, 0.0, 0.23), reach=0.87):
        self.map = fmap
        self.full = FullCheck(arm)
        self.shoulder = check_vector(shoulder, 3, "shoulder")
        self.reach = float(reach)

    def __repr__(self) -> str:
        return f"MapCheck({self.map!r})"

    def contains(self, points, gripper=None) -> np.ndarray:
        """Whether the arm reaches each sample of each path without collision.

        Parameters
        ----------
        points : array_like (..., T, 3)
        gripper : array_like (..., T), optional
            Hand command per sample (default open).

        Returns
        -------
        ndarray (..., T) of bool
        """
        P, G = check_paths(points, gripper)
        out, unknown = self._lookup(P, G)
        # a path is judged by its first sample outside X: follow it in full only when
        # an unknown sample comes before any the map already rejects
        redo = first_bad_sample(unknown) < first_bad_sample(~out & ~unknown)  # (...)
        if redo.any():
            idx = np.nonzero(redo)
            out[idx] = self.full.contains(P[idx], G[idx])
        return out

    def _lookup(self, P, G) -> tuple[np.ndarray, np.ndarray]:
        """Whether the map says each sample (..., T) is in X, and the samples it cannot
        answer: off its grid but within the arm's reach."""
        in_x, off = self.map._positive(P, G)
        unknown = off.reshape(-1)
        if unknown.any():  # only the off-grid samples need the distance to the shoulder
            rows = np.flatnonzero(unknown)
            flat = P.reshape(-1, 3)
            unknown[rows] = np.linalg.norm(flat[rows] - self.shoulder, axis=-1) <= self.reach
        return in_x, unknown.reshape(off.shape)

    def first_outside(self, paths, gripper=None, known_bad=None) -> np.ndarray:
        P, G, (first, redo, first_known) = self.map._scan(
            paths, gripper, known_bad, self.shoulder, self.reach
        )
        T = P.shape[-2]
        # an off-grid sample the arm may reach comes first: follow the path in full,
        # from the start up to its first known-bad sample
        flat_P, flat_G = P.reshape(-1, T, 3), G.reshape(-1, T)
        for i in np.flatnonzero(redo):
            first[i] = self.full.first_problem(flat_P[i], flat_G[i], int(first_known[i]))
        return first.reshape(P.shape[:-2])

    first_outside.__doc__ = _FIRST_DOC.format(
        how="the map answers inside its grid; a path with an off-grid sample the arm "
        "may reach before any failure is followed in full."
    )


# ---------------------------------------------------------------- compiled lookups
# One sample at a time, in the same arithmetic as the map's definition (trilinear
# interpolation of float32 margins in float64), so that a path's scan can stop at its
# first failure: judging 100 realisations then reads only the samples up to each
# one's first failure instead of all of them.


@compiled
def _cell(x, y, z, g, origin, spacing, dims, strides, layer):
    """Whether (x, y, z) is on the grid, its cell's flat index (in its hand's layer)
    and its place in the cell."""
    ux = (x - origin[0]) / spacing
    uy = (y - origin[1]) / spacing
    uz = (z - origin[2]) / spacing
    inside = (
        ux >= -1e-6
        and ux <= dims[0] - 1 + 1e-6
        and uy >= -1e-6
        and uy <= dims[1] - 1 + 1e-6
        and uz >= -1e-6
        and uz <= dims[2] - 1 + 1e-6
    )  # NaN is outside
    if not inside:
        return False, 0, 0.0, 0.0, 0.0
    ux = min(max(ux, 0.0), dims[0] - 1)
    uy = min(max(uy, 0.0), dims[1] - 1)
    uz = min(max(uz, 0.0), dims[2] - 1)
    ix = min(int(ux), dims[0] - 2)
    iy = min(int(uy), dims[1] - 2)
    iz = min(int(uz), dims[2] - 2)
    base = ix * strides[0] + iy * strides[1] + iz * strides[2]
    if g >= 0.5:
        base += layer
    return True, base, ux - ix, uy - iy, uz - iz


@compiled
def _interpolated(flat, base, fx, fy, fz, strides):
    """The trilinear interpolation of the margins in cell ``base`` at (fx, fy, fz)."""
    sx, sy, sz = strides[0], strides[1], strides[2]
    gx, gy, gz = 1 - fx, 1 - fy, 1 - fz
    c00 = flat[base] * gz + flat[base + sz] * fz
    c01 = flat[base + sy] * gz + flat[base + sy + sz] * fz
    c10 = flat[base + sx] * gz + flat[base + sx + sz] * fz
    c11 = flat[base + sx + sy] * gz + flat[base + sx + sy + sz] * fz
    return (c00 * gy + c01 * fy) * gx + (c10 * gy + c11 * fy) * fx


@compiled
def _in_x(base, fx, fy, fz, flat, sign, strides):
    """An on-grid sample's interpolated margin > 0, interpolating only where its cell's
    corners disagree (:meth:`FeasibilityMap._cell_signs`)."""
    s = sign[base]
    if s != 0:
        return s > 0
    return _interpolated(flat, base, fx, fy, fz, strides) > 0


@compiled
def _values(P, g, origin, spacing, dims, strides, layer, flat, sign):
    out = np.empty(P.shape[0])
    for n in range(P.shape[0]):
        inside, base, fx, fy, fz = _cell(
            P[n, 0], P[n, 1], P[n, 2], g[n], origin, spacing, dims, strides, layer
        )
        out[n] = _interpolated(flat, base, fx, fy, fz, strides) if inside else -np.inf
    return out


@compiled
def _positives(P, g, origin, spacing, dims, strides, layer, flat, sign):
    positive = np.zeros(P.shape[0], dtype=np.bool_)
    on_grid = np.zeros(P.shape[0], dtype=np.bool_)
    for n in range(P.shape[0]):
        inside, base, fx, fy, fz = _cell(
            P[n, 0], P[n, 1], P[n, 2], g[n], origin, spacing, dims, strides, layer
        )
        on_grid[n] = inside
        if inside:
            positive[n] = _in_x(base, fx, fy, fz, flat, sign, strides)
    return positive, on_grid


@compiled
def _scan_paths(P, G, known, origin, spacing, dims, strides, layer, flat, sign, shoulder, reach):
    """Per path (B, T): its first sample outside X or known bad (T when none), whether
    an off-grid sample within ``reach`` of ``shoulder`` comes before it (the map cannot
    answer: the path is to be followed in full) and its first known-bad sample."""
    B, T = known.shape
    first = np.empty(B, dtype=np.int64)
    redo = np.zeros(B, dtype=np.bool_)
    first_known = np.full(B, T, dtype=np.int64)
    for b in range(B):
        for t in range(T):
            if known[b, t]:
                first_known[b] = t
                break
        first[b] = first_known[b]
        for t in range(first_known[b]):
            x, y, z = P[b, t, 0], P[b, t, 1], P[b, t, 2]
            inside, base, fx, fy, fz = _cell(
                x, y, z, G[b, t], origin, spacing, dims, strides, layer
            )
            if inside:
                if _in_x(base, fx, fy, fz, flat, sign, strides):
                    continue
                first[b] = t
                break
            dx, dy, dz = x - shoulder[0], y - shoulder[1], z - shoulder[2]
            if np.sqrt(dx * dx + dy * dy + dz * dz) <= reach:  # numpy's norm, term by term
                redo[b] = True
                break
            first[b] = t
            break
    return first, redo, first_known
