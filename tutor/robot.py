r"""The robot arm: Pinocchio kinematics and collision checks on example-robot-data models.

The paper's Experiment 2 used a 7-DoF Sawyer; example-robot-data has none, so the
tutor uses the Franka Panda (7 arm joints + 2 finger joints, nq = 9, tool frame
``panda_hand_tcp``), the nearest 7-DoF arm it ships.

This module sits beside :mod:`tutor.tasks` and never imports it: the task passes its
geometry in as plain boxes.

Notation
--------
q : ndarray (nq,)
    A configuration: 7 arm joint angles (rad) then the 2 finger openings (m, 0 .. 0.04
    each; 0.04 is open). Inverse kinematics moves only the arm joints.
p, R : ndarray (3,), ndarray (3, 3)
    Position (m) and rotation of the tool frame (the tool centre point between the
    fingertips) in the robot base frame: x forward, y left, z up, table top at z = 0.
DOWN : ndarray (3, 3)
    The tool rotation at the start configuration :data:`START_CONFIGURATION`: the
    gripper points straight down with the fingers opening along y. Every position
    target keeps this rotation unless told otherwise.
g : float in [0, 1]
    The hand command: 0 open, 1 closed. A finger sits at ``0.04 * (1 - g)`` m.
box : (name, center (3,), size (3,))
    An environment obstacle, an axis-aligned box in the base frame (metres); ``size``
    is the full edge lengths.
X
    The admissible space of the paper: tool positions the arm reaches with the tool
    pointing down, within :data:`REACH_TOL`, without touching itself or a box.

Inverse kinematics is damped least squares on the 6-D frame error
:math:`e = (p^* - p,\ \log(R^* R^\top))` with the LOCAL_WORLD_ALIGNED Jacobian
:math:`J` (6 x 7):

.. math:: \Delta q = J^\top (J J^\top + \lambda^2 I)^{-1} e + (I - J^+ J)\, k\,(q_{rest} - q),

the second term (in the null space of the tool task) pulling the elbow gently
towards the start posture so that a position has one preferred configuration
whichever way it is approached. The update is added to q and clipped to the joint
limits.

Checking a whole realisation with IK and collision tests takes tens of milliseconds;
judging 100 realisations at every step of a session uses :class:`FeasibilityMap`
instead, a precomputed voxel map of X built by ``scripts/make_feasibility_map.py``.

An :class:`Arm` holds Pinocchio ``Data`` that every call overwrites: use one arm per
thread.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import lru_cache
from os.path import join
from pathlib import Path

import numpy as np

from .errors import InvalidFileError, InvalidParameterError
from .resources import asset

__all__ = [
    "load_robot",
    "srdf_path",
    "Arm",
    "get_arm",
    "IKResult",
    "Tracking",
    "FeasibilityMap",
    "FullCheck",
    "MapCheck",
    "check_paths",
    "default_map",
    "open_box",
    "scene_obstacles",
    "START_CONFIGURATION",
    "DOWN",
    "REACH_TOL",
    "TILT_TOL",
    "FINGER_OPEN",
    "DEFAULT_MAP_PATH",
]

#: The scene's start configuration (also in ``assets/pickplace.json``), shape (9,).
START_CONFIGURATION = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785, 0.04, 0.04])
START_CONFIGURATION.setflags(write=False)

#: Tool rotation at :data:`START_CONFIGURATION` (forward kinematics of the Panda):
#: pointing straight down, fingers along y. ``tests/test_robot.py`` checks the values.
_YAW = np.pi / 4 - 0.785  # joint 7 of the start configuration is 0.785, not pi / 4
DOWN = np.array(
    [
        [np.cos(_YAW), np.sin(_YAW), 0.0],
        [np.sin(_YAW), -np.cos(_YAW), 0.0],
        [0.0, 0.0, -1.0],
    ]
)
DOWN.setflags(write=False)

#: A path sample is reached when the tool is within this distance of it (m).
REACH_TOL = 0.005
#: ... and the tool tilts (or turns) less than this from the target rotation (rad).
TILT_TOL = 0.05
#: Opening of one finger joint with the hand open (m); closed is 0.
FINGER_OPEN = 0.04

DEFAULT_MAP_PATH = asset("feasibility_map.npz")
MAP_FORMAT = "lfd-tutor-feasibility-map"
MAP_VERSION = 1


@lru_cache(maxsize=4)
def load_robot(name: str = "panda"):
    """The example-robot-data model ``name`` as a RobotWrapper, loaded once per process."""
    import example_robot_data

    return example_robot_data.load(name)


def srdf_path(name: str = "panda") -> str:
    """Path of the SRDF file (disabled collision pairs) of the example-robot-data robot."""
    from example_robot_data.robots_loader import ROBOTS, getModelPath

    if name not in ROBOTS:
        raise InvalidParameterError(f"unknown robot {name!r}; choose one of {sorted(ROBOTS)}")
    loader = ROBOTS[name]
    if not loader.srdf_filename:
        raise InvalidParameterError(f"robot {name!r} has no SRDF file, so no collision filter")
    urdf = join(loader.path, loader.urdf_subpath, loader.urdf_filename)
    return join(getModelPath(urdf), loader.path, loader.srdf_subpath, loader.srdf_filename)


# --------------------------------------------------------------------------- inputs


def _vector(x, n: int, what: str) -> np.ndarray:
    """``x`` as a finite float array of shape (n,), or a named error."""
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{what} must be {n} numbers, got {x!r}") from exc
    if a.shape != (n,):
        raise InvalidParameterError(f"{what} must have shape ({n},), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InvalidParameterError(f"{what} must be finite, got {a}")
    return a


def _rotation(R) -> np.ndarray:
    try:
        a = np.asarray(R, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"rotation must be a 3 x 3 matrix, got {R!r}") from exc
    if a.shape != (3, 3) or not np.all(np.isfinite(a)):
        raise InvalidParameterError(f"rotation must be a finite 3 x 3 matrix, got shape {a.shape}")
    if np.abs(a.T @ a - np.eye(3)).max() > 1e-6 or np.linalg.det(a) < 0:
        raise InvalidParameterError("rotation must be a rotation matrix (orthonormal, det +1)")
    return a


def _boxes(obstacles) -> tuple[tuple[str, tuple[float, ...], tuple[float, ...]], ...]:
    """Validated, hashable obstacle boxes ``((name, center, size), ...)``."""
    if obstacles is None:
        return ()
    out, names = [], set()
    try:
        items = list(obstacles)
    except TypeError as exc:
        raise InvalidParameterError(
            "obstacles must be a sequence of (name, center (3,), size (3,)) boxes"
        ) from exc
    for item in items:
        try:
            name, center, size = item
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(
                f"an obstacle must be (name, center (3,), size (3,)), got {item!r}"
            ) from exc
        if not isinstance(name, str) or not name:
            raise InvalidParameterError(f"an obstacle's name must be a non-empty string: {name!r}")
        if name in names:
            raise InvalidParameterError(f"two obstacles are called {name!r}; names must differ")
        names.add(name)
        c = _vector(center, 3, f"the centre of obstacle {name!r}")
        s = _vector(size, 3, f"the size of obstacle {name!r}")
        if np.any(s <= 0):
            raise InvalidParameterError(f"obstacle {name!r} needs positive edge lengths, got {s}")
        out.append((name, tuple(map(float, c)), tuple(map(float, s))))
    return tuple(out)


def open_box(name: str, center, size, wall: float) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """An open-topped box (a bin) as five obstacle boxes: a floor and four walls.

    Parameters
    ----------
    name : str
        Prefix of the parts' names (``name``, ``name wall -x``, ...). The floor takes
        the plain name.
    center, size : array_like (3,)
        The bin's outer bounding box (m).
    wall : float
        Wall and floor thickness (m).

    Returns
    -------
    list of (name, center (3,), size (3,))
    """
    c = _vector(center, 3, f"the centre of {name!r}")
    s = _vector(size, 3, f"the size of {name!r}")
    if not (0 < wall < min(s) / 2):
        raise InvalidParameterError(f"wall thickness of {name!r} must be in (0, {min(s) / 2})")
    lo, hi = c - s / 2, c + s / 2
    parts = [(name, np.r_[c[:2], lo[2] + wall / 2], np.r_[s[:2], wall])]
    for axis, label in ((0, "x"), (1, "y")):
        for sign in (-1, 1):
            wc = c.copy()
            wc[axis] = (lo if sign < 0 else hi)[axis] - sign * wall / 2
            ws = s.copy()
            ws[axis] = wall
            parts.append((f"{name} wall {'-' if sign < 0 else '+'}{label}", wc, ws))
    return parts


def scene_obstacles(scene) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The boxes of a pick-and-place scene: table, tray and the bin (floor + 4 walls).

    Parameters
    ----------
    scene : object
        Anything with ``table_center``, ``table_size``, ``tray_center``, ``tray_size``,
        ``bin_center``, ``bin_size`` (3,) and ``bin_wall`` (m), such as
        :class:`tutor.tasks.pickplace.PickPlaceScene` (duck-typed: this module does not
        import the tasks).

    Returns
    -------
    list of (name, center (3,), size (3,))
    """
    try:
        return [
            ("table", np.asarray(scene.table_center, float), np.asarray(scene.table_size, float)),
            ("tray", np.asarray(scene.tray_center, float), np.asarray(scene.tray_size, float)),
            *open_box("bin", scene.bin_center, scene.bin_size, float(scene.bin_wall)),
        ]
    except AttributeError as exc:
        raise InvalidParameterError(f"not a pick-and-place scene: {exc}") from exc


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class IKResult:
    """Outcome of one inverse-kinematics solve.

    Attributes
    ----------
    q : ndarray (nq,)
        The configuration found (within the joint limits).
    position_error : float
        Distance from the tool to the target (m).
    rotation_error : float
        Angle between the tool's and the target rotation (rad).
    converged : bool
        Both errors below the solver's tolerances.
    iterations : int
    """

    q: np.ndarray
    position_error: float
    rotation_error: float
    converged: bool
    iterations: int = 0


@dataclass(frozen=True)
class Tracking:
    """The arm following a tool path (:meth:`Arm.follow`).

    Attributes
    ----------
    qs : ndarray (T, nq)
        Configuration at each sample.
    errors : ndarray (T,)
        Tool position error (m).
    rotation_errors : ndarray (T,)
        Tool rotation error (rad).
    converged : ndarray (T,) of bool
        Sample reached: position within ``reach_tol`` and rotation within ``tilt_tol``.
    collision : ndarray (T,) of bool
        The arm touches itself or an obstacle.
    at_limit : ndarray (T,) of bool
        Some arm joint sits at a joint limit.
    first_problem : int or None
        First sample not reached or in collision.
    reason : str
        What went wrong first, in plain words ("" when nothing did).
    """

    qs: np.ndarray
    errors: np.ndarray
    rotation_errors: np.ndarray
    converged: np.ndarray
    collision: np.ndarray
    at_limit: np.ndarray
    first_problem: int | None
    reason: str

    @property
    def ok(self) -> bool:
        """Every sample reached without collision."""
        return self.first_problem is None


def _geom_link(name: str) -> str:
    """Link name of a collision geometry ('panda_link7_0' -> 'panda_link7')."""
    return re.sub(r"_\d+$", "", name)


def _box_shape(size):
    try:
        import coal

        return coal.Box(*size)
    except ImportError:  # pin < 3.4 ships hpp-fcl instead of coal
        import hppfcl

        return hppfcl.Box(*size)


# --------------------------------------------------------------------------- the arm


class Arm:
    """A robot arm with a tool frame and box obstacles: FK, IK, collisions, path following.

    Parameters
    ----------
    robot : str
        example-robot-data name (default ``"panda"``).
    tool_frame : str
        Frame controlled by :meth:`ik` and :meth:`follow`.
    obstacles : sequence of (name, center (3,), size (3,))
        Axis-aligned boxes in the base frame (m). Every robot geometry that moves is
        checked against every box; geometries fixed to the base (``panda_link0``, which
        stands on the table) are not.
    q_rest : array_like (nq,), optional
        Posture the null-space term pulls towards (default :data:`START_CONFIGURATION`).

    Notes
    -----
    The kinematic model is shared with :func:`load_robot` (loaded once per process);
    the collision model is this arm's own copy. Self-collision pairs are all pairs
    minus those the robot's SRDF disables (neighbouring links).
    """

    def __init__(
        self, robot: str = "panda", tool_frame: str = "panda_hand_tcp", obstacles=(), *, q_rest=None
    ):
        import pinocchio as pin

        self._pin = pin
        self.robot_name = robot
        self.obstacles = _boxes(obstacles)
        srdf = srdf_path(robot)  # also checks the name
        wrapper = load_robot(robot)
        self.model = model = wrapper.model
        if not model.existFrame(tool_frame):
            raise InvalidParameterError(f"robot {robot!r} has no frame {tool_frame!r}")
        self.tool_frame = tool_frame
        self.frame_id = model.getFrameId(tool_frame)
        self.data = model.createData()
        self.nq = model.nq
        self.n_arm = 7 if robot == "panda" else model.nv
        self.lower = model.lowerPositionLimit.copy()
        self.upper = model.upperPositionLimit.copy()
        self.joint_names = list(model.names)[1:]
        self.q_rest = (
            START_CONFIGURATION.copy()
            if q_rest is None and robot == "panda"
            else pin.neutral(model)
            if q_rest is None
            else _vector(q_rest, self.nq, "q_rest")
        )

        geom = wrapper.collision_model.copy()
        geom.removeAllCollisionPairs()
        geom.addAllCollisionPairs()
        pin.removeCollisionPairs(model, geom, srdf, False)
        self.n_self_pairs = len(geom.collisionPairs)
        moving = [i for i, o in enumerate(geom.geometryObjects) if o.parentJoint != 0]
        for name, center, size in self.obstacles:
            placement = pin.SE3(np.eye(3), np.array(center))
            gid = geom.addGeometryObject(pin.GeometryObject(name, 0, placement, _box_shape(size)))
            for i in moving:
                geom.addCollisionPair(pin.CollisionPair(i, gid))
        self.geom_model = geom
        self.geom_data = geom.createData()
        self._pair_names = [
            (
                _geom_link(geom.geometryObjects[p.first].name),
                _geom_link(geom.geometryObjects[p.second].name),
            )
            for p in geom.collisionPairs
        ]

    def __repr__(self) -> str:
        names = ", ".join(n for n, _, _ in self.obstacles) or "none"
        return f"Arm({self.robot_name!r}, tool={self.tool_frame!r}, obstacles: {names})"

    # ------------------------------------------------------------------ helpers

    def _q(self, q, what: str = "q") -> np.ndarray:
        return _vector(q, self.nq, what)

    def fingers(self, gripper: float) -> float:
        """Finger joint opening (m) for the hand command ``gripper`` (0 open .. 1 closed)."""
        return FINGER_OPEN * (1.0 - min(max(float(gripper), 0.0), 1.0))

    # ------------------------------------------------------------------ kinematics

    def fk(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Tool frame pose at ``q``.

        Parameters
        ----------
        q : array_like (nq,)

        Returns
        -------
        position : ndarray (3,)
        rotation : ndarray (3, 3)
        """
        pin = self._pin
        q = self._q(q)
        pin.forwardKinematics(self.model, self.data, q)
        M = pin.updateFramePlacement(self.model, self.data, self.frame_id)
        return M.translation.copy(), M.rotation.copy()

    def ik(
        self,
        position,
        q0=None,
        rotation=None,
        *,
        max_iter: int = 200,
        tol: float = 1e-4,
        rot_tol: float = 1e-3,
        damping: float = 1e-2,
        posture_gain: float = 0.1,
    ) -> IKResult:
        """Arm configuration putting the tool at ``position`` with ``rotation``.

        Parameters
        ----------
        position : array_like (3,)
            Target tool position (m, base frame).
        q0 : array_like (nq,), optional
            Initial guess (default :data:`START_CONFIGURATION`); its finger joints are kept.
        rotation : array_like (3, 3), optional
            Target tool rotation (default :data:`DOWN`).
        max_iter : int
            Iteration cap.
        tol, rot_tol : float
            Stop when the position error is below ``tol`` (m) and the rotation error
            below ``rot_tol`` (rad); ``converged`` reports exactly this.
        damping : float
            lambda of the damped least squares.
        posture_gain : float
            k of the null-space pull towards ``q_rest`` (0 switches it off).

        Returns
        -------
        IKResult
        """
        p = _vector(position, 3, "the target position")
        R = DOWN if rotation is None else _rotation(rotation)
        q = self.q_rest.copy() if q0 is None else self._q(q0, "q0").copy()
        if not (isinstance(max_iter, int | np.integer) and max_iter >= 1):
            raise InvalidParameterError(f"max_iter must be a positive integer, got {max_iter!r}")
        q = np.clip(q, self.lower, self.upper)
        q, ep, er, it = self._solve(
            q, p, np.ascontiguousarray(R), max_iter, tol, rot_tol, damping, posture_gain
        )
        return IKResult(q, ep, er, bool(ep <= tol and er <= rot_tol), it)

    def _solve(self, q, p, R, max_iter, tol, rot_tol, damping, posture_gain):
        """The DLS loop on validated inputs; returns (q, position error, rotation error, its)."""
        pin, model, data, fid = self._pin, self.model, self.data, self.frame_id
        n = self.n_arm
        lo, hi = self.lower[:n], self.upper[:n]
        rest = self.q_rest[:n]
        lam2 = damping * damping * np.eye(6)
        eye = np.eye(n)
        e = np.empty(6)
        log3, jac, lwa = pin.log3, pin.computeFrameJacobian, pin.LOCAL_WORLD_ALIGNED
        it = 0
        checkpoint = np.inf  # error 10 iterations ago: stop when stuck (unreachable targets)
        while True:
            J = jac(model, data, q, fid, lwa)[:, :n]  # also updates data.oMf[fid]
            M = data.oMf[fid]
            e[:3] = p - M.translation
            e[3:] = log3(R @ M.rotation.T)
            ep = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
            er = math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5])
            if (ep <= tol and er <= rot_tol) or it >= max_iter:
                return q, ep, er, it
            if it % 10 == 0:
                err = ep + 0.1 * er
                if err > 0.99 * checkpoint:
                    return q, ep, er, it
                checkpoint = err
            # Limit the step so far targets are approached in straight-ish moves.
            if ep > 0.05:
                e[:3] *= 0.05 / ep
            if er > 0.3:
                e[3:] *= 0.3 / er
            JJt = J @ J.T
            JJt += lam2
            Jpinv = np.linalg.solve(JJt, J).T  # (n, 6): J^T (J J^T + lam^2 I)^-1
            dq = Jpinv @ e
            if posture_gain:
                dq += (eye - Jpinv @ J) @ (posture_gain * (rest - q[:n]))
            big = np.abs(dq).max()
            if big > 0.2:  # near singular poses: keep steps small instead of flailing
                dq *= 0.2 / big
            q[:n] = np.minimum(np.maximum(q[:n] + dq, lo), hi)
            it += 1

    def feasible(
        self, position, q0=None, *, reach_tol: float = REACH_TOL, tilt_tol: float = TILT_TOL
    ) -> bool:
        """Whether the tool can be at ``position`` (3,) pointing down, without any collision.

        Full fidelity: :meth:`ik` from ``q0`` (default the start configuration, fingers
        as in ``q0``), then :meth:`in_collision`. This is what :class:`FeasibilityMap`
        approximates.
        """
        r = self.ik(position, q0)
        return bool(
            r.position_error <= reach_tol
            and r.rotation_error <= tilt_tol
            and not self.in_collision(r.q)
        )

    # ------------------------------------------------------------------ collisions

    def in_collision(self, q) -> bool:
        """Whether the arm at ``q`` (nq,) touches itself or an obstacle (stops at the first)."""
        q = self._q(q)
        return bool(
            self._pin.computeCollisions(
                self.model, self.data, self.geom_model, self.geom_data, q, True
            )
        )

    def colliding_pair(self, q) -> tuple[str, str] | None:
        """The first pair of link / obstacle names in contact at ``q``, or None."""
        if not self.in_collision(q):
            return None
        for k, res in enumerate(self.geom_data.collisionResults):
            if res.isCollision():
                return self._pair_names[k]
        return None  # pragma: no cover - computeCollisions said there was one

    def clearance(self, q) -> float:
        """Smallest distance between colliding candidates at ``q`` (m; negative = penetration).

        Slow (~3 ms, mesh distances): for building maps and for tests, not for judging.
        """
        pin = self._pin
        q = self._q(q)
        pin.computeDistances(self.model, self.data, self.geom_model, self.geom_data, q)
        return float(min(r.min_distance for r in self.geom_data.distanceResults))

    # ------------------------------------------------------------------ paths

    def follow(
        self,
        path,
        gripper=None,
        q0=None,
        *,
        rotation=None,
        reach_tol: float = REACH_TOL,
        tilt_tol: float = TILT_TOL,
        check_collisions: bool = True,
        max_iter: int = 30,
    ) -> Tracking:
        """Track a tool path with IK, each sample warm-started from the previous one.

        Parameters
        ----------
        path : array_like (T, 3)
            Tool positions (m, base frame).
        gripper : array_like (T,), optional
            Hand command per sample, 0 open .. 1 closed (values outside are clipped);
            default open throughout.
        q0 : array_like (nq,), optional
            Configuration before the first sample (default :data:`START_CONFIGURATION`).
        rotation : array_like (3, 3), optional
            Tool rotation to hold (default :data:`DOWN`).
        reach_tol, tilt_tol : float
            A sample is reached when the tool is within ``reach_tol`` (m) and
            ``tilt_tol`` (rad) of its target.
        check_collisions : bool
            Test every sample for self- and obstacle collisions (about 30 us each).
        max_iter : int
            IK iterations per sample (the first sample gets 200).

        Returns
        -------
        Tracking
        """
        P = self._path(path)
        T = len(P)
        G = np.zeros(T) if gripper is None else self._gripper(gripper, T)
        R = np.ascontiguousarray(DOWN if rotation is None else _rotation(rotation))
        for what, v in (("reach_tol", reach_tol), ("tilt_tol", tilt_tol)):
            if not (np.isfinite(v) and v > 0):
                raise InvalidParameterError(f"{what} must be positive, got {v!r}")
        q = (self.q_rest if q0 is None else self._q(q0, "q0")).copy()
        q = np.clip(q, self.lower, self.upper)
        pin, model, data = self._pin, self.model, self.data
        gm, gd = self.geom_model, self.geom_data
        n = self.n_arm
        fingers = FINGER_OPEN * (1.0 - G)
        qs = np.empty((T, self.nq))
        errors, rot_errors = np.empty(T), np.empty(T)
        collision = np.zeros(T, bool)
        lo, hi = self.lower[:n] + 1e-9, self.upper[:n] - 1e-9
        for t in range(T):
            q[n:] = fingers[t]
            q, ep, er, _ = self._solve(
                q, P[t], R, 200 if t == 0 else max_iter, 1e-4, 1e-3, 1e-2, 0.1
            )
            qs[t] = q
            errors[t], rot_errors[t] = ep, er
            if check_collisions:
                collision[t] = pin.computeCollisions(model, data, gm, gd, q, True)
        converged = (errors <= reach_tol) & (rot_errors <= tilt_tol)
        at_limit = np.any((qs[:, :n] <= lo) | (qs[:, :n] >= hi), axis=1)
        bad = ~converged | collision
        first = int(np.argmax(bad)) if bad.any() else None
        reason = ""
        if first is not None:
            reason = self._reason(
                first,
                qs[first],
                errors[first],
                rot_errors[first],
                bool(collision[first]),
                converged[first],
                reach_tol,
            )
        return Tracking(qs, errors, rot_errors, converged, collision, at_limit, first, reason)

    def _reason(self, t, q, ep, er, collides, reached, reach_tol) -> str:
        if not reached:
            if ep > reach_tol:
                msg = (
                    f"cannot reach within {1e3 * reach_tol:.0f} mm at sample {t} "
                    f"(error {100 * ep:.1f} cm)"
                )
            else:
                msg = (
                    f"cannot keep the gripper pointing down at sample {t} "
                    f"(tilted {np.degrees(er):.0f} degrees)"
                )
            n = self.n_arm
            stuck = [
                self.joint_names[j]
                for j in range(n)
                if q[j] <= self.lower[j] + 1e-9 or q[j] >= self.upper[j] - 1e-9
            ]
            if stuck:
                msg += f": {', '.join(stuck)} at {'its' if len(stuck) == 1 else 'their'} "
                msg += "joint limit" + ("" if len(stuck) == 1 else "s")
            return msg
        pair = self.colliding_pair(q)
        a, b = pair if pair else ("the arm", "something")
        return f"collides: {a} with {b} at sample {t}"

    @staticmethod
    def _path(path) -> np.ndarray:
        try:
            P = np.asarray(path, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError("path must be an array of shape (T, 3)") from exc
        if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 1:
            raise InvalidParameterError(f"path must have shape (T, 3), got {P.shape}")
        if not np.all(np.isfinite(P)):
            raise InvalidParameterError(
                f"path has non-finite values at samples {np.flatnonzero(~np.isfinite(P).all(1))}"
            )
        return P

    @staticmethod
    def _gripper(gripper, T: int) -> np.ndarray:
        try:
            G = np.asarray(gripper, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"gripper must be {T} numbers in [0, 1]") from exc
        if G.shape != (T,):
            raise InvalidParameterError(
                f"gripper must have shape ({T},) like the path, got {G.shape}"
            )
        if not np.all(np.isfinite(G)):
            raise InvalidParameterError("gripper values must be finite (0 open .. 1 closed)")
        return np.clip(G, 0.0, 1.0)


@lru_cache(maxsize=8)
def _cached_arm(robot: str, tool_frame: str, key) -> Arm:
    return Arm(robot, tool_frame, key)


def get_arm(obstacles=(), robot: str = "panda", tool_frame: str = "panda_hand_tcp") -> Arm:
    """A shared :class:`Arm` for these obstacles, built once per process.

    Parameters
    ----------
    obstacles : sequence of (name, center (3,), size (3,))
    robot, tool_frame : str

    Returns
    -------
    Arm
        The same object for equal arguments (not thread-safe: one thread at a time).
    """
    return _cached_arm(robot, tool_frame, _boxes(obstacles))


# --------------------------------------------------------------------------- feasibility


class FeasibilityMap:
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
        self.origin = _vector(origin, 3, "origin")
        self.spacing = float(spacing)
        if not (np.isfinite(self.spacing) and self.spacing > 0):
            raise InvalidParameterError(f"spacing must be positive, got {spacing!r}")
        self.shape = m.shape[1:]
        self.meta = dict(meta or {})
        self._flat = m.ravel()
        nx, ny, nz = self.shape
        self._layer = nx * ny * nz
        self._strides = np.array([ny * nz, nz, 1])

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
        return _boxes(zip(names, centers, sizes, strict=True))

    def feasible(self, closed: bool = False) -> np.ndarray:
        """Voxel centres in X with the hand open (or closed), bool (nx, ny, nz)."""
        return self.margin[int(bool(closed))] > 0

    def grid_points(self) -> np.ndarray:
        """Voxel centres, shape (nx, ny, nz, 3)."""
        axes = [self.origin[i] + self.spacing * np.arange(self.shape[i]) for i in range(3)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

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
        P = np.asarray(points, dtype=float)
        if P.ndim < 1 or P.shape[-1] != 3:
            raise InvalidParameterError(f"points must have shape (..., 3), got {P.shape}")
        shape = P.shape[:-1]
        P = P.reshape(-1, 3)
        u = (P - self.origin) / self.spacing
        dims = np.array(self.shape)
        inside = np.all((u >= -1e-6) & (u <= dims - 1 + 1e-6), axis=1)  # NaN is outside
        u = np.where(inside[:, None], np.clip(u, 0, dims - 1), 0.0)
        i0 = np.minimum(u.astype(np.intp), dims - 2)
        f = u - i0
        base = i0 @ self._strides
        if gripper is not None:
            try:
                g = np.broadcast_to(np.asarray(gripper, dtype=float), shape).reshape(-1)
            except ValueError as exc:
                raise InvalidParameterError(
                    f"gripper must have shape {shape} like the points, got {np.shape(gripper)}"
                ) from exc
            base = base + np.where(g >= 0.5, self._layer, 0)
        sx, sy, sz = self._strides
        m = self._flat
        fx, fy, fz = f[:, 0], f[:, 1], f[:, 2]
        gx, gy, gz = 1 - fx, 1 - fy, 1 - fz
        c00 = m[base] * gz + m[base + sz] * fz
        c01 = m[base + sy] * gz + m[base + sy + sz] * fz
        c10 = m[base + sx] * gz + m[base + sx + sz] * fz
        c11 = m[base + sx + sy] * gz + m[base + sx + sy + sz] * fz
        v = (c00 * gy + c01 * fy) * gx + (c10 * gy + c11 * fy) * fx
        return np.where(inside, v, -np.inf).reshape(shape)

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
        return self.value(points, gripper) > 0

    def path_ok(self, paths, gripper=None) -> np.ndarray:
        """Whether every sample of each path (..., T, 3) is in X; bool (...)."""
        return self.contains(paths, gripper).all(axis=-1)

    def matches(
        self,
        obstacles,
        robot: str = "panda",
        tool_frame: str = "panda_hand_tcp",
        atol: float = 1e-6,
    ) -> bool:
        """Whether the map was built for these obstacles, robot and tool frame."""
        boxes = _boxes(obstacles)
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


def check_paths(points, gripper=None) -> tuple[np.ndarray, np.ndarray]:
    """Validate tool paths and their hand commands.

    Parameters
    ----------
    points : array_like (..., T, 3)
        Tool positions (m).
    gripper : array_like broadcastable to (..., T), optional
        Hand command per sample, 0 open .. 1 closed (default open).

    Returns
    -------
    points : ndarray (..., T, 3) of float
    gripper : ndarray (..., T) of float

    Raises
    ------
    InvalidParameterError
        Wrong shapes or values that are not numbers.
    """
    try:
        P = np.asarray(points, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError("points must be numbers of shape (..., T, 3)") from exc
    if P.ndim < 2 or P.shape[-1] != 3:
        raise InvalidParameterError(f"points must have shape (..., T, 3), got {P.shape}")
    if gripper is None:
        return P, np.zeros(P.shape[:-1])
    try:
        G = np.broadcast_to(np.asarray(gripper, dtype=float), P.shape[:-1])
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(
            f"gripper must have shape {P.shape[:-1]} like the points, got {np.shape(gripper)}"
        ) from exc
    return P, G


class FullCheck:
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

    def path_ok(self, paths, gripper=None) -> np.ndarray:
        """Whether every sample of each path (..., T, 3) is reached collision-free; (...)."""
        return self.contains(paths, gripper).all(axis=-1)


class MapCheck:
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
        self.shoulder = _vector(shoulder, 3, "shoulder")
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
        value = self.map.value(P, G)
        out = value > 0
        near = np.linalg.norm(P - self.shoulder, axis=-1) <= self.reach
        unknown = np.isneginf(value) & near  # off the grid but maybe reachable
        known_bad = ~out & ~unknown
        T = P.shape[-2]
        first_unknown = np.where(unknown.any(axis=-1), np.argmax(unknown, axis=-1), T)
        first_bad = np.where(known_bad.any(axis=-1), np.argmax(known_bad, axis=-1), T)
        # a path is judged by its first sample outside X: follow it in full only when
        # an unknown sample comes before any the map already rejects
        redo = first_unknown < first_bad  # (...)
        if redo.any():
            idx = np.nonzero(redo)
            out[idx] = self.full.contains(P[idx], G[idx])
        return out

    def path_ok(self, paths, gripper=None) -> np.ndarray:
        """Whether every sample of each path (..., T, 3) is in X; bool (...)."""
        return self.contains(paths, gripper).all(axis=-1)
