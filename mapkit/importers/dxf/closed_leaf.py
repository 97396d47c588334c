"""The doorway a door swing drawn over an unbroken wall stands for: where its leaf closes.

A swing (an arc about the hinge and the open leaf, :mod:`.door_swings`)
says exactly where its doorway is: the closed leaf runs from the hinge to
the end of the arc away from the open leaf's tip, the latch. People draw
swings over walls they leave unbroken: a threshold or frame drawn as a
rectangle across the doorway (a 0.1 m wall drawn closed under the door), a
facade's outer face drawn straight across a bay's French doors, a glazed
entrance's frame lines across the diagonal wall it sits in. A leaf cannot
swing through a wall: whatever walls cross the closed leaf's line are the
door's opening.

The opening is the rectangle along the wall from the hinge to the latch
(the closed leaf projected on the wall's direction), across the whole
wall the closed leaf lies in or beside (within ``JAMB_REACH``). It is
only an opening when that wall crosses the whole doorway, the open leaf
runs through it from the hinge (the door is drawn in the wall, not
against its face, where a walled-up doorway's swing may be left), and it
is no thicker than a wall.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import LineString, MultiLineString, Polygon

from mapkit.importers.dxf.openings import longest_edge_along
from mapkit.tolerances import (DOOR_SWING_RADIUS, DOOR_SWING_SNAP, DOOR_SWING_TIP_SHARE, JAMB_REACH, MAX_DOOR_WIDTH,
                               MERGE, MIN_OPENING_WIDTH, SWING_CUT_PROBES, WALL_DIRECTION_SNAP_DEG)


def closed_leaf_opening(item: MultiLineString, walls, max_wall_thickness: float) -> Polygon | None:
    """Footprint (metres) of the opening the swing ``item`` (an arc and its
    leaf, as :func:`.openings.drawing_items` gives them) stands for, cut
    through ``walls`` where its closed leaf lies; None when ``item`` is no
    swing or its closed leaf crosses no wall (see the module docstring)."""
    leaf = _closed_leaf(item)
    if leaf is None:
        return None
    hinge, latch, tip = leaf
    axis = (latch - hinge) / np.linalg.norm(latch - hinge)
    axis = _wall_direction(axis, LineString([hinge, latch]).buffer(JAMB_REACH), walls)
    normal = np.array([-axis[1], axis[0]])
    t0, t1 = float(hinge @ axis), float(latch @ axis)
    if t1 < t0:
        axis, normal, t0, t1 = -axis, -normal, -t0, -t1
    if not MIN_OPENING_WIDTH <= t1 - t0 <= MAX_DOOR_WIDTH:
        return None
    n_lo = min(float(hinge @ normal), float(latch @ normal)) - JAMB_REACH
    n_hi = max(float(hinge @ normal), float(latch @ normal)) + JAMB_REACH
    band = _rectangle(axis, normal, t0, t1, n_lo, n_hi)
    wide_band = _rectangle(axis, normal, t0, t1, n_lo - max_wall_thickness, n_hi + max_wall_thickness)
    walls = _clipped(walls, wide_band)  # (a whole building's walls are costly to cut per door)
    inside = walls.intersection(band)
    if inside.is_empty or inside.area <= 0:
        return None
    # The wall crosses the doorway: every probe across it, between the jambs, meets wall.
    for k in range(1, SWING_CUT_PROBES + 1):
        t = t0 + (t1 - t0) * k / (SWING_CUT_PROBES + 1)
        probe = LineString([axis * t + normal * n_lo, axis * t + normal * n_hi])
        if probe.intersection(inside).length <= MERGE:
            return None
    # Across, the opening spans the whole wall the leaf closes in (the
    # leaf may lie along one of its faces): the wall material between the
    # jambs, within a wall's thickness, that the probes met.
    wide = walls.intersection(wide_band)
    crossing = [p for p in shapely.get_parts(wide) if isinstance(p, Polygon) and p.intersects(inside)]
    # Drawn in the wall, not against it: the open leaf runs through wall
    # from the hinge (a leaf drawn against a wall's face only touches it).
    if LineString([hinge, tip]).intersection(walls).length <= 2 * MERGE:
        return None
    across = np.concatenate([np.asarray(p.exterior.coords)[:, :2] @ normal for p in crossing])
    s0, s1 = float(across.min()), float(across.max())
    if s1 - s0 > max_wall_thickness:
        return None
    return _rectangle(axis, normal, t0, t1, s0, s1)


def walled_swing_doorway(item: MultiLineString, gap: Polygon, walls, max_wall_thickness: float) -> Polygon | None:
    """The opening where the swing ``item`` closes (:func:`closed_leaf_opening`)
    when a wall crosses it there and ``gap``, the wall gap found for the
    drawing, lies mostly elsewhere: a gap between a jamb and the fixture
    beside the swing (a WC's bowl) is not the door's, its doorway is where
    the leaf closes, across the line drawn there. None otherwise."""
    walled = closed_leaf_opening(item, walls, max_wall_thickness)
    if walled is None or walled.intersection(gap).area >= 0.5 * min(walled.area, gap.area):
        return None
    return walled


def _closed_leaf(item: MultiLineString) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(hinge, latch, tip)`` of a swing drawing (the open leaf's tip): one arc (a polyline of at least
    three points on a circle of a door's radius) and one straight leaf from
    its centre (within ``DOOR_SWING_TIP_SHARE`` of the radius); the latch
    is the arc's end farther from the leaf's tip. None for anything else.

    The lines of a drawing are noded where they cross (:func:`.openings.drawing_items`):
    a leaf drawn across its arc's end cuts the arc in pieces, joined here again."""
    curves, straights = [], []
    for part in item.geoms:
        pts = np.asarray(part.coords)[:, :2]
        (curves if len(pts) >= 3 else straights).append(pts)
    if len(curves) > 1:
        curves = [np.asarray(g.coords)[:, :2] for g in shapely.get_parts(shapely.line_merge(MultiLineString(curves)))]
    if len(curves) != 1 or not straights:
        return None
    arc = curves[0]
    circle = _circle(arc[0], arc[len(arc) // 2], arc[-1])
    if circle is None:
        return None
    centre, radius = circle
    if not DOOR_SWING_RADIUS[0] <= radius <= DOOR_SWING_RADIUS[1]:
        return None
    snap = max(DOOR_SWING_SNAP, DOOR_SWING_TIP_SHARE * radius)
    best = None
    for pts in straights:
        for hinge, tip in ((pts[0], pts[-1]), (pts[-1], pts[0])):
            off = float(np.linalg.norm(hinge - centre))
            leaf_ok = abs(float(np.linalg.norm(tip - hinge)) - radius) <= snap
            if off <= snap and leaf_ok and (best is None or off < best[0]):
                best = (off, hinge, tip)
    if best is None:
        return None
    _, hinge, tip = best
    latch = max((arc[0], arc[-1]), key=lambda end: float(np.linalg.norm(end - tip)))
    if np.linalg.norm(latch - hinge) <= MERGE:
        return None
    return hinge, latch, tip


def _circle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Centre and radius of the circle through three points; None when they are in a line."""
    d = 2.0 * (a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]))
    if abs(d) <= MERGE * MERGE:
        return None
    sa, sb, sc = a @ a, b @ b, c @ c
    centre = np.array([sa * (b[1] - c[1]) + sb * (c[1] - a[1]) + sc * (a[1] - b[1]),
                       sa * (c[0] - b[0]) + sb * (a[0] - c[0]) + sc * (b[0] - a[0])]) / d
    return centre, float(np.linalg.norm(a - centre))


def _wall_direction(axis: np.ndarray, near: Polygon, walls) -> np.ndarray:
    """The direction of the longest wall edge in ``near`` within
    ``WALL_DIRECTION_SNAP_DEG`` of ``axis`` (a leaf drawn shut meets its
    pair's a few degrees off the wall); ``axis`` when there is none."""
    local = _clipped(walls, near)
    if local.is_empty:  # (an empty collection has no boundary)
        return axis
    edges = local.boundary.intersection(near)
    return longest_edge_along(edges, axis, WALL_DIRECTION_SNAP_DEG)


def _clipped(walls, area: Polygon):
    """``walls`` cut to the bounding box of ``area``."""
    x0, y0, x1, y1 = area.bounds
    try:
        return shapely.clip_by_rect(walls, x0, y0, x1, y1)
    except shapely.errors.GEOSException:  # GEOS's fast clip refuses some valid inputs
        return walls.intersection(area.envelope)


def _rectangle(axis: np.ndarray, normal: np.ndarray, t0: float, t1: float, s0: float, s1: float) -> Polygon:
    """The rectangle ``t0..t1`` along ``axis`` by ``s0..s1`` along ``normal``."""
    return Polygon([axis * t0 + normal * s0, axis * t1 + normal * s0, axis * t1 + normal * s1, axis * t0 + normal * s1])


__all__ = ["closed_leaf_opening", "walled_swing_doorway"]
