"""Room outlines: a drawing's own word on where one room is.

Architects draw each room's outline on a room layer ('Room - Utility').
A single line on the wall layer that cuts a room's outline into parts that
no door or opening joins is none of that room's walls: an overhead line, the
edge of the floor above, a setting-out line drawn on the wall layer (the UK
house of the corpus: a line across its utility room, through the walls on
both sides, sealed half of the room off). Walls drawn with two faces, and
anything between rooms, are not touched: only single-line wall material
(the lines that bound no double-line wall, thickened) deeper inside an
outline than ``THIN_WALL``.
"""

from __future__ import annotations

import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.ops import unary_union

from mapkit.importers.dxf.strokes import Stroke
from mapkit.shapes import polygon_parts
from mapkit.tolerances import ROOM_PART_MIN_AREA, THIN_WALL


def room_outlines(strokes: list[Stroke]) -> list[Polygon]:
    """The closed outlines of room layers' strokes, as polygons (metres)."""
    out = []
    for s in strokes:
        if (s.closed or s.filled) and len(s.coords) >= 3:
            out += [p for p in polygon_parts(shapely.make_valid(Polygon(s.coords))) if p.area > 0]
    return out


def lines_splitting_rooms(rooms: list[Polygon], walls, single_lines) -> Polygon | MultiPolygon:
    """The single-line wall material to take out of ``walls``: in each room
    outline that ``walls`` cut into more than one part of at least
    ``ROOM_PART_MIN_AREA`` (openings already cut), the ``single_lines``
    material deeper inside it than ``THIN_WALL``, where taking it out leaves
    fewer parts. Empty when no outline is so cut."""
    if single_lines.is_empty or not rooms:
        return Polygon()
    taken = []
    for room in rooms:
        inner = room.buffer(-THIN_WALL, join_style="mitre")
        if inner.is_empty:
            continue
        before = _parts(room, walls)
        if before <= 1:
            continue
        lines = single_lines.intersection(inner)
        if lines.is_empty or lines.area <= 0:
            continue
        if _parts(room, walls.difference(lines)) < before:
            taken.append(lines)
    return unary_union(taken) if taken else Polygon()


def _parts(room: Polygon, walls) -> int:
    """How many parts of at least ``ROOM_PART_MIN_AREA`` the walls cut ``room`` into."""
    return sum(p.area >= ROOM_PART_MIN_AREA for p in polygon_parts(room.difference(walls)))


__all__ = ["lines_splitting_rooms", "room_outlines"]
