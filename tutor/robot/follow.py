r"""The arm that follows a hand: a guide handle moved by the trainee, the arm after it.

Each :meth:`HandFollower.step` takes the handle's position and the hand command g and

1. clamps the target to the guide box (:func:`guide_limits`) and the reach sphere
   (:data:`REACH_CENTER`, :data:`REACH_RADIUS`): never lower than the table top plus
   :data:`FLOOR_CLEARANCE`, so the gripper cannot pass through the table;
2. runs a few iterations of the arm's damped-least-squares IK (:meth:`Arm.ik`'s solver),
   warm-started from the previous configuration, with the gripper pointing down; a jump
   longer than :data:`STEP_LEG` is taken in legs along the straight line, and a solution
   that would still put the tool under the table top is refused (the arm stays put);
3. sets the fingers from g (:meth:`Arm.fingers`) and checks collisions
   (:meth:`Arm.colliding_pair`): a configuration in contact is kept (the view paints
   the link red and the recording goes on), and the link is reported;
4. places the visual links (what the 3-D view draws).

The outcome is a :class:`FollowState` with plain words for the trainee. One step costs
well under a millisecond (``benchmarks/bench_follow.py``). Like :class:`Arm`, a
follower overwrites the arm's Pinocchio data: one thread at a time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from .arm import Arm, get_arm
from .checks import check_vector
from .model import DOWN, REACH_TOL, TILT_TOL, load_robot
from .obstacles import scene_obstacles

__all__ = [
    "HandFollower",
    "FollowState",
    "REACH_CENTER",
    "REACH_RADIUS",
    "FLOOR_CLEARANCE",
    "GUIDE_MARGIN",
    "guide_limits",
    "reach_sphere",
    "link_words",
]

#: Centre of the sphere the tool centre point reaches pointing down (m, base frame):
#: the shoulder (z = 0.333) less the wrist-to-fingertip length of the Panda's hand.
REACH_CENTER = np.array([0.0, 0.0, 0.12])
REACH_CENTER.setflags(write=False)
#: Radius of that sphere (m): measured by walking the IK outwards along rays, the arm
#: reaches 0.75 to 0.81 m from :data:`REACH_CENTER` in every direction above the table.
REACH_RADIUS = 0.74
#: The tool centre point stays this far above the table top (m): the fingertips reach
#: about 8 mm below it.
FLOOR_CLEARANCE = 0.012
#: The guide box reaches this far beyond the tray, the bin and the start pose (m).
GUIDE_MARGIN = 0.15
#: Longest straight leg one IK solve is asked to cover (m); longer jumps are split.
STEP_LEG = 0.05
#: Highest handle position above the start pose or the release point, whichever is higher.
GUIDE_HEADROOM = 0.2

#: What a trainee calls each link (robot link name -> plain words).
LINK_WORDS = {
    "panda_link0": "base",
    "panda_link1": "shoulder",
    "panda_link2": "shoulder",
    "panda_link3": "upper arm",
    "panda_link4": "elbow",
    "panda_link5": "forearm",
    "panda_link6": "wrist",
    "panda_link7": "wrist",
    "panda_hand": "hand",
    "panda_leftfinger": "left finger",
    "panda_rightfinger": "right finger",
}

#: Words when the handle was clamped ("table" / "reach") or the arm lags behind.
CLAMP_WORDS = {
    "table": "The hand is at the table: it cannot go lower.",
    "reach": "Out of the arm's reach: the arm stretches as far as it can.",
}
NOT_REACHED_WORDS = "The arm cannot get the hand exactly there: it goes as near as it can."


def link_words(name: str) -> str:
    """Plain words for a robot link or an obstacle ('panda_link5' -> 'forearm',
    'bin wall -x' -> 'bin')."""
    return LINK_WORDS.get(name, name.split(" wall")[0].replace("_", " "))


def guide_limits(scene) -> dict:
    """The box the browser clamps the handle to (m, base frame).

    Parameters
    ----------
    scene : PickPlaceScene
        Duck-typed: table, tray and bin boxes, ``release_height`` and the start
        configuration.

    Returns
    -------
    dict
        ``{"x": [lo, hi], "y": [lo, hi], "z": [lo, hi]}``: around the tray, the bin and
        the start pose by :data:`GUIDE_MARGIN`, inside the table's edges, from the table
        top plus :data:`FLOOR_CLEARANCE` up to :data:`GUIDE_HEADROOM` above the start
        pose or the release point.
    """
    boxes = scene_obstacles(scene)
    table = next(b for b in boxes if b[0] == "table")
    t_lo = table[1] - table[2] / 2
    t_hi = table[1] + table[2] / 2
    tray_c, tray_s = np.asarray(scene.tray_center, float), np.asarray(scene.tray_size, float)
    bin_c, bin_s = np.asarray(scene.bin_center, float), np.asarray(scene.bin_size, float)
    start = _start_position(scene)
    lows = np.array([tray_c - tray_s / 2, bin_c - bin_s / 2, start])
    highs = np.array([tray_c + tray_s / 2, bin_c + bin_s / 2, start])
    lo = np.maximum(lows.min(axis=0) - GUIDE_MARGIN, t_lo)
    hi = np.minimum(highs.max(axis=0) + GUIDE_MARGIN, t_hi)
    floor = float(t_hi[2] + FLOOR_CLEARANCE)
    top = float(max(start[2], float(scene.release_height)) + GUIDE_HEADROOM)
    return {
        "x": [round(float(lo[0]), 4), round(float(hi[0]), 4)],
        "y": [round(float(lo[1]), 4), round(float(hi[1]), 4)],
        "z": [round(floor, 4), round(top, 4)],
    }


def reach_sphere() -> dict:
    """The reach sphere as JSON for the browser: ``{"center": [x, y, z], "radius": r}``."""
    return {"center": [float(v) for v in REACH_CENTER], "radius": REACH_RADIUS}


def _start_position(scene) -> np.ndarray:
    arm = get_arm(scene_obstacles(scene), scene.robot, scene.tool_frame)
    return arm.fk(scene.start_configuration)[0]


@dataclass(frozen=True)
class FollowState:
    """Where the arm is after one step of the hand (:meth:`HandFollower.step`).

    Attributes
    ----------
    q : ndarray (nq,)
        The arm's configuration (fingers from ``grip``).
    position : ndarray (3,)
        The tool centre point reached (m).
    target : ndarray (3,)
        The handle's position after clamping (m).
    grip : float
        The hand command, 0 open .. 1 closed.
    reached : bool
        The tool is within :data:`~tutor.robot.REACH_TOL` of ``target``, pointing down.
    collision : str or None
        The robot link in contact with the table, tray, bin or another link.
    clamped : {"table", "reach", None}
        The handle was held at the table top, or at the edge of the arm's reach (or of
        the guide box).
    words : str
        What to tell the trainee ("" when all is well).
    placements : ndarray (L, 4, 4)
        The visual links' placements (the meshes the 3-D view draws), in the order of
        the robot's visual model.
    """

    q: np.ndarray
    position: np.ndarray
    target: np.ndarray
    grip: float
    reached: bool
    collision: str | None
    clamped: str | None
    words: str
    placements: np.ndarray

    def to_message(self) -> dict:
        """The state as JSON for the page (no configuration, no placements)."""
        return {
            "position": [round(float(v), 5) for v in self.position],
            "target": [round(float(v), 5) for v in self.target],
            "grip": float(self.grip),
            "reached": bool(self.reached),
            "collision": self.collision,
            "clamped": self.clamped,
            "words": self.words,
        }


class HandFollower:
    """The arm following a guide handle, step by step (see the module).

    Parameters
    ----------
    arm : Arm
        The arm, with the scene's obstacles.
    limits : dict
        The guide box (:func:`guide_limits`).
    start : array_like (nq,)
        The start configuration (:meth:`reset` goes back to it).
    iterations : int
        IK iterations per step (each ~15 us; a handle moved a few cm converges in 3-5).

    Use :meth:`for_scene` to make one for a pick-and-place scene.
    """

    def __init__(self, arm: Arm, limits: dict, start, iterations: int = 10):
        import pinocchio as pin

        if not isinstance(arm, Arm):
            raise InvalidParameterError(f"arm must be a tutor.robot.Arm, got {type(arm).__name__}")
        if isinstance(iterations, bool) or not isinstance(iterations, int) or iterations < 1:
            raise InvalidParameterError(
                f"iterations must be a whole number >= 1, got {iterations!r}"
            )
        self.arm = arm
        self._pin = pin
        self.limits = {k: list(limits[k]) for k in ("x", "y", "z")}
        self._lo = np.array([self.limits[k][0] for k in "xyz"], float)
        self._hi = np.array([self.limits[k][1] for k in "xyz"], float)
        self.start = check_vector(start, arm.nq, "the start configuration").copy()
        self.iterations = iterations
        self._visual = load_robot(arm.robot_name).visual_model
        self._vdata = self._visual.createData()
        self._R = np.ascontiguousarray(DOWN)
        self.state = self.reset()

    @classmethod
    def for_scene(cls, scene, arm: Arm | None = None, **options) -> HandFollower:
        """A follower for a pick-and-place scene (default arm: the scene's shared one)."""
        if arm is None:
            arm = get_arm(scene_obstacles(scene), scene.robot, scene.tool_frame)
        return cls(arm, guide_limits(scene), scene.start_configuration, **options)

    # ------------------------------------------------------------------ stepping

    def reset(self, q=None) -> FollowState:
        """Put the arm at ``q`` (default the start configuration); returns its state."""
        arm = self.arm
        q = self.start.copy() if q is None else check_vector(q, arm.nq, "q").copy()
        q = np.clip(q, arm.lower, arm.upper)
        grip = 1.0 - float(np.clip(q[arm.n_arm :].mean() / arm.fingers(0.0), 0, 1))
        self.state = self._state(q, None, grip, None)
        return self.state

    def clamp(self, target) -> tuple[np.ndarray, str | None]:
        """``target`` (3,) held inside the guide box and the reach sphere, and why.

        Returns
        -------
        target : ndarray (3,)
        clamped : {"table", "reach", None}
        """
        p = check_vector(target, 3, "the hand's target")
        c = np.minimum(np.maximum(p, self._lo), self._hi)
        why = None
        if p[2] < self._lo[2] - 1e-9:
            why = "table"
        elif np.any(c != p):
            why = "reach"
        d = c - REACH_CENTER
        r = float(np.sqrt(d @ d))
        if r > REACH_RADIUS:
            c = REACH_CENTER + d * (REACH_RADIUS / r)
            c[2] = max(c[2], self._lo[2])
            why = why or "reach"
        return c, why

    def step(self, target_xyz, grip) -> FollowState:
        """Move the arm towards the handle at ``target_xyz`` (3,) with hand ``grip``.

        Raises
        ------
        InvalidParameterError
            The target is not 3 finite numbers or the grip not a finite number (the
            follower is unchanged).
        """
        target, clamped = self.clamp(target_xyz)
        g = _grip(grip)
        arm = self.arm
        q = self.state.q.copy()
        q[arm.n_arm :] = arm.fingers(g)
        # A long jump is taken in legs of at most STEP_LEG along the straight line from
        # where the tool is: one long solve can swing the hand under the table top.
        here = self.state.position
        legs = max(1, int(np.ceil(np.linalg.norm(target - here) / STEP_LEG)))
        for leg in range(1, legs + 1):
            goal = here + (target - here) * (leg / legs)
            q, ep, er, _ = arm._solve(q, goal, self._R, self.iterations, 1e-4, 1e-3, 1e-2, 0.1)
        tool_z = self._tool_z(q)
        if tool_z < self._lo[2] - FLOOR_CLEARANCE:  # still under the table top: stay put
            q = self.state.q.copy()
            q[arm.n_arm :] = arm.fingers(g)
            ep = np.inf
        reached = bool(ep <= REACH_TOL and er <= TILT_TOL)
        self.state = self._state(q, target, g, clamped, reached)
        return self.state

    def _tool_z(self, q) -> float:
        """Height of the tool centre point at ``q`` (m)."""
        arm, pin = self.arm, self._pin
        pin.forwardKinematics(arm.model, arm.data, q)
        return float(pin.updateFramePlacement(arm.model, arm.data, arm.frame_id).translation[2])

    def _state(self, q, target, grip, clamped, reached=True) -> FollowState:
        """The state at ``q`` (``target`` None: where the tool is)."""
        arm, pin = self.arm, self._pin
        pair = arm.colliding_pair(q)  # also runs forward kinematics at q
        position = pin.updateFramePlacement(arm.model, arm.data, arm.frame_id).translation.copy()
        target = position.copy() if target is None else target
        collision = None if pair is None else pair[0]
        words = []
        if pair is not None:
            what = link_words(pair[0])
            verb = "touch" if what.endswith("s") else "touches"
            words.append(f"The {what} {verb} the {link_words(pair[1])}.")
        if clamped is not None:
            words.append(CLAMP_WORDS[clamped])
        elif not reached:
            words.append(NOT_REACHED_WORDS)
        pin.updateGeometryPlacements(arm.model, arm.data, self._visual, self._vdata)
        placements = np.array([M.homogeneous for M in self._vdata.oMg])
        for a in (q, position, target, placements):
            a.setflags(write=False)
        return FollowState(
            q=q,
            position=position,
            target=target,
            grip=grip,
            reached=reached,
            collision=collision,
            clamped=clamped,
            words=" ".join(words),
            placements=placements,
        )


def _grip(grip) -> float:
    """The hand command as a float in [0, 1] (values outside are clipped), or a named error."""
    if isinstance(grip, bool):
        return float(grip)
    try:
        g = float(grip)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(
            f"the hand command must be a number from 0 (open) to 1 (closed), got {grip!r}"
        ) from exc
    if not np.isfinite(g):
        raise InvalidParameterError(
            f"the hand command must be a finite number from 0 (open) to 1 (closed), got {grip!r}"
        )
    return min(max(g, 0.0), 1.0)
