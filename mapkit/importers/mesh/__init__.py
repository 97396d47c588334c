"""3D meshes (OBJ, PLY, STL, glTF/GLB, OFF) to a :class:`~mapkit.scene.Scene`.

    file --load--> welded mesh (metres, z up, floor at 0)
         --section--> walls at camera height, low obstacles, rooms
         --edges--> 3D feature edges and their kinds
         --hidden--> without the parts buried inside other solids

(modules of this package: :mod:`.load`, :mod:`.section`, :mod:`.edges`,
:mod:`.hidden`)

Doors in a mesh are just geometry (gaps and lintels), so ``openings`` is
empty; the importer provides the edges itself, so the pipeline does not
derive them from the walls.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import MultiPolygon

from mapkit.importers import warn_decision
from mapkit.errors import MapkitError, NoWallsError
from mapkit.importers.mesh.hidden import drop_hidden
from mapkit.importers.mesh.load import load_mesh
from mapkit.importers.mesh.section import MeshSections, as_multipolygon, boundary_outline
from linemap.lmap import KIND_NAMES
from mapkit.importers.mesh.edges import face_normals, feature_edges, merge_overlapping
from mapkit.options import BuildOptions
from mapkit.scene import Scene
from mapkit.tolerances import AXIS_DEG, MESH_LEVEL, MESH_MAX_SECTIONS, MESH_OBSTACLE_HEIGHTS, MIN_FREE_AREA

SUFFIXES = (".obj", ".ply", ".stl", ".glb", ".gltf", ".off")


def load_scene(path: Path, options: BuildOptions) -> Scene:
    """Import a mesh file; see the module docstring for the steps."""
    path = Path(path)
    mesh, info = load_mesh(path, options)
    warnings = info["warnings"]
    top = float(info["wall_height_m"])
    if top <= MESH_LEVEL:
        raise NoWallsError(f"{path}: the model is flat (nothing stands above the floor); check --up")
    if options.wall_height != BuildOptions.wall_height:
        warn_decision(warnings, f"--wall-height {options.wall_height:g} is for DXF plans; a mesh's walls are as high as "
                        f"the model's ({top:.3g} m)")
    cam_h = float(options.camera.get("height_m", 1.2))
    # The section must cut the walls: keep it strictly between floor and top.
    z = float(np.clip(cam_h, MESH_LEVEL, top - MESH_LEVEL))
    if z != cam_h:
        warn_decision(warnings, f"camera height {cam_h:g} m is outside the walls (0 to {top:.3g} m); walls cut at {z:.3g} m")

    sections = MeshSections(mesh)
    walls, _ = sections.cut(z)
    if walls.is_empty:
        raise NoWallsError(
            f"{path}: nothing of the model stands at camera height {z:.3g} m; check --up, --units or --camera-height"
        )
    low = [sections.cut(h)[0] for h in MESH_OBSTACLE_HEIGHTS if h < top]
    obstacles = (_outline(path, "the plan of the obstacles below camera height",
                          lambda: as_multipolygon(shapely.difference(shapely.union_all(low), walls)))
                 if low else MultiPolygon())

    if info["floor_faces"]:
        area = floor_area(mesh)
    else:
        area = enclosed_rooms(sections, mesh, top, z)
        if area.is_empty:
            raise MapkitError(
                f"{path}: the mesh has no floor and its walls enclose no room; add a floor surface or close the walls"
            )
    free = _outline(path, "the floor less the walls", lambda: shapely.difference(area, shapely.union_all([walls, obstacles])))
    if options.robot_radius > 0:
        free = free.buffer(-options.robot_radius)
    free = MultiPolygon([p for p in as_multipolygon(free).geoms if p.area >= MIN_FREE_AREA])
    if free.is_empty:
        raise MapkitError(f"{path}: no free space is left for the robot; check --robot-radius and --units")

    segments, kinds = feature_edges(mesh, options.crease_deg, options.min_edge_length, 0.0, top)
    segments, kinds, hidden_warnings = drop_hidden(segments, kinds, sections, options.min_edge_length)
    for w in hidden_warnings:
        warn_decision(warnings, w)
    segments, kinds = merge_overlapping(segments, kinds)
    counts = np.bincount(kinds, minlength=len(KIND_NAMES))
    info.update(
        section_height_m=z,
        segments=int(len(segments)),
        kinds={name: int(c) for name, c in zip(KIND_NAMES, counts) if c},
        free_area_m2=float(free.area),
    )
    return Scene(walls=walls, openings=[], free_space=free, wall_height=top, obstacles=obstacles,
                 segments=segments, kinds=kinds, info=info)


def floor_area(mesh) -> MultiPolygon:
    """What the floor faces (upward, horizontal, at z = 0) cover, seen from above."""
    vertices = np.asarray(mesh.vertices)
    faces = np.asarray(mesh.faces)
    normals, _ = face_normals(vertices, faces)
    at_floor = np.abs(vertices[faces][:, :, 2]).max(axis=1) <= MESH_LEVEL
    up = normals[:, 2] >= np.cos(np.radians(AXIS_DEG))
    return boundary_outline(vertices, faces[at_floor & up])


def enclosed_rooms(sections: MeshSections, mesh, top: float, z_camera: float) -> MultiPolygon:
    """Walls-only meshes: the indoor area, rooms and walls, seen from above.

    Doorways leave rooms open near the floor; the wall above a door closes
    them. So a point is indoors if, at some height, it is in an enclosed
    room or in wall material (the lintel over a doorway: the doorway itself
    is free space below it). Sections are taken between consecutive vertex
    heights (where the section changes), at most ``MESH_MAX_SECTIONS`` of
    them, and at the camera height.
    """
    levels = np.unique(np.round(np.asarray(mesh.vertices)[:, 2] / MESH_LEVEL) * MESH_LEVEL)
    levels = levels[(levels >= 0) & (levels <= top)]
    mids = 0.5 * (levels[1:] + levels[:-1])
    if len(mids) > MESH_MAX_SECTIONS:
        mids = mids[np.linspace(0, len(mids) - 1, MESH_MAX_SECTIONS).round().astype(int)]
    cuts = [sections.cut(float(h)) for h in np.r_[mids, z_camera]]
    rooms = shapely.union_all([r for _, r in cuts])
    if rooms.is_empty:
        return MultiPolygon()
    return as_multipolygon(shapely.union_all([rooms] + [w for w, _ in cuts]))


def _outline(path, what: str, make):
    """``make()``, GEOS work on the mesh's sections; as in
    MeshSections.section, faces crossing each other can make GEOS fail
    (a TopologyException), which becomes one line naming ``what``."""
    try:
        return make()
    except shapely.errors.GEOSException as exc:
        reason = str(exc).split(". ")[0][:100]
        raise MapkitError(f"{path}: {what} is not a valid outline ({reason}): the mesh's faces cross each other; "
                          "repair the model or export it again") from None
