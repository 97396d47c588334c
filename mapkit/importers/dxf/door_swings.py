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
arc's end by ``DOOR_SWING_TIP_SHARE`` of the radius. Looser still
(:func:`_loose_leaf_of`): a leaf from the arc's centre to a point inside
its sweep (the arc overshoots the open leaf), or a leaf whose tip is at one
end of a three-point arc whose other end, the latch, lies a leaf's length
from the hinge (the arc's centre far off the hinge, its radius half the
leaf's).
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
        if not is_door_sized_arc(arc, metres_per_unit):
            continue
        radius = float(arc.dxf.radius) * metres_per_unit
        leaf = _leaf_of(arc, radius, starts, ends, metres_per_unit, used)
        if leaf is None:
            leaf = _loose_leaf_of(arc, radius, starts, ends, metres_per_unit, used)
        if leaf is not None:
            used.add(leaf)
            pairs.append((arc, lines[leaf]))
    return pairs


def is_door_sized_arc(arc, metres_per_unit: float) -> bool:
    """Whether the ARC entity ``arc`` could be a door's swing: its radius a
    door's width (``DOOR_SWING_RADIUS``, metres) and its sweep at most
    ``DOOR_SWING_MAX_SWEEP_DEG``; ``metres_per_unit`` converts its units."""
    radius = float(arc.dxf.radius) * metres_per_unit
    sweep = (float(arc.dxf.end_angle) - float(arc.dxf.start_angle)) % 360.0
    return DOOR_SWING_RADIUS[0] <= radius <= DOOR_SWING_RADIUS[1] and 0 < sweep <= DOOR_SWING_MAX_SWEEP_DEG


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


def _loose_leaf_of(arc, radius: float, starts: np.ndarray, ends: np.ndarray, metres_per_unit: float,
                   used: set[int]) -> int | None:
    """Index of the line that is ``arc``'s leaf in a swing drawn more loosely
    than :func:`_leaf_of` accepts, or None:

    - a radial leaf: from the arc's centre (the hinge) to a point of the
      arc, inside its sweep, where the arc overshoots the leaf's tip (hal9k's
      plan: a tip 12 cm from the arc's end);
    - an arc through three points, its centre far off the hinge: the leaf's
      tip at one end of the arc (within ``DOOR_SWING_TIP_SHARE`` of the
      leaf's length), across it, and the arc's other end, where the closed
      door's latch is, as far from the hinge as the leaf is long.
    """
    centre = np.array([arc.dxf.center.x, arc.dxf.center.y], dtype=float) * metres_per_unit
    start, end = float(arc.dxf.start_angle), float(arc.dxf.end_angle)
    sweep = (end - start) % 360.0
    tips = [centre + radius * np.array([math.cos(math.radians(a)), math.sin(math.radians(a))]) for a in (start, end)]
    cos_cross = math.cos(math.radians(DOOR_SWING_MIN_CROSSING_DEG))
    best, best_err = None, math.inf
    for hinge, tip in ((starts, ends), (ends, starts)):
        d = tip - hinge
        length = np.linalg.norm(d, axis=1)
        snap = np.maximum(DOOR_SWING_SNAP, DOOR_SWING_TIP_SHARE * length)
        door_wide = (length >= DOOR_SWING_RADIUS[0]) & (length <= DOOR_SWING_RADIUS[1])
        # Radial: the hinge on the centre, the tip on the arc inside its sweep.
        from_centre = np.linalg.norm(hinge - centre, axis=1)
        to_tip = tip - centre
        angle = np.degrees(np.arctan2(to_tip[:, 1], to_tip[:, 0]))
        inside = (angle - start) % 360.0 <= sweep
        radial = door_wide & (from_centre <= snap) & (np.abs(length - radius) <= DOOR_SWING_TIP_SHARE * radius) & inside
        for k in np.nonzero(radial)[0]:
            err = float(from_centre[k])
            if int(k) not in used and err < best_err:
                best, best_err = int(k), err
        # Through three points: the tip at one end of the arc, the latch at the other.
        for near, far in ((tips[0], tips[1]), (tips[1], tips[0])):
            gap = np.linalg.norm(tip - near, axis=1)
            latch = np.abs(np.linalg.norm(far - hinge, axis=1) - length)
            a = math.atan2(near[1] - centre[1], near[0] - centre[0])
            tangent = np.array([-math.sin(a), math.cos(a)])
            across = np.abs(d @ tangent) <= cos_cross * length
            ok = door_wide & (gap <= snap) & (latch <= snap) & across
            for k in np.nonzero(ok)[0]:
                err = float(gap[k] + latch[k])
                if int(k) not in used and err < best_err:
                    best, best_err = int(k), err
    return best
