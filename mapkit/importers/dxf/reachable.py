"""Spaces no door leads into: shafts, light wells, roofs, voids.

A plan's walls enclose more than rooms. Between two walls runs a pipe
shaft or an expansion joint; a light well or a roof terrace is walled in
by the facades around it; a glazed roof over an entrance hall, seen from
the floor above, is a grid of closed panels. Each is a hole of the walls
as a room is, so it becomes free space of its own, cut off from the rest:
a place the robot can never be, whose regions the map would carry all the
same (and whose many small parts split the free space).

What tells a room from such a space is its entry: people reach a room
through a door (or a doorway, an opening between two wall ends). When a
plan's doors were found, a part of the free space that no door or doorway
touches (within the robot's radius, the margin the free space keeps from
the jambs) is left out. A door drawing whose gap was not found counts as a
door: the room it opens into stays (and the missing door shows in the
count of doors found). Plans without any door found keep every part: no
entry can be told from none.
"""

from __future__ import annotations

import shapely
from shapely.geometry import MultiPolygon, Polygon

from mapkit.shapes import polygon_parts
from mapkit.tolerances import DOOR_REACH_SLACK


def entered_parts(free: MultiPolygon, entries: list, robot_radius: float) -> tuple[MultiPolygon, list[Polygon]]:
    """``(kept, left_out)``: the parts of ``free`` (metres) that one of
    ``entries`` (door gap footprints, doorways, door drawings) touches, and
    the others.

    A part touches an entry within ``robot_radius + DOOR_REACH_SLACK``: the
    free space is shrunk by the robot's radius, so through a doorway
    narrower than the robot it stops that far short of the gap. With no
    entry, or when no part is touched, every part is kept."""
    parts = polygon_parts(free)
    if not entries or len(parts) <= 1:
        return free, []
    reach = robot_radius + DOOR_REACH_SLACK
    tree = shapely.STRtree(entries)
    touched = [len(tree.query(p, predicate="dwithin", distance=reach)) > 0 for p in parts]
    if not any(touched):
        return free, []
    kept = [p for p, t in zip(parts, touched) if t]
    left_out = [p for p, t in zip(parts, touched) if not t]
    if not left_out:
        return free, []
    return MultiPolygon(kept), left_out


def where_left_out(left_out: list[Polygon]) -> str:
    """The largest three of ``left_out`` by area and place, for a warning:
    ``"3.8 m2 at (115.7, 5.1), ... and 7 more"`` (metres)."""
    largest = sorted(left_out, key=lambda p: -p.area)[:3]
    where = ", ".join(f"{p.area:.1f} m2 at ({p.representative_point().x:.1f}, {p.representative_point().y:.1f})"
                      for p in largest)
    return where + (f" and {len(left_out) - len(largest)} more" if len(left_out) > len(largest) else "")


def describe_left_out(left_out: list[Polygon]) -> str:
    """One warning line about the spaces :func:`entered_parts` left out."""
    area = sum(p.area for p in left_out)
    return (f"{len(left_out)} enclosed space(s) that no door or doorway leads into ({area:.1f} m2: shafts, light "
            f"wells, roofs, or rooms whose doors are not drawn or were not found) left out of the free space: "
            f"{where_left_out(left_out)}; check them in 'mapkit preview'")


__all__ = ["describe_left_out", "entered_parts", "where_left_out"]
