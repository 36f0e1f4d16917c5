"""The robot arm: Pinocchio kinematics and collision checks on example-robot-data models.

The paper's Experiment 2 used a 7-DoF Sawyer; example-robot-data has none, so the
tutor uses the Franka Panda (7 arm joints + 2 finger joints, nq = 9, tool frame
``panda_hand_tcp``), the nearest 7-DoF arm it ships.
"""

from __future__ import annotations

from functools import lru_cache

__all__ = ["load_robot"]


@lru_cache(maxsize=4)
def load_robot(name: str = "panda"):
    """The example-robot-data model ``name`` as a RobotWrapper, loaded once per process."""
    import example_robot_data

    return example_robot_data.load(name)
