"""Build ``tutor/assets/feasibility_map.npz``: where the Panda's tool can be in the scene.

The map is a voxel grid over the region the task uses (x -0.25 .. 0.90, y -0.70 .. 0.75,
z -0.05 .. 0.65 m, 1 cm voxels; edit ``GRID`` to change it). A voxel centre is in X
when the tool reaches it pointing down (:data:`tutor.robot.DOWN`) within
:data:`tutor.robot.REACH_TOL` and :data:`tutor.robot.TILT_TOL`, with the fingers open,
and the arm then touches neither itself nor the table, tray or bin. That is exactly
:meth:`tutor.robot.Arm.feasible`.

1. Every voxel: :meth:`tutor.robot.Arm.feasible`, i.e. inverse kinematics from the
   start configuration (not warm-started from a neighbour, so a voxel's answer does
   not depend on the scan order), then one collision check.
2. Voxels next to the border of X (a neighbour of the other kind in their 3 x 3 x 3
   block): a signed margin, the smallest of the arm's clearance (mesh distances,
   negative when penetrating), REACH_TOL minus the position error and
   0.1 m/rad x (TILT_TOL minus the rotation error), clamped to +-spacing; other
   voxels store +-spacing.
   :class:`tutor.robot.FeasibilityMap` interpolates the margins trilinearly, which
   places the border within about a millimetre instead of half a voxel.

Takes a few minutes on two cores. Run after changing the scene or the robot module:

    .venv/bin/python scripts/make_feasibility_map.py [--spacing 0.01] [--out PATH]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from multiprocessing import get_context
from pathlib import Path

import numpy as np
from scipy import ndimage

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tutor.robot import (  # noqa: E402
    DEFAULT_MAP_PATH,
    DOWN,
    REACH_TOL,
    START_CONFIGURATION,
    TILT_TOL,
    FeasibilityMap,
    get_arm,
    scene_obstacles,
)
from tutor.tasks.pickplace import load_scene  # noqa: E402

#: The region the task uses (m, robot base frame): lower and upper voxel centres.
GRID = {"lower": (-0.25, -0.70, -0.05), "upper": (0.90, 0.75, 0.65)}
TILT_LENGTH = 0.1  # m per rad: turns a rotation error into a length for the margin

_STATE: dict = {}


def _init(obstacles, axes):
    _STATE["arm"] = get_arm(obstacles)
    _STATE["axes"] = axes


def _slice(i: int):
    """IK and collision checks (fingers open, closed) for every voxel of the x slice ``i``."""
    arm, (xs, ys, zs) = _STATE["arm"], _STATE["axes"]
    ny, nz = len(ys), len(zs)
    qs = np.empty((ny, nz, arm.nq))
    ep = np.empty((ny, nz))
    er = np.empty((ny, nz))
    hit = np.zeros((2, ny, nz), bool)
    for j in range(ny):
        for k in range(nz):
            r = arm.ik((xs[i], ys[j], zs[k]), START_CONFIGURATION)
            qs[j, k], ep[j, k], er[j, k] = r.q, r.position_error, r.rotation_error
            hit[0, j, k] = arm.in_collision(r.q)
            hit[1, j, k] = arm.in_collision(_closed(r.q))
    return i, qs, ep, er, hit


def _closed(q):
    q = q.copy()
    q[7:] = 0.0
    return q


def _margins(chunk):
    """Signed margins (m) of the voxels ``chunk`` = list of (q, ep, er, feasible)."""
    arm = _STATE["arm"]
    out = []
    for q, ep, er, feasible in chunk:
        m = min(arm.clearance(q), REACH_TOL - ep, TILT_LENGTH * (TILT_TOL - er))
        if feasible and m <= 0:  # distance and collision tests disagree at contact
            m = 1e-5
        elif not feasible and m > 0:
            m = -1e-5
        out.append(m)
    return out


def build(spacing: float = 0.01, processes: int | None = None, verbose: bool = True):
    scene = load_scene()
    obstacles = scene_obstacles(scene)
    lower, upper = np.array(GRID["lower"]), np.array(GRID["upper"])
    n = np.round((upper - lower) / spacing).astype(int) + 1
    axes = tuple(lower[d] + spacing * np.arange(n[d]) for d in range(3))
    processes = processes or os.cpu_count() or 1
    t0 = time.perf_counter()
    ctx = get_context("fork")
    qs = np.empty((*n, 9))
    ep, er = np.empty(n), np.empty(n)
    hit = np.zeros((2, *n), bool)
    margin = np.empty((2, *n), np.float32)
    with ctx.Pool(processes, initializer=_init, initargs=(obstacles, axes)) as pool:
        for done, (i, q, e, r, h) in enumerate(pool.imap_unordered(_slice, range(n[0])), 1):
            qs[i], ep[i], er[i], hit[:, i] = q, e, r, h
            if verbose and done % 10 == 0:
                print(f"  IK: {done}/{n[0]} x slices, {time.perf_counter() - t0:.0f} s", flush=True)
        full = np.ones((3, 3, 3), bool)
        for layer, hand in enumerate(("open", "closed")):
            feasible = (ep <= REACH_TOL) & (er <= TILT_TOL) & ~hit[layer]
            border = ndimage.binary_dilation(feasible, full) & ndimage.binary_dilation(
                ~feasible, full
            )
            idx = np.argwhere(border)
            if verbose:
                print(
                    f"  hand {hand}: {feasible.mean():.1%} of {feasible.size} voxels in X; "
                    f"{len(idx)} border voxels to measure",
                    flush=True,
                )
            items = [
                (
                    qs[tuple(v)] if layer == 0 else _closed(qs[tuple(v)]),
                    ep[tuple(v)],
                    er[tuple(v)],
                    feasible[tuple(v)],
                )
                for v in idx
            ]
            chunks = [items[s : s + 500] for s in range(0, len(items), 500)]
            values = []
            for c, part in enumerate(pool.imap(_margins, chunks), 1):
                values.extend(part)
                if verbose and c % 20 == 0:
                    elapsed = time.perf_counter() - t0
                    print(f"  margins: {c}/{len(chunks)}, {elapsed:.0f} s", flush=True)
            margin[layer] = np.where(feasible, spacing, -spacing)
            # Far outside the reach the IK error says little about the border: clamp.
            margin[layer][tuple(idx.T)] = np.clip(values, -spacing, spacing)
    names = [b[0] for b in obstacles]
    meta = {
        "robot": scene.robot,
        "tool_frame": scene.tool_frame,
        "obstacle_names": names,
        "obstacle_centers": np.array([b[1] for b in obstacles]),
        "obstacle_sizes": np.array([b[2] for b in obstacles]),
        "rotation": DOWN,
        "reach_tol": REACH_TOL,
        "tilt_tol": TILT_TOL,
    }
    if verbose:
        print(f"  done in {time.perf_counter() - t0:.0f} s", flush=True)
    return FeasibilityMap(margin, lower, spacing, meta)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--spacing", type=float, default=0.01, help="voxel size (m)")
    parser.add_argument("--processes", type=int, default=None)
    parser.add_argument("--out", type=Path, default=DEFAULT_MAP_PATH)
    args = parser.parse_args(argv)
    fmap = build(args.spacing, args.processes)
    fmap.save(args.out)
    size = args.out.stat().st_size
    print(f"wrote {args.out} ({fmap.shape} voxels, {size / 1e3:.0f} kB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
