"""One storey of an IFC model -> :class:`~mapkit.scene.Scene`, z from the storey's floor.

- walls: the footprints of the walls and columns standing on its floor
  (whichever storey holds them: a wall may rise through two) seen from
  above, less the gaps of their doors, windows and unfilled openings;
- openings: each door's and window's gap: its opening element's footprint
  within its host wall, between the heights of that opening (its real sill
  and head; an element filling no opening: its own extent);
- wall heights: each wall's top above the floor, at most the storey's
  height (walls of several heights: a height zone per height, over its
  walls, so each wall face rises to its own wall's top);
- free space: its spaces (``IfcSpace``) and door gaps, else its floor
  slabs, else what its walls enclose; less walls and the stairs, ramps and
  lifts standing in it; shrunk by the robot radius.
"""

from __future__ import annotations

from functools import partial

import shapely
from shapely.geometry import MultiPolygon, Polygon

from mapkit.errors import NoFreeSpaceError, NoWallsError
from mapkit.importers import warn_decision
from mapkit.importers.ifc.geometry import Mesh
from mapkit.importers.ifc.read import Storey, count_roles
from mapkit.options import BuildOptions
from mapkit.scene import HeightZone, Opening, Scene
from mapkit.shapes import polygon_parts
from mapkit.tolerances import IFC_GRID, IFC_LEVEL, IFC_SLAB_REACH, IFC_STACKED_OVERLAP, MIN_FREE_AREA, ZERO


def storey_scene(storey: Storey, meshes: dict[int, Mesh], standing: list, obstacles, options: BuildOptions,
                 info: dict) -> Scene:
    """The scene of ``storey``; ``standing`` are the walls and columns
    standing on its floor (:func:`standing_walls`), ``obstacles``
    (MultiPolygon) the footprints of the vertical connections within it;
    ``info`` (source, schema) is completed and stored in the scene."""
    info = dict(info) | {"storey": storey.name, "elevation_m": round(storey.elevation, 4),
                         "height_m": round(storey.height, 4)}
    warnings = info["warnings"] = list(info.get("warnings", []))  # this storey's own
    warn = partial(warn_decision, warnings)
    where = f"storey '{storey.name}'"
    walls_by_id = {e.id(): meshes[e.id()].footprint() for e in standing}
    solid = MultiPolygon(polygon_parts(shapely.union_all(list(walls_by_id.values()) or [MultiPolygon()])))
    if solid.is_empty:
        raise NoWallsError(f"{where} has no walls or columns with a body; check it with 'mapkit layers'")
    wall_height, zones = _wall_heights(storey, [meshes[e.id()] for e in standing], list(walls_by_id.values()), warn)
    openings = _merge_stacked(_openings(storey, meshes, walls_by_id, solid, warn), where, warn)
    gaps = shapely.union_all([o.footprint for o in openings] or [MultiPolygon()])
    walls = MultiPolygon(polygon_parts(solid.difference(gaps)))

    interior, source = _interior(storey, meshes, solid)
    if source != "spaces":
        warn(f"{where} has no spaces (IfcSpace): its free space is {source}")
    doors = [o.footprint for o in openings if o.kind == "door"]
    free = shapely.union_all([interior, *doors]).difference(walls)
    if not obstacles.is_empty:
        free = free.difference(obstacles)
    if options.robot_radius > ZERO.distance:
        free = free.buffer(-options.robot_radius)
    free = MultiPolygon([p for p in polygon_parts(free) if p.area >= MIN_FREE_AREA])

    cam_h = float(options.camera.get("height_m", 1.2))
    if cam_h >= wall_height:
        warn(f"{where}: camera height {cam_h:g} m is not below its walls' {wall_height:g} m")
    info["free_space"] = source
    info["counts"] = {k: v for k, v in count_roles([e for v in storey.elements.values() for e in v]).items()}
    info["layers"] = {"walls": sorted({e.is_a() for e in standing}),
                      "doors": ["IfcDoor"] if storey.of("door") else [], "windows": ["IfcWindow"] if storey.of("window") else []}
    info["areas_m2"] = {"walls": round(walls.area, 3), "free_space": round(free.area, 3)}
    scene = Scene(walls=walls, openings=openings, free_space=free, wall_height=wall_height, height_zones=zones,
                  obstacles=MultiPolygon(polygon_parts(obstacles)), info=info)
    if free.is_empty:
        raise NoFreeSpaceError(f"{where}: no free space left inside its walls after keeping {options.robot_radius:g} m "
                               "from them; check the storey with 'mapkit preview'", scene)
    return scene


def standing_walls(storey: Storey, walls: list, meshes: dict[int, Mesh]) -> list:
    """The walls and columns among ``walls`` (of any storey) standing on
    ``storey``'s floor: from at most ``IFC_LEVEL`` above it to more than
    that above it. A wall of two storeys stands in the lower one and in the
    upper one if it starts below that floor; a wall on the floor below
    (foundations) or hanging from the ceiling (a bulkhead) does not."""
    floor = storey.elevation + IFC_LEVEL
    return [e for e in walls if e.id() in meshes and meshes[e.id()].z_range[0] <= floor < meshes[e.id()].z_range[1]]


def _wall_heights(storey: Storey, walls: list[Mesh], footprints: list, warn) -> tuple[float, list[HeightZone]]:
    """Each wall's own height: its top above the storey's floor, at most
    the storey's height, walls within ``IFC_LEVEL`` of one another one
    height. One height: it, and no zones. Several: the tallest, and a
    height zone per height over the footprints of its walls, so that each
    wall face rises to its own wall's top (:mod:`mapkit.edges`: a face
    takes the height of the zone nearest it)."""
    tops = [min(m.z_range[1] - storey.elevation, storey.height) for m in walls]
    by_level: dict[int, list] = {}
    for top, fp in zip(tops, footprints):
        by_level.setdefault(round(top / IFC_LEVEL), []).append((top, fp))
    if len(by_level) <= 1:
        return (max(tops) if tops else storey.height), []
    zones = [HeightZone(MultiPolygon(polygon_parts(shapely.union_all([fp for _, fp in group]))),
                        float(max(t for t, _ in group)))
             for _, group in sorted(by_level.items())]
    heights = ", ".join(f"{z.height:.3g}" for z in zones)
    warn(f"storey '{storey.name}': walls of {len(zones)} heights ({heights} m): each wall face rises to its own "
         "wall's top, taken level (a sloping top at its highest point)")
    return max(z.height for z in zones), zones


def _openings(storey: Storey, meshes: dict[int, Mesh], walls_by_id: dict, solid, warn) -> list[Opening]:
    """Each door's, window's and unfilled opening's gap in its host wall."""
    out = []
    filled = set()
    for role in ("door", "window"):
        for element in storey.of(role):
            voids = [rel.RelatingOpeningElement for rel in (getattr(element, "FillsVoids", None) or [])]
            body = next((v for v in voids if v.id() in meshes), None)
            filled.update(v.id() for v in voids)
            opening = _gap(body or element, meshes, walls_by_id, solid, storey.elevation, role)
            if opening is None:
                warn(f"storey '{storey.name}': {element.is_a()} '{element.Name or element.GlobalId}' is in no wall; "
                     "left out")
            else:
                out.append(opening)
    for element in storey.of("opening"):
        if element.id() in filled or getattr(element, "HasFillings", None):
            continue
        hosts = [rel.RelatingBuildingElement for rel in (getattr(element, "VoidsElements", None) or [])]
        if not any(h.id() in walls_by_id for h in hosts):
            continue  # a hole in a slab (a stairwell) or a roof: no gap in a wall
        z0 = meshes[element.id()].z_range[0] - storey.elevation if element.id() in meshes else 0.0
        opening = _gap(element, meshes, walls_by_id, solid, storey.elevation, "door" if z0 <= IFC_LEVEL else "window")
        if opening is not None:
            out.append(opening)
    return out


def _merge_stacked(openings: list[Opening], where: str, warn) -> list[Opening]:
    """Openings over one another in the same gap (a window stacked on a
    window, a fanlight over a door) as one, from the lowest sill to the
    highest head: a scene's opening is closed wherever another opening's
    footprint is, so stacked ones would close each other. The transoms
    between them are left out of the map (a warning says how many)."""
    out: list[Opening] = []
    merged = 0
    for o in sorted(openings, key=lambda o: (o.kind != "door", o.sill)):
        same = next((k for k, p in enumerate(out)
                     if p.footprint.intersection(o.footprint).area >= IFC_STACKED_OVERLAP * min(p.footprint.area,
                                                                                               o.footprint.area)), None)
        if same is None:
            out.append(o)
            continue
        p = out[same]
        out[same] = Opening(shapely.union_all([p.footprint, o.footprint]), p.kind, min(p.sill, o.sill),
                            max(p.head, o.head))
        merged += 1
    if merged:
        warn(f"{where}: {merged} openings stacked over others in the same gap taken as one with them, from the "
             "lowest sill to the highest head (the transoms between are not in the map)")
    return out


def _gap(body, meshes: dict[int, Mesh], walls_by_id: dict, solid, elevation: float, kind: str) -> Opening | None:
    """The gap ``body`` (an opening element, or a door or window without
    one) makes in its host wall (the storey's walls if it has none here)."""
    if body.id() not in meshes:
        return None
    mesh = meshes[body.id()]
    hosts = [rel.RelatingBuildingElement for rel in (getattr(body, "VoidsElements", None) or [])]
    host = next((walls_by_id[h.id()] for h in hosts if h.id() in walls_by_id), solid)
    footprint = MultiPolygon(polygon_parts(mesh.footprint().intersection(host)))
    footprint = max(polygon_parts(footprint), key=lambda p: p.area, default=None)
    if footprint is None or footprint.area <= IFC_GRID**2:
        return None
    z0, z1 = mesh.z_range
    sill = max(0.0, z0 - elevation)
    sill = 0.0 if sill <= IFC_LEVEL else sill
    return Opening(footprint=footprint, kind=kind, sill=float(sill), head=float(z1 - elevation))


def _interior(storey: Storey, meshes: dict[int, Mesh], solid) -> tuple[MultiPolygon, str]:
    """Where the storey's rooms are, and what says so: its spaces, else its
    floor slabs, else the holes of its walls."""
    spaces = [meshes[e.id()].footprint() for e in storey.of("space") if e.id() in meshes]
    if spaces:
        return MultiPolygon(polygon_parts(shapely.union_all(spaces))), "spaces"
    slabs = [meshes[e.id()].footprint() for e in storey.of("slab") if e.id() in meshes
             and abs(meshes[e.id()].z_range[1] - storey.elevation) <= IFC_SLAB_REACH]
    if slabs:
        return MultiPolygon(polygon_parts(shapely.union_all(slabs))), "its floor slabs"
    holes = [Polygon(ring) for p in polygon_parts(solid) for ring in p.interiors]
    return MultiPolygon(polygon_parts(shapely.union_all(holes or [MultiPolygon()]))), "what its walls enclose"
