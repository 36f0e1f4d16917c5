r"""The arm: forward and inverse kinematics, collisions and path following (Pinocchio).

Inverse kinematics is damped least squares on the 6-D frame error
:math:`e = (p^* - p,\ \log(R^* R^\top))` with the LOCAL_WORLD_ALIGNED Jacobian
:math:`J` (6 x 7):

.. math:: \Delta q = J^\top (J J^\top + \lambda^2 I)^{-1} e + (I - J^+ J)\, k\,(q_{rest} - q),

the second term (in the null space of the tool task) pulling the elbow gently
towards the start posture so that a position has one preferred configuration
whichever way it is approached. The update is added to q and clipped to the joint
limits.

:class:`Arm` is the one place that runs Pinocchio's kinematics: the tasks and the
3-D view ask it for tool poses and link placements instead of calling Pinocchio.
An :class:`Arm` holds Pinocchio ``Data`` that every call overwrites: use one arm per
thread.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..errors import InvalidParameterError
from .checks import check_rotation, check_vector
from .model import (
    DOWN,
    FINGER_OPEN,
    REACH_TOL,
    START_CONFIGURATION,
    TILT_TOL,
    load_robot,
    srdf_path,
)
from .obstacles import box_shape, check_boxes

__all__ = ["Arm", "IKResult", "Tracking", "get_arm"]


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
        self.obstacles = check_boxes(obstacles)
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
            else check_vector(q_rest, self.nq, "q_rest")
        )

        geom = wrapper.collision_model.copy()
        geom.removeAllCollisionPairs()
        geom.addAllCollisionPairs()
        pin.removeCollisionPairs(model, geom, srdf, False)
        self.n_self_pairs = len(geom.collisionPairs)
        moving = [i for i, o in enumerate(geom.geometryObjects) if o.parentJoint != 0]
        for name, center, size in self.obstacles:
            placement = pin.SE3(np.eye(3), np.array(center))
            gid = geom.addGeometryObject(pin.GeometryObject(name, 0, placement, box_shape(size)))
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
        return check_vector(q, self.nq, what)

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

    def visual_placements(self, qs, visual_model=None) -> np.ndarray:
        """Placement of every visual geometry (the meshes a viewer draws) at each ``q``.

        Parameters
        ----------
        qs : array_like (T, nq) or (nq,)
            Configurations.
        visual_model : pinocchio.GeometryModel, optional
            The geometries to place (default: the robot's own visual model from
            :func:`load_robot`, in its order, ``visual_model.geometryObjects``).

        Returns
        -------
        ndarray (T, G, 4, 4), or (G, 4, 4) for one configuration
            Homogeneous transforms in the base frame, G = ``visual_model.ngeoms``.
        """
        pin = self._pin
        Q = self._configurations(qs)
        vmodel = load_robot(self.robot_name).visual_model if visual_model is None else visual_model
        if not hasattr(vmodel, "geometryObjects"):
            raise InvalidParameterError(
                f"visual_model must be a pinocchio GeometryModel, got {type(vmodel).__name__}"
            )
        vdata = vmodel.createData()
        model, data = self.model, self.data
        out = np.empty((len(Q), vmodel.ngeoms, 4, 4))
        for t, q in enumerate(Q):
            pin.forwardKinematics(model, data, q)
            pin.updateGeometryPlacements(model, data, vmodel, vdata)
            for g, M in enumerate(vdata.oMg):
                out[t, g] = M.homogeneous
        return out[0] if np.ndim(qs) == 1 else out

    def _configurations(self, qs) -> np.ndarray:
        """``qs`` as finite configurations (T, nq), T >= 1 (one row for a single q)."""
        try:
            Q = np.asarray(qs, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(
                f"configurations must be numbers of shape (T, {self.nq})"
            ) from exc
        if Q.ndim == 1:
            Q = Q[None]
        if Q.ndim != 2 or Q.shape[1] != self.nq or len(Q) < 1:
            raise InvalidParameterError(
                f"configurations must have shape (T, {self.nq}) or ({self.nq},), got {Q.shape}"
            )
        if not np.all(np.isfinite(Q)):
            raise InvalidParameterError("configurations must be finite (no NaN or inf)")
        return Q

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
        p = check_vector(position, 3, "the target position")
        R = DOWN if rotation is None else check_rotation(rotation)
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
        stop_at_problem: bool = False,
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
        stop_at_problem : bool
            Stop at the first sample not reached or in collision (a path is judged by
            its first problem): the samples after it are not followed and count as
            not reached (``errors`` nan, ``qs`` the configuration at the problem).

        Returns
        -------
        Tracking
        """
        P = self._path(path)
        T = len(P)
        G = np.zeros(T) if gripper is None else self._gripper(gripper, T)
        R = np.ascontiguousarray(DOWN if rotation is None else check_rotation(rotation))
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
            if stop_at_problem and (collision[t] or ep > reach_tol or er > tilt_tol):
                qs[t + 1 :] = q
                errors[t + 1 :] = rot_errors[t + 1 :] = np.nan
                break
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
    return _cached_arm(robot, tool_frame, check_boxes(obstacles))
