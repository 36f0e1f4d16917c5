"""The 3-D scene's geometry: the robot's meshes, the table, tray, bin, plants and hand.

The robot's visual meshes are example-robot-data's own (the COLLADA files of the
robot's Pinocchio visual model), read part by part with trimesh and drawn with fewer
triangles: each part keeps its colour and about :data:`ROBOT_KEEP` of its triangles
(quadric decimation, fast-simplification), shaded smooth except at sharp edges. The
Panda's 135k triangles took 29 ms of each frame with software GL (headless chromium,
a laptop without a GPU driver); its 14.5k (ROBOT_KEEP 0.1, within 3.2 mm of each
part's extent) look the same a few hundred pixels wide. Where
they are placed is :meth:`tutor.robot.Arm.visual_placements`. They are recorded once
per process as Meshcat commands so every scene reuses them. The rest are meshcat
primitives drawn from a :class:`~tutor.tasks.pickplace.PickPlaceScene`: the obstacle
boxes of :func:`tutor.robot.scene_obstacles` (table, tray, bin floor and walls), a
stem per plant (its status ball is the drawing's, :mod:`tutor.views.scene3d`), and the
hand marker, one ball for open and one for closed.
"""

from __future__ import annotations

import base64
import threading
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..errors import InvalidParameterError
from .meshcat_recorder import SceneRecorder, frame_commands

__all__ = [
    "RobotMeshes",
    "robot_meshes",
    "draw_fixtures",
    "draw_hand",
    "plant_balls",
    "stem_mesh",
    "hex_colour",
    "HAND_OPEN",
    "HAND_CLOSED",
]

HAND_OPEN = "#e6ab02"  #: the hand marker while the hand is open (yellow)
HAND_CLOSED = "#7b3294"  #: ... while it is closed, holding a plant (purple)
TABLE = "#c8b08a"
TRAY = "#5b5b5b"
BIN = "#8c8c8c"
STEM = "#5a7a3a"
HAND_RADIUS = 0.016  # m
#: segments of the 100 plants' balls (around, top to bottom) and stems (around). meshcat
#: draws spheres with 20 x 20 and cylinders with 50: the 100 plants were 98k of the
#: scene's 233k triangles, half of a frame's 60 ms on software GL (headless chromium);
#: a ball a few pixels wide looks the same with 12 x 8, and with 8 x 6 (80 triangles a
#: ball: on software GL a frame's cost follows its triangles, not its draw calls, and
#: the 100 balls at 12 x 8 were 17k of 43k; ``benchmarks/bench_frame.py``).
PLANT_BALL_SEGMENTS = (8, 6)
PLANT_STEM_SEGMENTS = 8


def hex_string(rgb) -> str:
    """``(r, g, b)`` bytes as ``"#rrggbb"``."""
    return "#" + "".join(f"{int(c):02x}" for c in rgb)


def rgb_floats(colours) -> np.ndarray:
    """``"#rrggbb"`` strings as an (n, 3) float32 array in [0, 1] (three.js r132 takes
    vertex and instance colours as given)."""
    raw = b"".join(hex_colour(c).to_bytes(3, "big") for c in colours)
    return (np.frombuffer(raw, np.uint8).reshape(-1, 3) / 255.0).astype(np.float32)


def hex_colour(colour: str) -> int:
    """``"#rrggbb"`` as the integer meshcat's materials take."""
    return int(colour.lstrip("#"), 16)


@dataclass(frozen=True)
class RobotMeshes:
    """The robot's visual meshes as recorded Meshcat commands, built once per process."""

    commands: tuple  # (kind, path, packed) set_object commands
    gz: bytes  # their gzipped frames, for the in-notebook viewer
    chunk: str  # the same in base64, for static pages
    node_names: tuple  # Meshcat path (under the root) of each visual geometry


_ROBOT_LOCK = threading.Lock()


#: the share of a robot part's triangles drawn (parts under ROBOT_SMALL_PART are whole)
ROBOT_KEEP = 0.1
ROBOT_SMALL_PART = 200


def _unit_normals(mesh) -> np.ndarray:
    """``mesh``'s vertex normals (n, 3), each of unit length: a corner whose faces' normals
    cancel (a sliver folded back on itself, as decimation leaves a few) takes one of its
    faces' normals instead of none, which would draw it black."""
    N = np.asarray(mesh.vertex_normals, dtype=np.float32).copy()
    bad = np.linalg.norm(N, axis=1) < 0.5
    if bad.any():
        own = np.zeros_like(N)
        own[np.asarray(mesh.faces).ravel()] = np.repeat(mesh.face_normals, 3, axis=0)
        N[bad] = own[bad]
    return N


def robot_parts(mesh_path: str, scale=(1.0, 1.0, 1.0), keep: float = ROBOT_KEEP):
    """The coloured parts of one visual mesh file, decimated, in the file's frame.

    Returns a list of ``(vertices (n, 3), faces (m, 3), normals (n, 3), colour)`` with
    ``colour`` an ``"#rrggbb"`` string (the part's material colour).
    """
    import fast_simplification
    import trimesh

    file = trimesh.load(mesh_path, force="scene")
    parts = []
    for node in file.graph.nodes_geometry:
        transform, name = file.graph[node]
        mesh = file.geometry[name]
        material = getattr(mesh.visual, "material", None)
        rgb = getattr(material, "main_color", None)
        colour = hex_string(rgb[:3]) if rgb is not None else "#e6ebed"
        points = trimesh.transform_points(mesh.vertices, transform) * np.asarray(scale)
        whole = trimesh.Trimesh(points, mesh.faces, process=True)  # shared corners merged
        V, F = whole.vertices, whole.faces
        if len(F) > ROBOT_SMALL_PART:
            V, F = fast_simplification.simplify(
                V.astype(np.float32), F.astype(np.int32), target_reduction=1.0 - keep
            )
        part = trimesh.Trimesh(V, F, process=True)
        # no zero-area faces and no loose corners: their normals would be zero (black)
        part.update_faces(part.nondegenerate_faces())
        part.remove_unreferenced_vertices()
        shaded = part.smooth_shaded
        parts.append(
            (
                np.asarray(shaded.vertices, dtype=np.float32),
                np.asarray(shaded.faces, dtype=np.uint32),
                _unit_normals(shaded),
                colour,
            )
        )
    return parts


def merged_parts(parts) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One link's coloured parts (:func:`robot_parts`) as one mesh with vertex colours.

    One mesh is one draw call, which on software GL costs about 0.1 ms whatever its size:
    the panda's 59 parts were 12 of a frame's 30 ms (2026-12-07); its 11 links move
    apart, so each link is one mesh. meshcat's three.js (r132) takes vertex colours as it
    takes a material's, so the colours are the parts' own.

    Returns
    -------
    vertices (n, 3), faces (m, 3), normals (n, 3), colours (n, 3) in [0, 1]
    """
    offsets = np.cumsum([0] + [len(V) for V, _, _, _ in parts[:-1]])
    vertices = np.concatenate([V for V, _, _, _ in parts])
    faces = np.concatenate([F + o for (_, F, _, _), o in zip(parts, offsets, strict=True)])
    normals = np.concatenate([N for _, _, N, _ in parts])
    rgb = rgb_floats([c for _, _, _, c in parts])
    colours = np.repeat(rgb, [len(V) for V, _, _, _ in parts], axis=0)
    return (vertices.astype(np.float32), faces.astype(np.uint32), normals.astype(np.float32),
            colours.astype(np.float32))


def _with_normals(geometry, normals):
    """A meshcat ``TriangularMeshGeometry`` that also sends its vertex ``normals``."""
    from meshcat.geometry import pack_numpy_array

    lower = geometry.lower

    def lowered(object_data):
        data = lower(object_data)
        data["data"]["attributes"]["normal"] = pack_numpy_array(normals.T)
        return data

    geometry.lower = lowered
    return geometry


@lru_cache(maxsize=2)
def _robot_meshes(name: str) -> RobotMeshes:
    import meshcat
    import meshcat.geometry as mg

    from ..robot import load_robot

    robot = load_robot(name)
    rec = SceneRecorder()
    vis = meshcat.Visualizer(window=rec)
    names = tuple(f"robot/visuals/{g.name}" for g in robot.visual_model.geometryObjects)
    for node, geom in zip(names, robot.visual_model.geometryObjects, strict=True):
        V, F, N, C = merged_parts(robot_parts(geom.meshPath, geom.meshScale))
        vis[node]["mesh"].set_object(
            _with_normals(mg.TriangularMeshGeometry(V, F, color=C), N),
            mg.MeshPhongMaterial(color=0xFFFFFF, shininess=30, vertexColors=True),
        )
    objects = tuple(c for c in rec.commands() if c[0] == "set_object")
    gz = frame_commands(objects)
    return RobotMeshes(objects, gz, base64.b64encode(gz).decode("ascii"), names)


def robot_meshes(name: str = "panda") -> RobotMeshes:
    """The meshes of the example-robot-data robot ``name`` (loaded once, thread-safe).

    ``node_names`` is in the order of the robot's visual model, the order of
    :meth:`tutor.robot.Arm.visual_placements`.
    """
    with _ROBOT_LOCK:
        return _robot_meshes(name)


def draw_fixtures(vis, scene) -> None:
    """Draw what never moves under ``lfd/``: table, tray, bin and the plants' stems (their
    balls, coloured by status, are :func:`plant_balls`).

    Parameters
    ----------
    vis : meshcat.Visualizer
    scene : PickPlaceScene
    """
    import meshcat.geometry as mg
    import meshcat.transformations as tf

    from ..robot import scene_obstacles

    colours = {"table": TABLE, "tray": TRAY}
    for name, center, size in scene_obstacles(scene):
        node = "lfd/" + name.replace(" ", "_")
        colour = colours.get(name, BIN)
        vis[node].set_object(mg.Box(list(size)), mg.MeshLambertMaterial(color=hex_colour(colour)))
        vis[node].set_transform(tf.translation_matrix(center))
    V, F, N = stem_mesh(scene)
    vis["lfd/stems"].set_object(
        _with_normals(mg.TriangularMeshGeometry(V, F), N),
        mg.MeshLambertMaterial(color=hex_colour(STEM)),
    )


def stem_mesh(scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 100 plants' stems as one mesh: ``(vertices (n, 3), faces (m, 3), normals (n, 3))``.

    One mesh is one draw call. On software GL (headless chromium, a machine without a GPU)
    each draw call costs about 0.1 ms whatever its size, and the 100 plants as 200 meshes
    were two thirds of a frame (22 of 30 ms, 2026-12-07). The stems never move, so they are
    drawn together; the balls, coloured by status, are one instanced mesh (:func:`plant_balls`).
    """
    import trimesh

    stem = trimesh.creation.cylinder(
        radius=0.5 * scene.plant_radius, height=scene.plant_height,
        sections=PLANT_STEM_SEGMENTS,
    )
    stem.apply_translation([0.0, 0.0, scene.plant_height / 2])  # standing on the tray
    V, F, N = stem.vertices, stem.faces, stem.vertex_normals
    bases = np.column_stack(
        [np.asarray(scene.plant_positions, dtype=float)[:, :2],
         np.full(len(scene.plant_positions), scene.tray_top)]
    )  # (k, 3)
    k, n = len(bases), len(V)
    vertices = (V[None] + bases[:, None]).reshape(-1, 3)
    faces = (F[None] + n * np.arange(k)[:, None, None]).reshape(-1, 3)
    normals = np.tile(N, (k, 1))
    return (vertices.astype(np.float32), faces.astype(np.uint32), normals.astype(np.float32))


def plant_balls(scene, colours) -> object:
    """The plants' balls, one on top of each stem, as one meshcat object: a three.js
    ``InstancedMesh`` (one draw call) whose instance ``i`` is coloured ``colours[i]``.

    Each ball was its own mesh, 100 of a frame's ~124 draw calls (about 0.1 ms each on
    software GL). The balls never move; a change of status sends the object again
    (about 8 kB: 100 matrices and colours, the sphere's parameters).

    Parameters
    ----------
    scene : PickPlaceScene
    colours : sequence of str
        ``"#rrggbb"`` per plant, in plant order.
    """
    import meshcat.geometry as mg
    from meshcat.geometry import pack_numpy_array

    positions = np.asarray(scene.plant_positions, dtype=float)[:, :2]
    k = len(positions)
    if len(colours) != k:
        raise InvalidParameterError(f"colours must have {k} entries, got {len(colours)}")
    width, height = PLANT_BALL_SEGMENTS
    radius = min(0.4 * scene.pitch, 1.6 * scene.plant_radius)
    sphere = segmented(mg.Sphere(radius), widthSegments=width, heightSegments=height)
    # three.js multiplies the material's colour (white) by the instance's; its r132 takes
    # both as given (no colour management), as it does the arm's vertex colours
    mesh = mg.Mesh(sphere, mg.MeshLambertMaterial(color=0xFFFFFF))
    matrices = np.tile(np.eye(4, dtype=np.float32).ravel(order="F"), (k, 1))  # (k, 16)
    matrices[:, 12:14] = positions  # a column-major matrix's translation: 12, 13, 14
    matrices[:, 14] = scene.tray_top + scene.plant_height
    rgb = rgb_floats(colours)
    lower = mesh.lower

    def lowered():
        data = lower()
        data["object"].update(
            type="InstancedMesh",
            count=k,
            # three.js would cull all instances by the one sphere at the origin
            frustumCulled=False,
            instanceMatrix={"array": pack_numpy_array(matrices.ravel())["array"]},
            instanceColor={"array": pack_numpy_array(rgb.ravel())["array"], "itemSize": 3},
        )
        return data

    mesh.lower = lowered
    return mesh


def segmented(geometry, **segments):
    """``geometry`` (a meshcat sphere or cylinder) drawn with ``segments`` (three.js's
    ``widthSegments``, ``heightSegments``, ``radialSegments``) instead of meshcat's."""
    lower = geometry.lower

    def lowered(object_data):
        return {**lower(object_data), **segments}

    geometry.lower = lowered
    return geometry


def draw_hand(vis, position) -> None:
    """The hand marker ``lfd/hand`` at ``position`` (3,): open ball shown, closed hidden."""
    import meshcat.geometry as mg
    import meshcat.transformations as tf

    hand = vis["lfd/hand"]
    hand["open"].set_object(
        mg.Sphere(HAND_RADIUS), mg.MeshLambertMaterial(color=hex_colour(HAND_OPEN))
    )
    hand["closed"].set_object(
        mg.Sphere(HAND_RADIUS), mg.MeshLambertMaterial(color=hex_colour(HAND_CLOSED))
    )
    hand["closed"].set_transform(tf.scale_matrix(1e-3))
    hand.set_transform(tf.translation_matrix(position))
