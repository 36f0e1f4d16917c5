"""The robot model (example-robot-data) and the conventions every other module shares.

The paper's Experiment 2 used a 7-DoF Sawyer; example-robot-data has none, so the
tutor uses the Franka Panda (7 arm joints + 2 finger joints, nq = 9, tool frame
``panda_hand_tcp``), the nearest 7-DoF arm it ships. This module loads it (once per
process), finds its SRDF collision filter, and fixes the start configuration, the
"pointing down" tool rotation and the tolerances of "reached".
"""

from __future__ import annotations

from functools import lru_cache
from os.path import join

import numpy as np

from ..errors import InvalidParameterError

__all__ = [
    "load_robot",
    "srdf_path",
    "START_CONFIGURATION",
    "DOWN",
    "REACH_TOL",
    "TILT_TOL",
    "FINGER_OPEN",
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
