"""A ZInD floor (rooms, openings) -> :class:`~mapkit.scene.Scene`.

ZInD draws the inside outline of each room. The walls are what lies
within ``ZIND_WALL_THICKNESS`` of some room and in no room, with the gaps
between neighbouring rooms' walls filled (``ZIND_WALL_GAP_CLOSE``). Each
door, window or opening cuts the wall behind it, from the annotating
room's face through to the other side (at most ``ZIND_OPENING_REACH``);
a gap annotated from both rooms is cut once. Each room is a height zone
with its own ceiling; free-standing parts (kitchen islands) are obstacles.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import shapely
from shapely.geometry import LineString, MultiPolygon, Polygon

from mapkit.importers import warn_decision
from mapkit.errors import MapkitError
from mapkit.importers.zind.annotations import ZindFloor, ZindOpening
from mapkit.options import BuildOptions
from mapkit.scene import HeightZone, Opening, Scene
from mapkit.tolerances import (
    MIN_FREE_AREA,
    ZERO,
    ZIND_FLOOR_SNAP,
    ZIND_OPENING_REACH,
    ZIND_OPENING_SLACK,
    ZIND_SAME_GAP_OVERLAP,
    ZIND_WALL_GAP_CLOSE,
    ZIND_WALL_THICKNESS,
)


def scene_from_floor(floor: ZindFloor, options: BuildOptions) -> Scene:
    """The scene of one ZInD floor; see the module docstring."""
    warnings = list(floor.warnings)

    warn = partial(warn_decision, warnings)

    rooms = [_polygon(r.outline, r.name, warn) for r in floor.rooms]
    inside = shapely.union_all(rooms)
    solid = inside.buffer(ZIND_WALL_THICKNESS + ZIND_WALL_GAP_CLOSE, join_style="mitre")
    solid = solid.buffer(-ZIND_WALL_GAP_CLOSE, join_style="mitre")
    wall_material = solid.difference(inside)

    gaps, one_sided = _gaps(floor, rooms, wall_material)
    openings: list[Opening] = []
    passages, window_gaps, kept = [], [], []
    for o, gap in gaps:
        if any(gap.intersection(t).area > 0.5 * min(gap.area, t.area) for t in passages + window_gaps):
            continue  # the same gap, annotated from the room on its other side
        sill = 0.0 if o.bottom < ZIND_FLOOR_SNAP else o.bottom
        head = max(o.top, sill + ZIND_FLOOR_SNAP)
        openings.append(Opening(gap, "window" if o.kind == "window" else "door", sill, head))
        (window_gaps if o.kind == "window" else passages).append(gap)
        kept.append(o.kind)
    missed = sum(len(r.openings) for r in floor.rooms) - len(gaps)
    if missed:
        warn(f"{missed} door(s), window(s) or opening(s) are not on a room's wall and were left out")
    if one_sided:
        warn(f"{one_sided} door(s) or opening(s) toward a neighbouring room are annotated from one side only: "
             "each is a recess in the wall, not a way through")

    cut = shapely.union_all(passages + window_gaps) if openings else Polygon()
    walls = _multi(wall_material.difference(cut))
    islands = [Polygon(v).buffer(0) for r in floor.rooms for v in r.internal if len(v) >= 3]
    obstacles = _multi(shapely.union_all(window_gaps + islands)) if (window_gaps or islands) else MultiPolygon()
    interior = shapely.union_all([inside, *passages])
    free = interior.difference(walls).difference(obstacles)
    if options.robot_radius > ZERO.distance:
        free = free.buffer(-options.robot_radius)
    free = MultiPolygon([p for p in shapely.get_parts(free) if isinstance(p, Polygon) and p.area >= MIN_FREE_AREA])
    if free.is_empty:
        raise MapkitError(f"floor '{floor.name}': no free space left in its rooms after keeping "
                          f"{options.robot_radius:g} m from the walls; lower --robot-radius")

    zones = [HeightZone(poly, r.ceiling_height) for r, poly in zip(floor.rooms, rooms)]
    heights = [z.height for z in zones]
    info = {
        "format": "ZInD",
        "floor": floor.name,
        "camera_height_m": round(floor.camera_height, 4),
        "ceiling_heights_m": [round(min(heights), 3), round(max(heights), 3)],
        "counts": {
            "rooms": len(rooms),
            "panoramas": len(floor.panos),
            "doors": kept.count("door"),
            "windows": kept.count("window"),
            "openings": kept.count("opening"),
        },
        "areas_m2": {"walls": round(walls.area, 3), "free_space": round(free.area, 3), "interior": round(interior.area, 3)},
        "warnings": warnings,
    }
    return Scene(walls=walls, openings=openings, free_space=free, wall_height=max(heights), obstacles=obstacles,
                 height_zones=zones, camera_height=floor.camera_height, info=info)


def _polygon(outline: np.ndarray, name: str, warn) -> Polygon:
    """A room's outline as a valid polygon (a self-crossing one repaired, with a warning)."""
    poly = Polygon(outline)
    if not poly.is_valid:
        fixed = shapely.make_valid(poly)
        parts = [p for p in shapely.get_parts(fixed) if isinstance(p, Polygon)]
        if not parts:
            raise MapkitError(f"room '{name}': its outline encloses no area")
        poly = max(parts, key=lambda p: p.area)
        warn(f"room '{name}': its outline crosses itself; kept its largest part ({poly.area:.1f} m2)")
    return poly


def _gaps(floor: ZindFloor, rooms: list[Polygon], wall_material) -> tuple[list, int]:
    """(opening, gap polygon) of every opening on a wall, and how many were cut short.

    A gap goes through the wall when nothing is behind it (an outside wall)
    or when the room behind annotates a gap there too (the same door seen
    from both sides). A door or opening that the room behind does not
    annotate is cut only to halfway to that room: seen from there it is a
    wall (the sample tour's garage has an "opening" onto a recess that its
    neighbour sees as plain wall)."""
    full = []
    for k, (room, poly) in enumerate(zip(floor.rooms, rooms)):
        for o in room.openings:
            gap = _cut(o, poly, wall_material, ZIND_OPENING_REACH)
            if gap is not None:
                full.append((k, o, poly, gap))
    out, one_sided = [], 0
    for k, o, poly, gap in full:
        behind = shapely.union_all([r for j, r in enumerate(rooms) if j != k] or [Polygon()])
        depth = float(shapely.distance(shapely.points(*o.ends.mean(axis=0)), behind)) if not behind.is_empty else np.inf
        seen_behind = any(j != k and gap.intersection(g).area > ZIND_SAME_GAP_OVERLAP * min(gap.area, g.area)
                          for j, _, _, g in full)
        if depth < ZIND_OPENING_REACH and not seen_behind and o.kind != "window":
            gap = _cut(o, poly, wall_material, 0.5 * depth)
            one_sided += 1
            if gap is None:
                continue
        out.append((o, gap))
    return out, one_sided


def _cut(o: ZindOpening, room: Polygon, wall_material, reach: float) -> Polygon | None:
    """The wall gap an opening makes: from the room's face outwards through
    the wall up to ``reach`` metres, the part of the wall that touches the
    annotated line."""
    a, b = o.ends
    along = b - a
    length = float(np.hypot(*along))
    if length < ZERO.derived_length:
        return None
    normal = np.array([-along[1], along[0]]) / length
    mid = 0.5 * (a + b)
    if room.contains(shapely.points(*(mid + 2 * ZIND_OPENING_SLACK * normal))):
        normal = -normal  # point outwards, away from the room
    back, out = -ZIND_OPENING_SLACK * normal, reach * normal
    rect = Polygon([a + back, b + back, b + out, a + out])
    line = LineString([a, b])
    parts = [p for p in shapely.get_parts(rect.intersection(wall_material))
             if isinstance(p, Polygon) and p.area > 0 and p.distance(line) <= 2 * ZIND_OPENING_SLACK]
    if not parts:
        return None
    gap = shapely.union_all(parts)
    return gap if isinstance(gap, Polygon) else max(shapely.get_parts(gap), key=lambda p: p.area)


def _multi(geom) -> MultiPolygon:
    return MultiPolygon([p for p in shapely.get_parts(geom) if isinstance(p, Polygon) and p.area > 0])
