"""Door swings drawn on a wall layer: an arc and its leaf line.

Many drawings keep everything on one layer (a hackerspace's plan on layer
``0``): the walls, and each door as its swing, an arc about the hinge
through the leaf's path, and the leaf itself, a line from the hinge as long
as the arc's radius. Read as walls, a swing becomes a wall triangle that
seals the room. Found here by their geometry, they become door drawings, so
the opening between the jambs is cut as any door's.

A swing: an ARC whose radius is a door's width (``DOOR_SWING_RADIUS``) and
whose sweep is at most ``DOOR_SWING_MAX_SWEEP_DEG`` (doors are drawn open
from a few degrees to square), and a LINE on the same layer, the leaf,
starting at one end of the arc and crossing it (at least
``DOOR_SWING_MIN_CROSSING_DEG`` from the arc's tangent there: a straight
wall that a rounded corner joins runs along it). People draw swings
loosely (an arc through three points, its centre off the hinge; a leaf
longer than the radius), so the leaf's length is only bounded
(``DOOR_SWING_LEAF_LENGTH`` times the radius) and its start may miss the
arc's end by ``DOOR_SWING_TIP_SHARE`` of the radius.
"""

from __future__ import annotations

import math

import numpy as np

from mapkit.tolerances import (DOOR_SWING_LEAF_LENGTH, DOOR_SWING_MAX_SWEEP_DEG, DOOR_SWING_MIN_CROSSING_DEG,
                               DOOR_SWING_RADIUS, DOOR_SWING_SNAP, DOOR_SWING_TIP_SHARE)


def find_door_swings(entities, metres_per_unit: float) -> list[tuple[object, object]]:
    """The ``(arc, leaf)`` entity pairs of ``entities`` (loose model-space
    entities of one role) that draw a door's swing; each arc and line is in
    at most one pair. ``metres_per_unit`` converts the drawing's units."""
    arcs = [e for e in entities if e.dxftype() == "ARC"]
    lines = [e for e in entities if e.dxftype() == "LINE"]
    if not arcs or not lines:
        return []
    starts = np.array([[e.dxf.start.x, e.dxf.start.y] for e in lines], dtype=float) * metres_per_unit
    ends = np.array([[e.dxf.end.x, e.dxf.end.y] for e in lines], dtype=float) * metres_per_unit
    used: set[int] = set()
    pairs = []
    for arc in arcs:
        radius = float(arc.dxf.radius) * metres_per_unit
        sweep = (float(arc.dxf.end_angle) - float(arc.dxf.start_angle)) % 360.0
        if not (DOOR_SWING_RADIUS[0] <= radius <= DOOR_SWING_RADIUS[1]) or not 0 < sweep <= DOOR_SWING_MAX_SWEEP_DEG:
            continue
        leaf = _leaf_of(arc, radius, starts, ends, metres_per_unit, used)
        if leaf is not None:
            used.add(leaf)
            pairs.append((arc, lines[leaf]))
    return pairs


def _leaf_of(arc, radius: float, starts: np.ndarray, ends: np.ndarray, metres_per_unit: float,
             used: set[int]) -> int | None:
    """Index of the line that is ``arc``'s leaf: from one end of the arc,
    across it (not along it, as the straight wall a rounded corner joins)."""
    centre = np.array([arc.dxf.center.x, arc.dxf.center.y], dtype=float) * metres_per_unit
    snap = max(DOOR_SWING_SNAP, DOOR_SWING_TIP_SHARE * radius)
    best, best_gap = None, math.inf
    for angle in (float(arc.dxf.start_angle), float(arc.dxf.end_angle)):
        a = math.radians(angle)
        tip = centre + radius * np.array([math.cos(a), math.sin(a)])
        tangent = np.array([-math.sin(a), math.cos(a)])
        for near, far in ((starts, ends), (ends, starts)):  # a leaf may be drawn either way round
            gap = np.linalg.norm(near - tip, axis=1)
            d = far - near
            length = np.linalg.norm(d, axis=1)
            across = np.abs(d @ tangent) <= math.cos(math.radians(DOOR_SWING_MIN_CROSSING_DEG)) * length
            ok = ((gap <= snap) & across & (length >= DOOR_SWING_LEAF_LENGTH[0] * radius)
                  & (length <= DOOR_SWING_LEAF_LENGTH[1] * radius))
            for k in np.nonzero(ok)[0]:
                if int(k) not in used and gap[k] < best_gap:
                    best, best_gap = int(k), float(gap[k])
    return best
