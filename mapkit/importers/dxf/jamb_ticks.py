"""Jamb ticks: short strokes across a single-line wall that mark an opening's jambs.

Plans drawn with single-line walls (the Hal9k hackerspace's) mark the two
jambs of each opening by a short tick across the wall line, and draw the
door's swing beside them; a doorway without a door is its two ticks alone.
Read as walls, a tick is a little cross on the wall line: its arms look like
wall ends (a door's gap is looked for beside it) and two ticks side by side
look like the two faces of a thick wall. They are marks, not walls.

:func:`split_jamb_ticks` takes them out of the wall strokes;
:func:`tick_doorways` gives the openings that two ticks mark on one wall
line with no door drawing at either (those beside a door are its jambs; the
door's own drawing cuts its opening).

A tick: a straight stroke at most ``JAMB_TICK_MAX_LENGTH`` long that crosses
a longer wall stroke near its own middle (``JAMB_TICK_MIDDLE_SHARE``),
within ``JAMB_TICK_ANGLE_DEG`` of square to it, its two ends free (no other
stroke within ``SNAP_GAP``: a short side of a pier or a wall's corner
meets other lines there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import LineString, Point, Polygon

from mapkit.importers.dxf.strokes import Stroke
from mapkit.tolerances import (JAMB_REACH, JAMB_TICK_ANGLE_DEG, JAMB_TICK_MAX_LENGTH, JAMB_TICK_MIDDLE_SHARE,
                               MAX_DOOR_WIDTH, MIN_OPENING_WIDTH, SNAP_GAP, THIN_WALL)


@dataclass(frozen=True)
class JambTick:
    """A tick across a wall line: where it crosses it (``point``, metres),
    the wall line's unit ``direction`` there, and which wall stroke it
    crosses (``wall``, an index into the strokes kept as walls)."""

    point: np.ndarray
    direction: np.ndarray
    wall: int


def split_jamb_ticks(strokes: list[Stroke]) -> tuple[list[Stroke], list[JambTick]]:
    """The wall strokes less the jamb ticks, and the ticks (see the module
    docstring). Strokes of a block insert (``group``) and fills are kept."""
    lines = [_segment(s) for s in strokes]
    candidates = [k for k, seg in enumerate(lines) if seg is not None and seg.length <= JAMB_TICK_MAX_LENGTH]
    if not candidates:
        return strokes, []
    geoms = [_line(s) for s in strokes]
    long_ = [k for k, g in enumerate(geoms) if g is not None and g.length > JAMB_TICK_MAX_LENGTH]
    if not long_:
        return strokes, []
    tree = shapely.STRtree([geoms[k] for k in long_])
    every = [g for g in geoms if g is not None]
    near_tree = shapely.STRtree(every)
    sin_max = math.sin(math.radians(JAMB_TICK_ANGLE_DEG))
    found: dict[int, tuple[np.ndarray, np.ndarray, int]] = {}
    for k in candidates:
        tick = lines[k]
        a, b = (np.asarray(c, dtype=float) for c in tick.coords)
        along = (b - a) / tick.length
        if any(len(near_tree.query(Point(p), predicate="dwithin", distance=SNAP_GAP)) > 1 for p in (a, b)):
            continue  # an end meets other linework: a short wall (a pier's side), not a free-standing tick
        for j in tree.query(tick, predicate="intersects"):
            wall = geoms[long_[j]]
            hit = tick.intersection(wall)
            if not isinstance(hit, Point):
                continue  # along the wall, or crossing it twice
            p = np.array([hit.x, hit.y])
            share = float((p - a) @ along) / tick.length
            if abs(share - 0.5) > JAMB_TICK_MIDDLE_SHARE / 2:
                continue  # ends on the wall (a wall joining it) or crosses near one end
            d = _direction_at(wall, hit)
            if abs(float(d @ along)) > sin_max:
                continue  # askew to the wall: not a tick across it
            found[k] = (p, d, long_[j])
            break
    if not found:
        return strokes, []
    kept = [s for k, s in enumerate(strokes) if k not in found]
    new_index = {old: new for new, old in enumerate(k for k in range(len(strokes)) if k not in found)}
    ticks = [JambTick(p, d, new_index[w]) for p, d, w in found.values() if w in new_index]
    return kept, ticks


def tick_doorways(ticks: list[JambTick], door_items, walls) -> list[Polygon]:
    """Openings marked by two ticks on one wall line, with nothing between
    them: consecutive along the line, ``MIN_OPENING_WIDTH`` to
    ``MAX_DOOR_WIDTH`` apart, neither within ``JAMB_REACH`` of a door
    drawing. Each is the stretch of wall between them, as thick as a
    single-line wall (``THIN_WALL``), where it lies mostly in ``walls``."""
    if len(ticks) < 2:
        return []
    doors = shapely.union_all(list(door_items)) if door_items else None
    free = [t for t in ticks if doors is None or doors.distance(Point(t.point)) > JAMB_REACH]
    by_wall: dict[int, list[JambTick]] = {}
    for t in ticks:
        by_wall.setdefault(t.wall, []).append(t)
    free_ids = {id(t) for t in free}
    out = []
    for on_wall in by_wall.values():
        d = on_wall[0].direction
        on_wall.sort(key=lambda t: float(t.point @ d))
        for s, e in zip(on_wall[:-1], on_wall[1:]):
            if id(s) not in free_ids or id(e) not in free_ids:
                continue
            width = float((e.point - s.point) @ d)
            if not MIN_OPENING_WIDTH <= width <= MAX_DOOR_WIDTH:
                continue
            normal = np.array([-d[1], d[0]]) * (THIN_WALL / 2.0)
            footprint = Polygon([s.point - normal, e.point - normal, e.point + normal, s.point + normal])
            if walls.intersection(footprint).area < 0.5 * footprint.area:
                continue
            out.append(footprint)
    return out


def _segment(stroke: Stroke) -> LineString | None:
    """The stroke as one straight segment, or None (a curve, an outline, a fill)."""
    if stroke.closed or stroke.filled or stroke.group is not None:
        return None
    pts = np.asarray(stroke.coords, dtype=float)
    if len(pts) != 2 or not np.hypot(*(pts[1] - pts[0])) > 0:
        return None
    return LineString(pts)


def _line(stroke: Stroke) -> LineString | None:
    pts = np.asarray(stroke.coords, dtype=float)
    if stroke.filled or len(pts) < 2:
        return None
    if stroke.closed:
        pts = np.vstack([pts, pts[:1]])
    return LineString(pts)


def _direction_at(line: LineString, point: Point) -> np.ndarray:
    """Unit direction of ``line``'s piece through ``point``."""
    coords = np.asarray(line.coords)[:, :2]
    best, best_d = coords[1] - coords[0], math.inf
    for p, q in zip(coords[:-1], coords[1:]):
        dist = LineString([p, q]).distance(point)
        if dist < best_d and np.hypot(*(q - p)) > 0:
            best, best_d = q - p, dist
    return best / np.hypot(*best)


__all__ = ["JambTick", "split_jamb_ticks", "tick_doorways"]
