r"""The robot arm: Pinocchio kinematics and collision checks on example-robot-data models.

The package sits beside :mod:`tutor.tasks` and never imports it: the task passes its
geometry in as plain boxes. Its modules:

:mod:`~tutor.robot.model`
    Loading the model (:func:`load_robot`, :func:`srdf_path`) and the shared
    conventions (:data:`START_CONFIGURATION`, :data:`DOWN`, the tolerances).
:mod:`~tutor.robot.checks`
    Validators of vectors, rotations and tool paths (:func:`check_paths`).
:mod:`~tutor.robot.obstacles`
    Obstacle boxes (:func:`open_box`, :func:`scene_obstacles`).
:mod:`~tutor.robot.arm`
    The arm: forward and inverse kinematics, collisions, path following
    (:class:`Arm`, :class:`IKResult`, :class:`Tracking`, :func:`get_arm`).
:mod:`~tutor.robot.feasibility`
    The admissible space X as a voxel map or full checks (:class:`FeasibilityMap`,
    :func:`default_map`, :class:`FullCheck`, :class:`MapCheck`).

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
"""

from __future__ import annotations

from .arm import Arm, IKResult, Tracking, get_arm
from .checks import check_paths
from .feasibility import (
    DEFAULT_MAP_PATH,
    FeasibilityMap,
    FullCheck,
    MapCheck,
    default_map,
    first_bad_sample,
)
from .model import (
    DOWN,
    FINGER_OPEN,
    REACH_TOL,
    START_CONFIGURATION,
    TILT_TOL,
    load_robot,
    srdf_path,
)
from .obstacles import open_box, scene_obstacles

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
    "first_bad_sample",
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
