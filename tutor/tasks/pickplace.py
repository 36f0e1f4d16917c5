r"""Experiment 2 of Sena & Howard: pick a plant from a 10 x 10 tray and drop it in a bin.

Section "Experiment 2" of the paper. Notation:

B^
    One test condition per plant (|B^| = 100); a condition is the plant's index.
X
    The admissible space: the gripper path is reachable (inverse kinematics
    succeeds) without self-collision or collision with the table, tray or bin.
delta_g, delta_r
    Grab and release thresholds: the mean grab (release) distance in the demo set
    plus 2 standard deviations plus 1 mm.

A state is :math:`\xi = (t, x, y, z, g)`: normalised time, the gripper (tool centre
point) position in the robot base frame in metres, and the hand g (1 closed, 0 open).
The gripper keeps pointing down, so orientation is not part of the state. The TP-GMM
sees three frames per condition: the start pose, the target plant and the bin, with
K = 7 components. The scene lives in ``assets/pickplace.json``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

__all__ = ["PickPlaceScene", "load_scene", "DEFAULT_SCENE_PATH"]

DEFAULT_SCENE_PATH = Path(__file__).resolve().parents[2] / "assets" / "pickplace.json"


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
    n_components: int = 7
    n_samples: int = 200
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
    data = json.loads((DEFAULT_SCENE_PATH if path is None else Path(path)).read_text())
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
        n_components=int(data.get("n_components", 7)),
        n_samples=int(data.get("n_samples", 200)),
        realisation_seconds=float(data.get("realisation_seconds", 25.0)),
        run_seconds=float(data.get("run_seconds", 900.0)),
    )
